#pragma once
// A cohort's patients file (fmpc simulate --patients, docs/cohorts.md): a CSV with a header row, a `label` column
// and one column per rule input the scene binds to a constant, read by the CLI's CSV reader so that every message
// points at its cell. Every row is checked before anything runs.
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::cli {

struct PatientRow {
  std::string label;
  std::vector<double> values;  // one per PatientsFile::inputs
  int line = 0;                // in the file
};

struct PatientsFile {
  std::vector<std::string> inputs;  // the input columns, in the file's order
  std::vector<PatientRow> patients;
};

// Reads and checks the file against the scene and its rule system: a `label` column; every other column an input of
// `system` that the scene binds to a constant (a column for an input bound per region or by strain, an unknown or
// repeated column, and a constant binding without a column are errors); every value a finite number (out of the
// input's range: a warning, evaluated as given, as `fmpc eval`); every label a safe folder name, unique also
// ignoring case; at least one row and at most sim::kMaxCohortPatients. nullopt after errors.
std::optional<PatientsFile> read_patients_file(const std::string& path, const sim::Scene& scene,
                                               const FuzzySystem& system, SourceFiles& sources,
                                               DiagnosticList& diagnostics);

}  // namespace fmpc::cli
