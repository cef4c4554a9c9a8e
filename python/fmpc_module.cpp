// The `fmpc` Python module (docs/python.md): rule files, their evaluation on numpy arrays (the interpreter, or a
// compiled .fzt lookup table), table compilation and scene runs, through the same library functions the fmpc CLI
// calls. Nothing here prints: diagnostics become fmpc.Diagnostic objects, and an error a user causes raises
// fmpc.Error (a ValueError) that carries them.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/eval/evaluation_report.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/utf8.h"
#include "compiler/passes/pipeline.h"
#include "diagnostics/number_format.h"
#include "compiler/ir/content_hash.h"
#include "kernels/table_math.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/input_file.h"
#include "runtime/io/memory_limit.h"
#include "runtime/io/rule_file_input.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "python/fmpc_module.h"
#include "python/python_diagnostics.h"
#include "python/session_module.h"

namespace py = pybind11;

namespace fmpc::python {

namespace {

// ---- arguments ----
// Every argument a function of the module takes comes in as a Python object and is converted here, so that a
// value of the wrong type or out of range is an fmpc.Error naming the argument. pybind11's own conversions raised
// RuntimeError "Unable to cast Python instance" (vary={'x': 2**40}, fix={'x': 10**400}) or TypeError
// "incompatible function arguments" without saying which argument. tests/fuzz/fuzz_python_arguments.cpp fuzzes
// every function through these.

std::string type_name(const py::handle& value) {
  return py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>();
}

// A str; bytes or anything else is refused.
std::string text_argument(const std::string& name, const py::handle& value) {
  if (!PyUnicode_Check(value.ptr())) raise_error(argument(name), "expected a str, not " + type_name(value));
  Py_ssize_t size = 0;
  const char* text = PyUnicode_AsUTF8AndSize(value.ptr(), &size);
  if (text == nullptr) {  // lone surrogates have no UTF-8 form
    PyErr_Clear();
    raise_error(argument(name), "the text cannot be written as UTF-8 (it holds a lone surrogate)");
  }
  return std::string(text, static_cast<std::size_t>(size));
}

// A path: a str or an os.PathLike naming one (pathlib.Path); no NUL byte.
std::string path_argument(const std::string& name, const py::handle& value) {
  py::object path = py::reinterpret_borrow<py::object>(value);
  if (!PyUnicode_Check(value.ptr())) {
    PyObject* fspath = PyOS_FSPath(value.ptr());
    if (fspath == nullptr) {
      PyErr_Clear();
      raise_error(argument(name), "expected a path (str or os.PathLike), not " + type_name(value));
    }
    path = py::reinterpret_steal<py::object>(fspath);
    if (!PyUnicode_Check(path.ptr())) raise_error(argument(name), "expected a path given as text, not bytes");
  }
  std::string text = text_argument(name, path);
  if (text.find('\0') != std::string::npos) raise_error(argument(name), "the path contains a NUL byte");
  return text;
}

bool flag_argument(const std::string& name, const py::handle& value) {
  if (!PyBool_Check(value.ptr())) raise_error(argument(name), "expected True or False, not " + type_name(value));
  return value.ptr() == Py_True;
}

// A real number in [low, high] (finite when the bounds are): an int, a float or another numbers.Real (numpy's
// numbers, fractions), not a bool.
double number_argument(const std::string& name, const py::handle& value, double low, double high) {
  const std::string range = "[" + format_number(low) + ", " + format_number(high) + "]";
  static const py::object real = py::module_::import("numbers").attr("Real");
  const bool is_real = PyFloat_Check(value.ptr()) || PyIndex_Check(value.ptr()) || py::isinstance(value, real);
  if (PyBool_Check(value.ptr()) || py::isinstance(value, py::module_::import("numpy").attr("bool_")) || !is_real)
    raise_error(argument(name), "expected a number in " + range + ", not " + type_name(value));
  double number = 0.0;
  if (PyIndex_Check(value.ptr()) && !PyFloat_Check(value.ptr())) {
    PyObject* whole = PyNumber_Index(value.ptr());
    if (whole != nullptr) {
      number = PyLong_AsDouble(whole);
      Py_DECREF(whole);
    }
  } else {
    PyObject* real_number = PyNumber_Float(value.ptr());
    if (real_number != nullptr) {
      number = PyFloat_AsDouble(real_number);
      Py_DECREF(real_number);
    }
  }
  if (PyErr_Occurred()) {  // an int beyond the doubles (10**400), or an __index__ that raised
    PyErr_Clear();
    raise_error(argument(name), "the number is too large: expected one in " + range);
  }
  if (!(number >= low && number <= high)) raise_error(argument(name), format_number(number) + " is not in " + range);
  return number;
}

// A whole number in [low, high]: an int or a numpy integer, not bool or float.
long long whole_argument(const std::string& name, const py::handle& value, long long low, long long high) {
  const std::string range = "from " + std::to_string(low) + " to " + std::to_string(high);
  if (PyBool_Check(value.ptr()) || py::isinstance(value, py::module_::import("numpy").attr("bool_")) ||
      !PyIndex_Check(value.ptr()))
    raise_error(argument(name), "expected a whole number " + range + ", not " + type_name(value));
  PyObject* whole = PyNumber_Index(value.ptr());
  int overflow = 0;
  const long long number = whole == nullptr ? 0 : PyLong_AsLongLongAndOverflow(whole, &overflow);
  Py_XDECREF(whole);
  if (PyErr_Occurred()) {
    PyErr_Clear();
    raise_error(argument(name), "expected a whole number " + range);
  }
  if (overflow != 0 || number < low || number > high)
    raise_error(argument(name), (overflow != 0 ? std::string("the number") : std::to_string(number)) + " is not " +
                                    range);
  return number;
}

// A dict; its keys are str.
py::dict dict_argument(const std::string& name, const py::handle& value) {
  if (!PyDict_Check(value.ptr())) raise_error(argument(name), "expected a dict, not " + type_name(value));
  py::dict dict = py::reinterpret_borrow<py::dict>(value);
  for (const auto& item : dict)
    if (!PyUnicode_Check(item.first.ptr()))
      raise_error(argument(name), "its keys name inputs: expected str keys, not " + type_name(item.first));
  return dict;
}

Reference reference_of(const py::handle& value) {
  const std::string semantics = text_argument("semantics", value);
  if (semantics == "matlab") return Reference::Matlab;
  if (semantics == "octave") return Reference::Octave;
  raise_error(argument("semantics"), "'" + semantics + "' is not a reference semantics; use 'matlab' or 'octave'");
}

// A 2-D array of points, one column per input, as float64 rows. Integer and float32 arrays are converted (exactly);
// any other dtype, another number of dimensions or another column count is an error naming the argument.
py::array_t<double, py::array::c_style> points_array(const py::object& points, const std::vector<Variable>& inputs) {
  py::array array;
  try {
    array = py::module_::import("numpy").attr("asarray")(points);
  } catch (const py::error_already_set& e) {  // a ragged list, an object numpy cannot take
    raise_error(argument("points"), std::string("numpy cannot read the points as an array: ") + e.what());
  }
  const char kind = array.dtype().kind();
  std::string names;
  for (const Variable& v : inputs) names += (names.empty() ? "" : ", ") + v.name;
  if (!(kind == 'f' || kind == 'i' || kind == 'u') || (kind == 'f' && array.dtype().itemsize() > 8))
    raise_error(argument("points"),
                "points have dtype " + py::str(array.dtype()).cast<std::string>() +
                    "; expected numbers (float64, or float32 / integers, converted exactly)");
  if (array.ndim() != 2 || static_cast<std::size_t>(array.shape(1)) != inputs.size()) {
    std::string shape;
    for (py::ssize_t d = 0; d < array.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(array.shape(d));
    raise_error(argument("points"),
                "points have shape (" + shape + (array.ndim() == 1 ? "," : "") + "); expected (n, " +
                    std::to_string(inputs.size()) + "): one row per point, one column per input (" + names + ")",
                {array.ndim() == 1 ? "one point: numpy.asarray(point).reshape(1, -1)" : "columns in this order: " + names});
  }
  if (kind == 'i' || kind == 'u') {
    // Integers beyond 2^53 would not convert exactly.
    const py::object numpy = py::module_::import("numpy");
    if (array.size() > 0 && py::float_(numpy.attr("max")(numpy.attr("abs")(array))).cast<double>() > 9007199254740992.0)
      raise_error(argument("points"), "integer points beyond 2^53 cannot be converted to float64 exactly");
  }
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
}

// Every row holding a NaN is reported (report_row) before any row is evaluated: a NaN in row 0 of 10^8 rows was
// found only after all of them (133 s).
template <typename ReportRow>
void refuse_nan_rows(const py::array_t<double, py::array::c_style>& in, std::size_t columns, ReportRow report_row) {
  const py::ssize_t rows = in.shape(0);
  const double* x = in.data();
  for (py::ssize_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c)
      if (std::isnan(x[r * static_cast<py::ssize_t>(columns) + static_cast<py::ssize_t>(c)])) {
        report_row(r);
        break;
      }
}

std::vector<SourceRange> origins_of_row(py::ssize_t row, std::size_t columns) {
  std::vector<SourceRange> origins;
  for (std::size_t c = 0; c < columns; ++c)
    origins.push_back(SourceRange{"points[" + std::to_string(row) + ", " + std::to_string(c) + "]", 0, 0, 0, 0});
  return origins;
}

py::object with_diagnostics(py::array_t<double> values, const DiagnosticList& diagnostics, bool wanted) {
  if (!wanted) return std::move(values);
  return py::make_tuple(values, to_python(diagnostics, SourceFiles{}));
}

// ---- rule files ----

struct RuleFileHandle {
  std::shared_ptr<const sim::LoadedRuleFile> file;
};

struct SystemHandle {
  std::shared_ptr<const sim::LoadedRuleFile> file;  // keeps `system` alive
  const FuzzySystem* system = nullptr;
};

std::shared_ptr<const sim::LoadedRuleFile> load_checked(const py::object& path_object) {
  const std::string path = path_argument("path", path_object);
  auto file = std::make_shared<sim::LoadedRuleFile>(sim::load_rule_file_from_disk(path));
  if (file->diagnostics.has_errors()) raise_error(file->diagnostics, file->sources);
  return file;
}

std::vector<PyDiagnostic> check(const py::object& path_object, const py::object& lint_object,
                                const py::object& threshold_object) {
  const std::string path = path_argument("path", path_object);
  const bool lint = flag_argument("lint", lint_object);
  const double coverage_threshold = number_argument("coverage_threshold", threshold_object, 0.0, 1.0);
  sim::LoadedRuleFile file = sim::load_rule_file_from_disk(path);
  if (lint) {
    LintOptions options;
    options.coverage_threshold = coverage_threshold;
    sim::lint_rule_file(file, options);
  }
  return to_python(file.diagnostics, file.sources);
}

SystemHandle system_of(const RuleFileHandle& handle, const py::object& name_object) {
  const std::string name = text_argument("name", name_object);
  DiagnosticList diagnostics;
  const FuzzySystem* system = select_system(handle.file->rules, handle.file->path, name, diagnostics);
  if (!system) raise_error(diagnostics, handle.file->sources);
  return SystemHandle{handle.file, system};
}

py::object evaluate_system(const SystemHandle& handle, const py::object& points, const py::object& semantics,
                           const py::object& return_diagnostics_object) {
  const FuzzySystem& system = *handle.system;
  EvaluationOptions options;
  options.reference = reference_of(semantics);
  const bool return_diagnostics = flag_argument("return_diagnostics", return_diagnostics_object);
  const auto in = points_array(points, system.inputs);
  const py::ssize_t rows = in.shape(0);
  const std::size_t columns = system.inputs.size();
  DiagnosticList diagnostics;
  refuse_nan_rows(in, columns, [&](py::ssize_t r) {
    Evaluation flagged;
    for (std::size_t c = 0; c < columns; ++c)
      if (std::isnan(in.data()[r * static_cast<py::ssize_t>(columns) + static_cast<py::ssize_t>(c)]))
        flagged.flags.inputs_nan.push_back(static_cast<int>(c));
    report_evaluation_flags(system, std::vector<double>(columns), origins_of_row(r, columns),
                            SourceRange{"points[" + std::to_string(r) + "]", 0, 0, 0, 0}, flagged, diagnostics);
  });
  if (diagnostics.has_errors()) raise_error(diagnostics, SourceFiles{});
  py::array_t<double> out(std::vector<py::ssize_t>{rows, static_cast<py::ssize_t>(system.outputs.size())});
  {
    py::gil_scoped_release unlocked;
    Interpreter interpreter(system, options);
    const double* x = in.data();
    double* y = out.mutable_data();
    std::vector<double> inputs(columns);
    for (py::ssize_t r = 0; r < rows; ++r) {
      inputs.assign(x + r * static_cast<py::ssize_t>(columns), x + (r + 1) * static_cast<py::ssize_t>(columns));
      const Evaluation evaluation = interpreter.evaluate(inputs);
      if (!evaluation.flags.inputs_nan.empty() || !evaluation.flags.inputs_out_of_range.empty() ||
          !evaluation.flags.outputs_no_rule_fired.empty())
        report_evaluation_flags(system, inputs, origins_of_row(r, columns),
                                SourceRange{"points[" + std::to_string(r) + "]", 0, 0, 0, 0}, evaluation, diagnostics);
      for (std::size_t o = 0; o < evaluation.outputs.size(); ++o) y[r * static_cast<py::ssize_t>(system.outputs.size()) + static_cast<py::ssize_t>(o)] = evaluation.outputs[o];
    }
  }
  if (diagnostics.has_errors()) raise_error(diagnostics, SourceFiles{});
  return with_diagnostics(out, diagnostics, return_diagnostics);
}

std::vector<std::string> names_of(const std::vector<Variable>& variables) {
  std::vector<std::string> names;
  for (const Variable& v : variables) names.push_back(v.name);
  return names;
}

std::vector<std::string> names_of_systems(const RuleFileHandle& handle) {
  std::vector<std::string> names;
  for (const FuzzySystem& system : handle.file->rules.systems) names.push_back(system.name);
  return names;
}

py::list variables_of(const std::vector<Variable>& variables) {
  py::list out;
  for (const Variable& v : variables) {
    py::dict entry;
    entry["name"] = v.name;
    entry["unit"] = v.unit;
    entry["min"] = v.min;
    entry["max"] = v.max;
    out.append(entry);
  }
  return out;
}

// ---- lookup tables ----

struct TableHandle {
  std::shared_ptr<const LookupTable> table;
  FuzzySystem interface;
};

TableHandle table_handle(LookupTable table) {
  TableHandle handle;
  handle.interface = table_interface(table);
  handle.table = std::make_shared<const LookupTable>(std::move(table));
  return handle;
}

TableHandle load_table(const py::object& path_object) {
  const std::string path = path_argument("path", path_object);
  // Only the signature is read of a file that is not a table (a rule file, or a gigabyte of anything else).
  std::string error;
  const std::optional<sim::KindOfInput> input =
      sim::read_input_file(path, {sim::InputKind{"lookup table", sim::kMaxTableFileBytes, fzt_signature()}}, error);
  if (!input)
    raise_error(SourceRange{path, 0, 0, 0, 0}, error,
                {"a rule file is loaded with fmpc.load(path); fmpc.compile_table(...) writes tables"});
  DiagnosticList diagnostics;
  std::optional<LookupTable> table = parse_fzt(path, input->contents, diagnostics);
  if (!table) raise_error(diagnostics, SourceFiles{});
  return table_handle(std::move(*table));
}

py::object evaluate_table(const TableHandle& handle, const py::object& points,
                          const py::object& return_diagnostics_object) {
  const bool return_diagnostics = flag_argument("return_diagnostics", return_diagnostics_object);
  const auto in = points_array(points, handle.interface.inputs);
  const py::ssize_t rows = in.shape(0);
  const std::size_t columns = handle.interface.inputs.size();
  const std::size_t outputs = handle.interface.outputs.size();
  DiagnosticList diagnostics;
  refuse_nan_rows(in, columns, [&](py::ssize_t r) {
    const double* row = in.data() + r * static_cast<py::ssize_t>(columns);
    report_table_inputs(handle.interface, std::vector<double>(row, row + columns), origins_of_row(r, columns),
                        diagnostics);
  });
  if (diagnostics.has_errors()) raise_error(diagnostics, SourceFiles{});
  diagnostics = DiagnosticList{};  // the warnings come again, in order, as the rows are evaluated
  py::array_t<double> out(std::vector<py::ssize_t>{rows, static_cast<py::ssize_t>(outputs)});
  {
    py::gil_scoped_release unlocked;
    std::vector<const double*> breakpoints;
    std::vector<int> counts;
    const TableView<double> view = view_of(*handle.table, breakpoints, counts);
    const double* x = in.data();
    double* y = out.mutable_data();
    std::vector<double> inputs(columns);
    for (py::ssize_t r = 0; r < rows; ++r) {
      inputs.assign(x + r * static_cast<py::ssize_t>(columns), x + (r + 1) * static_cast<py::ssize_t>(columns));
      report_table_inputs(handle.interface, inputs, origins_of_row(r, columns), diagnostics);
      interpolate_table(view, inputs.data(), y + r * static_cast<py::ssize_t>(outputs));
    }
  }
  if (diagnostics.has_errors()) raise_error(diagnostics, SourceFiles{});
  return with_diagnostics(out, diagnostics, return_diagnostics);
}

// compile_table: the pipeline and table builder `fmpc compile --target table` runs, the .fzt written atomically.
TableHandle compile_table(const SystemHandle& handle, const py::object& output_object, const py::object& fix_object,
                          const py::object& vary_object, const py::object& max_error_object,
                          const py::object& precision_object, const py::object& spacing_object,
                          const py::object& max_grid_points_object, const py::object& seed_object,
                          const py::object& threads_object, const py::object& semantics) {
  const FuzzySystem& system = *handle.system;
  const std::string output = path_argument("output", output_object);
  const std::string precision = text_argument("precision", precision_object);
  const std::string spacing = text_argument("spacing", spacing_object);
  const auto max_grid_points = static_cast<std::uint64_t>(
      whole_argument("max_grid_points", max_grid_points_object, 2, static_cast<long long>(kMaxFztValues)));
  const auto threads = static_cast<int>(whole_argument("threads", threads_object, 1, 256));
  const auto seed = static_cast<std::uint64_t>(
      whole_argument("seed", seed_object, 0, std::numeric_limits<long long>::max()));
  const double max_error = max_error_object.is_none()
                               ? default_table_max_error(system)
                               : number_argument("max_error", max_error_object, 0.0, HUGE_VAL);
  DiagnosticList diagnostics;
  Bindings bindings;
  for (const auto& [key, value] : dict_argument("fix", fix_object)) {
    const std::string name = text_argument("fix", key);
    const std::string where = "fix['" + name + "']";
    bindings.fixed.push_back({name, number_argument(where, value, -HUGE_VAL, HUGE_VAL), argument(where)});
  }
  for (const auto& [key, value] : dict_argument("vary", vary_object)) {
    const std::string name = text_argument("vary", key);
    const std::string where = "vary['" + name + "']";
    // None: the table builder chooses the breakpoints to meet max_error; 0 is not a count (it once meant None).
    const int points = value.is_none() ? 0 : static_cast<int>(whole_argument(where, value, 2, kMaxAxisPoints));
    bindings.varied.push_back({name, points, argument(where)});
  }
  TableBuildOptions options;
  options.max_error = max_error;
  if (!(options.max_error > 0.0) || !std::isfinite(options.max_error))
    diagnostics.error(argument("max_error"), "max_error must be a positive number of output units");
  if (precision != "double" && precision != "float")
    diagnostics.error(argument("precision"), "'" + precision + "' is not a table precision; use 'double' or 'float'");
  if (spacing != "refined" && spacing != "uniform")
    diagnostics.error(argument("spacing"), "'" + spacing + "' is not a spacing; use 'refined' or 'uniform'");
  if (output.empty()) diagnostics.error(argument("output"), "no output path for the .fzt table");
  options.value_type = precision == "float" ? TableValueType::Float32 : TableValueType::Float64;
  options.spacing = spacing == "uniform" ? BreakpointSpacing::Uniform : BreakpointSpacing::Refined;
  options.max_grid_points = max_grid_points;
  const sim::MemoryLimit memory = sim::memory_limit();
  options.memory_limit_bytes = memory.bytes;
  options.memory_limit_source = memory.source;
  options.seed = seed;
  options.threads = threads;
  options.evaluation.reference = reference_of(semantics);
  options.source_path = handle.file->path;
  std::string read_error;  // as fmpc compile: the table records the hash of the bytes it was compiled from
  if (const auto bytes = sim::read_input_file(handle.file->path, sim::kMaxRuleFileBytes, "rule file", read_error))
    options.source_hash = fnv1a64(*bytes);
  if (diagnostics.has_errors()) raise_error(diagnostics, handle.file->sources);
  std::optional<LookupTable> table;
  {
    py::gil_scoped_release unlocked;
    PipelineOptions pipeline;
    pipeline.interval_type2 = true;
    const std::optional<CompileResult> compiled = run_pipeline(system, bindings, pipeline, diagnostics);
    if (compiled && !diagnostics.has_errors()) table = build_table(system, *compiled, options, diagnostics);
    if (table && !diagnostics.has_errors()) sim::write_file_atomically(output, serialize_fzt(*table), diagnostics);
  }
  if (!table || diagnostics.has_errors()) raise_error(diagnostics, handle.file->sources);
  return table_handle(std::move(*table));
}

// ---- scenes ----

struct SimulationHandle {
  bool completed = false;
  std::string backend;
  std::string backend_note;
  std::size_t steps = 0;
  py::array_t<double> time, displacement, force, positions;
  py::object summary;
  std::vector<std::string> files;
  std::vector<PyDiagnostic> diagnostics;
};

SimulationHandle simulate(const py::object& scene_object, const py::object& output_object) {
  const std::string scene_path = path_argument("scene", scene_object);
  std::optional<std::string> output_directory;
  if (!output_object.is_none()) output_directory = path_argument("output_directory", output_object);
  if (output_directory && output_directory->empty())
    raise_error(argument("output_directory"), "an empty path names no folder: give one, or None for the scene's");
  DiagnosticList diagnostics;
  SourceFiles sources;
  std::string error;
  const std::optional<std::string> text = sim::read_input_file(scene_path, sim::kMaxSceneFileBytes, "scene file", error);
  if (!text) raise_error(SourceRange{scene_path, 0, 0, 0, 0}, error);
  sources.add(scene_path, *text);
  std::optional<sim::Scene> scene = sim::parse_scene(scene_path, *text, diagnostics);
  std::optional<sim::BackendChoice> backend;
  if (scene) backend = sim::choose_backend(*scene, diagnostics);
  std::optional<sim::BuiltScene> built;
  if (backend) built = sim::build_scene(*scene, diagnostics);
  if (built)
    for (const auto& [path, source] : built->sources) sources.add(path, source);
  diagnostics.sort_by_position();
  if (!built || diagnostics.has_errors()) raise_error(diagnostics, sources);
  sim::SceneRunOptions options;
  options.backend = backend->backend;
  options.output_directory = output_directory ? *output_directory : sim::default_output_directory(*scene);
  std::optional<sim::SceneRunResult> result;
  {
    py::gil_scoped_release unlocked;
    const std::vector<std::filesystem::path> earlier = sim::earlier_run_files(options.output_directory);
    result = sim::run_scene(*scene, *built, options, diagnostics);
    if (result) sim::remove_stale_files(earlier, result->files, diagnostics);
  }
  diagnostics.sort_by_position();
  // A run stopped by a non-finite state is an error too (its diagnostics say where).
  if (!result || diagnostics.has_errors()) raise_error(diagnostics, sources);
  SimulationHandle out;
  out.completed = result->completed;
  out.backend = backend->backend;
  out.backend_note = backend->note;
  out.steps = result->steps_taken;
  const auto samples = static_cast<py::ssize_t>(result->probe_curve.size());
  out.time = py::array_t<double>(samples);
  out.displacement = py::array_t<double>(samples);
  out.force = py::array_t<double>(samples);
  for (py::ssize_t i = 0; i < samples; ++i) {
    const sim::ProbeCurvePoint& point = result->probe_curve[static_cast<std::size_t>(i)];
    out.time.mutable_at(i) = point.time;
    out.displacement.mutable_at(i) = point.displacement;
    out.force.mutable_at(i) = point.force;
  }
  const auto vertices = static_cast<py::ssize_t>(result->final_positions.size());
  out.positions = py::array_t<double>(std::vector<py::ssize_t>{vertices, py::ssize_t{3}});
  for (py::ssize_t v = 0; v < vertices; ++v)
    for (py::ssize_t i = 0; i < 3; ++i)
      out.positions.mutable_at(v, i) = result->final_positions[static_cast<std::size_t>(v)][static_cast<std::size_t>(i)];
  out.summary = py::module_::import("json").attr("loads")(result->summary_json);
  out.files = result->files;
  out.diagnostics = to_python(diagnostics, sources);
  return out;
}

}  // namespace

void define_fmpc_module(py::module_& m) {
  m.doc() = "fmpc: fuzzy rule files (fmpc, MATLAB .fis, FLL, FCL), their evaluation on numpy arrays, lookup tables "
            "and the soft-tissue simulator (docs/python.md)";
  static py::exception<std::runtime_error> error(m, "Error", PyExc_ValueError);
  set_error_class(error.ptr());
  error.attr("__doc__") = "An error a user caused; .diagnostics lists every diagnostic (fmpc.Diagnostic), str() the errors";

  py::class_<PyDiagnostic>(m, "Diagnostic", "One diagnostic: severity, code, message, file, line, column, notes")
      .def_readonly("severity", &PyDiagnostic::severity)
      .def_readonly("code", &PyDiagnostic::code)
      .def_readonly("message", &PyDiagnostic::message)
      .def_readonly("file", &PyDiagnostic::file)
      .def_readonly("line", &PyDiagnostic::line)
      .def_readonly("column", &PyDiagnostic::column)
      .def_readonly("end_line", &PyDiagnostic::end_line)
      .def_readonly("end_column", &PyDiagnostic::end_column)
      .def_readonly("notes", &PyDiagnostic::notes)
      .def("__str__", [](const PyDiagnostic& d) { return d.text; })
      .def("__repr__", [](const PyDiagnostic& d) {
        return "<fmpc.Diagnostic " + d.severity + " " + d.file + ":" + std::to_string(d.line) + ":" +
               std::to_string(d.column) + ": " + d.message + ">";
      });

  py::class_<SystemHandle>(m, "System", "One fuzzy system of a rule file")
      .def_property_readonly("name", [](const SystemHandle& s) { return s.system->name; })
      .def_property_readonly("inputs", [](const SystemHandle& s) { return names_of(s.system->inputs); })
      .def_property_readonly("outputs", [](const SystemHandle& s) { return names_of(s.system->outputs); })
      .def_property_readonly("input_variables", [](const SystemHandle& s) { return variables_of(s.system->inputs); })
      .def_property_readonly("output_variables", [](const SystemHandle& s) { return variables_of(s.system->outputs); })
      .def("evaluate", &evaluate_system, py::arg("points"), py::arg("semantics") = py::str("matlab"),
           py::arg("return_diagnostics") = py::bool_(false),
           "Outputs at each row of `points` (n x inputs), as an n x outputs float64 array: the interpreter, the "
           "numbers `fmpc eval` prints. NaN inputs raise fmpc.Error; with return_diagnostics=True the warnings "
           "(inputs out of range, no rule fired) come back too, as (array, [Diagnostic]).")
      .def("compile_table", &compile_table, py::arg("output"), py::kw_only(), py::arg("fix") = py::dict(),
           py::arg("vary") = py::dict(), py::arg("max_error") = py::none(), py::arg("precision") = py::str("double"),
           py::arg("spacing") = py::str("refined"), py::arg("max_grid_points") = py::int_(1 << 21),
           py::arg("seed") = py::int_(1), py::arg("threads") = py::int_(2), py::arg("semantics") = py::str("matlab"),
           "Compiles a lookup table over the varying inputs (fix={'NAME': value}, vary={'NAME': points or None}) "
           "with |table - interpreter| <= max_error (default: 1% of the narrowest output range), writes it to "
           "`output` (.fzt) and returns it (fmpc compile --target table).");

  py::class_<RuleFileHandle>(m, "RuleFile", "A rule file loaded without errors (fmpc.load)")
      .def_property_readonly("path", [](const RuleFileHandle& f) { return f.file->path; })
      .def_property_readonly("dialect", [](const RuleFileHandle& f) { return std::string(fmpc::dialect_name(f.file->dialect)); })
      .def_property_readonly("systems", [](const RuleFileHandle& f) { return names_of_systems(f); })
      .def_property_readonly("diagnostics",
                             [](const RuleFileHandle& f) { return to_python(f.file->diagnostics, f.file->sources); })
      .def("system", &system_of, py::arg("name") = py::str(""),
           "The system named `name`, or the only one when the file defines one");

  py::class_<TableHandle>(m, "Table", "A compiled lookup table (.fzt)")
      .def_property_readonly("system", [](const TableHandle& t) { return t.table->system_name; })
      .def_property_readonly("inputs", [](const TableHandle& t) { return names_of(t.interface.inputs); })
      .def_property_readonly("outputs", [](const TableHandle& t) { return names_of(t.interface.outputs); })
      .def_property_readonly("max_error", [](const TableHandle& t) { return t.table->max_error; })
      .def_property_readonly("error_kind", [](const TableHandle& t) { return std::string(fmpc::to_string(t.table->error_kind)); })
      .def_property_readonly("grid_points", [](const TableHandle& t) { return t.table->grid_points(); })
      .def_property_readonly("fixed_inputs",
                             [](const TableHandle& t) {
                               py::dict fixed;
                               for (const fmpc::TableFixedInput& input : t.table->fixed_inputs) fixed[py::str(input.name)] = input.value;
                               return fixed;
                             })
      .def("evaluate", &evaluate_table, py::arg("points"), py::arg("return_diagnostics") = py::bool_(false),
           "Outputs at each row of `points` (n x varying inputs, in the order of .inputs) by multilinear "
           "interpolation, clamped to the axes (a warning); the numbers `fmpc eval TABLE.fzt` prints.");

  py::class_<SimulationHandle>(m, "Simulation", "What fmpc.simulate returns")
      .def_readonly("completed", &SimulationHandle::completed)
      .def_readonly("backend", &SimulationHandle::backend)
      .def_readonly("backend_note", &SimulationHandle::backend_note)
      .def_readonly("steps", &SimulationHandle::steps)
      .def_readonly("time", &SimulationHandle::time, "s, at each sample of the probe curve")
      .def_readonly("displacement", &SimulationHandle::displacement, "m, the probe's, along its direction")
      .def_readonly("force", &SimulationHandle::force, "N, on the probe, along its direction")
      .def_readonly("positions", &SimulationHandle::positions, "m, every vertex at the last step (n x 3)")
      .def_readonly("summary", &SimulationHandle::summary, "summary.json's fields, as a dict")
      .def_readonly("files", &SimulationHandle::files)
      .def_readonly("diagnostics", &SimulationHandle::diagnostics);

  m.def("load", [](const py::object& path) { return RuleFileHandle{load_checked(path)}; }, py::arg("path"),
        "Reads, parses and checks a rule file (fmpc, MATLAB .fis, FLL or FCL); raises fmpc.Error on any error.");
  m.def("check", &check, py::arg("path"), py::kw_only(), py::arg("lint") = py::bool_(true),
        py::arg("coverage_threshold") = py::float_(0.1),
        "Every error and lint warning of a rule file, as fmpc check reports them, as a list of fmpc.Diagnostic "
        "(raises nothing: the list is the answer).");
  m.def("load_table", &load_table, py::arg("path"), "Reads a compiled lookup table (.fzt)");
  m.def("simulate", &simulate, py::arg("scene"), py::arg("output_directory") = py::none(),
        "Runs a scene file (docs/scenes.md) and writes its outputs (to output_directory, default the scene's); "
        "returns the probe curve and final positions as arrays and the summary as a dict.");
  bind_session(m);
}

}  // namespace fmpc::python

PYBIND11_MODULE(fmpc, m) { fmpc::python::define_fmpc_module(m); }
