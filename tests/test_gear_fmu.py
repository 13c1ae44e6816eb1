"""Gear-shaft FMU: built by pythonfmu, valid for fmpy, equal to the in-process structure.

The FMU loads in the test's process (as in test_bearing_fmus.py; ``fmpy simulate`` runs it in a
fresh host process that must exit cleanly). The FMU is driven
through :class:`orchestrator.coupling.fmi.FmuStructure` and compared with the in-process structure
of
the same case (:class:`orchestrator.coupling.inprocess.InProcessStructure`) driven with the same
laws:
the FMU runs the same code on the same numbers, so the results agree bit for bit.
"""

import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from fmu_src.contract import GEAR_VARIABLES
from tests.helpers import run_here

CASE = "baguet2010_spur"

# laws used by the comparisons: anisotropic, cross-coupled, non-zero F0 (as text, run before each
# comparison's code)
LAWS = """
import numpy as np
from bearing_fmu.affine import AffineLaws
rng = np.random.default_rng(7)
kb = np.array([[2e8, 3e7], [-2e7, 1.5e8]]) * (1 + 0.1 * rng.random((4, 1, 1)))
cb = np.array([[2e4, 1e3], [1e3, 3e4]]) * (1 + 0.1 * rng.random((4, 1, 1)))
f0 = rng.normal(0.0, 300.0, (4, 2))
LAW_A = AffineLaws(f0, kb, cb)
LAW_B = AffineLaws(1.1 * f0, 0.9 * kb, 1.2 * cb)
def rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))
"""


@pytest.fixture(scope="module")
def gear_fmu(fmu_dir):
    return fmu_dir / "GearShaft.fmu"


def run_isolated(code: str) -> dict:
    """Run ``code`` after the laws' definitions (:func:`tests.helpers.run_here`)."""
    return run_here(textwrap.dedent(LAWS) + textwrap.dedent(code))


def test_gear_fmu_passes_fmpy_validation_with_units_and_descriptions(gear_fmu):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(gear_fmu)) == []
    md = read_model_description(str(gear_fmu))
    variables = {v.name: v for v in md.modelVariables}
    assert [v.name for v in md.modelVariables] == [v.name for v in GEAR_VARIABLES]
    assert all(v.description for v in md.modelVariables)
    for v in GEAR_VARIABLES:
        if v.type == "Real":
            assert variables[v.name].unit == v.unit, v.name
    # the carried case's fields are parameters, with the bounds the case schema declares
    teeth = variables["gear_pair.teeth[1]"]
    assert teeth.type == "Integer" and teeth.start == "26" and teeth.min == "5"
    assert variables["gear_pair.module"].min == "0.0" and variables["gear_pair.module"].unit == "m"
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
    assert names == [(v.name, v.causality) for v in GEAR_VARIABLES]


def test_a_case_that_does_not_fit_is_logged_not_raised():
    """Parameters each within bounds but not fitting together (the addendum of Table 1 read
    literally: the tips touch the mating root circle): the getters never raise into
    pythonfmu; NaN outputs with the read's status fmi2Error, the reason in the log, and doStep
    discards."""
    from fmu_src.slaves.gear_shaft import GearShaftSlave

    slave = GearShaftSlave(instance_name="t")
    slave._fmi_status_protocol = True  # as the patched library sets it
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    assert slave.set_real([vr["gear_pair.addendum_coefficient"]], [1.4]) is None
    values, status = slave.get_real([vr["s_1"], vr["mesh_force"]])
    assert status == 3 and all(math.isnan(x) for x in values)
    values, status = slave.get_real([vr["support_load_s_1"]])
    assert status == 3 and math.isnan(values[0])
    slave.exit_initialization_mode()
    assert slave.do_step(0.0, 1e-5) is False
    text = " | ".join(m.msg for m in slave.log_queue)
    assert "gear_pair (centre_distance" in text
    assert "the pinion tips touch the gear's root circle" in text
    assert "not stepping after an earlier failure" in text


def test_bad_values_are_refused_by_the_call_that_sets_them(gear_fmu):
    """FMI 2.0 through fmpy: fmi2SetReal/SetInteger of a value out of its declared bounds or
    not finite returns fmi2Error (fmpy raises), the log names the variable, the value and the
    limit, and the variable keeps its value; the 56 law inputs set in one call likewise."""
    out = run_isolated(f"""
        import json, math
        from fmpy.fmi1 import FMICallException
        from orchestrator.coupling.fmi import FmuError, FmuStructure
        fmu = FmuStructure(r"{gear_fmu}")
        s, vr = fmu.slave, fmu.slave.vr
        r = {{}}
        def attempt(key, call):
            since = len(s.messages)
            try:
                call()
                r[key] = "accepted"
            except FMICallException as exc:
                r[key] = [exc.status, s.log_tail(since=since)]
        attempt("module", lambda: s.fmu.setReal([vr["gear_pair.module"]], [-0.004]))
        attempt("teeth", lambda: s.fmu.setInteger([vr["gear_pair.teeth[2]"]], [3]))
        attempt("law", lambda: s.fmu.setReal([vr["K_ss_2"]], [math.nan]))
        r["module_kept"] = s.fmu.getReal([vr["gear_pair.module"]])[0]
        r["teeth_kept"] = s.fmu.getInteger([vr["gear_pair.teeth[2]"]])[0]
        bad = AffineLaws(LAW_A.f0, LAW_A.kb, LAW_A.cb.copy())
        bad.cb[2, 0, 1] = float("nan")
        try:
            fmu.set_bearing_laws(bad)
        except FmuError as exc:
            r["laws"] = str(exc)
        fmu.set_bearing_laws(LAW_A)
        fmu.solve_static()  # the instance still works
        fmu.close()
        print(json.dumps(r))
    """)
    assert out["module"][0] == 3
    assert "gear_pair.module = -0.004 m refused: must be > 0 m" in out["module"][1]
    assert out["teeth"][0] == 3
    assert "gear_pair.teeth[2] = 3 refused: must be >= 5" in out["teeth"][1]
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
    return run_isolated(f"""
        import json
        from fmu_src import description
        from fmu_src.case import load_case
        from orchestrator.coupling.fmi import FmuStructure
        from orchestrator.coupling.inprocess import InProcessStructure, ModelBearings
        from orchestrator.coupling.master import Master
        case = load_case({CASE!r})
        ref = InProcessStructure(description.structure(case))
        fmu = FmuStructure(r"{gear_fmu}")
        r = {{}}
        r["support"] = rel(fmu.support_loads(), ref.support_loads())
        # static iterations as the master does them: two law sets in initialisation mode
        for law in (LAW_B, LAW_A):
            ref.set_bearing_laws(law); ref.solve_static()
            fmu.set_bearing_laws(law); fmu.solve_static()
        r["static"] = rel(fmu.journal_states(), ref.journal_states())
        r["static_mesh"] = rel(fmu.mesh_force(), ref.mesh_force())
        r["static_iterations"] = [fmu.iterations(),
                                  ref.structure.static(LAW_A.f0, LAW_A.kb).iterations]
        # the master's last laws (linearised at X0) set without a new solve, then the transient
        ref.set_bearing_laws(LAW_B); fmu.set_bearing_laws(LAW_B)
        ref.exit_initialization(); fmu.exit_initialization()
        dt = ref.structure.mesh_period / 32
        t, worst = 0.0, 0.0
        for k in range(50):
            law = LAW_A if k % 2 else LAW_B
            ref.set_bearing_laws(law); fmu.set_bearing_laws(law)
            ref.do_step(t, dt); fmu.do_step(t, dt); t += dt
            worst = max(worst, rel(fmu.journal_states(), ref.journal_states()))
        r["steps"] = worst
        o = fmu.outputs()
        r["outputs"] = max(rel(o["mesh_force"], ref.mesh_force()),
                           rel(o["transmission_error"], ref.transmission_error()),
                           rel(fmu.gear_displacements(), ref.gear_displacements()),
                           rel(fmu.transmission_error(), ref.transmission_error()))
        r["moved"] = float(abs(fmu.journal_states()[:, 2:]).max())
        # rollback: save, 5 steps, restore, the same 5 steps again
        saved, rsaved = fmu.get_state(), ref.get_state()
        x50 = fmu.journal_states()
        for k in range(5):
            fmu.do_step(t + k * dt, dt); ref.do_step(t + k * dt, dt)
        x55 = fmu.journal_states()
        fmu.set_state(saved); ref.set_state(rsaved)
        r["restored"] = bool((fmu.journal_states() == x50).all()) and fmu.n_steps == 50
        for k in range(5):
            fmu.do_step(t + k * dt, dt)
        r["replayed"] = bool((fmu.journal_states() == x55).all())
        # serialised states (numeric arrays, fmu_src.state_codec) restore exactly too
        f = fmu.slave.fmu
        blob = f.serializeFMUstate(saved._handle)
        back = f.deSerializeFMUstate(blob)
        f.setFMUstate(back)
        r["deserialised"] = bool((fmu.journal_states() == x50).all())
        f.freeFMUstate(back)
        del saved
        r["live_states"] = len(fmu._states)
        fmu.close()
        # the master's coupled static solution and steps, in process and through the FMU
        states, its = [], []
        for slave in (InProcessStructure(description.structure(case)),
                      FmuStructure(r"{gear_fmu}", case=case)):
            bearings = ModelBearings(description.bearing_models(case, "short"),
                                     description.BEARING_FRAMES, description.bearing_speeds(case))
            m = Master(slave, bearings)
            m.solve_static()
            m.exit_initialization()
            its.append([m.step(k * dt, dt).iterations for k in range(8)])
            states.append(slave.journal_states())
        r["master"] = rel(states[1], states[0])
        r["master_iterations"] = its
        print(json.dumps(r))
    """)


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


def test_a_checked_case_reaches_the_fmu_unchanged(tmp_path):
    """Case.to_toml: a Case with overrides written as a case file reloads to the same values."""
    from fmu_src.case import load_case

    case = load_case(CASE).with_overrides({"operation.torque": "150 N.m",
                                           "operation.gravity": True,
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
    out = run_isolated(f"""
        import json
        import numpy as np
        from orchestrator.coupling.fmi import FmuError, FmuStructure
        fmu = FmuStructure(r"{gear_fmu}")
        msgs = {{}}
        # static solution that does not converge (almost no bearing stiffness)
        fmu.set_bearing_laws(AffineLaws(LAW_A.f0, 1e-12 * LAW_A.kb, LAW_A.cb))
        try:
            fmu.solve_static()
        except FmuError as exc:
            msgs["static"] = str(exc)
        fmu.set_bearing_laws(LAW_A)
        fmu.solve_static()  # the instance still works
        fmu.exit_initialization()
        dt = 2.3e-5
        fmu.do_step(0.0, dt)
        saved = fmu.get_state()
        x1 = fmu.journal_states()
        # absurd law: Newton diverges (non-finite residuals) -> NewmarkConvergenceError inside
        fmu.set_bearing_laws(AffineLaws(np.full((4, 2), 1e300), LAW_A.kb, LAW_A.cb))
        try:
            fmu.do_step(dt, dt)
        except FmuError as exc:
            msgs["newton"] = str(exc)
        # wrong time
        fmu.set_bearing_laws(LAW_A)
        try:
            fmu.do_step(5 * dt, dt)
        except FmuError as exc:
            msgs["time"] = str(exc)
        # back to the saved state: stepping works again
        fmu.set_state(saved)
        same = bool((fmu.journal_states() == x1).all())
        fmu.do_step(dt, dt)
        fmu.close()
        print(json.dumps(dict(msgs=msgs, same=same, n=fmu.n_steps)))
    """)
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
