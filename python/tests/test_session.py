"""fmpc.Session: a scene stepped from Python, a tool posed every tick and read back as numpy arrays, the GIL released
while stepping, errors raised as fmpc.Error."""
import os
import threading
import time
import unittest

import numpy

import fmpc
from fmpc_test_support import scratch, source

SCENE = """name: python_session
model: corotational_fem
mesh:
  box: {size: [0.02, 0.02, 0.01], cells: [6, 6, 3]}
  units: m
material:
  rules: RULES
  inputs: {HCV: 9.7, HBV: 9.5, ALD: 12, CLD: 11, NAFLD: 11.2}
  poisson_ratio: 0.4
mass: {density: 1000}
damping: {ratio: 0.5}
fixed:
  plane: {point: [0, 0, 0], normal: [0, 0, 1]}
tools:
  - name: tip
    shape: sphere
    radius: 0.003
    pose: {position: [0.01, 0.01, 0.0131]}
integrator: semi_implicit_euler
precision: double
"""


def session():
    text = SCENE.replace("RULES", source("rulesets", "liver_fibrosis", "mamdani.fis"))
    return fmpc.Session.from_yaml(text, os.path.join(scratch("session"), "block.yaml"))


class Session(unittest.TestCase):
    def test_a_haptic_loop(self):
        s = session()
        self.assertEqual(s.backend, "cpu")
        self.assertEqual(s.tool_names, ["tip"])
        self.assertEqual(s.vertex_count, 7 * 7 * 4)
        for tick in range(1, 101):
            s.set_tool_pose("tip", [0.01, 0.01, 0.0131 - 0.001 * min(1.0, tick / 80.0)])
            s.step_to(tick * 1e-3)
        self.assertGreaterEqual(s.time, 0.1)
        readings = s.tool_readings()
        self.assertEqual(readings["force"].shape, (1, 3))
        self.assertEqual(readings["torque"].shape, (1, 3))
        self.assertGreater(readings["force"][0, 2], 0.0)
        self.assertGreater(readings["contacts"][0], 0)
        positions = s.positions()
        self.assertEqual(positions.shape, (s.vertex_count, 3))
        self.assertEqual(positions.dtype, numpy.float64)
        self.assertTrue(numpy.all(numpy.isfinite(positions)))
        self.assertGreater(s.energies()["elastic"], 0.0)
        self.assertEqual(s.inversions["largest_count"], 0)
        with self.assertRaises(fmpc.Error) as caught:
            s.device_positions()
        self.assertIn("read positions() instead of a device pointer", str(caught.exception))

    def test_bad_input_raises_and_changes_nothing(self):
        s = session()
        s.step(5)
        before = s.positions()
        with self.assertRaises(fmpc.Error) as caught:
            s.set_tool_pose(0, [float("nan"), 0.01, 0.01])
        self.assertIn("is not finite", str(caught.exception))
        with self.assertRaises(fmpc.Error):
            s.set_tool_pose("shaft", [0.0, 0.0, 0.0])
        with self.assertRaises(fmpc.Error):
            s.set_tool_pose(0, [0.0, 0.0])
        for tool in (1.5, None, True, 2**70, -1):
            with self.assertRaises(fmpc.Error) as caught:
                s.set_tool_pose(tool, [0.01, 0.01, 0.02])
            self.assertEqual(caught.exception.diagnostics[0].file, "argument 'tool'")
        with self.assertRaises(fmpc.Error):
            s.swap_material(source("rulesets", "scenes", "strain_stiffening.fis"))
        with self.assertRaises(fmpc.Error):
            s.step(-1)
        self.assertEqual(s.steps, 5)
        self.assertTrue(numpy.array_equal(before, s.positions()))

    def test_the_material_swapped(self):
        s = session()
        s.step(10)
        s.swap_material(source("rulesets", "liver_fibrosis", "mamdani.fis"))
        self.assertEqual(s.steps, 10)
        s.step(10)

    def test_stepping_releases_the_gil(self):
        s = session()
        count = [0]
        stop = threading.Event()

        def spin():
            while not stop.is_set():
                count[0] += 1

        spinner = threading.Thread(target=spin)
        spinner.start()
        try:
            time.sleep(0.05)
            started = count[0]
            begin = time.monotonic()
            s.step(3000)
            elapsed = time.monotonic() - begin
            during = count[0] - started
        finally:
            stop.set()
            spinner.join()
        # A thread holding the GIL in C++ would have stopped the counter for the whole step.
        self.assertGreater(elapsed, 0.05)
        self.assertGreater(during, 1000)


if __name__ == "__main__":
    unittest.main()
