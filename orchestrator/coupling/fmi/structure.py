"""The gear-shaft FMU behind the master's :class:`~orchestrator.coupling.master.StructureSlave`
interface, with rollback through fmi2GetFMUstate / fmi2SetFMUstate. The FMU's ports are those
of a gear train (:func:`fmu_src.contract.gear_variables`): the names of the bearings, meshes
and gears come from the case the FMU is driven with, or else from the case it carries."""

from __future__ import annotations

import ctypes
import sys
import weakref
from pathlib import Path

import numpy as np

from fmu_src.contract import (
    bearing_names,
    gear_names,
    gear_parameters,
    journal_output_names,
    law_input_names,
    mesh_names,
    pack_laws,
    step_output_names,
    support_load_names,
    unpack_journal,
)
from fmu_src.state_codec import StateArrays
from orchestrator.coupling.fmi.instance import FmuError, FmuInstance, all_finite, status_name
from orchestrator.coupling.master import StructureSlave

__all__ = ["FmuState", "FmuStructure", "block_arguments"]


def block_arguments(addresses, law_vr, law_values, journal_vr, journal_values, extra_vr,
                    extra_values, times, dt: float) -> tuple:
    """The gear-shaft FMU's arguments of :func:`orchestrator.coupling.step.coupled_steps`
    (:mod:`orchestrator.coupling.fmi.steps`): the FMI functions' and the component's
    ``addresses``, the value references and buffers of the laws, the journal states and the
    other outputs, the block's step start ``times`` [s] and ``dt`` [s]. With empty lists, the
    arguments' types without an FMU (:func:`orchestrator.coupling.step.compile_step`)."""
    u32 = np.uint32
    return (np.array(addresses, dtype=np.int64), np.array(law_vr, dtype=u32),
            np.asarray(law_values, dtype=np.float64), np.array(journal_vr, dtype=u32),
            np.asarray(journal_values, dtype=np.float64), np.array(extra_vr, dtype=u32),
            np.asarray(extra_values, dtype=np.float64), np.zeros(1, dtype=np.int64),
            np.asarray(times, dtype=float), float(dt))


class FmuState:
    """A saved gear-shaft FMU state (fmi2GetFMUstate); freed when no longer referenced."""

    __slots__ = ("__weakref__", "_handle", "_owner", "clock", "n_steps", "t")

    def __init__(self, owner: FmuStructure, handle: ctypes.c_void_p, t: float, n_steps: int,
                 clock: float):
        self._owner = owner
        self._handle = handle
        self.t = t
        self.n_steps = n_steps
        self.clock = clock

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


def _bearing_speed_schedule(case):
    """``t -> (nb,)`` each bearing's shaft speed [rad/s] in a run-up of ``case``
    (``drive.speed_profile``), None at constant speed: what the master sets as the bearing
    FMUs' input ``omega`` (the gear-shaft FMU follows the profile itself, a parameter)."""
    from fmu_src.description import layout, speed_profile
    from gear_fmu.loads import bearing_ratios

    profile = speed_profile(case)
    if not profile.varies:
        return None
    at = bearing_ratios(layout(case))
    return lambda t: profile.speed(t) * at


class FmuStructure(StructureSlave):
    """The gear-shaft FMU (``GearShaft.fmu``) behind the master's structure interface.

    Parameters
    ----------
    fmu : path
        The built gear-shaft FMU (``gsb build-fmus``).
    case : fmu_src.case.Case, optional
        A checked case (e.g. with command-line overrides): its structural fields are set as
        the FMU's parameters (:func:`fmu_src.contract.gear_parameters`); default: the case the
        FMU carries. Its gear train must be the one the FMU was built for (the same names of
        bearings, meshes, gears and parameters: :func:`fmu_src.contract.gear_variables`).
    start_time : float
        Time of the initial (static) state [s].

    The instance starts in initialisation mode: :meth:`set_bearing_laws` + :meth:`solve_static`
    give static solutions (the FMU solves when its outputs are read). :meth:`exit_initialization`
    (done by the first :meth:`do_step` if not called before) leaves it; the FMU then rebuilds its
    modal damping on the modes with the symmetric part of the current Kb laws, which is what
    :meth:`gear_fmu.structure.Structure.set_damping_reference` does in process. :meth:`get_state` /
    :meth:`set_state` use fmi2GetFMUstate / fmi2SetFMUstate; a state is freed when its
    :class:`FmuState` is garbage-collected. An FMU failure raises :class:`FmuError` with the
    FMU's log message, the time and the step.
    """

    def __init__(self, fmu, case=None, start_time: float = 0.0,
                 instance_name: str = "gear_shaft"):
        self.slave = FmuInstance(fmu, instance_name)
        self._states: weakref.WeakSet = weakref.WeakSet()
        try:
            train = case if case is not None else self._carried_case()
            self._check_train(train)
            self._bearing_speeds = _bearing_speed_schedule(train)
        except BaseException:
            self.slave.close()
            raise
        f = self.slave.fmu
        f.setupExperiment(startTime=float(start_time))
        f.enterInitializationMode()
        if case is not None:
            self._set_case(case)
        self.in_init = True
        self.t = float(start_time)
        #: the FMU's structure's own clock, the sum of its steps (a run-up's speeds follow it)
        self.clock = float(start_time)
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
        laws = law_input_names(train)
        journal = journal_output_names(train)
        extra = step_output_names(train)
        support = support_load_names(train)
        #: the train's names (the suffixes of the FMU's ports), in the layout's order
        self.bearing_names = bearing_names(train)
        self.mesh_names = mesh_names(train)
        self.gear_names = gear_names(train)
        self.n_bearings = len(self.bearing_names)
        self.n_meshes, self.n_gears = len(self.mesh_names), len(self.gear_names)
        nb = self.n_bearings
        n_laws = len(laws)
        self._n_laws = n_laws
        self._law_vr = (ctypes.c_uint * n_laws)(*[vr[n] for n in laws])
        self._law_val = (ctypes.c_double * n_laws)()
        self._law_np = np.frombuffer(self._law_val, dtype=np.float64)
        self._jr_vr = (ctypes.c_uint * (4 * nb))(*[vr[n] for n in journal])
        self._jr_val = (ctypes.c_double * (4 * nb))()
        self._jr_np = np.frombuffer(self._jr_val, dtype=np.float64)
        self._ex_vr = (ctypes.c_uint * len(extra))(*[vr[n] for n in extra])
        self._ex_val = (ctypes.c_double * len(extra))()
        self._ex_index = {n: i for i, n in enumerate(extra)}
        self._sup_vr = (ctypes.c_uint * (2 * nb))(*[vr[n] for n in support])
        self._sup_val = (ctypes.c_double * (2 * nb))()
        self._it_vr = (ctypes.c_uint * 1)(vr["iterations"])
        self._it_val = (ctypes.c_int * 1)()

    def bearing_speeds_after(self, dt: float):
        return None if self._bearing_speeds is None else self._bearing_speeds(self.clock + dt)

    def _carried_case(self):
        """The case the FMU carries (``resources/case.toml``)."""
        from fmu_src.case import load_case
        from fmu_src.slaves.gear_shaft import CASE_RESOURCE

        path = Path(self.slave._dir) / "resources" / CASE_RESOURCE
        if not path.is_file():
            raise FmuError(f"gear-shaft FMU ({self.slave.path.name}) carries no case "
                           f"(resources/{CASE_RESOURCE}): give the case it simulates")
        return load_case(path)

    def _check_train(self, case) -> None:
        """FmuError unless the FMU has the ports and parameters of ``case``'s gear train."""
        names = [*law_input_names(case), *journal_output_names(case),
                 *step_output_names(case), *support_load_names(case)]
        names += [n for n, _, _ in gear_parameters(case)]
        missing = [n for n in names if n not in self.slave.vr]
        if missing:
            raise FmuError(
                f"gear-shaft FMU ({self.slave.path.name}) was built for another gear train "
                f"than case {case['case.name']!r}: it lacks {', '.join(missing[:6])}"
                f"{' ...' if len(missing) > 6 else ''} (build it for the case: gsb build-fmus "
                "CASE, or orchestrator.coupling.fmi.ensure_fmus with the case)")

    def _set_case(self, case) -> None:
        """Set the case's structural fields as the FMU's parameters (one call per type)."""
        values = {name: value for name, _, value in gear_parameters(case)}
        self.slave.set(values, f"gear-shaft FMU, case {case['case.name']!r}")

    # --- errors -------------------------------------------------------------------------------
    def _fail(self, what: str, status: int | None = None, since: int = 0, where: bool = True):
        at = f" at t = {self.t:.9g} s (after step {self.n_steps})" if where else ""
        st = "" if status is None else f" (status {status_name(status)})"
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
        """Set the law inputs (14 per bearing) in one call: each law's expansion, as a bearing
        FMU's outputs (force, Kb, Cb and the journal state they belong to; global frame)."""
        self._live()
        pack_laws(laws, self._law_np)
        self._check(self._set_real(self._c, self._law_vr, self._n_laws, self._law_val),
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
        self.clock += dt
        self.n_steps += 1

    def compiled_block(self, t: float, dt: float, n: int, time_of):
        """The FMU's functions, value references and buffers for
        :func:`orchestrator.coupling.step.coupled_steps` (:mod:`orchestrator.coupling.fmi.steps`),
        steps k from ``time_of(k)`` [s]."""
        from orchestrator.coupling.fmi.calls import address

        self._live()
        if self.in_init:
            self.exit_initialization()
        times = np.array([time_of(k) for k in range(n)], dtype=float)
        gear = [address(f) for f in (self._set_real, self._get_real, self._do_step,
                                     self._get_state, self._set_state, self._free_state)]
        args = block_arguments([*gear, address(self._c)], self._law_vr, self._law_np,
                               self._jr_vr, self._jr_np, self._ex_vr,
                               np.frombuffer(self._ex_val, dtype=np.float64), times, dt)
        self._since = len(self.slave.messages)
        n_steps = self.n_steps

        def finish(count: int) -> None:
            if count:
                self.t, self.n_steps = float(times[count - 1] + dt), n_steps + count
                for _ in range(count):  # (summed as the FMU's structure sums its steps)
                    self.clock += dt

        return args, n, finish

    def raise_compiled_failure(self, k, code, d1, d2, d3, t, dt) -> None:
        """The FMU's error of the block's step ``k`` whose call ``code``
        (:mod:`orchestrator.coupling.fmi.steps`) returned the status ``d1``."""
        from orchestrator.coupling.fmi import steps as fs

        since = self._since
        if code in (fs.JOURNALS_FAILED, fs.JOURNALS_NOT_FINITE, fs.RESTORE_FAILED,
                    fs.OUTPUTS_FAILED):
            self.t, self.n_steps = t + dt, self.n_steps + 1  # after the doStep
            self.clock += dt
        what = {fs.GET_STATE_FAILED: "fmi2GetFMUstate", fs.LAWS_FAILED:
                "setting the bearing laws", fs.JOURNALS_FAILED: "reading the journal states",
                fs.RESTORE_FAILED: "fmi2SetFMUstate", fs.OUTPUTS_FAILED: "reading outputs"}
        if code == fs.STEP_FAILED:
            self._fail(f"doStep {self.n_steps + 1} from t = {t:.9g} s (dt = {dt:.6g} s) failed",
                       d1, since, where=False)
        if code == fs.JOURNALS_NOT_FINITE:
            self._fail("reading the journal states failed", since=since)
        self._fail(what.get(code, f"call {code}"), d1, since)

    def _read_journal(self, what: str) -> np.ndarray:
        since = len(self.slave.messages)
        self._check(self._get_real(self._c, self._jr_vr, len(self._jr_val), self._jr_val), what,
                    since)
        out = unpack_journal(self._jr_np).copy()
        if not all_finite(self._jr_val):
            self._fail(f"{what} failed", since=since)
        return out

    def journal_states(self) -> np.ndarray:
        """(nb, 4) [s, t, s_dot, t_dot] at the bearings, global frame [m, m/s]."""
        self._live()
        return self._read_journal("reading the journal states")

    def get_state(self) -> FmuState:
        """Save the FMU state (fmi2GetFMUstate); freed with the returned object."""
        self._live()
        handle = ctypes.c_void_p()
        self._check(self._get_state(self._c, ctypes.byref(handle)), "fmi2GetFMUstate")
        state = FmuState(self, handle, self.t, self.n_steps, self.clock)
        self._states.add(state)
        return state

    def set_state(self, state: FmuState) -> None:
        """Restore a state of :meth:`get_state` exactly (fmi2SetFMUstate)."""
        self._live()
        if state._owner is not self or state._handle is None:
            raise FmuError("set_state: the state is freed or belongs to another FMU instance")
        self._check(self._set_state(self._c, state._handle), "fmi2SetFMUstate")
        self.t, self.n_steps, self.clock = state.t, state.n_steps, state.clock

    def checkpoint(self) -> dict:
        """The FMU state serialised (fmi2SerializeFMUstate, ``fmu``: its bytes as uint8),
        with the time and step count (``t``, ``n_steps``)."""
        self._live()
        if not self.slave.can_serialize:
            raise FmuError(f"gear-shaft FMU ({self.slave.path.name}) cannot serialise its "
                           "state (canSerializeFMUstate is false)")
        return {"fmu": np.frombuffer(self.slave.serialize_state(), dtype=np.uint8),
                "t": np.float64(self.t), "n_steps": np.int64(self.n_steps),
                "clock": np.float64(self.clock)}

    def restore(self, checkpoint: StateArrays) -> None:
        """Continue from :meth:`checkpoint` arrays (fmi2DeSerializeFMUstate + fmi2SetFMUstate:
        the FMU checks its own state)."""
        self._live()
        blob, t, n_steps = checkpoint.bytes("fmu"), checkpoint.float("t"), checkpoint.int("n_steps")
        clock = checkpoint.float("clock") if checkpoint.has("clock") else t  # (earlier files)
        if self.in_init:
            self.exit_initialization()
        self.slave.restore_serialized(blob)
        self.t, self.n_steps, self.clock = t, n_steps, clock

    def _free_handle(self, handle) -> None:
        if self.slave.fmu is not None:
            self._free_state(self._c, ctypes.byref(handle))

    def support_loads(self) -> np.ndarray:
        """(nb, 2) static loads of the structure on stiff bearings [N] (calculated
        parameters)."""
        self._live()
        self._check(self._get_real(self._c, self._sup_vr, len(self._sup_val), self._sup_val),
                    "reading the support loads")
        out = np.frombuffer(self._sup_val, dtype=np.float64).reshape(-1, 2).copy()
        if not np.isfinite(out).all():
            self._fail("support loads failed")
        return out

    # --- other outputs ------------------------------------------------------------------------
    def outputs(self) -> dict:
        """The step outputs by name (:func:`fmu_src.contract.step_output_names`:
        ``mesh_force_<mesh>``, ``transmission_error_<mesh>``, ``u_<gear>``, ``v_<gear>``) in
        one fmi2GetReal."""
        return dict(zip(self._ex_index, self._read_outputs().tolist(), strict=True))

    def _read_outputs(self) -> np.ndarray:
        self._live()
        n = len(self._ex_val)
        self._check(self._get_real(self._c, self._ex_vr, n, self._ex_val), "reading outputs")
        return np.frombuffer(self._ex_val, dtype=np.float64).copy()

    def step_outputs(self):
        """Mesh forces [N], transmission errors [m] (n_meshes,) and the (n_gears, 2) [u, v] of
        the gear nodes [m] in one fmi2GetReal (the row of the compiled step)."""
        row = self._read_outputs()
        n = self.n_meshes
        return row[:n], row[n:2 * n], row[2 * n:].reshape(-1, 2)

    def mesh_forces(self) -> np.ndarray:
        """Total normal tooth load of each mesh [N]."""
        return self.step_outputs()[0]

    def transmission_errors(self) -> np.ndarray:
        """Transmission error of each mesh's gear nodes [m]."""
        return self.step_outputs()[1]

    def gear_displacements(self) -> np.ndarray:
        """(n_gears, 2) [u, v] of the gear nodes [m] (the in-process Structure gives all six
        DOFs per node; the FMU outputs these two)."""
        return self.step_outputs()[2]

    def iterations(self) -> int:
        """Newton/contact iterations of the last step or static solution."""
        self._live()
        self._check(self._get_integer(self._c, self._it_vr, 1, self._it_val),
                    "reading iterations")
        return int(self._it_val[0])

    def close(self) -> None:
        """Free every saved state, terminate and free the instance (idempotent)."""
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

