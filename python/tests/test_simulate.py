"""fmpc.simulate: the probe curve and final positions as arrays, the summary as summary.json has it."""
import csv
import json
import os
import unittest

import numpy

import fmpc
from fmpc_test_support import scratch, source

SCENE = source("rulesets", "scenes", "liver_indentation.yaml")


class Simulate(unittest.TestCase):
    def test_the_demo_scene(self):
        folder = scratch("simulate")
        run = fmpc.simulate(SCENE, folder)
        self.assertTrue(run.completed)
        self.assertEqual(run.backend, "cpu")
        with open(os.path.join(folder, "summary.json")) as f:
            self.assertEqual(run.summary, json.load(f))
        self.assertEqual(run.summary["steps"], run.steps)
        self.assertEqual(run.positions.shape, (run.summary["mesh"]["vertices"], 3))
        self.assertTrue(numpy.all(numpy.isfinite(run.positions)))
        with open(os.path.join(folder, "time_series.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(run.time), len(rows))
        for name, values in (("time_s", run.time), ("probe_displacement_m", run.displacement),
                             ("probe_force_N", run.force)):
            self.assertTrue(numpy.array_equal(values, numpy.array([float(r[name]) for r in rows])), name)
        self.assertEqual(run.summary["probe"]["final_force_N"], run.force[-1])
        self.assertGreater(run.force[-1], 0.0)
        # Running again into the same folder leaves one run there (no stale frames).
        fmpc.simulate(SCENE, folder)
        self.assertEqual(len([n for n in os.listdir(folder) if n.endswith(".vtu")]), run.summary["outputs"]["frames"])

    def test_scene_mistakes_raise_with_their_position(self):
        folder = scratch("scene_errors")
        path = os.path.join(folder, "bad.yaml")
        with open(SCENE) as f:
            text = f.read()
        with open(path, "w") as f:
            f.write(text.replace("integrator: semi_implicit_euler", "integrator: leapfrogg"))
        with self.assertRaises(fmpc.Error) as caught:
            fmpc.simulate(path, folder)
        error = [d for d in caught.exception.diagnostics if d.severity == "error"][0]
        self.assertEqual(error.file, path)
        self.assertGreater(error.line, 0)
        with self.assertRaises(fmpc.Error):
            fmpc.simulate(os.path.join(folder, "none.yaml"), folder)


if __name__ == "__main__":
    unittest.main()
