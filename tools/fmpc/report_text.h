#pragma once
// Text pieces the `validate` and `diff` reports (and the studio's panels) share: numbers to four significant
// digits, markdown tables, and at most so many evaluation warnings for a cohort.
#include <cstddef>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace fmpc::cli {

// Four significant digits: what a reader compares at a glance (the CSV keeps every digit). NaN prints "nan".
std::string four_digits(double value);
// "1.234 kPa"; the number alone without a unit ("" or "dimensionless").
std::string four_digits_with_unit(double value, const std::string& unit);

// A GitHub-flavoured markdown table; `|` in a cell is escaped.
std::string markdown_table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows);

// Appends `from` to `to`, keeping the errors and the first `max_warnings` warnings; the rest are counted in a note
// located at `file` ("12 more warnings not shown").
void append_capped(const DiagnosticList& from, std::size_t max_warnings, const std::string& file, DiagnosticList& to);

}  // namespace fmpc::cli
