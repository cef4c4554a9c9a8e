#include "tools/fmpc/warning_policy.h"

#include <CLI/CLI.hpp>

#include "diagnostics/warning_codes.h"

namespace fmpc::cli {

namespace {

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

std::string unknown_code(const std::string& value, const std::string& code) {
  std::vector<std::string> names;
  for (const WarningCode& c : warning_codes()) names.push_back(c.name);
  std::string message = "-W" + value + ": '" + code + "' is not a warning code";
  if (auto suggestion = closest_name(code, names)) message += "; did you mean '" + *suggestion + "'?";
  return message + " (the codes are listed in docs/cli.md)";
}

}  // namespace

std::string apply_warning_flag(const std::string& value, WarningPolicy& policy) {
  if (value == "error") {
    policy.all_errors = true;
    return {};
  }
  if (value == "no-error") {
    policy.all_errors = false;
    return {};
  }
  struct Form {
    const char* prefix;
    void (*apply)(WarningPolicy&, const std::string&);
  };
  static const Form forms[] = {
      {"error=", [](WarningPolicy& p, const std::string& c) { p.errors.insert(c), p.not_errors.erase(c), p.disabled.erase(c); }},
      {"no-error=", [](WarningPolicy& p, const std::string& c) { p.not_errors.insert(c), p.errors.erase(c); }},
      {"no-", [](WarningPolicy& p, const std::string& c) { p.disabled.insert(c); }},
      {"", [](WarningPolicy& p, const std::string& c) { p.disabled.erase(c); }},
  };
  for (const Form& form : forms) {
    if (!starts_with(value, form.prefix)) continue;
    const std::string code = value.substr(std::string(form.prefix).size());
    // "-Wno-X" where the code itself is "no-X" (no-rule-fired, no-fire-out-of-range) silences that code.
    if (std::string(form.prefix) == "no-" && !is_warning_code(code) && is_warning_code(value)) {
      policy.disabled.insert(value);
      return {};
    }
    if (std::string(form.prefix).empty() && !is_warning_code(code)) return unknown_code(value, code);
    if (!is_warning_code(code)) return unknown_code(value, code);
    form.apply(policy, code);
    return {};
  }
  return unknown_code(value, value);
}

DiagnosticList with_warning_policy(const DiagnosticList& diagnostics, const WarningPolicy& policy,
                                   std::size_t& promoted) {
  DiagnosticList result;
  for (Diagnostic d : diagnostics.items()) {
    if (d.severity == Severity::Warning) {
      if (policy.disabled.count(d.code)) continue;
      const bool to_error = policy.errors.count(d.code) || (policy.all_errors && !policy.not_errors.count(d.code));
      if (to_error) {
        d.severity = Severity::Error;
        d.code = "error=" + d.code;
        ++promoted;
      }
    }
    result.add(std::move(d));
  }
  return result;
}

WarningPolicy& process_warning_policy() {
  static WarningPolicy policy;
  return policy;
}

std::size_t& promoted_warning_count() {
  static std::size_t count = 0;
  return count;
}

void add_warning_options(CLI::App& command) {
  auto values = std::make_shared<std::vector<std::string>>();
  command
      .add_option("-W", *values,
                  "Warning control, as compilers: -Wno-CODE silences CODE, -Werror makes every warning fail the "
                  "command (exit 1), -Werror=CODE only CODE, -Wno-error=CODE exempts CODE (repeatable; codes: "
                  "docs/cli.md)")
      ->type_name("FLAG")
      ->allow_extra_args(false)  // -Werror=X FILE: the file is not a second -W value
      ->check(CLI::Validator(
          [values](std::string& value) { return apply_warning_flag(value, process_warning_policy()); }, "FLAG",
          "warning flag"));
}

}  // namespace fmpc::cli
