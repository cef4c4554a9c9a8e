#include "python/python_diagnostics.h"

#include <pybind11/stl.h>

#include <stdexcept>

#include "compiler/frontend/utf8.h"

namespace py = pybind11;

namespace fmpc::python {

namespace {

PyObject* error_class = nullptr;

}  // namespace

void set_error_class(PyObject* error) { error_class = error; }

// Messages may quote any bytes of any file (a binary file read as a scene): a Python str takes UTF-8 only, so every
// text goes through valid_utf8 (a bad byte becomes U+FFFD) instead of raising UnicodeDecodeError.
std::vector<PyDiagnostic> to_python(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  std::vector<PyDiagnostic> out;
  for (const Diagnostic& d : diagnostics.items()) {
    std::string text = render(d, sources);
    while (!text.empty() && text.back() == '\n') text.pop_back();
    std::vector<std::string> notes;
    for (const std::string& note : d.notes) notes.push_back(valid_utf8(note));
    out.push_back(PyDiagnostic{severity_name(d.severity), valid_utf8(d.code), valid_utf8(d.message),
                               valid_utf8(d.range.file), d.range.line, d.range.column, d.range.end_line,
                               d.range.end_column, std::move(notes), valid_utf8(text)});
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
