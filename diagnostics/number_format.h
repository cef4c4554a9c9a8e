#pragma once
#include <string>

namespace fmpc {

// The shortest decimal text that reads back as exactly `value` (std::to_chars), so that writing a system and
// reading it again keeps every bit: 7.64 stays "7.64", 0.1 + 0.2 becomes "0.30000000000000004".
// Infinities are "inf"/"-inf" and NaN is "nan"; every writer in fmpc (fmpc text, MATLAB .fis, CSV) uses this.
std::string format_number(double value);

// `digits` significant digits for reports and messages (printf's %.*g: 0.0123, 1.5e+06); not for numbers that must
// read back exactly (format_number).
std::string significant_digits(double value, int digits);

}  // namespace fmpc
