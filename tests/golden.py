"""The golden run and its physics tolerance (docs/design.md section 6; no tests here).

The fixture ``tests/data/golden_spur.json`` holds the paper's spur case (hybrid bearings) over
:data:`PERIODS` mesh periods at the shipped step T/32 and at T/64, for the shipped settings and
with the time-integration refinements off, and the 2048-period summary of the shipped case
(written by ``python tests/data/generate_golden.py``, the one command that re-records it).

A change of arithmetic passes when it moves every channel (one component of one quantity of
one bearing: :data:`CHANNELS`) by at most :data:`FRACTION` of what halving the step moves it,
the largest difference over the run in both cases, and the 2048-period summary (R, the
bearing-force peak-to-peak, the line amplitudes) by at most :data:`SUMMARY_TOLERANCE`
(relative). This is a tolerance of physics, not of arithmetic: anything within it is smaller
than the time discretisation's own error. Bitwise reproducibility on one machine is tested
apart (``tests/system/test_determinism.py``).
"""

from __future__ import annotations

import json
import tempfile

import numpy as np

from tests.helpers import DATA, run_paper_case

FIXTURE = DATA / "golden_spur.json"
#: horizon of the trajectory fixture [mesh periods]
PERIODS = 4
#: the recorded steps per mesh period: the shipped one and half its step
STEPS = (32, 64)
#: the quantities compared, as the results file names them
CHANNELS = ("journal_position", "journal_velocity", "bearing_force", "mesh_force",
            "transmission_error")
#: settings of the fixture: the shipped case, and the refinements of gear_fmu.structure off
SETTINGS = {
    "shipped": {},
    "refinements off": {"simulation.consistent_start": False,
                        "simulation.locate_contact": False},
}
#: a channel may move by this fraction of what halving the step moves it
FRACTION = 0.1
#: relative tolerance on each number of the 2048-period summary
SUMMARY_TOLERANCE = 1e-3
SUMMARY_KEYS = ("dynamic_factor", "bearing_force_ptp", "line_amplitudes")


def load_fixture() -> dict:
    return json.loads(FIXTURE.read_text())


def trajectories(periods: int, steps_per_period: int, in_process: bool = True,
                 fmu_dir=None, **overrides) -> dict:
    """The :data:`CHANNELS` (and ``time``) of a short run of the spur case, as lists."""
    with tempfile.TemporaryDirectory() as tmp:
        r, _ = run_paper_case(tmp, periods=periods, in_process=in_process, fmu_dir=fmu_dir,
                              **{"simulation.steps_per_mesh_period": steps_per_period},
                              **overrides)
    return {name: np.asarray(r[name]).tolist() for name in ("time", *CHANNELS)}


def channel_tolerances(fine: dict, coarse: dict) -> dict:
    """Per quantity, the (n_channels,) tolerance: :data:`FRACTION` of the largest difference
    between the T/64 run (every second row: the same instants) and the T/32 run."""
    out = {}
    for name in CHANNELS:
        c = np.asarray(coarse[name])
        f = np.asarray(fine[name])[1::2].reshape(c.shape)
        if f.shape != c.shape or not np.allclose(np.asarray(fine["time"])[1::2],
                                                 coarse["time"], rtol=1e-12, atol=0.0):
            raise ValueError(f"{name}: the T/64 rows do not fall on the T/32 instants")
        out[name] = FRACTION * np.abs(f - c).reshape(len(c), -1).max(axis=0)
    return out


def compare(got: dict, recorded: dict, tolerances: dict) -> dict:
    """Per quantity, the largest (over its channels) of max |got - recorded| / tolerance:
    the run passes when every value is <= 1."""
    if len(got["time"]) != len(recorded["time"]):
        raise ValueError(f"{len(got['time'])} rows against {len(recorded['time'])} recorded")
    out = {}
    for name in CHANNELS:
        # a mesh channel is (rows, meshes) since the train generalisation, (rows,) before
        rows = len(got["time"])
        d = np.abs(np.asarray(got[name]).reshape(rows, -1)
                   - np.asarray(recorded[name]).reshape(rows, -1))
        out[name] = float((d.max(axis=0) / np.ravel(tolerances[name])).max())
    return out


def summary(report: dict) -> dict:
    """The numbers of a run report (:func:`orchestrator.analysis.metrics.run_report`) that the
    summary check compares, as lists."""
    return {k: np.asarray(report[k], dtype=float).tolist() for k in SUMMARY_KEYS}


def summary_deviation(got: dict, recorded: dict) -> float:
    """Largest relative difference over the summary's numbers (a line unresolved in both, NaN,
    counts as equal; in one only, as infinite)."""
    worst = 0.0
    for key in SUMMARY_KEYS:
        # R is one per mesh since the train generalisation (one value for the paper's pair)
        a, b = (np.asarray(x[key], dtype=float).ravel() for x in (got, recorded))
        if (np.isnan(a) != np.isnan(b)).any():
            return float("inf")
        ok = ~np.isnan(b)
        worst = max(worst, float((np.abs(a[ok] - b[ok]) / np.abs(b[ok])).max(initial=0.0)))
    return worst
