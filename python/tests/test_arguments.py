"""Arguments: every function converts each argument itself, so that a value of the wrong type or out of range is an
fmpc.Error naming the argument, never pybind11's TypeError or RuntimeError; NaN points are refused before any row
is evaluated. tests/fuzz/fuzz_python_arguments.cpp fuzzes the same conversions."""
import math
import os
import pathlib
import time
import unittest

import numpy

import fmpc
from fmpc_test_support import scratch, source

TIPPER = source("tests", "golden", "fll_eval", "tipper.fll")
GOLDEN_TABLE = source("tests", "golden", "eval_table", "liver.fzt")


def error_files(caught):
    return [d.file for d in caught.exception.diagnostics if d.severity == "error"]


class Arguments(unittest.TestCase):
    def assert_names(self, argument, call):
        with self.assertRaises(fmpc.Error) as caught:
            call()
        self.assertIn("argument '%s'" % argument, error_files(caught))

    def test_compile_table_values_name_their_argument(self):
        system = fmpc.load(TIPPER).system()
        out = os.path.join(scratch("arguments"), "t.fzt")
        # Issue 30: these raised RuntimeError "Unable to cast Python instance", or built a table from vary 0.
        self.assert_names("vary['service']", lambda: system.compile_table(out, vary={"service": 2**40}))
        self.assert_names("fix['service']", lambda: system.compile_table(out, fix={"service": 10**400}))
        self.assert_names("vary['service']", lambda: system.compile_table(out, vary={"service": 0}))
        self.assert_names("vary['service']", lambda: system.compile_table(out, vary={"service": 1}))
        self.assert_names("vary['service']", lambda: system.compile_table(out, vary={"service": 2.0}))
        self.assert_names("vary['service']", lambda: system.compile_table(out, vary={"service": True}))
        self.assert_names("fix['service']", lambda: system.compile_table(out, fix={"service": math.nan}))
        self.assert_names("fix['service']", lambda: system.compile_table(out, fix={"service": "5"}))
        self.assert_names("fix", lambda: system.compile_table(out, fix=[("service", 5)]))
        self.assert_names("fix", lambda: system.compile_table(out, fix={1: 5}))
        self.assert_names("max_grid_points", lambda: system.compile_table(out, max_grid_points=-1))
        self.assert_names("max_grid_points", lambda: system.compile_table(out, max_grid_points=2**64))
        self.assert_names("threads", lambda: system.compile_table(out, threads="2"))
        self.assert_names("seed", lambda: system.compile_table(out, seed=-1))
        self.assert_names("max_error", lambda: system.compile_table(out, max_error=math.nan))
        self.assert_names("max_error", lambda: system.compile_table(out, max_error=math.inf))
        self.assert_names("precision", lambda: system.compile_table(out, precision=b"float"))
        self.assert_names("output", lambda: system.compile_table(3))
        self.assert_names("output", lambda: system.compile_table("a\0b"))
        self.assertFalse(os.path.exists(out))
        # numpy numbers and paths are what they say.
        table = system.compile_table(pathlib.Path(out), fix={"food": numpy.float32(5.0)},
                                     vary={"service": numpy.int64(9)}, max_grid_points=numpy.uint16(1000),
                                     max_error=numpy.float64(5.0))
        self.assertEqual(table.inputs, ["service"])
        self.assertTrue(os.path.isfile(out))

    def test_check_load_and_evaluate_name_their_argument(self):
        # Issue 30: check(coverage_threshold=nan) returned as if the threshold were a number.
        self.assert_names("coverage_threshold", lambda: fmpc.check(TIPPER, coverage_threshold=math.nan))
        self.assert_names("coverage_threshold", lambda: fmpc.check(TIPPER, coverage_threshold=2))
        self.assert_names("coverage_threshold", lambda: fmpc.check(TIPPER, coverage_threshold="0.1"))
        self.assert_names("lint", lambda: fmpc.check(TIPPER, lint=1))
        self.assert_names("path", lambda: fmpc.check(None))
        self.assert_names("path", lambda: fmpc.load(b"x.fis"))
        self.assert_names("path", lambda: fmpc.load_table(5))
        self.assertEqual(fmpc.load(pathlib.Path(TIPPER)).systems, ["tipper"])
        system = fmpc.load(TIPPER).system()
        self.assert_names("name", lambda: fmpc.load(TIPPER).system(3))
        self.assert_names("points", lambda: system.evaluate([[1, 2], [3]]))
        self.assert_names("points", lambda: system.evaluate([["a", "b"]]))
        self.assert_names("points", lambda: system.evaluate(numpy.zeros((1, 2), dtype=complex)))
        self.assert_names("semantics", lambda: system.evaluate([[1, 2]], semantics=None))
        self.assert_names("return_diagnostics", lambda: system.evaluate([[1, 2]], return_diagnostics="yes"))
        table = fmpc.load_table(GOLDEN_TABLE)
        self.assert_names("return_diagnostics", lambda: table.evaluate([[1.0] * len(table.inputs)],
                                                                        return_diagnostics=0))
        self.assert_names("scene", lambda: fmpc.simulate(1.5))
        self.assert_names("output_directory", lambda: fmpc.simulate("s.yaml", output_directory=""))

    def test_messages_quoting_binary_files_are_text(self):
        # Found by fuzz_python_arguments: simulate on a binary file (a .fzt) raised UnicodeDecodeError from the
        # YAML error quoting its bytes; messages now replace bytes that are not UTF-8 with U+FFFD.
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.simulate(GOLDEN_TABLE)
        self.assertTrue(caught.exception.diagnostics)
        folder = scratch("binary")
        latin1 = os.path.join(folder, "latin1.fll")
        with open(latin1, "wb") as out:
            out.write(b"Engine: caf\xe9\n")
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.load(latin1)
        self.assertIn("not valid UTF-8", str(caught.exception))

    def test_nan_is_refused_before_any_row_is_evaluated(self):
        # Issue 30: a NaN in row 0 of 10^8 rows was found after all of them (133 s). 2 million rows of a 247-rule
        # system take minutes to evaluate; the refusal takes well under a second.
        system = fmpc.load(source("rulesets", "liver_fibrosis", "mamdani.fis")).system()
        points = numpy.full((2000000, 5), 10.0)
        points[0, 3] = numpy.nan
        points[1999999, 0] = numpy.nan
        start = time.monotonic()
        with self.assertRaises(fmpc.Error) as caught:
            system.evaluate(points)
        self.assertLess(time.monotonic() - start, 20.0)
        self.assertEqual(error_files(caught), ["points[0, 3]", "points[1999999, 0]"])


if __name__ == "__main__":
    unittest.main()
