"""examples/python/dask_sweep.py on a LocalCluster of 2 worker processes gives every curve of a
serial run in this process, bit for bit."""

import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import SOURCE_DIR

pytest.importorskip("distributed")

SCRIPT = SOURCE_DIR / "examples" / "python" / "dask_sweep.py"
STEPS = 40


def load_example():
    spec = importlib.util.spec_from_file_location("dask_sweep", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_sweep_on_two_dask_worker_processes_equals_the_serial_run_bit_for_bit(tmp_path):
    run = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--workers", "2",
                          "--steps", str(STEPS), "--out", str(tmp_path)],
                         env=dict(os.environ), capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    saved = np.load(tmp_path / "sweep.npz")

    sweep = load_example()
    cases = sweep.cases(quick=True)
    serial = sweep.sweep_serial(cases, STEPS)
    assert np.array_equal(saved["cases"], [(m.E, m.nu, rate) for m, rate in cases])
    assert saved["torques"].shape == (len(cases), STEPS)
    for k, (angles, torques) in enumerate(serial):
        assert np.array_equal(saved["angles"][k], angles), k
        assert np.array_equal(saved["torques"][k], torques), k
    # the curves are curves: the torque grows with the angle, and with E at the same nu and rate
    assert np.all(np.diff(saved["torques"][:, -10:], axis=1) > 0)
    assert saved["torques"][2, -1] > saved["torques"][0, -1] > 0
