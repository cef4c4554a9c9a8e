#pragma once
// Diagnostics in the Python module (docs/python.md): fmpc.Diagnostic objects, and fmpc.Error (a ValueError) raised
// with them when a user causes an error. Shared by the module's files (fmpc_module.cpp, session_module.cpp).
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace fmpc::python {

// fmpc.Diagnostic: one diagnostic as data, with the compiler-style text fmpc check would print (`str()`).
struct PyDiagnostic {
  std::string severity;  // "error", "warning", "note"
  std::string code;      // the warning's code ("unused-term"); empty for errors
  std::string message;
  std::string file;      // a path, or what the value came from ("points[3, 1]", "argument 'fix'")
  int line = 0;          // 1-based; 0 when there is no position
  int column = 0;
  int end_line = 0;
  int end_column = 0;
  std::vector<std::string> notes;
  std::string text;      // rendered, with the source line and caret where the file is known
};

std::vector<PyDiagnostic> to_python(const DiagnosticList& diagnostics, const SourceFiles& sources);

// The fmpc.Error class, set once at import.
void set_error_class(PyObject* error_class);

// Raises fmpc.Error with every diagnostic (its message: the rendered errors; .diagnostics: all of them).
[[noreturn]] void raise_error(const DiagnosticList& diagnostics, const SourceFiles& sources);
[[noreturn]] void raise_error(const SourceRange& where, const std::string& message,
                              std::vector<std::string> notes = {});

// Where an error in a Python argument points: "argument 'NAME'".
SourceRange argument(const std::string& name);

}  // namespace fmpc::python
