"""Lookup tables: compile_table writes a .fzt with its stated error, Table.evaluate equals `fmpc eval TABLE`."""
import os
import unittest

import numpy

import fmpc
from fmpc_test_support import fmpc_eval, scratch, source

MAMDANI = source("rulesets", "liver_fibrosis", "mamdani.fis")
GOLDEN_TABLE = source("tests", "golden", "eval_table", "liver.fzt")


class Tables(unittest.TestCase):
    def test_loaded_table_equals_fmpc_eval(self):
        table = fmpc.load_table(GOLDEN_TABLE)
        self.assertIn(table.error_kind, ("bound", "estimate"))
        random = numpy.random.default_rng(3)
        points = random.uniform(0.0, 30.0, size=(200, len(table.inputs)))
        mine = table.evaluate(points)
        _, theirs = fmpc_eval(GOLDEN_TABLE, table.inputs, points)
        self.assertTrue(numpy.array_equal(mine, theirs))
        empty = table.evaluate(numpy.empty((0, len(table.inputs))))
        self.assertEqual(empty.shape, (0, len(table.outputs)))

    def test_table_inputs_nan_raises_and_clamping_warns(self):
        table = fmpc.load_table(GOLDEN_TABLE)
        points = numpy.full((2, len(table.inputs)), 10.0)
        points[1, 0] = 1e9
        _, diagnostics = table.evaluate(points, return_diagnostics=True)
        self.assertEqual([d.file for d in diagnostics], ["points[1, 0]"])
        self.assertIn("the table holds the value at", diagnostics[0].message)
        points[0, 0] = numpy.nan
        with self.assertRaises(fmpc.Error) as caught:
            table.evaluate(points)
        self.assertEqual(caught.exception.diagnostics[0].file, "points[0, 0]")

    def test_compile_a_table_and_meet_its_error(self):
        system = fmpc.load(MAMDANI).system()
        path = os.path.join(scratch("compile"), "liver.fzt")
        fixed = {"ALD": 12.0, "CLD": 11.0, "NAFLD": 11.2}
        table = system.compile_table(path, fix=fixed, vary={"HCV": None, "HBV": None}, max_error=0.5)
        self.assertTrue(os.path.isfile(path))
        self.assertEqual(table.inputs, ["HCV", "HBV"])
        self.assertEqual(table.fixed_inputs, fixed)
        self.assertLessEqual(table.max_error, 0.5)
        reread = fmpc.load_table(path)
        random = numpy.random.default_rng(11)
        points = random.uniform(5.0, 25.0, size=(500, 2))
        values = reread.evaluate(points)
        self.assertTrue(numpy.array_equal(values, table.evaluate(points)))
        full = numpy.column_stack([points, numpy.tile([12.0, 11.0, 11.2], (len(points), 1))])
        reference = system.evaluate(full)
        self.assertLessEqual(numpy.max(numpy.abs(values - reference)), table.max_error)

    def test_compile_errors_name_the_argument(self):
        system = fmpc.load(MAMDANI).system()
        folder = scratch("compile_errors")
        with self.assertRaises(fmpc.Error) as caught:
            system.compile_table(os.path.join(folder, "t.fzt"), fix={"HCVV": 5.0}, precision="half")
        files = [d.file for d in caught.exception.diagnostics if d.severity == "error"]
        self.assertIn("argument 'precision'", files)
        with self.assertRaises(fmpc.Error) as caught:
            system.compile_table(os.path.join(folder, "t.fzt"), fix={"HCVV": 5.0})
        self.assertIn("argument 'fix['HCVV']'", [d.file for d in caught.exception.diagnostics])
        with self.assertRaises(fmpc.Error):
            system.compile_table(os.path.join(folder, "t.fzt"), fix={"HCV": "five"})
        with self.assertRaises(fmpc.Error):
            system.compile_table(os.path.join(folder, "t.fzt"), max_error=-1.0)
        with self.assertRaises(fmpc.Error) as caught:  # unreachable: refused before anything is evaluated
            system.compile_table(os.path.join(folder, "t.fzt"), max_error=1e-300)
        self.assertFalse(os.path.exists(os.path.join(folder, "t.fzt")))
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.load_table(MAMDANI)
        self.assertIn("it is not a lookup table", str(caught.exception))
        # A gigabyte that is not a table is refused after its first bytes (sparse: no disk, no memory used).
        big = os.path.join(folder, "big.fzt")
        with open(big, "wb") as out:
            out.truncate(1 << 30)
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.load_table(big)
        self.assertIn("it is not a lookup table", str(caught.exception))


if __name__ == "__main__":
    unittest.main()
