"""The master algorithm: Newton on the coupled structure-bearing system through the slaves.

The structure slave owns (X, Xdot, Xddot) and advances one Newmark step for given affine
bearing laws ``F = F0 - Kb X - Cb Xdot`` (global frame, one per bearing). The bearing slaves
are algebraic: journal state -> film force, Kb, Cb. A coupled step is defined once, compiled,
for every transport (:mod:`orchestrator.coupling.step`; docs/design.md section 4): the
structure steps with the laws linearised at the last iterate, the bearings are evaluated at
its journal states, and the step is accepted when their forces match the laws to ``tol``,
else taken again from the same state with the laws linearised there. :class:`Master` holds
the laws and the counters and hands its steps, a block at a time, to its ``stepper``
(:class:`orchestrator.coupling.step.CoupledSteps`, which
:func:`orchestrator.coupling.system.build_master` gives it).

The static solution X0 is the same iteration with the structure's static solve and the
velocities zero (:meth:`Master.solve_static`). Its first linearisation point comes from a
per-bearing static equilibrium under the loads a stiff support would carry (so no iterate
starts outside the clearance), solved by :meth:`BearingSet.static_position` through the
bearings' own ``evaluate``, the same calls whatever the transport.

The slaves are reached only through :class:`StructureSlave` and :class:`BearingSet`, which
declare everything the master and the runner use; :mod:`orchestrator.coupling.inprocess` (the
physics objects directly) and :mod:`orchestrator.coupling.fmi` (the FMUs through fmpy)
implement them.
"""

from __future__ import annotations

import itertools
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from bearing_fmu.affine import AffineLaws
from bearing_fmu.blas_threads import one_blas_thread
from bearing_fmu.static import newton_equilibrium
from fmu_src.state_codec import StateArrays, decode, encode, nest
from fmu_src.states import laws_arrays, laws_from_arrays

__all__ = [
    "CHECKPOINT_KIND",
    "SUBSTEPS",
    "BearingSet",
    "CouplingError",
    "Master",
    "NotConvergedError",
    "PythonGroup",
    "PythonStructure",
    "StepReport",
    "StructureSlave",
    "decode_checkpoint",
]

#: the kind tag of :meth:`Master.checkpoint` states (:mod:`fmu_src.state_codec`)
CHECKPOINT_KIND = "gsb.master_checkpoint"
#: the last resort for a step whose coupled iteration does not converge
#: (:class:`NotConvergedError`): taken again from its start as 2, then 4, then 8 equal
#: sub-steps (the floor: dt / 8). A shorter step shrinks the bearings' share of the
#: interface's Jacobian (the film's damping enters as Cb gamma / (beta dt), the structure's
#: mass as M / (beta dt^2)), which is what the iteration lacks at a kink or near an unloaded
#: film (docs/design.md section 4); the step's row is the last sub-step's.
SUBSTEPS = (2, 4, 8)


#: the Python evaluations of the bearing groups without a compiled form, by key
_PYTHON_GROUPS: dict = {}
_KEYS = itertools.count(1)


class PythonGroup:
    """Bearings evaluated in Python from the compiled coupled step (numba's object mode,
    :func:`orchestrator.coupling.step.evaluate_set`), a few microseconds per call:
    ``evaluate(indices, states, out)`` evaluates the set's bearings ``indices`` at their
    states (k, 4) into their rows (k, 5, 2). An exception is kept in ``error`` (the
    compiled loop returns the group's failed bearing, ``bearing_index`` on the exception, for
    the set to raise it). Registered while the set lives (``close()``)."""

    def __init__(self, evaluate, indices):
        self._evaluate = evaluate
        self.indices = np.ascontiguousarray(indices, dtype=np.int64)
        self.error: BaseException | None = None
        self.key = next(_KEYS)
        _PYTHON_GROUPS[self.key] = self

    def arguments(self) -> tuple:
        """The group of :func:`orchestrator.coupling.step.evaluate_set`."""
        return ((np.int64(self.key),), self.indices)

    def close(self) -> None:
        _PYTHON_GROUPS.pop(self.key, None)


def python_evaluate(key, states, out) -> int:
    """The compiled loop's call back into a :class:`PythonGroup`: -1, or the group's failed
    bearing (its error kept)."""
    group = _PYTHON_GROUPS[int(key)]
    group.error = None
    try:
        group._evaluate(group.indices, states, out)
    except Exception as exc:  # raised by the set with the block's rows (BearingSet.raise_failure)
        group.error = exc
        at = getattr(exc, "bearing_index", None)
        return int(np.flatnonzero(group.indices == at)[0]) if at in group.indices else 0
    return -1


#: the Python structures called back from the compiled coupled step, by key
_PYTHON_STRUCTURES: dict = {}


class PythonStructure:
    """A structure slave stepped from the compiled coupled step through call-backs into
    Python (numba's object mode; :meth:`StructureSlave.compiled_block`'s default): the
    operations of :mod:`orchestrator.coupling.step` on the slave's own methods, step k from
    ``times[k]`` [s]. An exception is kept in ``error`` (the compiled loop gets a failure
    code, the slave raises it)."""

    def __init__(self, slave, times, dt: float):
        self.slave = slave
        self.times = times
        self.dt = dt
        self.saved = None
        self.error: BaseException | None = None
        self.key = next(_KEYS)
        _PYTHON_STRUCTURES[self.key] = self

    def arguments(self) -> tuple:
        """The structure's arguments of :func:`orchestrator.coupling.step.coupled_steps`."""
        return (np.array([self.key], dtype=np.int64),)

    def close(self) -> None:
        _PYTHON_STRUCTURES.pop(self.key, None)
        self.saved = None

    def call(self, op: int, i: int, laws, out) -> int:
        """Operation ``op`` (0 begin, 1 solve, 2 retry, 3 accept, 4 end) of step ``i``: the
        laws ``(f0, kb, cb, x0, force0, expanded)`` of a solve, ``out`` its journal states or
        an accepted step's outputs. Returns 0, or 1 with the exception kept."""
        s = self.slave
        try:
            if op == 0:
                self.saved = s.get_state()
            elif op == 1:
                f0, kb, cb, x0, force0, expanded = laws
                s.set_bearing_laws(AffineLaws(f0.copy(), kb.copy(), cb.copy(),
                                              x0.copy() if expanded else None,
                                              force0.copy() if expanded else None))
                s.do_step(self.times[i], self.dt)
                out[:] = s.journal_states()
            elif op == 2:
                s.set_state(self.saved)
            elif op == 3:
                mesh, te, gear = s.step_outputs()
                out[:] = np.concatenate([np.ravel(mesh), np.ravel(te), np.ravel(gear)])
            else:
                self.saved = None
        except Exception as exc:  # raised by the slave with the block's rows
            self.error = exc
            return 1
        return 0


def python_structure_call(key, op, i, f0, kb, cb, x0, force0, expanded, out) -> int:
    """The compiled loop's call back into a :class:`PythonStructure`."""
    laws = (f0, kb, cb, x0, force0, bool(expanded))
    return _PYTHON_STRUCTURES[int(key)].call(int(op), int(i), laws, out)


class CouplingError(RuntimeError):
    """The coupled iteration did not converge (step, time and mismatch in the message)."""


class NotConvergedError(CouplingError):
    """A step whose coupled iteration ran out of iterations with the mismatch above ``tol``
    (every slave's own solve succeeded): the case :data:`SUBSTEPS` retries."""


class StructureSlave(ABC):
    """What the master and the runner need from the gear-shaft slave (in-process or FMU).

    Life cycle: laws + :meth:`solve_static` (repeated: the static iteration), then
    :meth:`exit_initialization` once, then blocks of coupled steps (:meth:`compiled_block`),
    then :meth:`close`.
    """

    #: bearings, meshes and gears of the train (the layout's)
    n_bearings: int
    n_meshes: int
    n_gears: int
    #: the in-process physics object (:class:`gear_fmu.structure.Structure`) where there is
    #: one, so that checks reuse its damping instead of building it again; None through FMUs
    physics = None

    @property
    def output_width(self) -> int:
        """What a step outputs (:meth:`step_outputs`): the mesh forces, the transmission
        errors, u and v of every gear's node."""
        return 2 * self.n_meshes + 2 * self.n_gears

    def bearing_speeds_after(self, dt: float):
        """The shaft speed at each bearing [rad/s] at the end of the next step of ``dt`` [s]
        in a run-up, on the structure's own clock (the sum of its steps, which its meshes'
        angles and loads follow; the bearings follow it:
        :meth:`orchestrator.coupling.master.BearingSet.set_speeds`); None at constant
        speed."""
        return None

    @abstractmethod
    def get_state(self):
        """An opaque copy of everything a step changes."""

    @abstractmethod
    def set_state(self, state) -> None:
        """Restore a state from :meth:`get_state`."""

    @abstractmethod
    def set_bearing_laws(self, laws: AffineLaws) -> None:
        """The affine laws (Eq. 17, global frame) used by the next step or static solve."""

    @abstractmethod
    def do_step(self, t: float, dt: float) -> None:
        """One Newmark step from t to t + dt with the current laws (no coupling iteration:
        a non-iterative master's step); raises on non-convergence."""

    def compiled_block(self, t: float, dt: float, n: int, time_of):
        """The structure's arguments of up to ``n`` coupled steps of dt from t [s]
        (:func:`orchestrator.coupling.step.coupled_steps`; step k from ``time_of(k)`` [s]):
        ``(arguments, m, finish)``, m <= n the steps they plan, ``finish(count)`` to call
        after the call with the number of accepted steps (the slave takes their state).

        By default the compiled loop calls this slave back in Python (:class:`PythonStructure`:
        :meth:`get_state`, :meth:`set_bearing_laws`, :meth:`do_step`, :meth:`journal_states`,
        :meth:`set_state`, :meth:`step_outputs`), a few microseconds per call: a structure of
        the user's own, or a test's; the in-process structure and the gear-shaft FMU give
        their compiled form."""
        callback = PythonStructure(self, [time_of(k) for k in range(n)], dt)
        self._callback = callback
        return callback.arguments(), n, lambda count: callback.close()

    def raise_compiled_failure(self, k: int, code: int, d1: int, d2: int, d3: int, t: float,
                               dt: float) -> None:
        """Raise the error of the block's step ``k`` from t [s] whose structure operation
        returned ``code`` with details ``d1, d2, d3`` (the transport's; by default the
        exception the Python call-back kept)."""
        callback = getattr(self, "_callback", None)
        if callback is not None and callback.error is not None:
            raise callback.error
        raise RuntimeError(f"structure step {k} from t = {t!r} s failed (code {code})")

    @abstractmethod
    def solve_static(self) -> None:
        """Static solution with the current laws (velocities and accelerations zero)."""

    @abstractmethod
    def exit_initialization(self) -> None:
        """End of the static phase: the static solution becomes the initial state and the
        modal damping is built on the modes with the symmetric part of the current Kb laws."""

    @abstractmethod
    def journal_states(self) -> np.ndarray:
        """(nb, 4) journal displacement and velocity at the bearing nodes, global frame."""

    @abstractmethod
    def support_loads(self) -> np.ndarray:
        """(nb, 2) static loads on the journals with a stiff support [N] (first guess)."""

    @abstractmethod
    def step_outputs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What the runner records of the current state: each mesh's total normal force [N],
        each mesh's transmission error r_b1 theta_1 + r_b2 theta_2 [m], and (n_gears, 2)
        u, v of each gear's node [m] (global frame)."""

    def checkpoint(self) -> dict:
        """The state after the last accepted step as flat arrays (name -> numpy array,
        :mod:`fmu_src.state_codec`), from which :meth:`restore` continues bit for bit in
        another process (resumed runs)."""
        raise NotImplementedError(f"{type(self).__name__} cannot save its state")

    def restore(self, checkpoint: StateArrays) -> None:
        """Continue from the arrays of a :meth:`checkpoint` (after the same static solution);
        :class:`~fmu_src.state_codec.StateFormatError` for arrays that do not fit."""
        raise NotImplementedError(f"{type(self).__name__} cannot restore a state")

    def close(self) -> None:  # noqa: B027 - optional: nothing to release by default
        """Release what the slave holds (FMU instances, files); idempotent."""


class BearingSet(ABC):
    """What the master and the runner need from the bearing slaves (in-process or FMUs)."""

    #: film-force evaluations of single bearings so far
    evaluations: int = 0

    @abstractmethod
    def evaluate(self, states: np.ndarray):
        """Film force (nb, 2), Kb (nb, 2, 2), Cb (nb, 2, 2) at journal states (nb, 4)."""

    def set_speeds(self, omegas) -> None:
        """The shaft speed at each bearing [rad/s] from the next evaluation on (a run-up,
        :meth:`orchestrator.coupling.master.StructureSlave.bearing_speeds_after`); a set whose
        speed is fixed cannot follow one."""
        raise NotImplementedError(f"{type(self).__name__}: the bearings' speed is fixed; it "
                                  f"cannot follow a varying speed (drive.speed_profile)")

    @property
    def count(self) -> int:
        """The number of bearings."""
        return len(self.clearances)

    def compiled_groups(self) -> tuple:
        """The bearings as groups of one kind each for the compiled loop
        (:func:`orchestrator.coupling.step.evaluate_set`): ``((arguments, indices), ...)``.
        By default one group called back in Python
        (:class:`orchestrator.coupling.master.PythonGroup`) through
        :meth:`evaluate`; the in-process models and the bearing FMUs give compiled groups."""
        group = getattr(self, "_default_group", None)
        if group is None:
            group = self._default_group = PythonGroup(self._evaluate_rows, range(self.count))
        return (group.arguments(),)

    def _evaluate_rows(self, index, states, out) -> None:
        force, kb, cb = self.evaluate(states)
        out[:, 0], out[:, 1:3], out[:, 3:5] = force, kb, cb

    def raise_failure(self, b: int, status: int, states: np.ndarray) -> None:
        """Raise the error of bearing ``b`` (0-based) whose group returned ``status`` at the
        journal states ``states`` (nb, 4) in the compiled loop (by default the exception the
        Python call-back kept)."""
        group = getattr(self, "_default_group", None)
        if group is not None and group.error is not None:
            exc, group.error = group.error, None
            raise exc
        raise RuntimeError(f"bearing {b + 1}: status {status} without an error")

    def record_states(self, states) -> None:  # noqa: B027 - optional
        """The journal states (nb, 4) [m, m/s] the compiled loop evaluated the set at last."""

    #: (nb,) radial clearance of each bearing [m] (bounds the first guess of X0)
    clearances: np.ndarray

    def static_position(self, loads: np.ndarray) -> np.ndarray:
        """(nb, 2) journal positions [m] balancing static loads (nb, 2) [N]: the first guess
        of X0.

        One Newton per journal from the centre, kept inside 0.95 C, every iterate evaluating
        the whole set (:func:`bearing_fmu.static.newton_equilibrium`). It is written once,
        here, for every transport: a bearing with memory (the hybrid solver's warm start)
        remembers the sequence of states it was evaluated at, so in-process and FMU runs give
        the same bits only if they evaluate the same sequence."""
        loads = np.asarray(loads, dtype=float)
        states = np.zeros((len(loads), 4))

        def law(x):
            states[:, :2] = x
            force, kb, _ = self.evaluate(states)
            return force, kb, None

        positions, _, _ = newton_equilibrium(
            law, loads, np.zeros_like(loads), 0.95 * np.asarray(self.clearances, dtype=float),
            tol=1e-10, maxit=100, what="(bearings' first guess of X0)")
        return positions

    @abstractmethod
    def exit_initialization(self) -> None:
        """End of the static phase (at the journal states of the last evaluation): the linear
        model freezes its coefficients there."""

    def checkpoint(self) -> dict:
        """What the bearings remember between calls (the solvers' warm starts) as flat arrays
        (:mod:`fmu_src.state_codec`); empty for memoryless bearings."""
        return {}

    def restore(self, checkpoint: StateArrays) -> None:  # noqa: B027 - memoryless by default
        """Restore the arrays of a :meth:`checkpoint`."""

    def close(self) -> None:  # noqa: B027 - optional: nothing to release by default
        """Release what the set holds (FMU instances); idempotent."""


@dataclass
class StepReport:
    """Outcome of one coupled step (or of the static solution)."""

    iterations: int
    mismatch: float  # relative force mismatch at acceptance
    bearing_force: np.ndarray  # (nb, 2) N
    laws: AffineLaws = field(repr=False)
    states: np.ndarray = field(default=None, repr=False)  # (nb, 4) accepted journal states


@dataclass
class Master:
    """Couple a structure slave with a bearing set.

    Parameters
    ----------
    structure : StructureSlave
    bearings : BearingSet
    tol : float
        Convergence limit l on ``||F_bearing(X) - F_law(X)|| / ||F_bearing(X)||`` (paper 1e-5).
    max_iterations : int
        Outer iterations per step before :class:`CouplingError`.
    """

    structure: StructureSlave
    bearings: BearingSet
    tol: float = 1e-5
    max_iterations: int = 30
    laws: AffineLaws | None = None
    total_iterations: int = 0
    total_bearing_evaluations: int = 0
    relaxed_steps: int = 0  # steps that needed the relaxation (orchestrator.coupling.step)
    #: the steps taken in sub-steps (:data:`SUBSTEPS`): (t [s], sub-steps) of each
    substepped: list = field(default_factory=list)
    #: takes blocks of coupled steps: ``stepper.block(master, t, dt, n, time_of)``
    #: (:class:`orchestrator.coupling.step.CoupledSteps`, given by
    #: :func:`orchestrator.coupling.system.build_master`)
    stepper: object = field(default=None, repr=False)

    def _evaluate(self, states):
        self.total_bearing_evaluations += 1
        return self.bearings.evaluate(states)

    def first_guess(self, loads: np.ndarray | None = None) -> np.ndarray:
        """(nb, 4) journal states of the first linearisation of X0 (module docstring): the
        bearings' equilibrium (:meth:`BearingSet.static_position`) under ``loads`` (nb, 2) [N],
        by default the structure's loads on stiff supports
        (:meth:`StructureSlave.support_loads`), which do not depend on the bearings: a caller
        solving one structure with several bearing sets computes them once."""
        if loads is None:
            loads = self.structure.support_loads()
        positions = self.bearings.static_position(loads)
        return np.hstack([positions, np.zeros_like(positions)])

    @one_blas_thread
    def solve_static(self, initial_states: np.ndarray | None = None) -> StepReport:
        """X0: iterate structure static solves and bearing linearisations (Sec. 2.2.3), from
        ``initial_states`` (default :meth:`first_guess`)."""
        if initial_states is None:
            initial_states = self.first_guess()
        states = np.array(initial_states, dtype=float)
        states[:, 2:] = 0.0
        force, kb, cb = self._evaluate(states)
        laws = AffineLaws.linearise(states, force, kb, cb)
        for it in range(1, self.max_iterations + 1):
            self.structure.set_bearing_laws(laws)
            self.structure.solve_static()
            states = self.structure.journal_states().copy()
            states[:, 2:] = 0.0
            force, kb, cb = self._evaluate(states)
            mismatch, laws = laws.relinearise(states, force, kb, cb)
            if mismatch <= self.tol:
                # leave the structure on the converged solution with the final laws
                self.structure.set_bearing_laws(laws)
                self.laws = laws
                return StepReport(it, mismatch, force, laws, states)
        raise CouplingError(
            f"static solution did not converge in {self.max_iterations} iterations: "
            f"relative bearing-force mismatch {mismatch:.3e} > tol {self.tol:.1e}"
        )

    @one_blas_thread
    def exit_initialization(self) -> None:
        """End the static phase of both slaves (linear bearings freeze, the structure builds
        its modal damping with the bearings' static stiffness)."""
        self.bearings.exit_initialization()
        self.structure.exit_initialization()

    def checkpoint(self) -> bytes:
        """The coupled state after the last accepted step (structure, bearing warm starts,
        the laws the next step starts from) as bytes: :meth:`restore` on a master built from
        the same case, after the same static solution, continues bit for bit.

        The bytes are a state of kind :data:`CHECKPOINT_KIND` (:mod:`fmu_src.state_codec`:
        numeric arrays in an npz archive, never a pickle): ``structure/...``,
        ``bearings/...`` (each slave's :meth:`StructureSlave.checkpoint` and
        :meth:`BearingSet.checkpoint`) and ``laws/...`` (:func:`fmu_src.states.laws_arrays`).
        """
        return encode(CHECKPOINT_KIND, nest("structure", self.structure.checkpoint())
                      | nest("bearings", self.bearings.checkpoint())
                      | nest("laws", laws_arrays(self.laws)))

    def restore(self, checkpoint: bytes) -> None:
        """Continue from :meth:`checkpoint` bytes; a
        :class:`~fmu_src.state_codec.StateFormatError` names what is wrong with bytes that are
        not such a checkpoint (:func:`decode_checkpoint`) or do not fit this master."""
        arrays = decode_checkpoint(checkpoint)
        laws = laws_from_arrays(arrays.sub("laws"), self.structure.n_bearings)
        self.structure.restore(arrays.sub("structure"))
        self.bearings.restore(arrays.sub("bearings"))
        arrays.check_all_read()
        self.laws = laws

    def close(self) -> None:
        """Release both slaves (FMU instances; nothing in-process); idempotent."""
        try:
            self.bearings.close()
        finally:
            self.structure.close()

    def _block(self, t: float, dt: float, n: int, time_of):
        if self.laws is None:
            raise CouplingError("call solve_static() (or set laws) before the first step")
        if self.stepper is None:
            raise CouplingError("the master has no stepper (build it with "
                                "orchestrator.coupling.system.build_master)")
        block = self.stepper.block(self, t, dt, n, time_of)
        if isinstance(block.error, NotConvergedError):
            block = self._in_substeps(block, dt, time_of)
        return block

    def _in_substeps(self, block, dt: float, time_of):
        """``block``, whose step ``block.count`` did not converge, with that step taken again
        from its start in :data:`SUBSTEPS` sub-steps (the first count that converges): the
        rows before it and the last sub-step's; its iterations those of all its sub-steps.
        If none converges, the state and ``block`` as they were, the error saying so."""
        t = time_of(block.count)
        try:
            saved = self.checkpoint()
        except NotImplementedError as exc:  # a slave of the user's own, without states
            block.error = NotConvergedError(f"{block.error}; not retried in sub-steps: {exc}")
            return block
        for m in SUBSTEPS:
            self.restore(saved)
            h, done, iterations, last = dt / m, 0, 0, None
            while done < m:
                sub = self.stepper.block(self, t + done * h, h, m - done,
                                         lambda j, first=done, h=h: t + (first + j) * h)
                done += sub.count
                iterations += int(sub.iterations.sum())
                last = sub if sub.count else last
                if sub.error is not None:
                    break
            if done == m:
                self.substepped.append((t, m))
                return _joined(block, last, iterations)
        self.restore(saved)
        block.error = NotConvergedError(f"{block.error}; nor in {', '.join(map(str, SUBSTEPS))}"
                                        f" sub-steps ({sub.error})")
        return block

    @one_blas_thread
    def step(self, t: float, dt: float) -> StepReport:
        """One coupled Newmark step from t to t + dt (:mod:`orchestrator.coupling.step`):
        its report, or the error of a step that failed."""
        block = self._block(t, dt, 1, lambda k: t)
        if block.error is not None:
            raise block.error
        return StepReport(int(block.iterations[0]), block.mismatch, block.bearing_force[0],
                          self.laws, block.states[0])

    @one_blas_thread
    def steps(self, first: int, dt: float, n: int):
        """Up to ``n`` steps of dt from step ``first`` (t = first dt [s]) in one compiled call:
        a :class:`orchestrator.coupling.step.StepBlock` of the steps taken (fewer than ``n``
        when the structure plans fewer at once) and the error of a step that failed (the
        steps before it taken)."""
        return self._block(first * dt, dt, n, lambda k: (first + k) * dt)

    @one_blas_thread
    def steps_from(self, t: float, dt: float, n: int):
        """:meth:`steps` from the time ``t`` [s] (the structure's) for a caller whose times
        are not whole multiples of dt (an FMU's communication steps cut into equal steps):
        the messages of a failed step k give t + k dt."""
        return self._block(t, dt, n, lambda k: t + k * dt)


def _joined(block, last, iterations: int):
    """``block``'s rows and the row of ``last`` (a block ending where ``block``'s failed step
    ends) as one block of ``block.count + 1`` steps, without an error."""
    def rows(a, b):
        return np.concatenate([a[:block.count], b[-1:]])

    block.states = rows(block.states, last.states)
    block.bearing_force = rows(block.bearing_force, last.bearing_force)
    block.mesh_force = rows(block.mesh_force, last.mesh_force)
    block.transmission_error = rows(block.transmission_error, last.transmission_error)
    block.gear_nodes = rows(block.gear_nodes, last.gear_nodes)
    block.iterations = np.concatenate([block.iterations[:block.count],
                                       np.array([iterations], dtype=block.iterations.dtype)])
    block.count += 1
    block.mismatch = last.mismatch
    block.error = None
    return block


def not_converged(t, dt, max_iterations, mismatch, tol) -> str:
    """The message of a step from t [s] that did not converge."""
    return (f"step at t = {t:.6e} s (dt = {dt:.3e} s) did not converge in {max_iterations} "
            f"iterations: relative bearing-force mismatch {mismatch:.3e} > tol {tol:.1e}")


def decode_checkpoint(data, what: str = "the checkpoint") -> StateArrays:
    """The arrays of :meth:`Master.checkpoint` bytes; a
    :class:`~fmu_src.state_codec.StateFormatError` starting with ``what`` for anything else
    (a pickle, another format, version or kind): what a resumed run checks before it starts."""
    return decode(data, CHECKPOINT_KIND, what)
