#pragma once
// The C++ namespace a generated header (evaluator or table arrays) puts its code in comes from the command line
// (`fmpc compile --namespace`) and is written into the header as code, so it is checked as code: once, here, for
// every emitter. `--namespace 'a{} int x; namespace b'` once wrote a declaration into a table header and exited 0,
// and `--namespace int` gave a header that did not compile.
#include <optional>
#include <string>

namespace fmpc {

// Why `name` cannot name the namespace of a generated header, or nullopt when it can: it must be identifiers joined
// by "::" (ASCII letters, digits and '_', not starting with a digit), none of them a C++20 keyword or alternative
// token (int, and, ...), reserved for the implementation (a leading '_' or a "__" anywhere), a macro of the headers
// generated code includes (assert, errno, NULL: any name in capitals only is refused as a likely macro), or
// `std` first.
std::optional<std::string> namespace_name_problem(const std::string& name);

}  // namespace fmpc
