#pragma once
// JSON documents (the run summary) are built as nlohmann::ordered_json (Debian nlohmann-json3-dev): members keep
// the order they were added in, and strings are escaped by the library (invalid UTF-8, e.g. in a file name, becomes
// U+FFFD rather than an invalid document). json_text lays the document out as nlohmann's dump(2) does, except for
// numbers: those are written in fmpc's one format (format_number: the shortest text that reads back as the same
// double), because nlohmann's own Grisu2 writes 2 as "2.0", switches to exponents at other magnitudes than
// std::to_chars, and is not always shortest. NaN and infinities, which JSON cannot hold, are written as null.
#include <string>

#include <nlohmann/json.hpp>

namespace fmpc::sim {

using JsonDocument = nlohmann::ordered_json;

// The document as text, with a final newline.
std::string json_text(const JsonDocument& document);

}  // namespace fmpc::sim
