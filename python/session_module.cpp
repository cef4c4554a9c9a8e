// fmpc.Session: a scene stepped from Python (runtime/session/session.h). Positions, forces and torques come back as
// numpy arrays; stepping and the material swap release the GIL. A session's calls are serialised by its own mutex,
// so another Python thread (a haptic device's) may pose a tool while a step runs: the pose waits for that step and
// acts from the next.
#include "python/session_module.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "python/python_diagnostics.h"
#include "runtime/session/session.h"

namespace py = pybind11;

namespace fmpc::python {

namespace {

struct PySession {
  std::unique_ptr<runtime::Session> session;
  mutable std::mutex mutex;
};

runtime::SessionOptions session_options(const std::string& backend) {
  runtime::SessionOptions options;
  if (backend == "auto")
    options.backend = runtime::SessionOptions::Backend::Auto;
  else if (backend == "cpu")
    options.backend = runtime::SessionOptions::Backend::Cpu;
  else if (backend == "cuda")
    options.backend = runtime::SessionOptions::Backend::Cuda;
  else
    raise_error(argument("backend"), "'" + backend + "' is not a backend; use 'auto', 'cpu' or 'cuda'");
  return options;
}

// Raises fmpc.Error with the diagnostics (the scene's lines quoted) unless `ok` and none is an error.
void check(bool ok, const PySession& s, const DiagnosticList& diagnostics) {
  if (ok && !diagnostics.has_errors()) return;
  raise_error(diagnostics, s.session->sources());
}

// Whether a session call's result says it succeeded (a bool, an optional); a list is always an answer.
bool succeeded(bool ok) { return ok; }
template <typename T>
bool succeeded(const std::optional<T>& value) {
  return value.has_value();
}
template <typename T>
bool succeeded(const std::vector<T>&) {
  return true;
}

// Runs `call(diagnostics)` on the session with the GIL released and the session's lock held, and returns its result;
// raises fmpc.Error where it failed or added an error.
template <typename Call>
auto locked_call(const PySession& s, Call call) {
  DiagnosticList diagnostics;
  std::optional<decltype(call(diagnostics))> result;
  {
    py::gil_scoped_release unlocked;
    const std::lock_guard<std::mutex> lock(s.mutex);
    result.emplace(call(diagnostics));
  }
  check(succeeded(*result), s, diagnostics);
  return std::move(*result);
}

// A session made by `create(diagnostics)` with the GIL released; fmpc.Error where it could not be made.
template <typename Create>
std::unique_ptr<PySession> created(Create create) {
  DiagnosticList diagnostics;
  auto out = std::make_unique<PySession>();
  {
    py::gil_scoped_release unlocked;
    out->session = create(diagnostics);
  }
  if (!out->session) raise_error(diagnostics, SourceFiles{});
  return out;
}

std::unique_ptr<PySession> open_scene(const std::string& path, const std::string& backend) {
  const runtime::SessionOptions options = session_options(backend);
  return created([&](DiagnosticList& d) { return runtime::Session::open(path, d, options); });
}

py::array_t<double> points_array(const std::vector<runtime::Point3>& points) {
  py::array_t<double> out(std::vector<py::ssize_t>{static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto view = out.mutable_unchecked<2>();
  for (py::ssize_t v = 0; v < static_cast<py::ssize_t>(points.size()); ++v)
    for (py::ssize_t i = 0; i < 3; ++i) view(v, i) = points[static_cast<std::size_t>(v)][static_cast<std::size_t>(i)];
  return out;
}

// A tool named by its index or its name.
std::size_t tool_index(const PySession& s, const py::object& tool) {
  if (py::isinstance<py::str>(tool)) {
    const std::string name = tool.cast<std::string>();
    if (const auto found = s.session->find_tool(name)) return *found;
    raise_error(argument("tool"), "the scene has no tool '" + name + "'");
  }
  if (!py::isinstance<py::int_>(tool) || py::isinstance<py::bool_>(tool))
    raise_error(argument("tool"), "expected a tool's index or name, got " + py::repr(tool).cast<std::string>());
  int overflow = 0;
  const long long index = PyLong_AsLongLongAndOverflow(tool.ptr(), &overflow);
  if (overflow != 0 || index < 0 || static_cast<std::size_t>(index) >= s.session->tool_count())
    raise_error(argument("tool"), "tool " + py::repr(tool).cast<std::string>() + " does not exist; the scene has " +
                                      std::to_string(s.session->tool_count()));
  return static_cast<std::size_t>(index);
}

// Three (or four) numbers from a sequence; any other shape is an error naming the argument. NaN passes (the session
// refuses it with its own message).
template <std::size_t N>
std::array<double, N> numbers(const py::object& value, const std::string& name) {
  const py::array_t<double> array = py::array_t<double>::ensure(value);
  if (!array || array.ndim() != 1 || static_cast<std::size_t>(array.shape(0)) != N)
    raise_error(argument(name),
                "expected " + std::to_string(N) + " numbers, got " + py::repr(value).cast<std::string>());
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = array.at(static_cast<py::ssize_t>(i));
  return out;
}

}  // namespace

void bind_session(py::module_& m) {
  py::class_<PySession>(m, "Session",
                        "A scene stepped step by step (docs/runtime.md): tools posed every tick, their forces read "
                        "back, the state read, the material swapped between two steps")
      .def(py::init(&open_scene), py::arg("scene"), py::arg("backend") = "auto",
           "Loads and builds a scene file (docs/scenes.md) on backend 'auto' (the scene's choice), 'cpu' or 'cuda'")
      .def_static(
          "from_yaml",
          [](const std::string& text, const std::string& path, const std::string& backend) {
            const runtime::SessionOptions options = session_options(backend);
            return created([&](DiagnosticList& d) { return runtime::Session::from_yaml(text, path, d, options); });
          },
          py::arg("text"), py::arg("path") = "scene.yaml", py::arg("backend") = "auto",
          "A scene given as YAML text; `path` names it in messages and resolves its relative files")
      .def(
          "step",
          [](PySession& s, long long steps) {
            if (steps < 0) raise_error(argument("steps"), "steps must be >= 0, got " + std::to_string(steps));
            locked_call(s, [&](DiagnosticList& d) { return s.session->step(static_cast<std::size_t>(steps), d); });
          },
          py::arg("steps") = 1, "Advances `steps` steps (the GIL released while stepping)")
      .def(
          "step_to",
          [](PySession& s, double time) {
            locked_call(s, [&](DiagnosticList& d) { return s.session->step_to(time, d); });
          },
          py::arg("time"), "Advances to at least `time` seconds (the GIL released while stepping)")
      .def_property_readonly(
          "time", [](const PySession& s) { return s.session->time(); }, "s")
      .def_property_readonly(
          "dt", [](const PySession& s) { return s.session->time_step(); }, "s, the time step")
      .def_property_readonly("steps", [](const PySession& s) { return s.session->steps_taken(); })
      .def_property_readonly(
          "backend", [](const PySession& s) { return s.session->backend() == sim::Backend::Cuda ? "cuda" : "cpu"; })
      .def_property_readonly("vertex_count", [](const PySession& s) { return s.session->vertex_count(); })
      .def_property_readonly("tool_names",
                             [](const PySession& s) {
                               std::vector<std::string> names;
                               for (const sim::RigidTool& tool : s.session->simulation().setup().tools)
                                 names.push_back(tool.name);
                               return names;
                             })
      .def(
          "set_tool_pose",
          [](PySession& s, const py::object& tool, const py::object& position, const py::object& orientation) {
            const std::size_t index = tool_index(s, tool);
            runtime::ToolPose pose;
            pose.position = numbers<3>(position, "position");
            pose.orientation = numbers<4>(orientation, "orientation");
            locked_call(s, [&](DiagnosticList& d) { return s.session->set_tool_pose(index, pose, d); });
          },
          py::arg("tool"), py::arg("position"), py::arg("orientation") = std::vector<double>{1.0, 0.0, 0.0, 0.0},
          "Poses a tool (its index or name) for the steps from now on: position (m), orientation a quaternion "
          "(w, x, y, z)")
      .def(
          "tool_readings",
          [](const PySession& s) {
            const std::vector<runtime::ToolReading> readings =
                locked_call(s, [&](DiagnosticList& d) { return s.session->tool_readings(d); });
            std::vector<runtime::Point3> force, torque;
            py::array_t<long long> contacts(static_cast<py::ssize_t>(readings.size()));
            py::array_t<double> deepest(static_cast<py::ssize_t>(readings.size()));
            for (std::size_t t = 0; t < readings.size(); ++t) {
              force.push_back(readings[t].force);
              torque.push_back(readings[t].torque);
              contacts.mutable_at(static_cast<py::ssize_t>(t)) = static_cast<long long>(readings[t].contacts);
              deepest.mutable_at(static_cast<py::ssize_t>(t)) = readings[t].deepest;
            }
            py::dict out;
            out["force"] = points_array(force);
            out["torque"] = points_array(torque);
            out["contacts"] = contacts;
            out["deepest"] = deepest;
            return out;
          },
          "Every tool's reaction now: force (tools x 3, N, on the tool), torque (tools x 3, N m, about its origin), "
          "contacts (vertices inside it), deepest (m)")
      .def(
          "positions",
          [](const PySession& s) {
            const std::vector<runtime::Point3> points =
                locked_call(s, [&](DiagnosticList& d) { return s.session->positions(d); });
            return points_array(points);
          },
          "Every vertex's position now (n x 3, m)")
      .def(
          "velocities",
          [](const PySession& s) {
            const std::vector<runtime::Point3> points =
                locked_call(s, [&](DiagnosticList& d) { return s.session->velocities(d); });
            return points_array(points);
          },
          "Every vertex's velocity now (n x 3, m/s)")
      .def(
          "device_positions",
          [](const PySession& s) {
            const std::optional<runtime::DevicePositions> pointer =
                locked_call(s, [&](DiagnosticList& d) { return s.session->device_positions(d); });
            // Addresses, for a CUDA array interface (CuPy, PyTorch) of the caller's; valid until the next step.
            py::dict out;
            out["x"] = reinterpret_cast<std::uintptr_t>(pointer->x);
            out["y"] = reinterpret_cast<std::uintptr_t>(pointer->y);
            out["z"] = reinterpret_cast<std::uintptr_t>(pointer->z);
            out["count"] = pointer->count;
            out["dtype"] = pointer->double_precision ? "float64" : "float32";
            return out;
          },
          "CUDA only: where the positions live on the device, no copy: x, y, z (addresses of `count` values each, "
          "structure of arrays), count, dtype; fmpc.Error on the CPU")
      .def(
          "energies",
          [](const PySession& s) {
            const std::optional<runtime::Energies> energies =
                locked_call(s, [&](DiagnosticList& d) { return s.session->energies(d); });
            py::dict out;
            out["kinetic"] = energies->kinetic;
            out["elastic"] = energies->elastic;
            out["potential"] = energies->potential;
            return out;
          },
          "The energies now (J): kinetic, elastic, potential")
      .def_property_readonly(
          "inversions",
          [](const PySession& s) {
            const std::lock_guard<std::mutex> lock(s.mutex);
            const sim::InversionReport& report = s.session->inversions();
            py::dict out;
            out["current_count"] = report.current_count;
            out["largest_count"] = report.largest_count;
            out["first_step"] = report.largest_count > 0 ? py::object(py::int_(report.first_step)) : py::none();
            out["first_element"] = report.largest_count > 0 ? py::object(py::int_(report.first_element)) : py::none();
            return out;
          },
          "Inverted tetrahedra: at the last check, the most at one check, and the first (step, element)")
      .def(
          "swap_material",
          [](PySession& s, const std::string& file) {
            locked_call(s, [&](DiagnosticList& d) { return s.session->swap_material(file, d); });
          },
          py::arg("file"),
          "Swaps the material for a rule file or a compiled table (.fzt) between two steps, keeping the state");
}

}  // namespace fmpc::python
