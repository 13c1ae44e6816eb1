"""The bearing FMUs behind the master's :class:`~orchestrator.coupling.master.BearingSet` interface.

Two kinds of bearing FMU are accepted, told apart by their variables:

* this package's bearing FMUs (:func:`fmu_src.contract.bearing_variables`): force, stiffness
  and damping are outputs;
* any algebraic FMU with the minimal contract (:data:`MINIMAL_INPUTS`, :data:`MINIMAL_OUTPUTS`:
  the journal state in, the film force out, global frame, SI units): the stiffness and damping
  are then central finite differences of its force (steps :data:`FD_STEP`). Of the parameters a
  case gives a bearing, those the FMU declares are set; an input ``omega`` gets the shaft speed.

Every call's status is checked; a failure raises
:class:`~orchestrator.coupling.fmi.instance.FmuError` with the FMU's log, naming the bearing
(``exc.bearing``: its name, ``exc.bearing_index``: its 0-based index in the set).
"""

from __future__ import annotations

import ctypes

import numpy as np

from fmu_src.contract import (
    DAMPING_NAMES,
    FORCE_NAMES,
    STATE_NAMES,
    STIFFNESS_NAMES,
    bearing_component,
)
from fmu_src.state_codec import StateArrays
from orchestrator.coupling.fmi.instance import FmuError, FmuInstance, all_finite, status_name
from orchestrator.coupling.master import BearingSet, PythonGroup

__all__ = ["MINIMAL_INPUTS", "MINIMAL_OUTPUTS", "FmuBearings", "group_arguments"]

#: what any bearing FMU must have: Real inputs (journal state, global frame [m, m/s]) ...
MINIMAL_INPUTS = STATE_NAMES
#: ... and Real outputs (film force on the journal, global frame [N])
MINIMAL_OUTPUTS = FORCE_NAMES
#: relative finite-difference steps for force-only FMUs: h = FD_STEP * C on positions and
#: FD_STEP * C * omega on velocities (central differences: truncation ~ FD_STEP^2, round-off
#: ~ eps / FD_STEP, both near 1e-10 of the stiffness)
FD_STEP = 1e-5


def group_arguments(calls, in_vr, out_vr) -> tuple:
    """The arguments of :func:`orchestrator.coupling.fmi.steps.fmu_bearing_group` for bearing
    FMUs: per FMU the addresses of its FMI functions ``calls``, its input and output value
    references, and the buffers of one exchange. With empty lists, their types without an FMU
    (:func:`orchestrator.coupling.step.bearing_slots`' placeholder)."""
    k = len(calls)

    def table(rows, dtype):
        return np.array(rows, dtype=dtype).reshape(k, len(rows[0]) if k else 0)

    return (table(calls, np.int64), table(in_vr, np.uint32), table(out_vr, np.uint32),
            np.empty((k, 4)), np.empty((k, 10)))


class FmuBearings(BearingSet):
    """Bearing FMUs, one instance per bearing, each of its own file (swap a model by naming
    another file).

    Parameters
    ----------
    fmus : sequence of path
        FMU file of each bearing (the layout's order).
    parameters : sequence of dict
        Parameter values of each bearing (names of :func:`fmu_src.contract.bearing_variables`).
        This package's FMUs must accept all of them; a force-only FMU gets those it declares.
    omegas : sequence of float
        Shaft speed magnitude at each bearing [rad/s].
    names : sequence of str, optional
        The bearings' names (messages, ``exc.bearing``; each instance is named
        :func:`fmu_src.contract.bearing_component` of it); default "1", "2", ...
    """

    _OUTPUTS = FORCE_NAMES + STIFFNESS_NAMES + DAMPING_NAMES

    def __init__(self, fmus, parameters, omegas, names=None):
        fmus, parameters = list(fmus), list(parameters)
        self.names = ([str(b + 1) for b in range(len(fmus))] if names is None
                      else [str(n) for n in names])
        if not (len(fmus) == len(parameters) == len(omegas) == len(self.names)):
            raise ValueError(f"FmuBearings: {len(fmus)} FMU files, {len(parameters)} "
                             f"parameter sets, {len(omegas)} speeds and {len(self.names)} "
                             "names: one of each per bearing")
        self.slaves = []
        self.force_only = []  # per bearing: stiffness and damping by finite differences
        self.clearances = []  # per bearing [m]: FD steps, the first guess's bound
        self._omegas = [float(w) for w in omegas]
        try:
            for b, (path, params) in enumerate(zip(fmus, parameters, strict=True)):
                who = f"bearing {self.names[b]}"
                s = FmuInstance(path, bearing_component(self.names[b]))
                self.slaves.append(s)
                self.force_only.append(self._check_contract(who, s))
                if not self.force_only[-1]:
                    unknown = sorted(set(params) - set(s.vr))
                    if unknown:
                        raise FmuError(f"{who} ({s.path.name}): unknown FMU parameters "
                                       f"{unknown}")
                s.fmu.setupExperiment(startTime=0.0)
                s.fmu.enterInitializationMode()
                s.set({k: v for k, v in params.items() if k in s.vr}, who)
                if "omega" in s.vr:
                    s.set({"omega": float(omegas[b])}, who)
                self.clearances.append(self._clearance(who, s, params))
        except BaseException:
            self.close()
            raise
        self.in_init = True
        self._in_vr = [(ctypes.c_uint * 4)(*[s.vr[n] for n in STATE_NAMES]) for s in self.slaves]
        self._out_vr = [(ctypes.c_uint * (2 if fo else 10))(
            *[s.vr[n] for n in (FORCE_NAMES if fo else self._OUTPUTS)])
            for s, fo in zip(self.slaves, self.force_only, strict=True)]
        # the laws of one evaluation, bearing by bearing in the FMUs' output order (force,
        # Kb, Cb: rows of ModelBearings.evaluate's (nb, 5, 2)), and each bearing's journal
        # state, read and written by the FMI calls in place (_exchange)
        nb = len(self.slaves)
        self._laws = (ctypes.c_double * (10 * nb))()
        self._laws_np = np.frombuffer(self._laws, dtype=np.float64).reshape(nb, 5, 2)
        self._states = (ctypes.c_double * (4 * nb))()
        self._states_np = np.frombuffer(self._states, dtype=np.float64).reshape(nb, 4)
        size = ctypes.sizeof(ctypes.c_double)
        self._calls = [(s.fmu.dll.fmi2SetReal, s.fmu.dll.fmi2GetReal, s.fmu.component)
                       for s in self.slaves]  # valid while self.slaves is (close empties it)
        self._law_at = [ctypes.cast(ctypes.addressof(self._laws) + 10 * size * b,
                                    ctypes.POINTER(ctypes.c_double)) for b in range(nb)]
        self._state_at = [ctypes.cast(ctypes.addressof(self._states) + 4 * size * b,
                                      ctypes.POINTER(ctypes.c_double)) for b in range(nb)]

    @staticmethod
    def _check_contract(who: str, s: FmuInstance) -> bool:
        """True for a force-only FMU; FmuError naming what is missing for anything else."""
        kinds = {v.name: (v.causality, v.type) for v in s.md.modelVariables}
        missing = [f"input {n}" for n in MINIMAL_INPUTS if kinds.get(n) != ("input", "Real")]
        missing += [f"output {n}" for n in MINIMAL_OUTPUTS if kinds.get(n) != ("output", "Real")]
        if missing:
            raise FmuError(f"{who} ({s.path.name}) lacks the minimal bearing "
                           f"contract: {', '.join(missing)} (docs/fmu-variables.md)")
        jac = STIFFNESS_NAMES + DAMPING_NAMES
        return not all(kinds.get(n) == ("output", "Real") for n in jac)

    def _failed(self, b: int, state, reason: str) -> FmuError:
        """The error of bearing ``b`` (0-based) failing at its global journal state (s, t,
        s_dot, t_dot) [m, m/s], carried as ``bearing`` (its name), ``bearing_index`` (b),
        ``state`` and ``reason`` for a run's message in units
        (:func:`orchestrator.run.runner.failure_text`)."""
        state = np.array(state, dtype=float)
        exc = FmuError(f"bearing {self.names[b]} ({self.slaves[b].path.name}) failed at state "
                       f"{state.tolist()}: {reason}")
        exc.bearing, exc.bearing_index = self.names[b], b
        exc.state, exc.reason = state, reason
        return exc

    def _call(self, b: int, s: FmuInstance, status: int, what: str, states) -> None:
        if status > 1:  # discard, error, fatal
            raise self._failed(b, states, f"{what} returned {status_name(status)}; FMU log: "
                                          f"{s.log_tail()}")

    def _exchange(self, b: int, s: FmuInstance, n: int) -> None:
        """Set the journal state of bearing b from its row of the state buffer, read its first
        ``n`` outputs into its row of the law buffer (FmuError on a failed call or a
        non-finite output)."""
        set_real, get_real, c = self._calls[b]
        state = self._states_np[b]
        self._call(b, s, set_real(c, self._in_vr[b], 4, self._state_at[b]), "fmi2SetReal",
                   state)
        self._call(b, s, get_real(c, self._out_vr[b], n, self._law_at[b]), "fmi2GetReal",
                   state)
        if not all_finite(self._laws[10 * b:10 * b + n]):
            raise self._failed(b, state, f"non-finite outputs; FMU log: {s.log_tail()}")

    def _force(self, b: int, s: FmuInstance, state, n: int) -> np.ndarray:
        """Set the journal state of bearing b, read its first ``n`` outputs."""
        self._states_np[b] = state
        self._exchange(b, s, n)
        return self._laws_np[b].reshape(10)[:n].copy()

    def _fd_jacobian(self, b: int, s: FmuInstance, state):
        """Kb = -dF/dX, Cb = -dF/dXdot of a force-only FMU by central differences (steps
        :data:`FD_STEP`), then the force at ``state`` itself (its evaluation state last)."""
        hx = FD_STEP * self.clearances[b]
        hv = hx * self._omegas[b]
        jac = np.empty((2, 4))
        for j, h in enumerate((hx, hx, hv, hv)):
            plus, minus = np.array(state, dtype=float), np.array(state, dtype=float)
            plus[j] += h
            minus[j] -= h
            jac[:, j] = -(self._force(b, s, plus, 2) - self._force(b, s, minus, 2)) / (2 * h)
        return self._force(b, s, state, 2), jac[:, :2], jac[:, 2:]

    @staticmethod
    def _clearance(who, s, params) -> float:
        """Radial clearance C [m] of bearing ``b``: the FMU's own value when it declares one
        (what the film uses), else the case's (a force-only FMU)."""
        if "C" in s.vr:
            return float(s.fmu.getReal([s.vr["C"]])[0])
        if "C" in params:
            return float(params["C"])
        raise FmuError(f"{who} ({s.path.name}): neither the FMU nor the case gives "
                       "the radial clearance C [m] (it scales the finite-difference steps and "
                       "bounds the first guess of X0)")

    def evaluate(self, states):
        if not self.slaves:
            raise FmuError("the bearing FMUs are closed")
        laws = self._laws_np
        self._states_np[:] = states
        for b, s in enumerate(self.slaves):
            if self.force_only[b]:
                laws[b, 0], laws[b, 1:3], laws[b, 3:5] = self._fd_jacobian(b, s, states[b])
            else:
                self._exchange(b, s, 10)
        self.evaluations += self.count
        out = laws.copy()
        return out[:, 0], out[:, 1:3], out[:, 3:5]

    @property
    def count(self) -> int:
        return len(self.slaves)

    def set_speeds(self, omegas) -> None:
        """Each bearing FMU's input ``omega`` [rad/s] from the next evaluation on (a run-up);
        :class:`~orchestrator.coupling.fmi.instance.FmuError` for an FMU without that input,
        which cannot follow one."""
        for b, (s, w) in enumerate(zip(self.slaves, omegas, strict=True)):
            who = f"bearing {self.names[b]}"
            if "omega" not in s.vr:
                raise FmuError(f"{who} ({s.path.name}): no input omega, so it cannot follow "
                               f"a varying speed (drive.speed_profile)")
            s.set({"omega": float(w)}, who)
            self._omegas[b] = float(w)

    def compiled_groups(self) -> tuple:
        """The bearing FMUs with the Jacobian outputs as one group called from compiled code
        (:func:`orchestrator.coupling.fmi.steps.fmu_bearing_group`), the force-only ones
        (finite differences) as a group called back in Python."""
        if not self.slaves:
            raise FmuError("the bearing FMUs are closed")
        from orchestrator.coupling.fmi.calls import address

        groups = []
        full = [b for b, fo in enumerate(self.force_only) if not fo]
        if full:
            groups.append((group_arguments([[address(f) for f in self._calls[b]] for b in full],
                                           [list(self._in_vr[b]) for b in full],
                                           [list(self._out_vr[b]) for b in full]),
                           np.array(full, dtype=np.int64)))
        partial = [b for b, fo in enumerate(self.force_only) if fo]
        if partial:
            if getattr(self, "_python", None) is None:
                self._python = PythonGroup(self._evaluate_force_only, partial)
            groups.append(self._python.arguments())
        return tuple(groups)

    def _evaluate_force_only(self, index, states, out) -> None:
        for g, b in enumerate(index):
            try:
                out[g, 0], out[g, 1:3], out[g, 3:5] = self._fd_jacobian(b, self.slaves[b],
                                                                         states[g])
            except FmuError as exc:
                exc.bearing_index = int(b)
                raise

    def raise_failure(self, b, status, states) -> None:
        """The error of bearing FMU ``b`` whose call (``status // 8``: fmi2SetReal,
        fmi2GetReal, non-finite outputs) failed with the fmi2Status ``status % 8``."""
        python = getattr(self, "_python", None)
        if python is not None and python.error is not None:
            exc, python.error = python.error, None
            raise exc
        s = self.slaves[b]
        which, fmi_status = divmod(int(status), 8)
        if which == 3:
            raise self._failed(b, states[b], f"non-finite outputs; FMU log: {s.log_tail()}")
        what = "fmi2SetReal" if which == 1 else "fmi2GetReal"
        raise self._failed(b, states[b], f"{what} returned {status_name(fmi_status)}; FMU "
                                         f"log: {s.log_tail()}")

    def exit_initialization(self) -> None:
        """Leave initialisation mode (the linear FMU freezes its coefficients here)."""
        for b, s in enumerate(self.slaves):
            f = s.fmu
            since = len(s.messages)
            status = f.dll.fmi2ExitInitializationMode(f.component)
            if status > 1 or s.errors_since(since):
                raise FmuError(f"bearing {self.names[b]} ({s.path.name}): "
                               "fmi2ExitInitializationMode "
                               f"returned {status_name(status)}; FMU log: "
                               f"{s.log_tail(since=since)}")
        self.in_init = False

    def checkpoint(self) -> dict:
        """Each bearing FMU's state serialised (its solver's warm start), ``<b>/fmu`` its
        bytes as uint8; nothing for an FMU that cannot serialise (a force-only FMU of the
        user's own: assumed memoryless)."""
        return {f"{b}/fmu": np.frombuffer(s.serialize_state(), dtype=np.uint8)
                for b, s in enumerate(self.slaves) if s.can_serialize}

    def restore(self, checkpoint: StateArrays) -> None:
        blobs = [checkpoint.bytes(f"{b}/fmu") if s.can_serialize else None
                 for b, s in enumerate(self.slaves)]
        for s, data in zip(self.slaves, blobs, strict=True):
            if data is not None:
                s.restore_serialized(data)

    def close(self) -> None:
        """Terminate and free every instance, remove the extracted FMU folders."""
        for s in self.slaves:
            s.close()
        self.slaves = []
        python = getattr(self, "_python", None)
        if python is not None:
            python.close()
            self._python = None

