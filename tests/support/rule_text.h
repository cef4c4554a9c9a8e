#pragma once
// A system written as fmpc text in a test, read through the same loader as every command.
#include <catch2/catch.hpp>

#include <string>

#include "compiler/frontend/rule_file_loader.h"

namespace fmpc::testing {

// The one system of `text`; fails the test when the text has errors or several systems.
inline FuzzySystem system_from_text(const std::string& text) {
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file("t.fis", text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems.front();
}

}  // namespace fmpc::testing
