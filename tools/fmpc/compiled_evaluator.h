#pragma once
// A generated evaluator header (compiler/backend/cpp/emit_cpp.h) compiled at run time into a shared object with
// the system C++ compiler and loaded with dlopen, so that `fmpc trade` measures the compiled code itself rather
// than an estimate. Needs a C++17 compiler on PATH (or --cxx / $CXX); docs/trade.md says so.
#include <cstddef>
#include <memory>
#include <string>

namespace fmpc::cli {

class CompiledEvaluator {
 public:
  using BatchDouble = void (*)(const double*, double*, std::size_t);
  using BatchFloat = void (*)(const float*, float*, std::size_t);

  // Compiles `header` (whose namespace is `namespace_name`) with `compiler` and `flags` in a fresh temporary
  // folder. Returns nullptr with `error` set (the compiler's own messages included) when anything fails.
  static std::unique_ptr<CompiledEvaluator> build(const std::string& header, const std::string& namespace_name,
                                                  const std::string& compiler, const std::string& flags,
                                                  std::string& error);
  ~CompiledEvaluator();
  CompiledEvaluator(const CompiledEvaluator&) = delete;
  CompiledEvaluator& operator=(const CompiledEvaluator&) = delete;

  // n points, inputs n x inputs row-major, outputs n x outputs (evaluate_batch of the generated header).
  BatchDouble batch_double() const { return batch_double_; }
  BatchFloat batch_float() const { return batch_float_; }
  std::size_t shared_object_bytes() const { return bytes_; }

 private:
  CompiledEvaluator() = default;
  void* handle_ = nullptr;
  std::string folder_;
  BatchDouble batch_double_ = nullptr;
  BatchFloat batch_float_ = nullptr;
  std::size_t bytes_ = 0;
};

}  // namespace fmpc::cli
