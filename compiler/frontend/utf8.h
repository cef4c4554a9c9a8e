#pragma once
#include <cstddef>
#include <string_view>

namespace fmpc {

// Byte offset of the first byte that does not start a well-formed UTF-8 sequence (Unicode 15, Table 3-7: no
// overlong forms, no surrogates, nothing above U+10FFFF), or npos. Both readers check their text with it before
// ANTLR sees it: ANTLR's input stream throws std::range_error on what this refuses (fuzz_matlab_fis found
// F4 90 8A 8B, above U+10FFFF, passing a looser check).
std::size_t first_invalid_utf8(std::string_view text);

}  // namespace fmpc
