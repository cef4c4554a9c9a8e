#include <CLI/CLI.hpp>
#include <iostream>

#include "compiler/eval/output_comparison.h"
#include "compiler/frontend/fll.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/passes/mamdani_to_sugeno.h"
#include "compiler/passes/rename_duplicate_terms.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

namespace {

struct ConvertOptions {
  std::string file;
  std::string to;
  std::string output = "-";
  std::string system;
  bool allow_lossy = false;
};

// The written text read back, system by system, as `fmpc` would read the file (MATLAB's format or the fmpc
// language), against the systems it was written from: what would change in the outputs (empty: nothing). Names
// that read back otherwise are a warning in `diagnostics_out` (-Wrenamed-term), located at the system or `path`.
std::vector<std::string> changes_on_reading_back(const std::string& text, bool matlab,
                                                 const std::vector<FuzzySystem>& intended, const std::string& path,
                                                 ProgressLine& progress, DiagnosticList& diagnostics_out) {
  DiagnosticList diagnostics;
  const RuleFile back = matlab ? read_matlab_fis("converted.fis", text, diagnostics)
                               : load_rule_file("converted.fis", text, diagnostics);
  if (diagnostics.has_errors()) {
    std::vector<std::string> changes{"the written file does not read back"};
    for (const Diagnostic& d : diagnostics.items())
      if (d.severity == Severity::Error) changes.push_back("line " + std::to_string(d.range.line) + ": " + d.message);
    return changes;
  }
  if (back.systems.size() != intended.size())
    return {"the written file holds " + std::to_string(back.systems.size()) + " systems, not " +
            std::to_string(intended.size())};
  std::vector<std::string> changes;
  for (std::size_t k = 0; k < intended.size(); ++k) {
    const std::string prefix = intended.size() > 1 ? "system '" + intended[k].name + "': " : std::string();
    OutputComparison comparison;
    comparison.progress = [&](std::size_t done, std::size_t total) {
      progress.show_fraction(static_cast<double>(k) + static_cast<double>(done) / static_cast<double>(total),
                             static_cast<double>(intended.size()), "system");
    };
    for (const std::string& change : output_changes(intended[k], back.systems[k], comparison))
      changes.push_back(prefix + change);
    // Names do not change outputs, but the points a user evaluates name inputs: a renamed one is said.
    const std::vector<std::string> renamed = name_changes(intended[k], back.systems[k]);
    if (!renamed.empty())
      diagnostics_out.warning(intended[k].range.valid() ? intended[k].range : SourceRange{path, 0, 0, 0, 0},
                              "renamed-term",
                              prefix + std::to_string(renamed.size()) + " name" + (renamed.size() == 1 ? "" : "s") +
                                  " cannot be written as they are",
                              renamed);
  }
  return changes;
}

int run_convert(const ConvertOptions& options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  DiagnosticList diagnostics;
  std::string text;
  std::vector<FuzzySystem> intended;  // what the written text must compute
  bool matlab_text = options.to == "matlab";
  std::vector<std::string> approximation;  // --to sugeno: how the Sugeno system differs from the Mamdani one
  if (options.to == "fmpc") {
    RuleFile selected = file.rules;
    if (!options.system.empty()) {
      const FuzzySystem* system = select_system(file, options.system, diagnostics);
      selected.systems.clear();
      if (system) selected.systems.push_back(*system);
    }
    for (FuzzySystem& system : selected.systems) {
      const std::vector<std::string> renames = rename_duplicate_terms(system);
      if (!renames.empty())
        diagnostics.warning(system.range, "renamed-term",
                            "system '" + system.name + "' repeats term names, which fmpc rules cannot tell apart; " +
                                std::to_string(renames.size()) + " terms renamed",
                            renames);
    }
    text = write_fmpc(selected);
    intended = selected.systems;
  } else if (options.to == "sugeno") {
    // The converted system is written in the dialect the file was read in (fmpc text or MATLAB .fis).
    if (const FuzzySystem* system = select_system(file, options.system, diagnostics)) {
      FuzzySystem sugeno = *system;
      convert_mamdani_to_sugeno(sugeno, diagnostics);
      if (!diagnostics.has_errors()) {
        intended.push_back(sugeno);
        matlab_text = file.dialect == Dialect::Matlab;
        // The approximation is what --to sugeno asks for; it is measured and said, not refused.
        approximation = output_changes(*system, sugeno, {{}, 1000, false, {}});
        if (file.dialect == Dialect::Matlab) {
          text = write_matlab_fis(sugeno, diagnostics);
        } else if (file.dialect == Dialect::Fll) {
          text = write_fll(sugeno, diagnostics);
        } else if (file.dialect == Dialect::Fcl) {
          text = write_fcl(sugeno, diagnostics);
        } else {
          RuleFile converted;
          converted.path = file.rules.path;
          converted.systems.push_back(std::move(sugeno));
          text = "# Converted from " + options.file + " by `fmpc convert --to sugeno` (MATLAB convertToSugeno):\n" +
                 "# each output term is the constant at its centroid; weighted-average defuzzification.\n\n" +
                 write_fmpc(converted);
        }
      }
    }
  } else if (const FuzzySystem* system = select_system(file, options.system, diagnostics)) {
    if (options.to == "fll") text = write_fll(*system, diagnostics);
    else if (options.to == "fcl") text = write_fcl(*system, diagnostics);
    else text = write_matlab_fis(*system, diagnostics);
    intended.push_back(*system);
  }
  const SourceRange whole_file{options.file, 0, 0, 0, 0};
  if (!approximation.empty()) {
    std::vector<std::string> notes = approximation;
    notes.insert(notes.begin(), "each output term became the constant at its centroid (MATLAB's convertToSugeno), "
                                "so the outputs are an approximation of the Mamdani system's:");
    diagnostics.warning(whole_file, "sugeno-approximation", "the Sugeno system computes different outputs", notes);
  }
  // A conversion that would change what the system computes is refused unless asked for (issue 11): the text is
  // read back as fmpc would read the file and evaluated against the system it was written from.
  if (!diagnostics.has_errors()) {
    ProgressLine progress("convert");
    std::vector<std::string> changes =
        changes_on_reading_back(text, matlab_text, intended, options.file, progress, diagnostics);
    progress.finish();
    // What the writer itself reports as changing the outputs (an output unit scenes would read otherwise).
    std::size_t lossy_warnings = 0;
    for (const Diagnostic& d : diagnostics.items()) lossy_warnings += d.code == kMatlabLossy ? 1 : 0;
    if (changes.empty() && lossy_warnings > 0)
      changes.push_back(std::to_string(lossy_warnings) + " of the warnings above (-Wmatlab-lossy) change what the "
                                                         "file means");
    if (!changes.empty()) {
      const Dialect written = options.to == "fll"   ? Dialect::Fll
                              : options.to == "fcl" ? Dialect::Fcl
                              : options.to == "sugeno" ? file.dialect
                              : matlab_text         ? Dialect::Matlab
                                                    : Dialect::Fmpc;
      const std::string target = written == Dialect::Matlab ? "MATLAB's .fis format"
                                 : written == Dialect::Fll  ? "fuzzylite's FLL"
                                 : written == Dialect::Fcl  ? "FCL (IEC 61131-7)"
                                                            : "the fmpc language";
      if (options.allow_lossy) {
        diagnostics.warning(whole_file, "lossy-conversion",
                            "written in " + target + " with --allow-lossy: the file computes different outputs",
                            changes);
      } else {
        std::vector<std::string> notes = changes;
        notes.push_back("the warnings above say what " + target +
                        " cannot hold; --allow-lossy writes the file anyway");
        diagnostics.error(whole_file,
                          "converting to " + target + " would change what the system computes; nothing written",
                          notes);
      }
    }
  }
  print_diagnostics(diagnostics, file.sources, std::cerr);
  if (diagnostics.has_errors()) return kExitErrors;
  std::string error;
  if (!write_text_file_atomically(options.output, text, error)) {
    std::cerr << options.output << ": error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

}  // namespace

void register_convert_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* command = app.add_subcommand(
      "convert",
      "Convert a rule file between the fmpc language, MATLAB's .fis format (versions 1 and 2 read, 2.0 written),\n"
      "fuzzylite's FLL and IEC 61131-7 FCL, or a Mamdani system into a Sugeno one (--to sugeno, as MATLAB's\n"
      "convertToSugeno; written in the file's own format). What the target cannot hold is reported as a warning;\n"
      "a conversion that would change what the system computes is refused (nothing written) unless --allow-lossy\n"
      "is given.");
  command->add_option("file", options->file, "Rule file to convert (fmpc, MATLAB .fis, FLL or FCL)")->required();
  command->add_option("--to", options->to, "Target format")
      ->required()
      ->check(CLI::IsMember({"fmpc", "matlab", "fll", "fcl", "sugeno"}));
  command->add_option("-o,--output", options->output, "Output file, written atomically (default stdout)");
  command->add_option("--system", options->system, "Which system of the file to convert (MATLAB holds one)");
  command->add_flag("--allow-lossy", options->allow_lossy,
                    "Write the file even where the target format changes the outputs (it says by how much)");
  command->callback([options, &exit_code] { exit_code = run_convert(*options); });
}

}  // namespace fmpc::cli
