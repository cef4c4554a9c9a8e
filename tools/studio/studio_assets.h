#pragma once
// The studio's web page (tools/studio/web: index.html, studio.css and the scripts), embedded into fmpc at build
// time (cmake/FmpcEmbedText.cmake), so that the binary serves it from anywhere without an installed copy.
#include <string_view>

namespace fmpc {

// The file's text by its name ("index.html", "studio.js"); empty for a name that is not part of the page.
std::string_view studio_asset(std::string_view name);

}  // namespace fmpc

namespace fmpc::studio {
using fmpc::studio_asset;
}  // namespace fmpc::studio
