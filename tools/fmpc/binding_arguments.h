#pragma once
// --fix NAME=VALUE and --vary NAME[:POINTS] as the commands that specialise a system read them (fmpc trade; fmpc
// compile may share it). Mistakes become located diagnostics naming the argument.
#include <string>
#include <vector>

#include "compiler/passes/pipeline.h"
#include "diagnostics/diagnostic.h"

namespace fmpc::cli {

Bindings parse_binding_arguments(const std::vector<std::string>& fix, const std::vector<std::string>& vary,
                                 DiagnosticList& diagnostics);

}  // namespace fmpc::cli
