#pragma once
// Whether two systems compute the same outputs: what `fmpc convert` checks before it writes a file, by reading the
// written text back and comparing it with the system it meant to write (docs/matlab_fis.md, "Lossy conversion").
#include <functional>
#include <string>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

struct OutputComparison {
  EvaluationOptions evaluation;
  std::size_t random_points = 1000;
  bool settings = true;  // compare the settings too (false where a change of settings is what was asked for)
  // Called before each probe point with (points done, points in all): 1,300 points of a 100,000-rule system take
  // minutes.
  std::function<void(std::size_t, std::size_t)> progress;
};

// The ways `written` computes different outputs from `intended`, in words, or nothing when it computes the same:
// - the settings that decide outputs where probes may not reach: system type, type-2 or not, type reduction,
//   defuzzifier, the norms, the output sampling, the no-fire policy and its value, the variables and their ranges;
// - the outputs (and type-2 intervals) at probe points: every corner of the inputs' box (up to 8 inputs), its
//   centre, 101 points across each input's range with the others at their middle, and `random_points` seeded
//   uniform points; the largest difference per output and where, when above 1e-12 of the output's range.
// Names of variables and terms, descriptions, units and rule labels are not compared (the writers report them).
// The settings in the first group above that differ, each as "the defuzzifier changes from centroid to bisector"
// (variables are not compared here).
std::vector<std::string> setting_changes(const FuzzySystem& a, const FuzzySystem& b);

std::vector<std::string> output_changes(const FuzzySystem& intended, const FuzzySystem& written,
                                        const OutputComparison& comparison = {});

// The names `written` spells differently from `intended` (the system's, its variables' and their terms'), in words:
// the fmpc language writes '"' in a name as '\'' and a line break as a space, and the points a user evaluates
// name inputs and outputs, so a changed name is never silent (`fmpc convert` warns, -Wrenamed-term).
std::vector<std::string> name_changes(const FuzzySystem& intended, const FuzzySystem& written);

}  // namespace fmpc
