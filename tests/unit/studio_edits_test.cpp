// tools/studio/studio_rule_edits.h: the studio's edits change exactly the text of the item they edit (a number, a
// rule), keep comments, units and layout everywhere else, quote names that need it, and refuse texts with errors,
// unknown names and MATLAB files with a message.
#include <catch2/catch.hpp>

#include <string>

#include "tools/studio/studio_files.h"
#include "tools/studio/studio_rule_edits.h"

namespace fmpc::studio {
namespace {

const char* kText = R"(# a comment that stays
system s
  type mamdani

input x "reading" in [0, 10] kPa
  low is triangle(start 0, peak 2, end 5)   # low readings
  high is gauss(mean 8000 Pa, sd 1.5 kPa)

output y in [0, 1] dimensionless
  "F0-F1" is triangle(start 0, peak 0.2, end 0.5)
  big is triangle(start 0.5, peak 1, end 1)

rule r1: if x is low then y is "F0-F1"  # keep me
rule "second one": if x is high then y is big weight 0.5
)";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

TEST_CASE("studio edits: a parameter's number, nothing else", "[studio]") {
  std::string error;
  const auto peak = set_term_parameter("t.fis", kText, "s", "x", "low", "peak", 2.5, error);
  REQUIRE(peak);
  CHECK(*peak == replaced(kText, "peak 2,", "peak 2.5,"));
  // A unit that is not the variable's goes (the value is in the variable's unit); the variable's own stays.
  const auto mean = set_term_parameter("t.fis", kText, "", "x", "high", "mean", 7.25, error);
  REQUIRE(mean);
  CHECK(*mean == replaced(kText, "mean 8000 Pa", "mean 7.25"));
  const auto sd = set_term_parameter("t.fis", kText, "s", "x", "high", "sd", 2, error);
  REQUIRE(sd);
  CHECK(*sd == replaced(kText, "sd 1.5 kPa", "sd 2 kPa"));
  const auto quoted = set_term_parameter("t.fis", kText, "s", "y", "F0-F1", "end", 0.45, error);
  REQUIRE(quoted);
  CHECK(*quoted == replaced(kText, "end 0.5)\n  big", "end 0.45)\n  big"));
}

TEST_CASE("studio edits: refusals say why", "[studio]") {
  std::string error;
  CHECK_FALSE(set_term_parameter("t.fis", kText, "s", "x", "low", "middle", 1, error));
  CHECK(error == "term 'low' of 'x' has no parameter 'middle'");
  CHECK_FALSE(set_term_parameter("t.fis", kText, "s", "x", "medium", "peak", 1, error));
  CHECK(error == "'x' has no term 'medium'");
  CHECK_FALSE(set_term_parameter("t.fis", kText, "s", "z", "low", "peak", 1, error));
  CHECK(error == "there is no variable 'z'");
  CHECK_FALSE(set_term_parameter("t.fis", kText, "s", "x", "low", "peak", std::nan(""), error));
  CHECK(error == "give a finite number");
  CHECK_FALSE(set_term_parameter("t.fis", kText, "other", "x", "low", "peak", 1, error));
  CHECK(error == "there is no system 'other' in the text");
  CHECK_FALSE(set_term_parameter("t.fis", replaced(kText, "then y is big", "then y is bigg"), "s", "x", "low", "peak", 1,
                                 error));
  CHECK(error == "the text has errors: fix them first (they are listed under the editor)");
  CHECK_FALSE(set_term_parameter("t.fis", "[System]\nName='m'\n", "", "x", "low", "peak", 1, error));
  CHECK(error.find("MATLAB .fis file; the table and the membership editor change fmpc files") != std::string::npos);
}

TEST_CASE("studio edits: rules are rewritten, added and deleted in place", "[studio]") {
  std::string error;
  RuleSpec spec;
  spec.antecedent = {{"x", "high", true, "very"}};
  spec.consequent = {{"y", "F0-F1", false, ""}};
  spec.weight = 0.75;
  const auto set = set_rule("t.fis", kText, "s", 1, spec, error);
  REQUIRE(set);
  CHECK(*set == replaced(kText, "rule \"second one\": if x is high then y is big weight 0.5",
                         "rule \"second one\": if x is not very high then y is \"F0-F1\" weight 0.75"));
  const auto first = set_rule("t.fis", kText, "s", 0, RuleSpec{{{"x", "high", false, ""}}, {{"y", "big", false, ""}}, true, 1},
                              error);
  REQUIRE(first);
  CHECK(*first == replaced(kText, "rule r1: if x is low then y is \"F0-F1\"  # keep me",
                           "rule r1: if x is high then y is big  # keep me"));
  const auto added = add_rule("t.fis", kText, "s", RuleSpec{}, error);
  REQUIRE(added);
  CHECK(*added == std::string(kText) + "rule r3: if x is low then y is \"F0-F1\"\n");
  const auto removed = delete_rule("t.fis", kText, "s", 0, error);
  REQUIRE(removed);
  CHECK(*removed == replaced(kText, "rule r1: if x is low then y is \"F0-F1\"  # keep me\n", ""));
  CHECK_FALSE(set_rule("t.fis", kText, "s", 1, RuleSpec{{{"x", "nope", false, ""}}, {{"y", "big", false, ""}}, true, 1},
                       error));
  CHECK(error == "'x' has no term 'nope'");
  CHECK_FALSE(set_rule("t.fis", kText, "s", 1, RuleSpec{{}, {{"y", "big", false, ""}}, true, 1}, error));
  CHECK(error == "a rule needs at least one condition and one conclusion");
  CHECK_FALSE(delete_rule("t.fis", kText, "s", 7, error));
  CHECK(error == "there is no rule 8");
}

TEST_CASE("studio edits: the first rule of a system goes after its variables", "[studio]") {
  const std::string text = "system s\ninput x in [0, 1] kPa\n  a is gauss(mean 0.5, sd 0.1)\noutput y in [0, 1] kPa\n"
                           "  b is gauss(mean 0.5, sd 0.1)\n";
  std::string error;
  const auto added = add_rule("t.fis", text, "", RuleSpec{}, error);
  REQUIRE(added);
  CHECK(*added == text + "\nrule r1: if x is a then y is b\n");
}

TEST_CASE("offset_of counts lines and byte columns", "[studio]") {
  const std::string text = "ab\ncd\n";
  CHECK(offset_of(text, 1, 1) == 0u);
  CHECK(offset_of(text, 2, 2) == 4u);
  CHECK(offset_of(text, 2, 3) == 5u);  // one past the last character of the line
  CHECK_FALSE(offset_of(text, 2, 4));
  CHECK_FALSE(offset_of(text, 4, 1));
  CHECK_FALSE(offset_of(text, 0, 1));
}

TEST_CASE("text_version is the content hash as 16 hex digits", "[studio]") {
  CHECK(text_version("") == "cbf29ce484222325");
  CHECK(text_version("a") != text_version("b"));
}

}  // namespace
}  // namespace fmpc::studio
