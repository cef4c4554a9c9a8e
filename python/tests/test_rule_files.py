"""fmpc.load and fmpc.check: systems, and every diagnostic as an object with its position."""
import os
import unittest

import fmpc
from fmpc_test_support import scratch, source

MAMDANI = source("rulesets", "liver_fibrosis", "mamdani.fis")


class RuleFiles(unittest.TestCase):
    def test_load_reads_systems_and_variables(self):
        rules = fmpc.load(MAMDANI)
        self.assertEqual(rules.dialect, "fmpc")
        system = rules.system()
        self.assertEqual(system.inputs, ["HCV", "HBV", "ALD", "CLD", "NAFLD"])
        self.assertEqual(len(system.outputs), 1)
        self.assertEqual(system.input_variables[0]["name"], "HCV")
        self.assertLess(system.input_variables[0]["min"], system.input_variables[0]["max"])
        self.assertFalse([d for d in rules.diagnostics if d.severity == "error"])

    def test_a_mistake_raises_with_file_line_and_column(self):
        folder = scratch("mistake")
        path = os.path.join(folder, "broken.fmpc")
        with open(path, "w") as f:
            f.write("system s\n  type mamdani\n\ninput x in [0, 1] kPa\n  a is triangle(start 0, peak 0.5, end 1)\n\n"
                    "output y in [0, 1] kPa\n  b is triangle(start 0, peak 0.5, end 1)\n\n"
                    "rule r1: if x is c then y is b\n")
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.load(path)
        errors = [d for d in caught.exception.diagnostics if d.severity == "error"]
        self.assertTrue(errors)
        self.assertEqual(errors[0].file, path)
        self.assertGreater(errors[0].line, 0)
        self.assertGreater(errors[0].column, 0)
        self.assertIn(path + ":%d:%d: error:" % (errors[0].line, errors[0].column), str(caught.exception))
        self.assertIsInstance(caught.exception, ValueError)

    def test_missing_file_and_table_given_as_rule_file(self):
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.load(os.path.join(scratch("missing"), "none.fis"))
        self.assertIn("cannot read", caught.exception.diagnostics[0].message)
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.load(source("tests", "golden", "eval_table", "liver.fzt"))
        self.assertIn("compiled lookup table", caught.exception.diagnostics[0].message)

    def test_unknown_system_suggests_the_closest(self):
        rules = fmpc.load(MAMDANI)
        with self.assertRaises(fmpc.Error) as caught:
            rules.system(rules.systems[0] + "x")
        self.assertIn("did you mean", " ".join(caught.exception.diagnostics[0].notes))

    def test_check_returns_warnings_as_objects_without_raising(self):
        path = source("tests", "golden", "lint_warnings", "warnings.fis")
        diagnostics = fmpc.check(path)
        codes = [d.code for d in diagnostics if d.severity == "warning"]
        self.assertIn("unused-term", codes)
        self.assertIn("coverage-hole", codes)
        unused = [d for d in diagnostics if d.code == "unused-term"][0]
        self.assertEqual((unused.file, unused.line, unused.column), (path, 18, 3))
        self.assertIn("[-Wunused-term]", str(unused))
        self.assertEqual([d for d in fmpc.check(path, lint=False) if d.severity == "warning"], [])
        missing = fmpc.check(os.path.join(scratch("lint"), "none.fis"))
        self.assertEqual(missing[0].severity, "error")


if __name__ == "__main__":
    unittest.main()
