"""Probes of tests/fmu_src/test_gear_fmu.py: the gear-shaft FMU driven through
:class:`orchestrator.coupling.fmi.FmuStructure` beside the in-process structure, with the same
bearing laws (run in the test's process)."""

from __future__ import annotations

import contextlib
import math

import numpy as np

from tests.probes import counted_calls, dispatch, probes_of


def laws(nb: int = 4):
    """Two sets of affine laws of ``nb`` bearings (anisotropic, cross-coupled, non-zero F0):
    ``(LAW_A, LAW_B)``."""
    from bearing_fmu.affine import AffineLaws

    rng = np.random.default_rng(7)
    kb = np.array([[2e8, 3e7], [-2e7, 1.5e8]]) * (1 + 0.1 * rng.random((nb, 1, 1)))
    cb = np.array([[2e4, 1e3], [1e3, 3e4]]) * (1 + 0.1 * rng.random((nb, 1, 1)))
    f0 = rng.normal(0.0, 300.0, (nb, 2))
    return AffineLaws(f0, kb, cb), AffineLaws(1.1 * f0, 0.9 * kb, 1.2 * cb)


def _case(case: str):
    from fmu_src.case import load_case

    return load_case(case)


def rel(a, b) -> float:
    """Largest |a - b| relative to the largest |b|."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def refuse_bad_values(fmu: str) -> dict:
    """Out-of-bounds and non-finite values set through fmpy, and laws with a NaN: per value,
    the call's status and the log since, or "accepted"; the values kept; the laws' error."""
    from fmpy.fmi1 import FMICallException

    from bearing_fmu.affine import AffineLaws
    from orchestrator.coupling.fmi import FmuError, FmuStructure

    law_a, _ = laws()
    structure = FmuStructure(fmu)
    s, vr = structure.slave, structure.slave.vr
    r = {}

    def attempt(key, call):
        since = len(s.messages)
        try:
            call()
            r[key] = "accepted"
        except FMICallException as exc:
            r[key] = [exc.status, s.log_tail(since=since)]

    attempt("module", lambda: s.fmu.setReal([vr["gears.pinion.module"]], [-0.004]))
    attempt("teeth", lambda: s.fmu.setInteger([vr["gears.gear.teeth"]], [3]))
    attempt("law", lambda: s.fmu.setReal([vr["K_ss_2"]], [math.nan]))
    r["module_kept"] = s.fmu.getReal([vr["gears.pinion.module"]])[0]
    r["teeth_kept"] = s.fmu.getInteger([vr["gears.gear.teeth"]])[0]
    bad = AffineLaws(law_a.f0, law_a.kb, law_a.cb.copy())
    bad.cb[2, 0, 1] = float("nan")
    try:
        structure.set_bearing_laws(bad)
    except FmuError as exc:
        r["laws"] = str(exc)
    structure.set_bearing_laws(law_a)
    structure.solve_static()  # the instance still works
    structure.close()
    return r


def comparison(fmu: str, case: str) -> dict:
    """The FMU and the in-process structure driven side by side: static solutions, 50 Newmark
    steps with alternating laws, the outputs, a rollback, a serialised state, then a second
    instance coupled by the master with short-bearing models. Relative differences and
    flags."""
    from fmu_src import description
    from orchestrator.coupling.fmi import FmuStructure
    from orchestrator.coupling.inprocess import InProcessStructure, ModelBearings
    from orchestrator.coupling.master import Master
    from orchestrator.coupling.step import CoupledSteps

    case = _case(case)
    ref = InProcessStructure(description.structure(case))
    law_a, law_b = laws(ref.n_bearings)
    structure = FmuStructure(fmu)  # the case it carries
    r = {}
    r["support"] = rel(structure.support_loads(), ref.support_loads())
    # static iterations as the master does them: two law sets in initialisation mode
    for law in (law_b, law_a):
        ref.set_bearing_laws(law)
        ref.solve_static()
        structure.set_bearing_laws(law)
        structure.solve_static()
    r["static"] = rel(structure.journal_states(), ref.journal_states())
    r["static_mesh"] = max(rel(a, b) for a, b in zip(structure.step_outputs(),
                                                     ref.step_outputs(), strict=True))
    r["static_iterations"] = [structure.iterations(),
                              ref.structure.static(law_a.f0, law_a.kb).iterations]
    # the master's last laws (linearised at X0) set without a new solve, then the transient
    ref.set_bearing_laws(law_b)
    structure.set_bearing_laws(law_b)
    ref.exit_initialization()
    structure.exit_initialization()
    dt = ref.structure.mesh_period / 32
    t, worst = 0.0, 0.0
    for k in range(50):
        law = law_a if k % 2 else law_b
        ref.set_bearing_laws(law)
        structure.set_bearing_laws(law)
        ref.do_step(t, dt)
        structure.do_step(t, dt)
        t += dt
        worst = max(worst, rel(structure.journal_states(), ref.journal_states()))
    r["steps"] = worst
    forces, errors, nodes = ref.step_outputs()
    o = structure.outputs()
    r["outputs"] = max(rel([o[f"mesh_force_{m}"] for m in structure.mesh_names], forces),
                       rel([o[f"transmission_error_{m}"] for m in structure.mesh_names], errors),
                       rel(structure.gear_displacements(), nodes),
                       rel(structure.transmission_errors(), errors),
                       rel(structure.mesh_forces(), forces))
    r["output_shapes"] = [list(np.shape(a)) for a in structure.step_outputs()]
    r["moved"] = float(abs(structure.journal_states()[:, 2:]).max())
    # rollback: save, 5 steps, restore, the same 5 steps again
    saved, rsaved = structure.get_state(), ref.get_state()
    x50 = structure.journal_states()
    for k in range(5):
        structure.do_step(t + k * dt, dt)
        ref.do_step(t + k * dt, dt)
    x55 = structure.journal_states()
    structure.set_state(saved)
    ref.set_state(rsaved)
    r["restored"] = bool((structure.journal_states() == x50).all()) and structure.n_steps == 50
    for k in range(5):
        structure.do_step(t + k * dt, dt)
    r["replayed"] = bool((structure.journal_states() == x55).all())
    # serialised states (numeric arrays, fmu_src.state_codec) restore exactly too
    f = structure.slave.fmu
    blob = f.serializeFMUstate(saved._handle)
    back = f.deSerializeFMUstate(blob)
    f.setFMUstate(back)
    r["deserialised"] = bool((structure.journal_states() == x50).all())
    f.freeFMUstate(back)
    del saved
    r["live_states"] = len(structure._states)
    structure.close()
    # the master's coupled static solution and steps, in process and through the FMU
    states, its = [], []
    for slave in (InProcessStructure(description.structure(case)),
                  FmuStructure(fmu, case=case)):
        short = case.with_overrides({"bearings.*.model": "short"})
        bearings = ModelBearings(description.bearing_models(short),
                                 description.bearing_frames(case),
                                 description.bearing_speeds(case))
        m = Master(slave, bearings, stepper=CoupledSteps(slave, bearings))
        m.solve_static()
        m.exit_initialization()
        its.append([m.step(k * dt, dt).iterations for k in range(8)])
        states.append(slave.journal_states())
        m.close()
    r["master"] = rel(states[1], states[0])
    r["master_iterations"] = its
    return r


def failures(fmu: str) -> dict:
    """A static solution that does not converge, a Newton that diverges, a step at the wrong
    time (from the state saved before: a failed step leaves the structure at no computed state,
    and the FMU refuses to step on from it): the messages; then the saved state restored, and a
    step."""
    from bearing_fmu.affine import AffineLaws
    from orchestrator.coupling.fmi import FmuError, FmuStructure

    structure = FmuStructure(fmu)
    law_a, _ = laws(structure.n_bearings)
    msgs = {}
    # static solution that does not converge (almost no bearing stiffness)
    structure.set_bearing_laws(AffineLaws(law_a.f0, 1e-12 * law_a.kb, law_a.cb))
    try:
        structure.solve_static()
    except FmuError as exc:
        msgs["static"] = str(exc)
    structure.set_bearing_laws(law_a)
    structure.solve_static()  # the instance still works
    structure.exit_initialization()
    dt = 2.3e-5
    structure.do_step(0.0, dt)
    saved = structure.get_state()
    x1 = structure.journal_states()
    # absurd law: Newton diverges (non-finite residuals) -> NewmarkConvergenceError inside
    structure.set_bearing_laws(AffineLaws(np.full((structure.n_bearings, 2), 1e300), law_a.kb,
                                          law_a.cb))
    try:
        structure.do_step(dt, dt)
    except FmuError as exc:
        msgs["newton"] = str(exc)
    # wrong time
    structure.set_state(saved)
    structure.set_bearing_laws(law_a)
    try:
        structure.do_step(5 * dt, dt)
    except FmuError as exc:
        msgs["time"] = str(exc)
    # back to the saved state: stepping works again
    structure.set_state(saved)
    same = bool((structure.journal_states() == x1).all())
    structure.do_step(dt, dt)
    structure.close()
    return dict(msgs=msgs, same=same, n=structure.n_steps)


def native_io(fmu: str, case: str) -> dict:
    """The master's calls on the gear-shaft FMU (the law inputs set, a doStep, the journal
    outputs read), beside the in-process structure with the same laws, and how many
    of the sets and reads reached the slave's Python (``GearShaftSlave.set_real`` and
    ``get_real`` counted): the patched library serves the others from the slave's buffer
    (fmu_src/native/patches/0012-native-structure-io.patch). Along: initialisation (static
    solutions), steps with alternating laws, a restored state, laws with a NaN, a failed step,
    and fmi2Reset."""
    from bearing_fmu.affine import AffineLaws
    from fmu_src import description
    from fmu_src.slaves.gear_shaft import GearShaftSlave
    from orchestrator.coupling.fmi import FmuError, FmuStructure
    from orchestrator.coupling.inprocess import InProcessStructure

    def count() -> dict:
        out = dict(calls)
        calls.update(set_real=0, get_real=0)
        return out

    case = _case(case)
    nb = len(case.names("bearings"))
    law_a, law_b = laws(nb)
    r = {"same": [], "calls": {}}

    def start(structure, ref):
        for law in (law_b, law_a):  # two static solutions, as the master's iteration
            ref.set_bearing_laws(law)
            structure.set_bearing_laws(law)
            ref.solve_static()
            structure.solve_static()
            r["same"].append(bool((structure.journal_states() == ref.journal_states()).all()))
        ref.exit_initialization()
        structure.exit_initialization()

    def steps(structure, ref, t, n):
        for k in range(n):
            law = law_a if k % 2 else law_b
            ref.set_bearing_laws(law)
            structure.set_bearing_laws(law)
            ref.do_step(t, dt)
            structure.do_step(t, dt)
            t += dt
            r["same"].append(bool((structure.journal_states() == ref.journal_states()).all()))
        return t

    with counted_calls(GearShaftSlave, ("set_real", "get_real")) as calls:
        structure = FmuStructure(fmu, case=case)
        try:
            ref = InProcessStructure(description.structure(case))
            dt = ref.structure.mesh_period / 32
            count()
            start(structure, ref)
            r["calls"]["initialisation"] = count()
            t = steps(structure, ref, 0.0, 12)
            r["calls"]["steps"] = count()
            # a restored state: its journals, then the same steps again
            saved, rsaved = structure.get_state(), ref.get_state()
            steps(structure, ref, t, 3)
            structure.set_state(saved)
            ref.set_state(rsaved)
            r["same"].append(bool((structure.journal_states() == ref.journal_states()).all()))
            t = steps(structure, ref, t, 3)
            r["calls"]["restored"] = count()
            # laws with a NaN: refused by the set, in the slave's Python, none applied
            structure.set_bearing_laws(law_a)
            bad = AffineLaws(law_a.f0, law_a.kb, law_a.cb.copy())
            bad.cb[1, 1, 0] = math.nan
            try:
                structure.set_bearing_laws(bad)
                r["nan"] = None
            except FmuError as exc:
                r["nan"] = str(exc)
            structure.do_step(t, dt)  # with the laws set before (law_a)
            ref.set_bearing_laws(law_a)
            ref.do_step(t, dt)
            t += dt
            r["same"].append(bool((structure.journal_states() == ref.journal_states()).all()))
            r["calls"]["nan"] = count()
            # a failed step: the journals read fmi2Error, in Python, until a state is restored
            saved = structure.get_state()
            structure.set_bearing_laws(AffineLaws(np.full((nb, 2), 1e300), law_a.kb,
                                                  law_a.cb))
            with contextlib.suppress(FmuError):
                structure.do_step(t, dt)
            try:
                structure.journal_states()
                r["after_failure"] = None
            except FmuError as exc:
                r["after_failure"] = str(exc)
            structure.set_state(saved)
            ref.do_step(t, dt)
            structure.set_bearing_laws(law_a)
            structure.do_step(t, dt)
            r["same"].append(bool((structure.journal_states() == ref.journal_states()).all()))
            r["calls"]["failure"] = count()
            # fmi2Reset: a new slave, whose buffer the library asks for again
            f = structure.slave.fmu
            f.reset()
            f.setupExperiment(startTime=0.0)
            f.enterInitializationMode()
            structure._set_case(case)  # the parameters are back at their start values
            structure.in_init, structure.t, structure.n_steps = True, 0.0, 0
            ref = InProcessStructure(description.structure(case))
            count()
            start(structure, ref)
            steps(structure, ref, 0.0, 4)
            r["calls"]["after_reset"] = count()
        finally:
            structure.close()
    return r


PROBES = probes_of(refuse_bad_values, comparison, failures, native_io)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
