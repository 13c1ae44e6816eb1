"""Probes of tests/fmu_src/test_fmi_behaviour.py: every FMU through fmpy as any FMI master
calls it (:class:`orchestrator.coupling.fmi.FmuInstance`), and a system checkpointed in one
process and restarted in another."""

from __future__ import annotations

import math
import pickle

from tests.probes import dispatch, probes_of


def refuse_bad_values(fmu: str) -> dict:
    """Out-of-bounds and non-finite values set in initialisation mode: per value, the call's
    status and the log since, or "accepted"; then the values kept."""
    from fmpy.fmi1 import FMICallException

    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "b")
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    vr = s.vr
    r = {}
    for key, name, value in (("C", "C", -1e-4), ("mu", "mu", 0.0), ("nan", "s", math.nan),
                             ("omega", "omega", -5.0)):
        since = len(s.messages)
        try:
            s.fmu.setReal([vr[name]], [value])
            r[key] = ["accepted"]
        except FMICallException as exc:
            r[key] = [exc.status, s.log_tail(since=since)]
    since = len(s.messages)
    try:
        s.fmu.setInteger([vr["rotation_sign"]], [0])
        r["sign"] = ["accepted"]
    except FMICallException as exc:
        r["sign"] = [exc.status, s.log_tail(since=since)]
    r["kept"] = [s.fmu.getReal([vr["C"]])[0], s.fmu.getReal([vr["mu"]])[0],
                 s.fmu.getInteger([vr["rotation_sign"]])[0]]
    s.close()
    return r


def read_outside_the_clearance(fmu: str) -> dict:
    """Outputs read with the journal at 1.2 C: the status and the log, then a read back inside
    the clearance."""
    from fmpy.fmi1 import FMICallException

    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "b")
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    vr = s.vr
    c = s.fmu.getReal([vr["C"]])[0]
    s.fmu.setReal([vr["s"], vr["t"]], [1.2 * c, 0.0])  # accepted: an input, not yet used
    since = len(s.messages)
    try:
        values = s.fmu.getReal([vr["F_s"], vr["K_ss"]])
        r = dict(status=0, values=values)
    except FMICallException as exc:
        r = dict(status=exc.status, log=s.log_tail(since=since))
    s.fmu.setReal([vr["s"]], [0.5 * c])  # back inside: the next read works
    r["after"] = s.fmu.getReal([vr["F_s"], vr["eccentricity"]])
    s.close()
    return r


def state_round_trip(fmu: str) -> dict:
    """Outputs at one state after a saved state is restored (and after a serialised one is),
    against the first evaluation there, with the warm start moved away in between."""
    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "b")
    f, vr = s.fmu, s.vr
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.setReal([vr["omega"]], [325.0])
    outs = [vr[n] for n in ("F_s", "F_t", "K_ss", "K_st", "K_ts", "K_tt", "C_ss", "C_st",
                            "C_ts", "C_tt")]
    c = f.getReal([vr["C"]])[0]
    ins = [vr[n] for n in ("s", "t", "s_dot", "t_dot")]

    def at(x):
        f.setReal(ins, x)
        return f.getReal(outs)

    at([0.5 * c, -0.3 * c, 0.0, 0.0])
    f.exitInitializationMode()
    at([0.55 * c, -0.3 * c, 1e-3, 0.0])  # the warm start now holds this solve
    state = f.getFMUstate()
    blob = f.serializeFMUstate(state)
    first = at([0.6 * c, -0.25 * c, 2e-3, -1e-3])
    for k in range(5):  # move the warm start far away
        at([-0.4 * c, 0.5 * c * (k + 1) / 5, -3e-3, 2e-3])
    f.setFMUstate(state)
    again = at([0.6 * c, -0.25 * c, 2e-3, -1e-3])
    at([-0.4 * c, 0.5 * c, -3e-3, 2e-3])
    back = f.deSerializeFMUstate(blob)
    f.setFMUstate(back)
    restored = at([0.6 * c, -0.25 * c, 2e-3, -1e-3])
    f.freeFMUstate(back)
    f.freeFMUstate(state)
    s.close()
    return dict(same=first == again, serialised=first == restored)


def checkpoint(fmu_dir: str, path: str, phase: str) -> dict:
    """The paper's case through the five FMUs. ``phase`` "first": static solution, 6 steps,
    every FMU's serialised state and the master's laws written to ``path``, 6 steps more;
    "second": fresh instances restored from ``path`` run the last 6 steps. Returns the journal
    states at the end."""
    from fmu_src import description
    from fmu_src.case import load_case
    from orchestrator.coupling.system import build_master

    case = load_case("baguet2010_spur")
    dt = description.time_step(case)
    m = build_master(case, fmu_dir=fmu_dir)
    fmus = [m.structure.slave.fmu] + [s.fmu for s in m.bearings.slaves]
    if phase == "first":
        m.solve_static()
        m.exit_initialization()
        for k in range(6):
            m.step(k * dt, dt)
        blobs = []
        for f in fmus:
            st = f.getFMUstate()
            blobs.append(f.serializeFMUstate(st))
            f.freeFMUstate(st)
        with open(path, "wb") as fh:
            pickle.dump(dict(blobs=blobs, laws=m.laws, t=m.structure.t,
                             n=m.structure.n_steps), fh)
    elif phase == "second":
        with open(path, "rb") as fh:
            saved = pickle.load(fh)
        m.bearings.exit_initialization()
        m.structure.exit_initialization()
        for f, blob in zip(fmus, saved["blobs"], strict=True):
            st = f.deSerializeFMUstate(blob)
            f.setFMUstate(st)
            f.freeFMUstate(st)
        m.laws, m.structure.t, m.structure.n_steps = saved["laws"], saved["t"], saved["n"]
    else:
        raise ValueError(f"phase = {phase!r}: expected 'first' or 'second'")
    for k in range(6, 12):
        m.step(k * dt, dt)
    x = m.structure.journal_states().tolist()
    m.close()
    return dict(x=x)


PROBES = probes_of(refuse_bad_values, read_outside_the_clearance, state_round_trip, checkpoint)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
