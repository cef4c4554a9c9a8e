#include "python/python_diagnostics.h"

#include <pybind11/stl.h>

#include <stdexcept>

namespace py = pybind11;

namespace fmpc::python {

namespace {

PyObject* error_class = nullptr;

// As the renderer spells them.
std::string severity_name(Severity severity) {
  return severity == Severity::Error ? "error" : severity == Severity::Warning ? "warning" : "note";
}

}  // namespace

void set_error_class(PyObject* error) { error_class = error; }

std::vector<PyDiagnostic> to_python(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  std::vector<PyDiagnostic> out;
  for (const Diagnostic& d : diagnostics.items()) {
    std::string text = render(d, sources);
    while (!text.empty() && text.back() == '\n') text.pop_back();
    out.push_back(PyDiagnostic{severity_name(d.severity), d.code, d.message, d.range.file, d.range.line,
                               d.range.column, d.range.end_line, d.range.end_column, d.notes, std::move(text)});
  }
  return out;
}

void raise_error(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  const std::vector<PyDiagnostic> items = to_python(diagnostics, sources);
  std::string message;
  for (const PyDiagnostic& d : items)
    if (d.severity == "error") message += (message.empty() ? "" : "\n") + d.text;
  if (message.empty()) message = "fmpc: error";
  py::object error = py::reinterpret_borrow<py::object>(error_class)(message);
  error.attr("diagnostics") = py::cast(items);
  PyErr_SetObject(error_class, error.ptr());
  throw py::error_already_set();
}

void raise_error(const SourceRange& where, const std::string& message, std::vector<std::string> notes) {
  DiagnosticList diagnostics;
  diagnostics.error(where, message, std::move(notes));
  raise_error(diagnostics, SourceFiles{});
}

SourceRange argument(const std::string& name) { return SourceRange{"argument '" + name + "'", 0, 0, 0, 0}; }

}  // namespace fmpc::python
