#pragma once
// Generated headers carry verbatim copies of fmpc's kernel headers (kernels/*_math.h, embedded at build time:
// embedded_kernels.h), so the interpreter, the CUDA kernels and generated code compile one definition of every
// formula. This is how a copy is made: which files a header carries, and the text of each as generated code holds it.
#include <string>
#include <vector>

namespace fmpc {

// The kernel headers a type-1 header carries, in dependency order: fmpc_hd.h, fuzzy_kinds.h, fuzzy_math.h.
const std::vector<std::string>& type1_embedded_math_files();
// Those of an interval type-2 header: the type-1 ones, then type2_math.h and type_reduction_math.h.
const std::vector<std::string>& type2_embedded_math_files();

// The text of the embedded kernel headers `paths` (as in embedded_kernel_source), in the order given, with their
// namespace renamed to `math_namespace`, their `#pragma once` and their includes of one another dropped (fmpc_hd.h's
// macros behind `#ifndef FMPC_HD`); empty when a file was not embedded.
std::string embedded_kernel_math(const std::vector<std::string>& paths, const std::string& math_namespace);

// embedded_kernel_math of type1_embedded_math_files(): fmpc's membership math.
std::string embedded_fuzzy_math(const std::string& math_namespace);

// What lies between `namespace fmpc {` and `}  // namespace fmpc` in the embedded kernel header `path`, without the
// blank lines at either end: definitions that generated code places in a namespace of its own
// (kernels/lane_exp_math.h). Empty when the file was not embedded or has no such namespace.
std::string embedded_namespace_body(const std::string& path);

}  // namespace fmpc
