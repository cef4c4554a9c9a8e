#include "runtime/scene/cohort.h"

#include <cctype>
#include <cerrno>
#include <cstdlib>

namespace fmpc::sim {

std::string folded_label(const std::string& label) {
  std::string folded = label;
  for (char& c : folded) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return folded;
}

std::optional<std::string> unsafe_patient_label(const std::string& label) {
  if (label.empty()) return std::string("the label is empty");
  if (label.size() > kMaxPatientLabelBytes)
    return "the label has " + std::to_string(label.size()) + " bytes; at most " +
           std::to_string(kMaxPatientLabelBytes) + " name a folder";
  for (const char c : label) {
    const auto u = static_cast<unsigned char>(c);
    if (!(std::isalnum(u) && u < 128) && c != '_' && c != '-' && c != '.')
      return std::string("the label names a folder: use letters, digits, '_', '-' and '.' only");
  }
  if (label.front() == '.' || label.front() == '-')
    return std::string("the label names a folder: it cannot start with '.' or '-'");
  for (const char* reserved : {kCohortTableFile, kCohortPlotFile})
    if (folded_label(label) == reserved) return "'" + label + "' is the name of a file the cohort writes";
  return std::nullopt;
}

std::optional<CohortShard> parse_cohort_shard(const std::string& text, std::string& error) {
  const std::size_t slash = text.find('/');
  const auto whole = [](const std::string& part) -> std::optional<std::size_t> {
    if (part.empty() || part.size() > 9) return std::nullopt;
    for (const char c : part)
      if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
    return static_cast<std::size_t>(std::strtoull(part.c_str(), nullptr, 10));
  };
  const auto index = slash == std::string::npos ? std::nullopt : whole(text.substr(0, slash));
  const auto count = slash == std::string::npos ? std::nullopt : whole(text.substr(slash + 1));
  if (!index || !count) {
    error = "'" + text + "' is not I/N (two whole numbers below 10^9, e.g. 0/4: the first of four shards)";
    return std::nullopt;
  }
  if (*count == 0) {
    error = "'" + text + "': N is the number of shards, at least 1";
    return std::nullopt;
  }
  if (*index >= *count) {
    error = "'" + text + "': I counts from 0, so it must be below N (shards 0/" + std::to_string(*count) + " to " +
            std::to_string(*count - 1) + "/" + std::to_string(*count) + ")";
    return std::nullopt;
  }
  return CohortShard{*index, *count};
}

std::vector<std::size_t> shard_patients(std::size_t patient_count, const CohortShard& shard) {
  std::vector<std::size_t> members;
  if (shard.count == 0) return members;
  for (std::size_t p = shard.index; p < patient_count; p += shard.count) members.push_back(p);
  return members;
}

std::optional<std::vector<int>> parse_device_list(const std::string& text, int device_count, std::string& error) {
  const std::string present = device_count == 1 ? "the one device present is 0"
                                                 : "the devices present are 0 to " + std::to_string(device_count - 1);
  if (text == "all") {
    if (device_count <= 0) {
      error = "'all': no CUDA device is present";
      return std::nullopt;
    }
    std::vector<int> all(static_cast<std::size_t>(device_count));
    for (int d = 0; d < device_count; ++d) all[static_cast<std::size_t>(d)] = d;
    return all;
  }
  std::vector<int> devices;
  std::size_t from = 0;
  while (true) {
    const std::size_t comma = text.find(',', from);
    const std::string entry = text.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
    bool digits = !entry.empty() && entry.size() <= 4;
    for (const char c : entry) digits = digits && std::isdigit(static_cast<unsigned char>(c));
    if (!digits) {
      error = "'" + text + "': '" + entry + "' is not a device number (give 'all' or numbers separated by commas, e.g. 0,1)";
      return std::nullopt;
    }
    const int device = std::atoi(entry.c_str());
    if (device >= device_count) {
      error = "'" + text + "': device " + entry + " is not present; " +
              (device_count <= 0 ? std::string("no CUDA device is present") : present);
      return std::nullopt;
    }
    for (const int earlier : devices)
      if (earlier == device) {
        error = "'" + text + "': device " + entry + " is named twice (each device runs one batch)";
        return std::nullopt;
      }
    devices.push_back(device);
    if (comma == std::string::npos) break;
    from = comma + 1;
  }
  return devices;
}

std::vector<PatientRange> split_patients(std::size_t patient_count, std::size_t parts) {
  std::vector<PatientRange> ranges;
  if (parts == 0 || patient_count == 0) return ranges;
  const std::size_t used = parts < patient_count ? parts : patient_count;
  const std::size_t base = patient_count / used, larger = patient_count % used;
  std::size_t begin = 0;
  for (std::size_t r = 0; r < used; ++r) {
    const std::size_t size = base + (r < larger ? 1 : 0);
    ranges.push_back(PatientRange{begin, begin + size});
    begin += size;
  }
  return ranges;
}

Scene patient_scene(const Scene& scene, const std::string& label, const std::vector<std::string>& inputs,
                    const std::vector<double>& values) {
  Scene patient = scene;
  patient.material.patient = label;
  // Frames and the force-displacement picture per patient only when the scene asks (outputs.cohort).
  if (!scene.outputs.cohort_frames) patient.outputs.frames = 0;
  patient.outputs.plot = scene.outputs.plot && scene.outputs.cohort_plot;
  for (InputBinding& binding : patient.material.bindings) {
    if (binding.kind != InputBinding::Kind::Constant) continue;
    for (std::size_t i = 0; i < inputs.size() && i < values.size(); ++i)
      if (inputs[i] == binding.input) binding.value = values[i];
  }
  return patient;
}

}  // namespace fmpc::sim
