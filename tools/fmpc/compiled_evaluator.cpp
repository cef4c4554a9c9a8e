#include "tools/fmpc/compiled_evaluator.h"

#include <dlfcn.h>
#include <stdlib.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace fmpc::cli {

namespace {

namespace fs = std::filesystem;

bool write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return static_cast<bool>(out);
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Single quotes for /bin/sh: the paths come from the temporary folder, the compiler from the user.
std::string shell_quoted(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// dlsym returns an object pointer; copying its bits is the portable way to a function pointer.
template <typename Function>
Function symbol(void* handle, const char* name) {
  void* address = dlsym(handle, name);
  Function function = nullptr;
  if (address) std::memcpy(&function, &address, sizeof function);
  return function;
}

}  // namespace

std::unique_ptr<CompiledEvaluator> CompiledEvaluator::build(const std::string& header,
                                                            const std::string& namespace_name,
                                                            const std::string& compiler, const std::string& flags,
                                                            std::string& error) {
  std::string pattern = (fs::temp_directory_path() / "fmpc-trade-XXXXXX").string();
  if (!mkdtemp(pattern.data())) {
    error = "cannot create a temporary folder under " + fs::temp_directory_path().string();
    return nullptr;
  }
  std::unique_ptr<CompiledEvaluator> result(new CompiledEvaluator);
  result->folder_ = pattern;
  const fs::path folder(pattern);
  const std::string wrapper = "#include \"evaluator.h\"\n"
                              "extern \"C\" void fmpc_trade_double(const double* x, double* y, std::size_t n) {\n"
                              "  " + namespace_name + "::evaluate_batch(x, y, n);\n}\n"
                              "extern \"C\" void fmpc_trade_float(const float* x, float* y, std::size_t n) {\n"
                              "  " + namespace_name + "::evaluate_batch(x, y, n);\n}\n";
  if (!write_file(folder / "evaluator.h", header) || !write_file(folder / "wrapper.cpp", wrapper)) {
    error = "cannot write into " + folder.string();
    return nullptr;
  }
  const fs::path library = folder / "evaluator.so";
  const std::string command = shell_quoted(compiler) + " " + flags + " -shared -fPIC -o " +
                              shell_quoted(library.string()) + " " + shell_quoted((folder / "wrapper.cpp").string()) +
                              " > " + shell_quoted((folder / "compile.log").string()) + " 2>&1";
  if (std::system(command.c_str()) != 0) {
    error = "compiling the generated evaluator failed: " + command + "\n" + read_file(folder / "compile.log");
    return nullptr;
  }
  result->handle_ = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!result->handle_) {
    error = std::string("cannot load the compiled evaluator: ") + dlerror();
    return nullptr;
  }
  result->batch_double_ = symbol<BatchDouble>(result->handle_, "fmpc_trade_double");
  result->batch_float_ = symbol<BatchFloat>(result->handle_, "fmpc_trade_float");
  if (!result->batch_double_ || !result->batch_float_) {
    error = "the compiled evaluator lacks its entry points";
    return nullptr;
  }
  std::error_code ignored;
  result->bytes_ = static_cast<std::size_t>(fs::file_size(library, ignored));
  return result;
}

CompiledEvaluator::~CompiledEvaluator() {
  if (handle_) dlclose(handle_);
  if (!folder_.empty()) {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }
}

}  // namespace fmpc::cli
