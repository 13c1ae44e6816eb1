"""Gear-shaft FMU: built by pythonfmu, valid for fmpy, equal to the in-process structure.

The FMU loads in the test's process (as in test_bearing_fmus.py; ``fmpy simulate`` runs it in a
fresh host process that must exit cleanly). The FMU is driven through
:class:`orchestrator.coupling.fmi.FmuStructure` and compared with the in-process structure of the
same case (:class:`orchestrator.coupling.inprocess.InProcessStructure`) driven with the same
laws (:mod:`tests.probes.gear_fmu`): the FMU runs the same code on the same numbers, so the
results agree bit for bit.
"""

import math
import subprocess
import sys

import numpy as np
import pytest

from fmu_src.contract import gear_variables
from tests.helpers import run_here

CASE = "baguet2010_spur"

PROBES = "tests.probes.gear_fmu"


@pytest.fixture(scope="module")
def gear_fmu(fmu_dir):
    return fmu_dir / "GearShaft.fmu"


def test_gear_fmu_passes_fmpy_validation_with_units_and_descriptions(gear_fmu):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(gear_fmu)) == []
    md = read_model_description(str(gear_fmu))
    variables = {v.name: v for v in md.modelVariables}
    assert [v.name for v in md.modelVariables] == [v.name for v in gear_variables()]
    assert all(v.description for v in md.modelVariables)
    for v in gear_variables():
        if v.type == "Real":
            assert variables[v.name].unit == v.unit, v.name
    # the carried case's fields are parameters, with the bounds the case schema declares
    teeth = variables["gears.pinion.teeth"]
    assert teeth.type == "Integer" and teeth.start == "26" and teeth.min == "5"
    module = variables["gears.pinion.module"]  # > 0: the least accepted is the next double
    assert variables["shafts.gear_shaft.outer_diameter[1]"].start == "0.09"
    assert variables["bearings.'3'.position"].start == "0"
    assert module.min == "5e-324" and module.unit == "m" and module.description.endswith("(> 0)")
    assert variables["rotation_sign_3"].causality == "calculatedParameter"
    assert variables["K_st_3"].unit == "N/m" and variables["C_tt_4"].unit == "N.s/m"
    assert variables["s_dot_2"].unit == "m/s" and variables["mesh_force"].unit == "N"
    assert variables["support_load_t_4"].causality == "calculatedParameter"
    # no direct feedthrough: outputs change at doStep only
    assert all(not u.dependencies for u in md.outputs)
    assert md.coSimulation.canGetAndSetFMUstate
    assert md.defaultExperiment.stepSize is not None


def test_slave_registers_exactly_the_contract():
    """The slave class (no FMI layer) exposes the contract's variables in its order."""
    from fmu_src.slaves.gear_shaft import GearShaftSlave

    slave = GearShaftSlave(instance_name="t")
    names = [(v.name, v.causality.name) for v in slave.vars.values()]
    assert names == [(v.name, v.causality) for v in gear_variables()]


def test_a_case_that_does_not_fit_is_logged_not_raised():
    """Parameters each within bounds but not fitting together (the addendum of Table 1 read
    literally: the tips touch the mating root circle): the getters never raise into
    pythonfmu; NaN outputs with the read's status fmi2Error, the reason in the log, and doStep
    discards."""
    from fmu_src.slaves.gear_shaft import GearShaftSlave

    slave = GearShaftSlave(instance_name="t")
    slave._fmi_status_protocol = True  # as the patched library sets it
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    assert slave.set_real([vr["gears.pinion.addendum_coefficient"],
                           vr["gears.gear.addendum_coefficient"]], [1.4, 1.4]) is None
    values, status = slave.get_real([vr["s_1"], vr["mesh_force"]])
    assert status == 3 and all(math.isnan(x) for x in values)
    values, status = slave.get_real([vr["support_load_s_1"]])
    assert status == 3 and math.isnan(values[0])
    slave.exit_initialization_mode()
    assert slave.do_step(0.0, 1e-5) is False
    text = " | ".join(m.msg for m in slave.log_queue)
    assert "meshes.mesh (gears pinion and gear: centre_distance" in text
    assert "the pinion tips touch the gear's root circle" in text
    assert "not stepping after an earlier failure" in text


def test_bad_values_are_refused_by_the_call_that_sets_them(gear_fmu):
    """FMI 2.0 through fmpy: fmi2SetReal/SetInteger of a value out of its declared bounds or
    not finite returns fmi2Error (fmpy raises), the log names the variable, the value and the
    limit, and the variable keeps its value; the 56 law inputs set in one call likewise."""
    out = run_here(module=PROBES, args=["refuse_bad_values", {"fmu": gear_fmu}])
    assert out["module"][0] == 3
    assert "gears.pinion.module = -0.004 m refused: must be > 0 m" in out["module"][1]
    assert out["teeth"][0] == 3
    assert "gears.gear.teeth = 3 refused: must be >= 5" in out["teeth"][1]
    assert out["law"][0] == 3 and "K_ss_2 = nan N/m refused: not a finite number" in out["law"][1]
    assert out["module_kept"] == 0.004 and out["teeth_kept"] == 157
    assert "setting the bearing laws (status error)" in out["laws"]
    assert "C_st_3 is not a finite number" in out["laws"]


@pytest.fixture(scope="module")
def comparison(gear_fmu):
    """The FMU and the in-process structure driven side by side.

    Static solutions, 50 Newmark steps with alternating laws, the outputs, a rollback, a
    serialised state, then a second instance coupled by the master with short-bearing models.
    """
    return run_here(module=PROBES, args=["comparison", {"fmu": gear_fmu, "case": CASE}])


def test_fmu_static_solution_equals_in_process(comparison):
    assert comparison["support"] == 0.0
    assert comparison["static"] == 0.0 and comparison["static_mesh"] == 0.0
    its = comparison["static_iterations"]
    assert its[0] == its[1]


def test_fmu_newmark_steps_equal_in_process(comparison):
    assert comparison["steps"] == 0.0 and comparison["outputs"] == 0.0
    assert comparison["moved"] > 1e-6  # the journals really move (unbalance): not trivial


def test_fmu_state_round_trip_is_exact(comparison):
    assert comparison["restored"] and comparison["replayed"] and comparison["deserialised"]
    assert comparison["live_states"] == 0  # FmuState objects free their FMU copy


def test_master_through_the_fmu_equals_master_in_process(comparison):
    assert comparison["master"] == 0.0
    its = comparison["master_iterations"]
    assert its[0] == its[1] and max(its[0]) >= 2  # rollbacks (set_state) happened



@pytest.mark.parametrize("case", [CASE, "baguet2010_helical"])
def test_the_laws_and_journals_are_served_without_python_with_the_same_bits(gear_fmu, case):
    """The patched library serves the master's set of the 56 law inputs (while stepping) and
    its read of the 16 journal outputs (those of the current state) from the slave's buffer;
    what it does not serve reaches the slave's Python, whose calls are counted. Along the way
    the journals equal the in-process structure's bit for bit (the spur case the FMU carries,
    and the helical one set through its parameters)."""
    out = run_here(module=PROBES, args=["native_io", {"fmu": gear_fmu, "case": case}])
    assert len(out["same"]) == 2 + 12 + 3 + 1 + 3 + 1 + 1 + 2 + 4 and all(out["same"])
    calls = out["calls"]
    # initialisation: each set makes the static solution stale, each solve reads in Python;
    # the second read of a solution is the library's
    assert calls["initialisation"] == {"set_real": 2, "get_real": 2}
    # stepping: none, through steps, a restored state and the steps after it
    assert calls["steps"] == {"set_real": 0, "get_real": 0}
    assert calls["restored"] == {"set_real": 0, "get_real": 0}
    # laws with a NaN go to the slave, which refuses them (none applied: the step after it
    # takes the laws set before)
    assert calls["nan"] == {"set_real": 1, "get_real": 0}
    assert "C_ts_2 is not a finite number (no input applied)" in out["nan"]
    # after a failed step the journals read fmi2Error in Python, until a state is restored
    assert calls["failure"] == {"set_real": 0, "get_real": 1}
    assert "reading the journal states (status error)" in out["after_failure"]
    # fmi2Reset makes a new slave: the library serves it as the first
    assert calls["after_reset"] == {"set_real": 2, "get_real": 2}

def test_a_checked_case_reaches_the_fmu_unchanged(tmp_path):
    """Case.to_toml: a Case with overrides written as a case file reloads to the same values."""
    from fmu_src.case import load_case

    case = load_case(CASE).with_overrides({"drive.torque": "150 N.m",
                                           "drive.gravity": [0.0, -9.81],
                                           "case.description": 'quote " and backslash \\'})
    path = tmp_path / "case.toml"
    path.write_text(case.to_toml())
    assert load_case(path).values == case.values


def test_ensure_fmus_builds_missing_fmus_once(tmp_path):
    from orchestrator.coupling.fmi import ensure_fmus

    path = ensure_fmus(["GearShaft"], tmp_path)["GearShaft"]
    stamp = path.stat().st_mtime_ns
    assert ensure_fmus(["GearShaft"], tmp_path)["GearShaft"].stat().st_mtime_ns == stamp
    with pytest.raises(ValueError, match="unknown FMU 'Nope'"):
        ensure_fmus(["Nope"], tmp_path)


def test_failures_are_reported_and_the_process_survives(gear_fmu):
    out = run_here(module=PROBES, args=["failures", {"fmu": gear_fmu}])
    m = out["msgs"]
    assert "static solution failed" in m["static"] and "did not converge" in m["static"]
    assert "doStep 2 from t = 2.3e-05 s" in m["newton"] and "(status discard)" in m["newton"]
    assert "NewmarkConvergenceError: Newmark step 2" in m["newton"]
    assert "but the structure is at t = 2.3e-05 s" in m["time"]
    assert out["same"] and out["n"] == 2


def test_fmpy_simulate_from_a_fresh_process(gear_fmu, tmp_path):
    """``fmpy simulate`` runs the FMU stand-alone (the shipped paper case, start values)."""
    out = tmp_path / "out.csv"
    proc = subprocess.run(
        [sys.executable, "-m", "fmpy", "simulate", str(gear_fmu), "--stop-time", "2.4e-4",
         "--output-interval", "2.4e-5", "--output-file", str(out)],
        capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, f"exit code {proc.returncode}: {proc.stderr[-2000:]}"
    lines = out.read_text().splitlines()
    header = lines[0].replace('"', "").split(",")
    assert "s_1" in header and "mesh_force" in header and "transmission_error" in header
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    assert len(rows) == 11
    force = np.array([r[header.index("mesh_force")] for r in rows])
    # the static tooth load T / r_b1 of the shipped case (independent of the FMU), plus the
    # dynamic part over 10 steps from the static solution: measured within 1.97 %, margin 1.5
    from fmu_src.examples import paper_gear_pair

    pair = paper_gear_pair()
    w0 = 220.0 / (pair.base_radius[0] * math.cos(pair.base_helix_angle))
    print(f"\nfmpy simulate: mesh force / (T / r_b1) - 1 within "
          f"{np.abs(force / w0 - 1).max():.2e}")
    assert np.abs(force / w0 - 1).max() < 3e-2
