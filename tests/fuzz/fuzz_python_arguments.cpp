// libFuzzer target: the Python module's argument conversions (python/fmpc_module.cpp), through an embedded
// interpreter running the module's own definition. The bytes choose a function of the module (check, load,
// load_table, System.system/evaluate/compile_table, Table.evaluate, simulate) and decode into Python values for its
// arguments: None, bools, ints of any size, floats of any bits, text with lone surrogates, bytes, lists, tuples,
// dicts, paths, numpy scalars and arrays of any dtype and shape, and the names the fixtures hold (their inputs,
// the accepted spellings). The contract under test: every call returns or raises fmpc.Error; any other exception
// (TypeError, RuntimeError, OverflowError, ...) is a finding, reported by abort().
//
// The process works in a fresh temporary folder; paths the bytes spell are kept inside it (a '/' in one becomes
// '_'), so that compile_table and simulate never write elsewhere. Leak detection is off for this target: the
// interpreter keeps its objects until exit (tests/fuzz/run_fuzzers.sh and run_fuzz_smoke.cmake pass it).
#include <pybind11/embed.h>
#include <pybind11/numpy.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "python/fmpc_module.h"

namespace py = pybind11;

PYBIND11_EMBEDDED_MODULE(fmpc, m) { fmpc::python::define_fmpc_module(m); }

namespace {

struct Fixtures {
  py::object fmpc, numpy, pathlib, rule_file, system, table, error;
  std::vector<std::string> words;  // names and spellings the module takes, so that calls reach past the checks
};

// Reads the fuzzer's bytes as a stream; past the end, zeros.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t next() { return at_ < size_ ? data_[at_++] : 0; }
  std::string take(std::size_t count) {
    std::string text;
    for (std::size_t k = 0; k < count && at_ < size_; ++k) text += static_cast<char>(data_[at_++]);
    return text;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_, at_ = 0;
};

// A path the bytes spell, kept inside the working folder.
std::string inside(std::string path) {
  for (char& c : path)
    if (c == '/') c = '_';
  return path;
}

py::object text_of(const std::string& bytes) {
  // Lone surrogates included: "surrogateescape" maps each undecodable byte to one.
  PyObject* text = PyUnicode_DecodeUTF8(bytes.data(), static_cast<Py_ssize_t>(bytes.size()), "surrogateescape");
  if (text == nullptr) throw py::error_already_set();
  return py::reinterpret_steal<py::object>(text);
}

py::object value(Bytes& in, const Fixtures& f, int depth);

py::object numpy_array(Bytes& in, const Fixtures& f) {
  static const char* const dtypes[] = {"float64", "float32", "float16", "int64", "uint64", "int8",
                                       "bool",    "complex128", "object", "U3",    "longdouble"};
  const char* dtype = dtypes[in.next() % (sizeof dtypes / sizeof *dtypes)];
  const int ndim = in.next() % 4;
  py::tuple shape(ndim);
  py::ssize_t count = 1;
  for (int d = 0; d < ndim; ++d) {
    const py::ssize_t extent = in.next() % 5;
    shape[static_cast<std::size_t>(d)] = py::int_(extent);
    count *= extent;
  }
  py::list values;
  for (py::ssize_t k = 0; k < count; ++k) {
    const std::uint8_t kind = in.next();
    if (kind % 4 == 0) {
      values.append(py::float_(std::nan("")));
    } else {
      double number = 0.0;
      const std::string bits = in.take(8);
      std::memcpy(&number, (bits + std::string(8, '\0')).data(), sizeof number);
      values.append(py::float_(kind % 4 == 1 ? number : static_cast<double>(static_cast<std::int8_t>(kind))));
    }
  }
  py::object array = f.numpy.attr("array")(values);
  if (std::string(dtype) != "float64") array = array.attr("astype")(dtype);
  return array.attr("reshape")(shape);
}

py::object value(Bytes& in, const Fixtures& f, int depth) {
  const std::uint8_t tag = in.next();
  switch (depth > 3 ? tag % 9 : tag % 16) {
    case 0: return py::none();
    case 1: return py::bool_(tag & 16);
    case 2: return py::int_(static_cast<std::int8_t>(in.next()));
    case 3: {  // an int of up to 32 bytes, either sign
      const std::string bytes = in.take(in.next() % 33);
      PyObject* number = _PyLong_FromByteArray(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                                               /*little_endian=*/1, /*is_signed=*/1);
      if (number == nullptr) throw py::error_already_set();
      return py::reinterpret_steal<py::object>(number);
    }
    case 4: {
      double number = 0.0;
      const std::string bits = in.take(8);
      std::memcpy(&number, (bits + std::string(8, '\0')).data(), sizeof number);
      return py::float_(number);
    }
    case 5: {
      static const double specials[] = {std::nan(""), HUGE_VAL, -HUGE_VAL, -0.0, 1e308, 5e-324, 0.1, 2.0, 1e6};
      return py::float_(specials[in.next() % (sizeof specials / sizeof *specials)]);
    }
    case 6: return text_of(in.take(in.next() % 24));
    case 7: return py::bytes(in.take(in.next() % 12));
    case 8: return py::str(f.words[in.next() % f.words.size()]);
    case 9: {
      py::list list;
      for (int k = in.next() % 5; k > 0; --k) list.append(value(in, f, depth + 1));
      return std::move(list);
    }
    case 10: {
      py::dict dict;
      for (int k = in.next() % 4; k > 0; --k) dict[value(in, f, depth + 1)] = value(in, f, depth + 1);
      return std::move(dict);
    }
    case 11: return numpy_array(in, f);
    case 12: return f.pathlib.attr("Path")(inside(in.take(in.next() % 16)));
    case 13: {
      static const char* const scalars[] = {"float32", "float64", "int64", "uint8", "bool_", "complex64"};
      return f.numpy.attr(scalars[in.next() % 6])(static_cast<std::int8_t>(in.next()));
    }
    case 14: return py::make_tuple(value(in, f, depth + 1), value(in, f, depth + 1));
    default: {  // a dict of a fixture's names: what fix= and vary= take
      py::dict dict;
      for (int k = 1 + in.next() % 2; k > 0; --k) dict[py::str(f.words[in.next() % 4])] = value(in, f, depth + 1);
      return std::move(dict);
    }
  }
}

// A value for a path argument: as decoded, but text is kept inside the working folder unless it names a fixture
// the call only reads (`read_only`).
py::object path_value(Bytes& in, const Fixtures& f, bool read_only) {
  py::object v = value(in, f, 0);
  if (PyUnicode_Check(v.ptr())) {
    Py_ssize_t size = 0;
    const char* text = PyUnicode_AsUTF8AndSize(v.ptr(), &size);
    if (text == nullptr) {
      PyErr_Clear();
      return v;  // lone surrogates: refused before any file is named
    }
    const std::string path(text, static_cast<std::size_t>(size));
    if (read_only && path.rfind(getenv("FMPC_FUZZ_FIXTURES"), 0) == 0) return v;
    return py::str(inside(path));
  }
  return v;
}

Fixtures& fixtures() {
  static Fixtures* f = [] {
    static py::scoped_interpreter interpreter;
    // A fresh working folder: everything the calls write lands there.
    char folder[] = "/tmp/fmpc_fuzz_python_XXXXXX";
    if (mkdtemp(folder) == nullptr || chdir(folder) != 0) abort();
    auto* fixtures = new Fixtures;
    fixtures->fmpc = py::module_::import("fmpc");
    fixtures->numpy = py::module_::import("numpy");
    fixtures->pathlib = py::module_::import("pathlib");
    fixtures->error = fixtures->fmpc.attr("Error");
    const char* root = getenv("FMPC_FUZZ_FIXTURES");
    if (root == nullptr) {
      std::fprintf(stderr, "FMPC_FUZZ_FIXTURES must name the source tree (tests/golden is read from it)\n");
      abort();
    }
    const std::string rules = std::string(root) + "/tests/golden/fll_eval/tipper.fll";
    const std::string table = std::string(root) + "/tests/golden/eval_table/liver.fzt";
    fixtures->rule_file = fixtures->fmpc.attr("load")(rules);
    fixtures->system = fixtures->rule_file.attr("system")();
    fixtures->table = fixtures->fmpc.attr("load_table")(table);
    fixtures->words = {"service", "food", "tip", "HCV", "matlab", "octave", "double", "float", "refined",
                       "uniform", "tipper", "", rules, table, "out.fzt", "-", ".", ".."};
    return fixtures;
  }();
  return *f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixtures& f = fixtures();
  Bytes in(data, size);
  py::object function;
  py::list arguments;
  py::dict keywords;
  // Each optional keyword is given when its byte is odd.
  const auto maybe = [&](const char* name, auto make) {
    if (in.next() & 1) keywords[name] = make();
  };
  const auto any = [&] { return value(in, f, 0); };
  const auto path = [&] { return path_value(in, f, true); };
  const auto output = [&] { return path_value(in, f, false); };
  try {
    switch (in.next() % 8) {
      case 0:
        function = f.fmpc.attr("check");
        arguments.append(path());
        maybe("lint", any);
        maybe("coverage_threshold", any);
        break;
      case 1:
        function = f.fmpc.attr("load");
        arguments.append(path());
        break;
      case 2:
        function = f.fmpc.attr("load_table");
        arguments.append(path());
        break;
      case 3:
        function = f.system.attr("evaluate");
        arguments.append(any());
        maybe("semantics", any);
        maybe("return_diagnostics", any);
        break;
      case 4:
        function = f.system.attr("compile_table");
        arguments.append(output());
        for (const char* name : {"fix", "vary", "max_error", "precision", "spacing", "max_grid_points", "seed",
                                 "threads", "semantics"})
          maybe(name, any);
        break;
      case 5:
        function = f.table.attr("evaluate");
        arguments.append(any());
        maybe("return_diagnostics", any);
        break;
      case 6:
        function = f.rule_file.attr("system");
        maybe("name", any);
        break;
      default:
        function = f.fmpc.attr("simulate");
        arguments.append(path());
        maybe("output_directory", output);
        break;
    }
  } catch (const py::error_already_set&) {
    return 0;  // the bytes did not make a value (numpy refused a conversion): nothing to call
  } catch (const py::cast_error&) {
    return 0;
  }
  try {
    (void)function(*py::tuple(arguments), **keywords);
  } catch (py::error_already_set& e) {
    if (e.matches(f.error)) return 0;
    std::fprintf(stderr, "fuzz_python_arguments: %s raised %s, not fmpc.Error\n",
                 py::repr(function).cast<std::string>().c_str(), e.what());
    abort();
  }
  return 0;
}
