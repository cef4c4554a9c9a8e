#pragma once
// fmpc.Session (docs/python.md, docs/runtime.md): runtime/session/session.h for Python.
#include <pybind11/pybind11.h>

namespace fmpc::python {

void bind_session(pybind11::module_& module);

}  // namespace fmpc::python
