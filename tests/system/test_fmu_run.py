"""The paper's case run through real FMUs (gear-shaft FMU + four bearing FMUs, fmpy) against the
in-process master, which tests/orchestrator/run/test_run.py checks against a monolithic
Newton-Raphson.

Both transports run the same code on the same numbers along the same sequence of calls (one
static first guess, :meth:`orchestrator.coupling.master.BearingSet.static_position`), so every
registered bearing model gives the same bits through its FMU as in-process: every channel of
the results file, the iterations, the static solution. The FMUs load in the test's own
process (a fresh host process is tested in test_bearing_fmus.py and test_fmu_system.py).
"""

import numpy as np
import pytest

from bearing_fmu import MODELS
from tests.helpers import run_isolated

CHANNELS = ("journal_position", "journal_velocity", "bearing_force", "mesh_force",
            "transmission_error", "gear_node", "iterations")


def compare(fmu_dir, model, periods, tmp, steps=None, overrides=None) -> dict:
    """Both transports of one run: the channels that differ (an empty list when every bit is
    the same), the iterations per step of each, the FMU run's mode, the steps."""
    from fmu_src.case import load_case
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import run_case

    case = load_case("baguet2010_spur", overrides or None)
    out = {}
    for in_process in (True, False):
        run = case.with_overrides({"bearings.*.model": model, "simulation.mesh_periods": periods})
        s = run_case(run, in_process=in_process, out_dir=tmp, fmu_dir=fmu_dir, progress=False,
                     steps=steps)
        out[in_process] = (read_results(s.results), s)
    (a, sa), (b, sb) = out[True], out[False]
    return {"differ": [k for k in CHANNELS if not np.array_equal(a[k], b[k])]
            + ([] if np.array_equal(sa.static_positions, sb.static_positions) else ["X0"]),
            "it_in": sa.iterations_per_step, "it_fmu": sb.iterations_per_step,
            "mode": b["attrs"]["mode"], "steps": len(a["time"])}


def test_fmu_cosimulation_equals_the_in_process_master(fmu_dir, tmp_path):
    """256 steps of the paper's case with hybrid bearings, bit for bit."""
    r = compare(fmu_dir, "hybrid", 8, tmp_path)
    assert r["mode"] == "fmu" and r["steps"] == 256
    assert r["differ"] == [] and r["it_fmu"] == r["it_in"]


#: steps of each other registered model (fd: a Reynolds solve per evaluation, a few steps)
STEPS = {"linear": 64, "lumped": 64, "short": 64, "fd": 6}


def test_every_registered_model_is_run():
    assert sorted([*STEPS, "hybrid"]) == sorted(MODELS)


@pytest.mark.parametrize("model", sorted(STEPS))
def test_every_bearing_model_runs_coupled_through_fmus(fmu_dir, tmp_path, model):
    """Each registered model through its FMU, coupled with the gear-shaft FMU by the master,
    gives the in-process run of the same model bit for bit (the same iterations too)."""
    r = compare(fmu_dir, model, 2, tmp_path, steps=STEPS[model])
    assert r["mode"] == "fmu" and r["steps"] == STEPS[model]
    assert r["differ"] == [] and r["it_fmu"] == r["it_in"]
    if model in ("linear", "lumped"):  # affine laws: the master converges in one pass
        assert r["it_fmu"] == 1.0


def test_swapping_the_bearing_fmu_is_a_file_name(fmu_dir):
    """The bearing set of a case differs between models only by the FMU file it loads."""
    r = run_isolated(module="tests.probes.fmu_run",
                     args=["bearing_fmu_files", {"fmu_dir": fmu_dir}])
    assert r == {"hybrid": ["BearingHybrid.fmu"], "lumped": ["BearingLumped.fmu"]}


#: drivetrain, damping and time-integration settings reach the gear-shaft FMU as parameters
#: (inertias, String choices, Boolean flags): each through FMUs equals in-process bit for bit
SETTINGS = {
    "motor and load behind couplings, Rayleigh damping": {
        "drive.motor_inertia": 0.5, "drive.motor_coupling_stiffness": 1e4,
        "drive.motor_coupling_damping": 5.0, "drive.output_end": "load",
        "drive.load_inertia": 5.0, "drive.load_coupling_stiffness": 1e5,
        "simulation.damping_model": "rayleigh",
        "simulation.rayleigh_frequencies": [1000.0, 5000.0]},
    "rigid motor, structure basis, mesh damping, refinements off": {
        "drive.motor_inertia": 0.05, "simulation.damping_basis": "structure",
        "simulation.mesh_damping_ratio": 0.05, "simulation.consistent_start": False,
        "simulation.locate_contact": False, "gears.pinion.polar_inertia": 0.004,
        "gears.gear.polar_inertia": 4.6},
}


@pytest.mark.parametrize("name", sorted(SETTINGS))
def test_drivetrain_and_damping_settings_through_fmus(fmu_dir, tmp_path, name):
    r = compare(fmu_dir, "lumped", 2, tmp_path, steps=64, overrides=SETTINGS[name])
    assert r["mode"] == "fmu" and r["steps"] == 64
    assert r["differ"] == []
