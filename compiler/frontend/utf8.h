#pragma once
#include <cstddef>
#include <string>
#include <string_view>

#include "diagnostics/diagnostic.h"

namespace fmpc {

// Byte offset of the first byte that does not start a well-formed UTF-8 sequence (Unicode 15, Table 3-7: no
// overlong forms, no surrogates, nothing above U+10FFFF), or npos. Both readers check their text with it before
// ANTLR sees it: ANTLR's input stream throws std::range_error on what this refuses (fuzz_matlab_fis found
// F4 90 8A 8B, above U+10FFFF, passing a looser check).
std::size_t first_invalid_utf8(std::string_view text);

// An error at the first byte of `text` that is not UTF-8 ("the file is not valid UTF-8 here", its line and column),
// and true; false when all of it is UTF-8. The MATLAB, FLL and FCL readers check their text with it (the fmpc
// language's parser has its own message).
bool report_invalid_utf8(const std::string& path, std::string_view text, DiagnosticList& diagnostics);

// `text` with every byte that does not start a well-formed sequence replaced by U+FFFD: for messages that quote
// bytes of any file (a binary file read as a scene) where only valid text may go (Python's str).
std::string valid_utf8(std::string_view text);

// A UTF-8 byte order mark (EF BB BF, which Windows editors put at the start of a file) is not part of the text.
// Every text reader takes it away the same way: replaced by three spaces, so that columns still count the bytes of
// the original file. load_rule_file does it for all four rule formats (a BOM once made an FLL file read as the fmpc
// language), the CLI's CSV reader for points and patients (a BOM once made the first column '\ufefflabel').
bool starts_with_byte_order_mark(std::string_view text);
std::string blank_byte_order_mark(std::string text);

}  // namespace fmpc
