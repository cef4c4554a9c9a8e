#pragma once
// The order of the IR passes (DESIGN section 2) and what `fmpc compile` hands to the back ends:
//   specialize(bindings) -> prune_rules -> fuse_consequents -> drop_dead_terms
// specialize first, so that pruning sees the fixed inputs' grades; pruning before fusing, so that dead rules are
// not fused into live ones; dropping terms last, once no rule names them. docs/compiler.md explains each pass.
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "compiler/passes/pass_report.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

struct FixedInput {
  std::string name;
  double value = 0.0;
  SourceRange origin;  // where the binding was written (a scene line, or the command-line argument)
};

// The most breakpoints one table axis may be given (`--vary NAME:POINTS`, compile_table's vary={NAME: POINTS}).
inline constexpr int kMaxAxisPoints = 1000000;

struct VariedInput {
  std::string name;
  int points = 0;  // breakpoints of its table axis, 2 to kMaxAxisPoints; 0 = chosen by the table builder
  SourceRange origin;
};

// Inputs neither fixed nor varied vary, with points chosen automatically.
struct Bindings {
  std::vector<FixedInput> fixed;
  std::vector<VariedInput> varied;
};

struct PipelineOptions {
  double prune_epsilon = 0.0;          // prune_rules: 0 removes only the rules that cannot fire (exact)
  std::vector<std::string> dump_after;  // pass names whose result to print (print_ir); "all" = every pass
  // The caller's back end takes interval type-2 systems (every fmpc compile target and fmpc trade do); otherwise
  // they are refused.
  bool interval_type2 = false;
};

struct IrDump {
  std::string pass;
  std::string text;
};

struct CompileResult {
  FuzzySystem system;  // specialised: only the varying inputs remain, in the source's declaration order
  std::vector<int> source_inputs;   // per input of `system`: its index in the source system
  std::vector<int> axis_points;     // per input of `system`: the --vary NAME:points given, 0 when automatic
  std::vector<std::pair<int, double>> fixed;  // (source input index, value), in declaration order
  std::vector<PassReport> reports;  // one per pass, in pipeline order
  std::vector<IrDump> dumps;        // the dumps asked for, in pipeline order

  // Sum of the passes' bounds (each bounds one step: the triangle inequality bounds the chain).
  double error_bound() const;
};

// The pass names in pipeline order.
const std::vector<std::string>& pipeline_pass_names();

// Resolves the bindings against `source` and runs the passes. Errors (located at the binding's origin, with
// "did you mean"): an unknown input, an input bound twice or both fixed and varied, a NaN value, fewer than 2
// points, an unknown --dump-after pass, nothing left to vary; an interval type-2 system unless
// options.interval_type2, and then a prune_epsilon > 0 (no bound is known for type reduction). Type-2 systems go
// through every pass: specialize folds each end of the firing interval, prune_rules removes the rules whose upper
// firing bound is 0, fuse_consequents works on each end, drop_dead_terms is the same (each pass's header).
// A fixed value outside the input's range is a warning (evaluated as given, as the interpreter does).
// Unlabelled rules are labelled "rN" (their 1-based position in the source) so reports name them stably.
std::optional<CompileResult> run_pipeline(const FuzzySystem& source, const Bindings& bindings,
                                          const PipelineOptions& options, DiagnosticList& diagnostics);

}  // namespace fmpc
