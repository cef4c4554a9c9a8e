#pragma once
// A cohort's patients as the simulator sees them (fmpc simulate --patients, docs/cohorts.md): the scene's material
// inputs replaced by each patient's values, the labels that name their output folders, the limits and the shards
// that spread a cohort over processes, GPUs or hosts. Reading the patients file is the CLI's (tools/fmpc).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

// Patients in one patients file (docs/limits.md): checked before any patient is built.
inline constexpr std::size_t kMaxCohortPatients = 100000;
// Springs (or tetrahedra with the FEM) of every patient of one run together: each patient's setup lives on the host
// (and the GPU batch indexes spring ends with int), so a cohort is refused before the patients are built when the
// first patient's size times the patients of the run exceeds it. Shard larger cohorts (--shard I/N).
inline constexpr double kMaxCohortSprings = 2e8;
// A label names its patient's output folder.
inline constexpr std::size_t kMaxPatientLabelBytes = 64;

// Why `label` cannot name a patient's folder on every file system (empty, too long, a character other than a
// letter, digit, '_', '-' or '.', a leading '.' or '-', or the name of a cohort file), or nullopt.
std::optional<std::string> unsafe_patient_label(const std::string& label);

// The folder name two labels share on a case-insensitive file system (macOS, Windows): labels equal here collide.
std::string folded_label(const std::string& label);

// Every N-th patient from the I-th: shard I of N (0 <= I < N).
struct CohortShard {
  std::size_t index = 0;
  std::size_t count = 1;
};

// "I/N" with 0 <= I < N and N >= 1, or nullopt with the reason in `error`.
std::optional<CohortShard> parse_cohort_shard(const std::string& text, std::string& error);

// The patients (indices into the file's rows, 0-based) shard `shard` runs: index, index + count, ...
std::vector<std::size_t> shard_patients(std::size_t patient_count, const CohortShard& shard);

// A cohort spread over the GPUs of one node (fmpc simulate --patients --devices, docs/cohorts.md): the devices
// parsed from "all" or a comma-separated list of CUDA device numbers ("0,1"). `device_count` is how many the process
// sees. "all" with no device, an entry that is not a whole number, a device out of range, a repeated device or an
// empty list: nullopt with the reason in `error`.
std::optional<std::vector<int>> parse_device_list(const std::string& text, int device_count, std::string& error);

// Patients [begin, end) of a run that one device (or one CPU slot) runs as its batch.
struct PatientRange {
  std::size_t begin = 0;
  std::size_t end = 0;
};

// `patient_count` patients in file order over `parts` batches: consecutive ranges whose sizes differ by at most one,
// the larger first; never an empty range (fewer ranges than parts when there are fewer patients).
std::vector<PatientRange> split_patients(std::size_t patient_count, std::size_t parts);

// The scene for one patient: each named input's constant binding set to the patient's value, material.patient set
// to the label, and its frames and force-displacement picture left out unless outputs.cohort asks for them (a
// patient writes summary.json and time_series.csv by default). Every name must be an input the scene binds to a
// constant (the caller checked).
Scene patient_scene(const Scene& scene, const std::string& label, const std::vector<std::string>& inputs,
                    const std::vector<double>& values);

// The files a cohort writes beside the patients' folders.
inline constexpr const char* kCohortTableFile = "cohort.csv";
inline constexpr const char* kCohortPlotFile = "cohort_force_displacement.png";

}  // namespace fmpc::sim
