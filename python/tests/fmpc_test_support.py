"""What the module's tests share: the paths ctest passes, the fmpc executable, a scratch folder per test."""
import csv
import io
import os
import subprocess
import tempfile

import numpy

SOURCE = os.environ.get("FMPC_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
FMPC = os.environ.get("FMPC_BINARY", "fmpc")
WORK = os.environ.get("FMPC_WORK_DIR", tempfile.gettempdir())


def source(*parts):
    return os.path.join(SOURCE, *parts)


def scratch(name):
    os.makedirs(WORK, exist_ok=True)
    return tempfile.mkdtemp(prefix=name + "_", dir=WORK)


def fmpc_eval(path, names, points, *extra):
    """`fmpc eval PATH --csv POINTS` on the rows of `points`; returns the output columns as float64, exactly as
    printed (fmpc prints the shortest text that reads back as the same double)."""
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(names)
    for row in points:
        writer.writerow([repr(float(v)) if numpy.isfinite(v) else ("inf" if v > 0 else "-inf") for v in row])
    run = subprocess.run([FMPC, "eval", path, "--csv", "-", *extra], input=text.getvalue(), capture_output=True,
                         text=True, check=False)
    if run.returncode != 0:
        raise AssertionError("fmpc eval failed (%d): %s" % (run.returncode, run.stderr))
    rows = list(csv.reader(io.StringIO(run.stdout)))
    return rows[0], numpy.array([[float(v) for v in r[len(names):]] for r in rows[1:]], dtype=numpy.float64)
