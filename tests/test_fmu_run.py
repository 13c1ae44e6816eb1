"""The paper's case run through real FMUs (gear-shaft FMU + four bearing FMUs, fmpy) against the
in-process master, which tests/test_run.py checks against a monolithic Newton-Raphson.

Each configuration runs in a fresh interpreter that exits normally (the way a user's host runs
the FMUs; see test_bearing_fmus.py for why).
"""

import pytest

from bearing_fmu import MODELS
from tests.helpers import run_isolated


def compare(fmu_dir, model, periods, tmp, steps=None, overrides=None):
    return run_isolated(f"""
        import json
        import numpy as np
        from fmu_src.case import load_case
        from orchestrator.results import read_results
        from orchestrator.run import run_case
        case = load_case("baguet2010_spur", {overrides or {}!r})
        out = {{}}
        for in_process in (True, False):
            s = run_case(case, bearing={model!r}, periods={periods}, in_process=in_process,
                         out_dir={str(tmp)!r}, fmu_dir={str(fmu_dir)!r}, progress=False,
                         figures=False, steps={steps!r})
            r = read_results(s.results)
            out[in_process] = (r["journal_position"], r["journal_velocity"],
                               r["bearing_force"], s.iterations_per_step, r["attrs"]["mode"])
        def rel(k):
            return float(np.abs(out[False][k] - out[True][k]).max()
                         / np.abs(out[True][k]).max())
        print(json.dumps({{
            "position": rel(0), "velocity": rel(1), "force": rel(2),
            "it_in": out[True][3], "it_fmu": out[False][3], "mode": out[False][4],
            "steps": len(out[True][0])}}))
    """)


def test_fmu_cosimulation_equals_the_in_process_master(fmu_dir, tmp_path):
    """256 steps of the paper's case with hybrid bearings: the FMUs and the in-process slaves
    run the same code on the same numbers; they differ only through the FMU's first guess of
    X0 (another sequence of warm starts of the hybrid solver). Measured: positions 1.2e-12,
    velocities 1.0e-10, force 3.4e-11; asserted with a margin of 3, far inside the coupling
    tolerance 1e-5."""
    r = compare(fmu_dir, "hybrid", 8, tmp_path)
    print(f"\nFMUs vs in-process, 256 steps: positions {r['position']:.1e}, velocities "
          f"{r['velocity']:.1e}, force {r['force']:.1e} (relative); {r['it_fmu']:.2f} vs "
          f"{r['it_in']:.2f} iterations per step")
    assert r["mode"] == "fmu" and r["steps"] == 256
    assert r["position"] < 4e-12 and r["velocity"] < 3e-10 and r["force"] < 1e-10
    assert r["it_fmu"] == r["it_in"]


#: every registered model through FMUs: steps run, and the agreement measured (positions,
#: velocities, relative) with the cause of any difference; asserted with a margin of 3.
#: hybrid runs in the test above; fd (a Reynolds solve per evaluation) for a few steps only.
AGREEMENT = {
    # its coefficients come from the hybrid film at X0, reached by another sequence of warm
    # starts of the hybrid solver (the FMU transport's first guess of X0)
    "linear": (64, 1.5e-12, 7.7e-11),
    # exactly the same numbers
    "lumped": (64, 0.0, 0.0),
    # no warm start, but the FMU transport's first guess of X0 (a Newton through the FMU)
    # starts the static iteration elsewhere: the same X0 to round-off
    "short": (64, 9.2e-13, 5.5e-11),
    # both: the FD solver's warm start (its last pressure field) and the first guess of X0
    "fd": (6, 6.7e-14, 7.2e-11),
}


def test_the_agreement_table_covers_every_registered_model():
    assert sorted([*AGREEMENT, "hybrid"]) == sorted(MODELS)


@pytest.mark.parametrize("model", sorted(AGREEMENT))
def test_every_bearing_model_runs_coupled_through_fmus(fmu_dir, tmp_path, model):
    """Each registered model through its FMU, coupled with the gear-shaft FMU by the master,
    equals the in-process run of the same model (same iterations, same trajectories)."""
    steps, position, velocity = AGREEMENT[model]
    r = compare(fmu_dir, model, 2, tmp_path, steps=steps)
    print(f"\n{model}: FMUs vs in-process, {r['steps']} steps: positions {r['position']:.1e}, "
          f"velocities {r['velocity']:.1e}; {r['it_fmu']:.2f} vs {r['it_in']:.2f} iterations "
          "per step")
    assert r["mode"] == "fmu" and r["steps"] == steps
    assert r["it_fmu"] == r["it_in"]
    if model in ("linear", "lumped"):  # affine laws: the master converges in one pass
        assert r["it_fmu"] == 1.0
    assert r["position"] <= 3 * position and r["velocity"] <= 3 * velocity


def test_swapping_the_bearing_fmu_is_a_file_name(fmu_dir):
    """The bearing set of a case differs between models only by the FMU file it loads."""
    r = run_isolated(f"""
        import json
        from fmu_src.case import load_case
        from orchestrator.fmi import system_from_case
        case = load_case("baguet2010_spur")
        out = {{}}
        for model in ("hybrid", "lumped"):
            st, b = system_from_case(case, model, {str(fmu_dir)!r})
            out[model] = sorted({{s.path.name for s in b.slaves}})
            b.close(); st.close()
        print(json.dumps(out))
    """)
    assert r == {"hybrid": ["BearingHybrid.fmu"], "lumped": ["BearingLumped.fmu"]}


#: drivetrain, damping and time-integration settings reach the gear-shaft FMU as parameters
#: (inertias, String choices, Boolean flags): each through FMUs equals in-process exactly with
#: the lumped bearings (the same numbers on both sides, measured 0.0)
SETTINGS = {
    "motor and load behind couplings, Rayleigh damping": {
        "drivetrain.motor_inertia": 0.5, "drivetrain.motor_coupling_stiffness": 1e4,
        "drivetrain.motor_coupling_damping": 5.0, "drivetrain.output_end": "load",
        "drivetrain.load_inertia": 5.0, "drivetrain.load_coupling_stiffness": 1e5,
        "simulation.damping_model": "rayleigh",
        "simulation.rayleigh_frequencies": [1000.0, 5000.0]},
    "rigid motor, structure basis, mesh damping, refinements off": {
        "drivetrain.motor_inertia": 0.05, "simulation.damping_basis": "structure",
        "simulation.mesh_damping_ratio": 0.05, "simulation.consistent_start": False,
        "simulation.locate_contact": False, "gear_pair.polar_inertia": [0.004, 4.6]},
}


@pytest.mark.parametrize("name", sorted(SETTINGS))
def test_drivetrain_and_damping_settings_through_fmus(fmu_dir, tmp_path, name):
    r = compare(fmu_dir, "lumped", 2, tmp_path, steps=64, overrides=SETTINGS[name])
    print(f"\n{name}: FMUs vs in-process, {r['steps']} steps: positions {r['position']:.1e}, "
          f"velocities {r['velocity']:.1e}")
    assert r["mode"] == "fmu" and r["steps"] == 64
    assert r["position"] == 0.0 and r["velocity"] == 0.0
