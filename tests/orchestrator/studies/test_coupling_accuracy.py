"""The coupling-accuracy study (:mod:`orchestrator.studies.coupling_accuracy`) against what the
schemes must do independently of the measured table:

* the reference is ``gsb run``'s master (the same positions as a run, bit for bit);
* affine bearings (``linear``, ``lumped``): every linearisation of an affine law is that law,
  so the one pass of a non-iterating master is the converged step and both lags equal the
  iterative master to round-off, while the hybrid bearing's do not;
* the order: a lag-L law is the bearing's first-order Taylor expansion about X_n-L used at
  X_n+1, so its force error is (1/2) F'' (X_n+1 - X_n-L)^2 ~ ((L + 1) v dt)^2: second order in
  dt (a force held from X_n-L would be first order), lag 1's error four times lag 0's;
* the command prints the table.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from fmu_src.case import load_case
from orchestrator.studies.coupling_accuracy import (
    iterative,
    non_iterative,
    orbit_error,
    study,
    table,
)
from tests.helpers import ROOT

CASE = "baguet2010_spur"


def test_orbit_error_is_the_largest_difference_over_the_larger_peak_to_peak():
    t = np.linspace(0.0, 2.0 * np.pi, 201)
    ref = np.zeros((t.size, 4, 4))
    ref[:, 0, 0], ref[:, 0, 1] = 3.0 * np.cos(t), np.sin(t)  # ptp 6 along s, 2 along t
    ref[:, 1, :2] = 1e3  # other bearings are not compared
    x = ref.copy()
    x[50, 0, 1] += 0.3  # along t: still over the larger (s) peak-to-peak
    x[:, 2, :] = 0.0
    assert orbit_error(x, ref) == pytest.approx(0.3 / 6.0, rel=1e-12)
    assert orbit_error(ref, ref) == 0.0
    with pytest.raises(ValueError, match="201 and 200 instants"):
        orbit_error(x, ref[1:])


def test_the_reference_is_gsb_runs_master():
    from orchestrator.api import simulate

    case = load_case(CASE)
    result = simulate(case, in_process=True, steps=24, progress=False)
    ref = iterative(case, 24)
    assert np.array_equal(ref[1:, :, :2], result["journal_position"])
    assert np.array_equal(ref[1:, :, 2:], result["journal_velocity"])


@pytest.mark.parametrize("model", ["linear", "lumped"])
def test_affine_bearings_make_both_lags_the_iterative_master(model):
    case = load_case(CASE, {"bearings.*.model": model})
    ref = iterative(case, 64)
    scale = np.abs(ref).max(axis=(0, 1))
    for lag in (0, 1):
        x = non_iterative(case, 64, lag)
        # round-off: 0 with the newest dependency versions, 4.8e-11 of the velocities' largest
        # with the oldest allowed (numpy 1.26, scipy 1.11, numba 0.59)
        assert (np.abs(x - ref).max(axis=(0, 1)) <= 2e-10 * scale).all(), (model, lag)
    hybrid = load_case(CASE)
    assert orbit_error(non_iterative(hybrid, 64, 0), iterative(hybrid, 64)) > 1e-2


def test_the_coupling_error_is_second_order_and_lag_1_four_times_lag_0():
    """4 mesh periods at dt/2, dt/4, dt/8 (measured: orders 1.85, 2.08 for lag 0 and 2.03,
    1.93 for lag 1; lag 1 / lag 0 = 4.25, 3.76, 4.16)."""
    base = load_case(CASE)
    spm = base["simulation.steps_per_mesh_period"]
    errors = []
    for k in (1, 2, 3):
        case = base.with_overrides({"simulation.steps_per_mesh_period": spm * 2**k})
        n = 4 * spm * 2**k
        ref = iterative(case, n)
        errors.append([orbit_error(non_iterative(case, n, lag), ref) for lag in (0, 1)])
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    ratios = errors[:, 1] / errors[:, 0]
    print(f"\norders (lag 0, lag 1) per halving: {orders.round(2).tolist()}; "
          f"lag 1 / lag 0: {ratios.round(2).tolist()}")
    assert ((orders > 1.7) & (orders < 2.3)).all()
    assert ((ratios > 3.3) & (ratios < 4.8)).all()


def test_study_rows_compare_at_the_case_steps_instants():
    """One mesh period, dt and dt/2: the iterative master at dt is its own reference, and a
    scheme's error against it at dt/2 is within the sum of the two differences it is made of
    (the triangle inequality, up to the two references' peak-to-peaks: within 10 %)."""
    result = study(CASE, periods=1, levels=2, detune=0.0)
    first, second = result["rows"]
    assert first["iterative"] == 0.0 and first["same"] == first["case_step"]
    assert first["detuned"] is None
    assert second["steps"] == 2 * first["steps"] == 64
    assert math.isclose(second["dt"], first["dt"] / 2, rel_tol=1e-15)
    for lag in (0, 1):
        assert second["case_step"][lag] <= 1.1 * (second["same"][lag] + second["iterative"])
    text = table(result, "the command")
    assert text.count("\n| dt") == 2 and "Printed by `the command`." in text


def test_the_command_prints_the_table():
    proc = subprocess.run([sys.executable, "-m", "orchestrator.studies.coupling_accuracy",
                           "--periods", "1", "--levels", "2"],
                          capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = proc.stdout
    assert "| step [s] | steps / mesh period | lag 0 | lag 1 |" in out
    assert "| dt = 2.324e-05 | 32 |" in out and "| dt/2 = 1.162e-05 | 64 |" in out
    assert "lag 1, step x (1 - 1e-06)" in out
    assert ("Printed by `python -m orchestrator.studies.coupling_accuracy baguet2010_spur "
            "--periods 1 --levels 2 --detune 1e-06`.") in out
    bad = subprocess.run([sys.executable, "-m", "orchestrator.studies.coupling_accuracy",
                          "no_such_case"], capture_output=True, text=True, timeout=600,
                         cwd=ROOT)
    assert bad.returncode == 2 and "no_such_case" in bad.stderr


def test_the_documented_table_is_the_studys_output_at_its_defaults():
    """docs/fmu-variables.md (generated from fmu_src.build.variables_doc.ACCURACY) shows the
    table with the study's current columns, printed by the command at its default arguments
    (the numbers themselves are the command's: re-run it when the physics changes)."""
    from fmu_src.build.variables_doc import ACCURACY
    from orchestrator.studies.coupling_accuracy import DETUNE, LEVELS, command_line

    fake = {"case": CASE, "periods": 1, "dt": 1.0, "steps_per_mesh_period": 32,
            "detune": DETUNE, "orbit_ptp": [1.0, 1.0],
            "rows": [{"k": k, "dt": 2.0**-k, "steps": 1, "same": {0: 1.0, 1: 1.0},
                      "detuned": {0: 1.0, 1: 1.0}, "case_step": {0: 1.0, 1: 1.0},
                      "iterative": 1.0} for k in range(LEVELS)]}
    header = next(line for line in table(fake).splitlines() if line.startswith("| step"))
    page = (ROOT / "docs" / "fmu-variables.md").read_text()
    for text in (page, ACCURACY):
        assert header in text
        assert f"Printed by `{command_line()}`." in text
        assert text.count("\n| dt") == LEVELS
