#pragma once
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// MATLAB files may give two terms of one variable the same name (rules there name terms by number); the fmpc
// language names terms by name. Renames the second and later ones "NAME_2", "NAME_3", ... (skipping names in use)
// so the system can be written as fmpc text with the same meaning. Returns one line per rename, for a warning:
// "output 'theta': term 3 'out1mf' -> 'out1mf_2'".
std::vector<std::string> rename_duplicate_terms(FuzzySystem& system);

}  // namespace fmpc
