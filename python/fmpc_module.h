#pragma once
// The `fmpc` Python module's contents, defined on a module object: the extension (PYBIND11_MODULE in
// fmpc_module.cpp) and the fuzz target of its argument conversions (tests/fuzz/fuzz_python_arguments.cpp, an
// embedded interpreter) define the same module.
#include <pybind11/pybind11.h>

namespace fmpc::python {

void define_fmpc_module(pybind11::module_& m);

}  // namespace fmpc::python
