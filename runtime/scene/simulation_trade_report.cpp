// The simulation trade's outputs (runtime/scene/simulation_trade.h): the CSV, the markdown report, the decision
// line and the chosen variant written back as a scene.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/scene/simulation_trade.h"
#include "runtime/scene/trade_runs.h"

namespace fmpc::sim {

namespace {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c == '\n' ? ' ' : c;
  }
  return quoted + "\"";
}

std::string model_column(const TradeModel& model) {
  return model.element_law >= 0 ? trade_model_name(model) : std::string("springs");
}

std::string status_text(const SimulationTradeRow& row) {
  if (!row.skipped.empty()) return row.skipped;
  if (!row.completed) return "failed: " + row.failure;
  if (row.inverted_elements > 0) return "completed, " + std::to_string(row.inverted_elements) + " inverted elements";
  return "completed";
}

// "displacement max 1.2%, probe force 3%": the measures a decision keeps.
std::string measured_text(const SimulationTradeResult& result, const TradeErrors& errors) {
  std::string text;
  if (result.measures.displacement) text += "displacement max " + trade_percent(errors.displacement_max);
  if (result.measures.probe_force)
    text += std::string(text.empty() ? "" : ", ") + "probe force " +
            (errors.probe_force ? trade_percent(*errors.probe_force) : std::string("none"));
  return text;
}

double largest_measured(const SimulationTradeResult& result, const SimulationTradeRow& row) {
  double value = result.measures.displacement ? row.errors.displacement_max : 0.0;
  if (result.measures.probe_force)
    value = std::max(value, row.errors.probe_force ? *row.errors.probe_force : HUGE_VAL);
  return value;
}

// A path the written scene names: relative to its own folder when the two share a root, else absolute.
std::string path_from(const std::string& path, const std::string& out_path) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path absolute = fs::absolute(path, error);
  const fs::path folder = fs::absolute(fs::path(out_path), error).parent_path();
  const fs::path relative = absolute.lexically_relative(folder);
  return relative.empty() ? absolute.generic_string() : relative.generic_string();
}

// What the estimates that ordered the runs were worth (docs/trade.md, "Cheapest first"): the measured CPU time over
// the estimate, at its extremes, for the runs that went on past their prefix; empty when nothing was estimated.
std::string cheapest_first_text(const SimulationTradeResult& result) {
  std::size_t estimated = 0, ran = 0, skipped = 0;
  double low = HUGE_VAL, high = 0.0, nearest = HUGE_VAL;
  const double chosen = result.chosen ? result.rows[*result.chosen].cpu_seconds : HUGE_VAL;
  std::size_t fewest_steps = 0, most_steps = 0;
  for (const SimulationTradeRow& row : result.rows) {
    if (!(row.estimated_seconds > 0.0)) continue;
    ++estimated;
    fewest_steps = estimated == 1 ? row.estimate_steps : std::min(fewest_steps, row.estimate_steps);
    most_steps = std::max(most_steps, row.estimate_steps);
    if (!row.skipped.empty()) {
      ++skipped;
      nearest = std::min(nearest, row.estimated_seconds / chosen);
    }
    if (!row.completed) continue;
    ++ran;
    const double ratio = row.cpu_seconds / row.estimated_seconds;
    low = std::min(low, ratio);
    high = std::max(high, ratio);
  }
  if (estimated == 0) return "";
  std::ostringstream text;
  text << "\nCheapest first: " << estimated << " variants were timed over their first " << fewest_steps;
  if (most_steps != fewest_steps) text << " to " << most_steps;
  text << " steps and their CPU time extrapolated; " << skipped << " estimated above the cheapest run meeting "
          "--max-error were skipped";
  if (ran > 0)
    text << "; of the " << ran << " that ran on, the measured time was " << significant_digits(low, 3) << " to "
         << significant_digits(high, 3) << " times the estimate";
  if (skipped > 0 && std::isfinite(nearest))
    text << "; the nearest skipped estimate is " << significant_digits(nearest, 3) << " times the chosen's time";
  text << ".\n";
  return text.str();
}

}  // namespace

std::vector<std::string> simulation_trade_columns() {
  return {"variant",          "model",       "precision",  "integrator",
          "dt_s",             "vertices",    "displacement_max_rel_error",
          "displacement_rms_rel_error",      "probe_force_rel_error",
          "steps_per_second", "memory_bytes", "mapping",   "refinements",
          "tetrahedra",       "steps",       "inverted_elements", "status",
          "element",          "mesh",        "real_time_factor", "wall_seconds", "meets_max_error",
          "cpu_seconds",      "estimated_cpu_seconds"};
}

std::string simulation_trade_csv(const SimulationTradeResult& result) {
  std::ostringstream csv;
  const std::vector<std::string> columns = simulation_trade_columns();
  for (std::size_t c = 0; c < columns.size(); ++c) csv << (c ? "," : "") << columns[c];
  csv << '\n';
  for (const SimulationTradeRow& row : result.rows) {
    const bool springs = trade_has_springs(row.model);
    const auto error_text = [&](double value) { return row.completed ? format_number(value) : std::string(); };
    csv << csv_field(row.variant) << ',' << model_column(row.model) << ','
        << (row.precision == Precision::Float ? "float" : "double") << ',' << scene_name(row.integrator.integrator)
        << ',' << format_number(row.dt) << ',' << row.vertices << ',' << error_text(row.errors.displacement_max) << ','
        << error_text(row.errors.displacement_rms) << ','
        << (row.completed && row.errors.probe_force ? format_number(*row.errors.probe_force) : "") << ','
        << format_number(row.steps_per_second) << ',' << format_number(row.memory_bytes) << ','
        << (springs ? scene_name(row.mapping) : "") << ',' << row.refinements << ',' << row.tetrahedra << ','
        << row.steps << ',' << row.inverted_elements << ',' << csv_field(status_text(row)) << ','
        << (row.element_kind >= 0 ? element_kind_row(row.element_kind).keyword : "") << ','
        << (row.mesh == TradeMesh::Uniform ? "uniform" : "scene") << ',' << format_number(row.real_time_factor) << ','
        << format_number(row.wall_seconds) << ','
        << (result.max_error ? (meets_max_error(result, row) ? "yes" : "no") : "") << ','
        << (row.completed || !row.failure.empty() ? format_number(row.cpu_seconds) : "") << ','
        << (row.estimated_seconds > 0.0 ? format_number(row.estimated_seconds) : "") << '\n';
  }
  return csv.str();
}

std::string simulation_trade_decision(const SimulationTradeResult& result) {
  if (!result.max_error) return "";
  std::ostringstream line;
  const std::size_t variants = result.rows.size() - 1;
  line << "Decision: ";
  if (result.chosen) {
    const SimulationTradeRow& row = result.rows[*result.chosen];
    line << row.variant << " meets --max-error " << trade_percent(*result.max_error) << " ("
         << measured_text(result, row.errors) << ") in " << significant_digits(row.cpu_seconds, 3)
         << " s of CPU time for " << format_number(result.duration) << " s simulated (real-time factor "
         << significant_digits(row.real_time_factor, 3) << "): the cheapest of the " << result.meeting << " of "
         << variants << " variants that meet it.";
    return line.str();
  }
  const SimulationTradeRow* closest = nullptr;
  for (std::size_t i = 1; i < result.rows.size(); ++i)
    if (result.rows[i].completed && (!closest || largest_measured(result, result.rows[i]) <
                                                     largest_measured(result, *closest)))
      closest = &result.rows[i];
  line << "no variant of " << variants << " meets --max-error " << trade_percent(*result.max_error);
  if (closest) line << "; the closest is " << closest->variant << " (" << measured_text(result, closest->errors) << ")";
  line << ".";
  return line.str();
}

std::string simulation_trade_markdown(const SimulationTradeResult& result) {
  std::ostringstream md;
  const auto errors_text = [&](const TradeErrors& e) {
    std::string text = "displacement max " + trade_percent(e.displacement_max) + ", RMS " + trade_percent(e.displacement_rms);
    if (e.probe_force) text += ", probe force " + trade_percent(*e.probe_force);
    return text;
  };
  md << "# fmpc trade: scene " << result.scene_name << "\n\n";
  md << "Every run simulates " << format_number(result.duration) << " s on " << result.backend
     << "; errors are relative, at the final time, against the reference, over the scene's " << result.coarse_vertices
     << " compared vertices" << (result.has_probe_force ? " and the probe force" : "")
     << "; speed in steps per CPU second and as the real-time factor (simulated seconds per wall second); memory an "
        "estimate from the array sizes (docs/trade.md).\n\n";
  md << "Reference: " << result.reference_description << ".\n";
  md << "Its estimated error (its difference from itself with twice the step";
  if (result.reference_mesh_difference) md << ", and on the mesh one refinement coarser";
  md << "; at most the difference if it converges at first order or better): step "
     << errors_text(result.reference_time_difference);
  if (result.reference_mesh_difference) md << "; mesh " << errors_text(*result.reference_mesh_difference);
  else md << "; mesh: not estimated (the reference is on the scene's own mesh)";
  md << ".\n";
  if (result.max_error) {
    md << "Refined until both estimates are under a fifth of --max-error (" << trade_percent(*result.max_error / 5.0)
       << "), in " << result.reference_rounds.size() << " round" << (result.reference_rounds.size() == 1 ? "" : "s")
       << ":\n\n";
    for (const std::string& round : result.reference_rounds) md << "- " << round << "\n";
  }
  md << "\n| variant | dt (s) | vertices | displacement max error | displacement RMS error | probe force error | "
        "steps/CPU s | real-time factor | memory | inverted | status |\n";
  md << "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
  for (std::size_t i = 0; i < result.rows.size(); ++i) {
    const SimulationTradeRow& row = result.rows[i];
    const auto error = [&](double value) { return row.completed ? trade_percent(value) : std::string("-"); };
    const std::string mark = result.chosen && *result.chosen == i ? "**" : "";
    if (!row.skipped.empty()) {
      md << "| " << row.variant << " | - | - | - | - | - | - | - | - | - | " << row.skipped << " |\n";
      continue;
    }
    md << "| " << mark << row.variant << mark << " | " << significant_digits(row.dt, 3) << " | " << row.vertices
       << " | " << error(row.errors.displacement_max) << " | " << error(row.errors.displacement_rms) << " | "
       << (row.completed && row.errors.probe_force ? trade_percent(*row.errors.probe_force) : "-") << " | "
       << significant_digits(row.steps_per_second, 3) << " | " << significant_digits(row.real_time_factor, 3) << " | "
       << significant_digits(row.memory_bytes / 1024.0, 3) << " KiB | " << row.inverted_elements << " | "
       << status_text(row) << (meets_max_error(result, row) ? ", meets --max-error" : "") << " |\n";
  }
  md << cheapest_first_text(result);
  if (result.max_error) md << "\n" << simulation_trade_decision(result) << "\n";
  return md.str();
}

std::optional<std::string> chosen_scene_text(const Scene& scene, const std::string& text,
                                             const SimulationTradeResult& result, const std::string& out_path,
                                             DiagnosticList& diagnostics) {
  if (!result.chosen) return std::nullopt;
  const SimulationTradeRow& row = result.rows[*result.chosen];
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& error) {
    diagnostics.error(SourceRange{scene.path, 0, 0, 0, 0}, std::string("the scene cannot be read again: ") + error.what());
    return std::nullopt;
  }
  const TradeModel& model = row.model;
  if (trade_has_springs(model)) {
    root["model"] = "springs";
    root.remove("fem");
    if (model.element_law < 0) root["material"]["mapping"] = scene_name(model.mapping);
    if (model.element_law >= 0) root["springs"]["volume_term"] = true;
    else if (root["springs"] && root["springs"]["volume_term"]) root["springs"].remove("volume_term");
  } else {
    root["model"] = "fem";
    YAML::Node fem(YAML::NodeType::Map);
    fem.SetStyle(YAML::EmitterStyle::Flow);
    fem["law"] = element_law_row(model.element_law).keyword;
    fem["element"] = element_kind_row(std::max(row.element_kind, 0)).keyword;
    root["fem"] = fem;
    root.remove("springs");
    root.remove("law");
    for (const char* key : {"mapping", "thickness", "flexion_fraction"})
      if (root["material"] && root["material"][key]) root["material"].remove(key);
  }
  root["precision"] = row.precision == Precision::Float ? "float" : "double";
  root["integrator"] = scene_name(row.integrator.integrator);
  root["dt"] = format_number(row.dt);
  const unsigned refinements = scene.mesh.refinements + row.refinements;
  if (refinements > 0) root["mesh"]["refinements"] = refinements;
  if (row.mesh == TradeMesh::Uniform) root["mesh"]["size_far"] = format_number(scene.mesh.surface.options.size.size_near);
  // Files the scene names, resolved against its own folder, named from the written scene's.
  if (root["mesh"]["file"]) root["mesh"]["file"] = path_from(scene.mesh.file, out_path);
  if (root["mesh"]["surface"]) root["mesh"]["surface"] = path_from(scene.mesh.file, out_path);
  for (const char* key : {"rules", "table"})
    if (root["material"] && root["material"][key]) root["material"][key] = path_from(scene.material.file, out_path);

  YAML::Emitter emitter;
  emitter << root;
  std::ostringstream out;
  out << "# Written by fmpc trade --max-error " << format_number(*result.max_error) << " from " << scene.path << ": "
      << row.variant << ", the cheapest of the " << result.meeting << " of " << result.rows.size() - 1
      << " variants that met it.\n";
  out << "# Measured against the reference (" << result.reference_description << ") over "
      << format_number(result.duration) << " s: " << measured_text(result, row.errors) << " (displacement RMS "
      << trade_percent(row.errors.displacement_rms) << "); " << significant_digits(row.steps_per_second, 3)
      << " steps per CPU second, real-time factor " << significant_digits(row.real_time_factor, 3) << " on "
      << result.backend << ".\n";
  out << emitter.c_str() << "\n";
  // The written scene must read back as a scene.
  DiagnosticList check;
  if (!parse_scene(out_path, out.str(), check)) {
    std::string first;
    for (const Diagnostic& d : check.items())
      if (d.severity == Severity::Error && first.empty()) first = d.message;
    diagnostics.error(SourceRange{}, "--write-scene: the chosen variant's scene does not read back (" + first +
                                         "); this is a bug in fmpc trade");
    return std::nullopt;
  }
  return out.str();
}

}  // namespace fmpc::sim
