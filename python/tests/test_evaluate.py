"""System.evaluate on numpy arrays: equal to `fmpc eval` bit for bit, and every misuse an fmpc.Error."""
import unittest

import numpy

import fmpc
from fmpc_test_support import fmpc_eval, source

FILES = [source("rulesets", "liver_fibrosis", name) for name in ("mamdani.fis", "sugeno.fis", "it2.fis")]


def random_points(system, count, seed):
    random = numpy.random.default_rng(seed)
    lows = numpy.array([v["min"] for v in system.input_variables])
    highs = numpy.array([v["max"] for v in system.input_variables])
    points = random.uniform(lows, highs, size=(count, len(lows)))
    points[0] = lows  # the ends of every range, and a tie of equal values
    points[1] = highs
    points[2] = (lows + highs) / 2
    return points


class Evaluate(unittest.TestCase):
    def test_equals_fmpc_eval_bit_for_bit(self):
        for path in FILES:
            system = fmpc.load(path).system()
            points = numpy.vstack([numpy.loadtxt(source("rulesets", "liver_fibrosis", "example_patients.csv"),
                                                 delimiter=",", skiprows=1), random_points(system, 300, 7)])
            for semantics in ("matlab", "octave"):
                mine = system.evaluate(points, semantics=semantics)
                header, theirs = fmpc_eval(path, system.inputs, points, "--semantics", semantics)
                # Interval type-2 files add OUTPUT.lower and OUTPUT.upper columns; the crisp output comes first.
                columns = [header.index(name) - len(system.inputs) for name in system.outputs]
                self.assertEqual(mine.shape, (len(points), len(system.outputs)))
                self.assertEqual(mine.dtype, numpy.float64)
                self.assertTrue(numpy.array_equal(mine, theirs[:, columns]), (path, semantics))

    def test_infinite_and_out_of_range_inputs_warn_and_match_fmpc_eval(self):
        system = fmpc.load(FILES[0]).system()
        points = numpy.array([[numpy.inf, 5, 5, 5, 5], [-numpy.inf, 7, 7, 7, 7], [1e300, 5, 5, 5, 5]])
        values, diagnostics = system.evaluate(points, return_diagnostics=True)
        _, theirs = fmpc_eval(FILES[0], system.inputs, points)
        self.assertTrue(numpy.array_equal(values, theirs, equal_nan=True))
        ranges = [d for d in diagnostics if d.code == "input-out-of-range"]
        self.assertEqual([d.file for d in ranges], ["points[0, 0]", "points[1, 0]", "points[2, 0]"])
        self.assertEqual(ranges[0].severity, "warning")

    def test_nan_raises_naming_the_cell(self):
        system = fmpc.load(FILES[0]).system()
        points = numpy.full((3, 5), 7.0)
        points[2, 1] = numpy.nan
        with self.assertRaises(fmpc.Error) as caught:
            system.evaluate(points)
        errors = [d for d in caught.exception.diagnostics if d.severity == "error"]
        self.assertEqual(len(errors), 1)
        self.assertEqual(errors[0].file, "points[2, 1]")
        self.assertIn("input 'HBV' is NaN", errors[0].message)

    def test_empty_arrays(self):
        system = fmpc.load(FILES[0]).system()
        values = system.evaluate(numpy.empty((0, 5)))
        self.assertEqual(values.shape, (0, 1))
        with self.assertRaises(fmpc.Error):
            system.evaluate(numpy.empty((0,)))
        with self.assertRaises(fmpc.Error):
            system.evaluate(numpy.empty((0, 4)))

    def test_wrong_shapes(self):
        system = fmpc.load(FILES[0]).system()
        for shape in [(5,), (2, 4), (2, 6), (1, 5, 1), ()]:
            with self.assertRaises(fmpc.Error, msg=str(shape)) as caught:
                system.evaluate(numpy.zeros(shape) + 7)
            message = caught.exception.diagnostics[0].message
            self.assertIn("expected (n, 5)", message)
            self.assertEqual(caught.exception.diagnostics[0].file, "argument 'points'")

    def test_dtypes(self):
        system = fmpc.load(FILES[0]).system()
        floats = numpy.array([[5.0, 5.0, 5.0, 5.0, 5.0], [9.0, 9.5, 12.0, 11.0, 11.25]])
        expected = system.evaluate(floats)
        self.assertTrue(numpy.array_equal(system.evaluate(floats.astype(numpy.float32)), expected))
        self.assertTrue(numpy.array_equal(system.evaluate(floats[:1].astype(numpy.int32)), expected[:1]))
        self.assertTrue(numpy.array_equal(system.evaluate(floats.tolist()), expected))
        self.assertTrue(numpy.array_equal(system.evaluate(numpy.asfortranarray(floats)), expected))
        self.assertTrue(numpy.array_equal(system.evaluate(numpy.hstack([floats, floats])[:, ::2][:, :5]),
                                          system.evaluate(numpy.ascontiguousarray(numpy.hstack([floats, floats])[:, ::2][:, :5]))))
        for bad in (floats.astype(str), floats.astype(object), floats.astype(complex), floats > 6):
            with self.assertRaises(fmpc.Error, msg=str(bad.dtype)) as caught:
                system.evaluate(bad)
            self.assertIn("dtype", caught.exception.diagnostics[0].message)
        with self.assertRaises(fmpc.Error):
            system.evaluate(numpy.array([[2**60, 5, 5, 5, 5]], dtype=numpy.int64))

    def test_unknown_semantics(self):
        system = fmpc.load(FILES[0]).system()
        with self.assertRaises(fmpc.Error) as caught:
            system.evaluate(numpy.full((1, 5), 7.0), semantics="fuzzylite")
        self.assertEqual(caught.exception.diagnostics[0].file, "argument 'semantics'")


if __name__ == "__main__":
    unittest.main()
