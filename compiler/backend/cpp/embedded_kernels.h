#pragma once
// The text of fmpc's kernel headers, embedded at build time (cmake/FmpcEmbedText.cmake) so that generated code
// carries a verbatim copy of the one definition of each formula instead of a second hand-written one.
#include <string_view>

namespace fmpc {

// The text of `path` ("kernels/fuzzy_math.h", "kernels/fuzzy_kinds.h", "kernels/fmpc_hd.h"), or an empty view
// for a file that was not embedded.
std::string_view embedded_kernel_source(std::string_view path);

}  // namespace fmpc
