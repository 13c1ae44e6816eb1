"""Probes of tests/fmu_src/test_fmi_behaviour.py: every FMU through fmpy as any FMI master
calls it (:class:`orchestrator.coupling.fmi.FmuInstance`), and a system checkpointed in one
process and restarted in another."""

from __future__ import annotations

import io
import math
import pickle

import numpy as np

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
        np.savez(path, *[np.frombuffer(b, dtype=np.uint8) for b in blobs], f0=m.laws.f0,
                 kb=m.laws.kb, cb=m.laws.cb, states=m.laws.states, force_at=m.laws.force_at,
                 t=m.structure.t, n=m.structure.n_steps)
    elif phase == "second":
        from bearing_fmu.affine import AffineLaws

        saved = np.load(path, allow_pickle=False)
        m.bearings.exit_initialization()
        m.structure.exit_initialization()
        for k, f in enumerate(fmus):
            st = f.deSerializeFMUstate(saved[f"arr_{k}"].tobytes())
            f.setFMUstate(st)
            f.freeFMUstate(st)
        m.laws = AffineLaws(*(saved[n] for n in ("f0", "kb", "cb", "states", "force_at")))
        m.structure.t, m.structure.n_steps = float(saved["t"]), int(saved["n"])
    else:
        raise ValueError(f"phase = {phase!r}: expected 'first' or 'second'")
    for k in range(6, 12):
        m.step(k * dt, dt)
    x = m.structure.journal_states().tolist()
    m.close()
    return dict(x=x)


class WritesAFile:
    """A pickle that creates ``path`` when it is loaded (what a crafted state could do)."""

    def __init__(self, path: str):
        self.path = path

    def __reduce__(self):
        return (open, (self.path, "w"))


def refuse_foreign_states(fmu: str, gear: bool, marker: str) -> dict:
    """fmi2DeSerializeFMUstate / fmi2SetFMUstate of bytes that are not the FMU's own state: a
    pickle that would create ``marker``, text, another kind, the FMU's kind with an entry of
    another shape. Per case the status, the log and the call that refused it; then whether the
    FMU's own state still restores exactly."""
    from fmpy.fmi1 import FMICallException

    from fmu_src.state_codec import encode
    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "x")
    f, vr = s.fmu, s.vr
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    if gear:
        names = ["s_1", "t_1", "s_dot_1", "mesh_force_mesh"]
    else:
        names = ["F_s", "F_t", "K_ss", "C_tt"]
        c = f.getReal([vr["C"]])[0]
        f.setReal([vr[n] for n in ("omega", "s", "t")], [325.0, 0.5 * c, -0.3 * c])
    outs = [vr[n] for n in names]
    f.getReal(outs)
    f.exitInitializationMode()
    if gear:
        f.doStep(0.0, 1e-5)
    else:
        f.setReal([vr["s"], vr["s_dot"]], [0.55 * c, 1e-3])
    saved = f.getReal(outs)
    state = f.getFMUstate()
    good = f.serializeFMUstate(state)
    f.freeFMUstate(state)
    with np.load(io.BytesIO(good), allow_pickle=False) as z:  # numpy reads it, no pickle
        arrays = {n: z[n] for n in z.files}
    kind = str(arrays.pop("__kind__"))
    arrays.pop("__format_version__")
    # an entry of another shape: one checked against the live structure or model when the
    # state is set (a scalar for memoryless models: checked when deserialised)
    vectors = [n for n in sorted(arrays) if n.startswith(("structure/x", "model/"))
               and arrays[n].ndim == 1]
    big = vectors[0] if vectors else "values/D"
    other = arrays | {big: np.zeros(3, arrays[big].dtype)}
    r = {"kind": kind, "refused": {}}
    for name, blob in (("pickle", pickle.dumps(WritesAFile(marker))), ("text", b"a state"),
                       ("kind", encode("gsb.other", {"x": 1.0})),
                       ("shape", encode(kind, other))):
        since = len(s.messages)
        stage = "fmi2DeSerializeFMUstate"
        try:
            st = f.deSerializeFMUstate(blob)
            stage = "fmi2SetFMUstate"
            try:
                f.setFMUstate(st)
                r["refused"][name] = ["accepted"]
            finally:
                f.freeFMUstate(st)
        except FMICallException as exc:
            r["refused"][name] = [exc.status, s.log_tail(since=since), stage, big]
    st = f.deSerializeFMUstate(good)
    f.setFMUstate(st)
    f.freeFMUstate(st)
    r["again"] = f.getReal(outs) == saved
    s.close()
    return r


def _raw(s):
    """fmi2DoStep and fmi2GetReal of an FmuInstance as an FMI host calls them: the status
    whatever it is (fmpy raises on a non-OK status), the values read even then."""
    import ctypes

    f = s.fmu
    dll, c = f.dll, f.component

    def do_step(t, dt):
        since = len(s.messages)
        return [dll.fmi2DoStep(c, t, dt, 0), s.messages[since:]]

    def get_real(names):
        n = len(names)
        values = (ctypes.c_double * n)()
        status = dll.fmi2GetReal(c, (ctypes.c_uint * n)(*[s.vr[k] for k in names]), n, values)
        return [status, list(values)]
    return do_step, get_real


def bearing_step_that_cannot_be_computed(fmu: str, film: bool) -> dict:
    """A bearing FMU stepped as a fixed-step host steps it (inputs set, fmi2DoStep, outputs
    read) after inputs at which its law cannot be computed: the journal at 1.2 C (a film
    model) and at 1e305 m (every model: the law overflows). Per case the doStep's status and
    log, the read's status and values; then a valid state again."""
    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "b")
    f, vr = s.fmu, s.vr
    do_step, get_real = _raw(s)
    outputs = ["F_s", "F_t", "K_ss", "K_st", "K_ts", "K_tt", "C_ss", "C_st", "C_ts", "C_tt"]
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    c = f.getReal([vr["C"]])[0]
    f.setReal([vr["s"], vr["t"]], [0.3 * c, -0.2 * c])
    f.exitInitializationMode()
    r = {"good": [do_step(0.0, 1e-3), get_real(outputs)]}
    bad = {"overflow": [1e305, 0.0]} | ({"outside": [1.2 * c, 0.0]} if film else {})
    for k, (name, state) in enumerate(bad.items()):
        f.setReal([vr["s"], vr["t"]], state)
        r[name] = [do_step((k + 1) * 1e-3, 1e-3), get_real(outputs), get_real(["F_s"])]
    f.setReal([vr["s"], vr["t"]], [0.3 * c, -0.2 * c])
    r["again"] = [do_step(3e-3, 1e-3), get_real(outputs)]
    s.close()
    return r


def gear_step_that_cannot_be_computed(fmu: str) -> dict:
    """The gear-shaft FMU after one good step: a step with laws whose Newton iteration diverges
    (F_s_1 = 1e300 N) and a step of 1e6 s (more mesh periods than a step may span), each from
    the saved state after the good step. Per case the doStep's status and log and the read of
    the journal states (status and values); then a good step from the saved state."""
    from fmu_src.case import shipped_case
    from fmu_src.contract import GEAR_DEFAULT_CASE, journal_output_names
    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "g")
    f, vr = s.fmu, s.vr
    do_step, get_real = _raw(s)
    journal = journal_output_names(shipped_case(GEAR_DEFAULT_CASE.removesuffix(".toml")))
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.exitInitializationMode()
    dt = 1e-5
    r = {"good": [do_step(0.0, dt), get_real(journal)]}
    saved = f.getFMUstate()
    f.setReal([vr["F_s_1"]], [1e300])
    r["diverging"] = [do_step(dt, dt), get_real(journal), do_step(dt, dt)]
    f.setFMUstate(saved)
    r["huge_dt"] = [do_step(dt, 1e6), get_real(journal)]
    f.setFMUstate(saved)
    r["again"] = [do_step(dt, dt), get_real(journal)]
    f.freeFMUstate(saved)
    s.close()
    return r


def declared_bounds(fmu: str) -> dict:
    """Every parameter and input with a min or max in modelDescription.xml set (in
    initialisation mode) to that bound and to the nearest value beyond it (the next double;
    the next integer): per variable and value, the setter's status."""
    import ctypes

    from orchestrator.coupling.fmi import FmuInstance

    s = FmuInstance(fmu, "x")
    f = s.fmu
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    r = {}
    for v in s.md.modelVariables:
        if v.causality not in ("parameter", "input") or v.type not in ("Real", "Integer"):
            continue
        real = v.type == "Real"
        kind = float if real else int
        setter = f.dll.fmi2SetReal if real else f.dll.fmi2SetInteger
        ctype = ctypes.c_double if real else ctypes.c_int
        tries = []
        for bound, away in ((v.min, -math.inf), (v.max, math.inf)):
            if bound is None:
                continue
            at = kind(bound)
            beyond = math.nextafter(at, away) if real else at + (1 if away > 0 else -1)
            for value in (at, beyond):
                status = setter(f.component, (ctypes.c_uint * 1)(v.valueReference), 1,
                                (ctype * 1)(value))
                tries.append([value, value == at, status])
        if tries:
            r[v.name] = {"description": v.description, "tries": tries,
                         "min": v.min, "max": v.max}
    s.close()
    return r


PROBES = probes_of(refuse_bad_values, read_outside_the_clearance, state_round_trip, checkpoint,
                   refuse_foreign_states, bearing_step_that_cannot_be_computed,
                   gear_step_that_cannot_be_computed, declared_bounds)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
