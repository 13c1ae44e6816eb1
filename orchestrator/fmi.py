"""FMU slaves driven through fmpy: the same master interface as :mod:`orchestrator.inprocess`.

Calls go through fmpy's low-level functions with preallocated ctypes arrays (a few µs each).
A slave that fails (e.g. eccentricity >= 1, a Newmark step that does not converge) logs the
reason with status error and returns NaN outputs or a non-OK status; it is turned into a
Python exception (:class:`FmuError`) here, with the slave's log.

:class:`FmuBearings` drives the bearing FMUs, :class:`FmuStructure` the gear-shaft FMU.
"""

from __future__ import annotations

import ctypes
import math
import shutil
import sys
import weakref
from pathlib import Path

import numpy as np

from fmu_src.contract import (
    BEARING_VARIABLES,
    DAMPING_NAMES,
    FORCE_NAMES,
    GEAR_OUTPUTS,
    STIFFNESS_NAMES,
    journal_output_names,
    law_input_names,
    support_load_names,
)
from orchestrator.master import BearingSet, StructureSlave

__all__ = [
    "BEARING_FMUS",
    "DEFAULT_FMU_DIR",
    "FmuBearings",
    "FmuError",
    "FmuState",
    "FmuStructure",
    "bearing_parameters",
    "case_toml",
    "ensure_fmus",
    "system_from_case",
]

#: bearing model name -> bearing FMU file stem (``gsb build-fmus``)
BEARING_FMUS = {"hybrid": "BearingHybrid", "short": "BearingShort", "fd": "BearingFd",
                "linear": "BearingLinear", "lumped": "BearingLumped"}
DEFAULT_FMU_DIR = Path("build") / "fmus"

_STATUS = ("ok", "warning", "discard", "error", "fatal", "pending")


def _status_name(status: int) -> str:
    return _STATUS[status] if 0 <= status < len(_STATUS) else f"illegal status {status}"


class FmuError(RuntimeError):
    """An FMU call failed; the message carries the slave's log."""


class _Fmu:
    """One instantiated FMI 2.0 co-simulation slave with a message log."""

    def __init__(self, path: Path | str, instance_name: str):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        path = Path(path)
        if not path.is_file():
            raise FmuError(f"FMU file not found: {path}")
        self.path = path
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.messages: list[str] = []
        self.errors = 0  # messages logged with status error or fatal
        self._dir = extract(str(path))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=instance_name)

        from fmpy.fmi2 import calloc as _calloc
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
        )
        from fmpy.fmi2 import free as _free

        def logger(env, name, status, category, message):
            self.messages.append(f"[{_status_name(status)}] {message.decode(errors='replace')}")
            if status >= 3:
                self.errors += 1

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(logger)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(_free)
        self._callbacks = cb  # keep the ctypes callbacks alive
        self.fmu.instantiate(loggingOn=True, callbacks=cb)

    def set(self, values: dict) -> None:
        reals = {k: v for k, v in values.items() if self.types[k] == "Real"}
        ints = {k: v for k, v in values.items() if self.types[k] == "Integer"}
        if reals:
            self.fmu.setReal([self.vr[k] for k in reals], [float(v) for v in reals.values()])
        if ints:
            self.fmu.setInteger([self.vr[k] for k in ints], [int(v) for v in ints.values()])

    def log_tail(self, n: int = 3, since: int = 0) -> str:
        """The last ``n`` log messages (from index ``since`` on), for error messages."""
        tail = self.messages[since:][-n:]
        return "; ".join(tail) if tail else "(no message in the FMU log)"

    def close(self) -> None:
        """Terminate and free the instance, remove the extracted folder (idempotent)."""
        if self.fmu is None:
            return
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            self.fmu = None
            shutil.rmtree(self._dir, ignore_errors=True)


class FmuBearings(BearingSet):
    """Bearing FMUs (any of the five models: same variables), one instance per bearing.

    Parameters
    ----------
    fmus : sequence of path
        FMU file of each bearing (swap a model by naming another file).
    parameters : sequence of dict
        Parameter values of each bearing (names of :data:`fmu_src.contract.BEARING_VARIABLES`).
    omegas : sequence of float
        Shaft speed magnitude at each bearing [rad/s].
    """

    _INPUTS = ("s", "t", "s_dot", "t_dot")
    _OUTPUTS = FORCE_NAMES + STIFFNESS_NAMES + DAMPING_NAMES

    def __init__(self, fmus, parameters, omegas):
        names = {v.name for v in BEARING_VARIABLES if v.causality == "parameter"}
        self.slaves = []
        for b, (path, params) in enumerate(zip(fmus, parameters, strict=True)):
            unknown = set(params) - names
            if unknown:
                raise ValueError(f"bearing {b + 1}: unknown FMU parameters {sorted(unknown)}")
            s = _Fmu(path, f"bearing{b + 1}")
            s.fmu.setupExperiment(startTime=0.0)
            s.fmu.enterInitializationMode()
            s.set(params)
            s.set({"omega": float(omegas[b])})
            self.slaves.append(s)
        self.in_init = True
        fm = self.slaves[0].fmu
        self._in_vr = [(ctypes.c_uint * 4)(*[s.vr[n] for n in self._INPUTS]) for s in self.slaves]
        self._out_vr = [(ctypes.c_uint * 10)(*[s.vr[n] for n in self._OUTPUTS])
                        for s in self.slaves]
        self._in_val = (ctypes.c_double * 4)()
        self._out_val = (ctypes.c_double * 10)()
        self._set = fm.fmi2SetReal
        self._get = fm.fmi2GetReal

    def evaluate(self, states):
        nb = len(self.slaves)
        force = np.empty((nb, 2))
        kb = np.empty((nb, 2, 2))
        cb = np.empty((nb, 2, 2))
        for b, s in enumerate(self.slaves):
            for i in range(4):
                self._in_val[i] = states[b, i]
            s.fmu.fmi2SetReal(s.fmu.component, self._in_vr[b], 4, self._in_val)
            s.fmu.fmi2GetReal(s.fmu.component, self._out_vr[b], 10, self._out_val)
            out = np.frombuffer(self._out_val, dtype=np.float64).copy()
            if not np.all(np.isfinite(out)):
                log = "; ".join(s.messages[-3:])
                raise FmuError(f"bearing {b + 1} ({s.path.name}) failed at state "
                               f"{states[b].tolist()}: {log}")
            force[b] = out[:2]
            kb[b] = out[2:6].reshape(2, 2)
            cb[b] = out[6:].reshape(2, 2)
        return force, kb, cb

    def static_position(self, loads):
        """Per-bearing 2-D Newton on F(X) + W = 0 through the FMU, kept inside the clearance."""
        pos = np.zeros((len(self.slaves), 2))
        for b, s in enumerate(self.slaves):
            clearance = float(s.fmu.getReal([s.vr["C"]])[0])
            x = np.zeros(2)
            states = np.zeros((len(self.slaves), 4))
            for _ in range(100):
                states[b, :2] = x
                f, k, _ = self.evaluate(states)
                res = f[b] + loads[b]
                if np.linalg.norm(res) <= 1e-10 * max(np.linalg.norm(loads[b]), 1e-300):
                    break
                step = np.linalg.solve(k[b], res)
                alpha = 1.0
                while np.hypot(*(x + alpha * step)) >= 0.95 * clearance:
                    alpha *= 0.5
                x = x + alpha * step
            pos[b] = x
        return pos

    def exit_initialization(self) -> None:
        """Leave initialisation mode (the linear FMU freezes its coefficients here)."""
        for s in self.slaves:
            s.fmu.exitInitializationMode()
        self.in_init = False

    def close(self) -> None:
        """Terminate and free every instance, remove the extracted FMU folders."""
        for s in self.slaves:
            s.close()
        self.slaves = []


class FmuState:
    """A saved gear-shaft FMU state (fmi2GetFMUstate); freed when no longer referenced."""

    __slots__ = ("__weakref__", "_handle", "_owner", "n_steps", "t")

    def __init__(self, owner: FmuStructure, handle: ctypes.c_void_p, t: float, n_steps: int):
        self._owner = owner
        self._handle = handle
        self.t = t
        self.n_steps = n_steps

    def free(self) -> None:
        """Release the FMU's copy now (idempotent; also done on garbage collection)."""
        owner, self._owner = self._owner, None
        if owner is not None and self._handle is not None:
            owner._free_handle(self._handle)
        self._handle = None

    def __del__(self):
        if sys.is_finalizing():  # the FMU library may already be gone
            return
        try:
            self.free()
        except Exception:  # a destructor must not raise
            pass


class FmuStructure(StructureSlave):
    """The gear-shaft FMU (``GearShaft.fmu``) behind the master's structure interface.

    Parameters
    ----------
    fmu : path
        The built gear-shaft FMU (``gsb build-fmus GearShaft``).
    case_file : path, optional
        Case file of the system (the FMU's ``case_file`` parameter; default: the paper's spur
        case shipped in the FMU).
    case : orchestrator.case.Case, optional
        A checked case (e.g. with command-line overrides) instead of ``case_file``: written to
        a temporary case file (SI values, :func:`case_toml`) removed by :meth:`close`.
    start_time : float
        Time of the initial (static) state [s].

    The instance starts in initialisation mode: :meth:`set_bearing_laws` + :meth:`solve_static`
    give static solutions (the FMU solves when its outputs are read). :meth:`exit_initialization`
    (done by the first :meth:`do_step` if not called before) leaves it; the FMU then rebuilds its
    modal damping on the modes with the symmetric part of the current Kb laws, which is what
    :meth:`gear_fmu.structure.Structure.set_damping_reference` does in process
    (:meth:`set_damping_reference` is that call's equivalent). :meth:`get_state` /
    :meth:`set_state` use fmi2GetFMUstate / fmi2SetFMUstate; a state is freed when its
    :class:`FmuState` is garbage-collected. An FMU failure raises :class:`FmuError` with the
    FMU's log message, the time and the step.
    """

    n_bearings = 4

    def __init__(self, fmu, case_file=None, case=None, start_time: float = 0.0,
                 instance_name: str = "gear_shaft"):
        self._tmpdir = None
        if case is not None:
            if case_file is not None:
                raise ValueError("give case_file or case, not both")
            import tempfile

            self._tmpdir = tempfile.mkdtemp(prefix="gsb_case_")
            case_file = Path(self._tmpdir) / "case.toml"
            case_file.write_text(case_toml(case))
        self.slave = _Fmu(fmu, instance_name)
        self._states: weakref.WeakSet = weakref.WeakSet()
        f = self.slave.fmu
        f.setupExperiment(startTime=float(start_time))
        f.enterInitializationMode()
        if case_file is not None:
            f.setString([self.slave.vr["case_file"]], [str(case_file)])
        self.in_init = True
        self.t = float(start_time)
        self.n_steps = 0
        vr = self.slave.vr
        # raw ctypes functions (fmpy sets their argtypes; statuses are checked here)
        dll = f.dll
        self._c = f.component
        self._set_real = dll.fmi2SetReal
        self._get_real = dll.fmi2GetReal
        self._get_integer = dll.fmi2GetInteger
        self._do_step = dll.fmi2DoStep
        self._get_state = dll.fmi2GetFMUstate
        self._set_state = dll.fmi2SetFMUstate
        self._free_state = dll.fmi2FreeFMUstate
        laws = law_input_names()
        journal = journal_output_names()
        extra = [name for name, _, _ in GEAR_OUTPUTS]
        support = support_load_names()
        self._law_vr = (ctypes.c_uint * 40)(*[vr[n] for n in laws])
        self._law_val = (ctypes.c_double * 40)()
        self._law_np = np.frombuffer(self._law_val, dtype=np.float64).reshape(4, 10)
        self._jr_vr = (ctypes.c_uint * 16)(*[vr[n] for n in journal])
        self._jr_val = (ctypes.c_double * 16)()
        self._jr_np = np.frombuffer(self._jr_val, dtype=np.float64).reshape(4, 4)
        self._ex_vr = (ctypes.c_uint * len(extra))(*[vr[n] for n in extra])
        self._ex_val = (ctypes.c_double * len(extra))()
        self._ex_index = {n: i for i, n in enumerate(extra)}
        self._one_vr = {n: (ctypes.c_uint * 1)(vr[n]) for n in extra}
        self._one_val = (ctypes.c_double * 1)()
        self._sup_vr = (ctypes.c_uint * 8)(*[vr[n] for n in support])
        self._sup_val = (ctypes.c_double * 8)()
        self._it_vr = (ctypes.c_uint * 1)(vr["iterations"])
        self._it_val = (ctypes.c_int * 1)()

    # --- errors -------------------------------------------------------------------------------
    def _fail(self, what: str, status: int | None = None, since: int = 0, where: bool = True):
        at = f" at t = {self.t:.9g} s (after step {self.n_steps})" if where else ""
        st = "" if status is None else f" (status {_status_name(status)})"
        raise FmuError(f"gear-shaft FMU ({self.slave.path.name}): {what}{st}{at}; FMU log: "
                       f"{self.slave.log_tail(since=since)}")

    def _check(self, status: int, what: str, since: int = 0) -> None:
        if status > 1:  # discard, error, fatal
            self._fail(what, status, since)

    def _live(self):
        if self.slave.fmu is None:
            raise FmuError("the gear-shaft FMU is closed")

    # --- master interface ---------------------------------------------------------------------
    def set_bearing_laws(self, laws) -> None:
        """Set the 40 law inputs (F0, Kb, Cb of bearings 1-4, global frame) in one call."""
        self._live()
        v = self._law_np
        v[:, 0:2] = laws.f0
        v[:, 2:6] = np.reshape(laws.kb, (4, 4))
        v[:, 6:10] = np.reshape(laws.cb, (4, 4))
        self._check(self._set_real(self._c, self._law_vr, 40, self._law_val),
                    "setting the bearing laws")

    def solve_static(self) -> None:
        """Static solution for the current laws (initialisation mode only): read the outputs."""
        self._live()
        if not self.in_init:
            raise FmuError("the gear-shaft FMU solves static solutions only in initialisation "
                           "mode (before exit_initialization / the first do_step)")
        self._read_journal("static solution")

    def exit_initialization(self) -> None:
        """Leave initialisation mode: the current static solution becomes the initial state and
        the FMU's modal damping is rebuilt with the symmetric part of the current Kb laws."""
        self._live()
        if not self.in_init:
            return
        since, errors = len(self.slave.messages), self.slave.errors
        status = self.slave.fmu.dll.fmi2ExitInitializationMode(self._c)
        self.in_init = False
        self._check(status, "exitInitializationMode", since)
        if self.slave.errors > errors:
            self._fail("initialisation failed", since=since)

    def set_damping_reference(self, bearing_stiffness=None) -> None:
        """Equivalent of :meth:`Structure.set_damping_reference` for the FMU: exit initialisation.

        The FMU takes the reference from its current Kb laws (symmetric part); a given
        ``bearing_stiffness`` (4, 2, 2) must equal that (the FMU has no input for another one).
        """
        if bearing_stiffness is not None:
            kb = self._law_np[:, 2:6].reshape(4, 2, 2)
            ref = 0.5 * (kb + kb.transpose(0, 2, 1))
            given = np.asarray(bearing_stiffness, dtype=float)
            given = 0.5 * (given + np.swapaxes(given, -1, -2))
            if given.shape != (4, 2, 2) or not np.allclose(given, ref, rtol=1e-12, atol=0.0):
                raise ValueError("the gear-shaft FMU takes its damping reference from its current "
                                 "Kb laws; set_bearing_laws() with that stiffness first")
        self.exit_initialization()

    def do_step(self, t: float, dt: float) -> None:
        """One Newmark step from t to t + dt with the current laws (FmuError on failure)."""
        if self.in_init:
            self.exit_initialization()
        since = len(self.slave.messages)
        status = self._do_step(self._c, t, dt, 0)
        if status != 0:
            self._fail(f"doStep {self.n_steps + 1} from t = {t:.9g} s (dt = {dt:.6g} s) failed",
                       status, since, where=False)
        self.t = t + dt
        self.n_steps += 1

    def _read_journal(self, what: str) -> np.ndarray:
        since = len(self.slave.messages)
        self._check(self._get_real(self._c, self._jr_vr, 16, self._jr_val), what, since)
        out = self._jr_np.copy()
        if not np.isfinite(out).all():
            self._fail(f"{what} failed", since=since)
        return out

    def journal_states(self) -> np.ndarray:
        """(4, 4) [s, t, s_dot, t_dot] at bearings 1-4, global frame [m, m/s]."""
        self._live()
        return self._read_journal("reading the journal states")

    def get_state(self) -> FmuState:
        """Save the FMU state (fmi2GetFMUstate); freed with the returned object."""
        self._live()
        handle = ctypes.c_void_p()
        self._check(self._get_state(self._c, ctypes.byref(handle)), "fmi2GetFMUstate")
        state = FmuState(self, handle, self.t, self.n_steps)
        self._states.add(state)
        return state

    def set_state(self, state: FmuState) -> None:
        """Restore a state of :meth:`get_state` exactly (fmi2SetFMUstate)."""
        self._live()
        if state._owner is not self or state._handle is None:
            raise FmuError("set_state: the state is freed or belongs to another FMU instance")
        self._check(self._set_state(self._c, state._handle), "fmi2SetFMUstate")
        self.t, self.n_steps = state.t, state.n_steps

    def _free_handle(self, handle) -> None:
        if self.slave.fmu is not None:
            self._free_state(self._c, ctypes.byref(handle))

    def support_loads(self) -> np.ndarray:
        """(4, 2) static loads of the structure on stiff bearings [N] (calculated parameters)."""
        self._live()
        self._check(self._get_real(self._c, self._sup_vr, 8, self._sup_val),
                    "reading the support loads")
        out = np.frombuffer(self._sup_val, dtype=np.float64).reshape(4, 2).copy()
        if not np.isfinite(out).all():
            self._fail("support loads failed")
        return out

    # --- other outputs ------------------------------------------------------------------------
    def outputs(self) -> dict:
        """Mesh and gear-node outputs by name (mesh_force, transmission_error, u_pinion, ...)."""
        self._live()
        n = len(self._ex_val)
        self._check(self._get_real(self._c, self._ex_vr, n, self._ex_val), "reading outputs")
        return {name: float(self._ex_val[i]) for name, i in self._ex_index.items()}

    def _extra(self, name: str) -> float:
        self._live()
        self._check(self._get_real(self._c, self._one_vr[name], 1, self._one_val),
                    f"reading {name}")
        return float(self._one_val[0])

    def mesh_force(self) -> float:
        """Total normal tooth load of the mesh [N]."""
        return self._extra("mesh_force")

    def transmission_error(self) -> float:
        """Transmission error of the gear nodes [m]."""
        return self._extra("transmission_error")

    def gear_displacements(self) -> np.ndarray:
        """(2, 2) [u, v] of the pinion and gear nodes [m] (the in-process Structure gives all
        six DOFs per node; the FMU outputs these two)."""
        o = self.outputs()
        return np.array([[o["u_pinion"], o["v_pinion"]], [o["u_gear"], o["v_gear"]]])

    def iterations(self) -> int:
        """Newton/contact iterations of the last step or static solution."""
        self._live()
        self._check(self._get_integer(self._c, self._it_vr, 1, self._it_val),
                    "reading iterations")
        return int(self._it_val[0])

    def close(self) -> None:
        """Free every saved state, terminate and free the instance (idempotent)."""
        if self._tmpdir is not None:
            shutil.rmtree(self._tmpdir, ignore_errors=True)
            self._tmpdir = None
        if self.slave.fmu is None:
            return
        for state in list(self._states):
            state.free()
        self._states = weakref.WeakSet()
        self.slave.close()

    def __enter__(self) -> FmuStructure:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        if sys.is_finalizing():
            return
        try:
            self.close()
        except Exception:  # a destructor must not raise
            pass


# --- a case through FMUs --------------------------------------------------------------------
def _toml_value(value) -> str:
    import json

    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write the non-finite value {value!r} to a case file")
        return repr(value)  # shortest round-trip form: the case reloads bit for bit
    if isinstance(value, str):
        return json.dumps(value)  # a valid TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to a case file")


def case_toml(case) -> str:
    """A checked case as a case file (SI numbers; reloads to the same values, overrides
    included): how a :class:`orchestrator.case.Case` reaches the gear-shaft FMU."""
    sections: dict[str, list[str]] = {}
    for key, value in case.values.items():
        if value is None:
            continue
        section, name = key.split(".")
        sections.setdefault(section, []).append(f"{name} = {_toml_value(value)}")
    parts = [f"# written by orchestrator.fmi from {case.source} (SI units)"]
    for section, lines in sections.items():
        parts.append(f"\n[{section}]")
        parts.extend(lines)
    return "\n".join(parts) + "\n"


def ensure_fmus(names, fmu_dir=None) -> dict[str, Path]:
    """Paths of the named FMUs in ``fmu_dir`` (default ``build/fmus``), building those that are
    missing or whose variables differ from the contract (built by an older version)."""
    from fmpy import read_model_description

    from fmu_src.build import FMUS, build_fmus

    fmu_dir = Path(DEFAULT_FMU_DIR if fmu_dir is None else fmu_dir)
    paths, stale = {}, []
    for name in names:
        if name not in FMUS:
            raise ValueError(f"unknown FMU {name!r}; available: {', '.join(FMUS)}")
        path = fmu_dir / f"{name}.fmu"
        paths[name] = path
        expected = [(v.name, v.causality) for v in FMUS[name].variables]
        try:
            md = read_model_description(str(path))
            current = [(v.name, v.causality) for v in md.modelVariables]
        except Exception:  # missing or unreadable: build it
            current = None
        if current != expected:
            stale.append(name)
    if stale:
        build_fmus(fmu_dir, stale)
    return paths


def bearing_parameters(case) -> list[dict]:
    """Parameters of the four bearing FMUs of a case (:data:`fmu_src.contract.BEARING_VARIABLES`;
    frames of :data:`orchestrator.system.BEARING_FRAMES`)."""
    from orchestrator import system

    out = []
    for data, frame in zip(system.bearing_data(case), system.BEARING_FRAMES, strict=True):
        out.append(dict(D=data.diameter, L=data.length, C=data.clearance, mu=data.viscosity,
                        frame_angle=frame.angle, rotation_sign=frame.rotation_sign,
                        n_theta=case["bearings.nodes"], n_xi=case["bearings.axial_intervals"],
                        k_lumped=case["bearings.lumped_stiffness"],
                        c_lumped=case["bearings.lumped_damping"]))
    return out


def system_from_case(case, model: str | None = None, fmu_dir=None):
    """(FmuStructure, FmuBearings) of a case: the gear-shaft FMU built from the case's values
    and four instances of the bearing FMU of ``model`` (default ``bearings.model``), taken from
    ``fmu_dir`` (default ``build/fmus``; built there if missing or stale)."""
    from orchestrator import system

    model = case["bearings.model"] if model is None else model
    if model not in BEARING_FMUS:
        raise ValueError(f"unknown bearing model {model!r}; available: {', '.join(BEARING_FMUS)}")
    paths = ensure_fmus(["GearShaft", BEARING_FMUS[model]], fmu_dir)
    structure = FmuStructure(paths["GearShaft"], case=case)
    try:
        bearings = FmuBearings([paths[BEARING_FMUS[model]]] * 4, bearing_parameters(case),
                               system.bearing_speeds(case))
    except Exception:
        structure.close()
        raise
    return structure, bearings
