"""The master algorithm: Newton on the coupled structure-bearing system through the slaves.

The structure slave owns (X, Xdot, Xddot) and advances one Newmark step for given affine
bearing laws ``F = F0 - Kb X - Cb Xdot`` (global frame, one per bearing). The bearing slaves
are algebraic: journal state -> film force, Kb, Cb. One coupled step (docs/design.md section 4):

1. save the structure state;
2. set the affine laws linearised at the last iterate; ``do_step``;
3. read the journal states, evaluate the bearings there;
4. if the film forces differ from the affine laws by more than ``tol`` (relative to the force
   norm), re-linearise at the new iterate, restore the saved state and repeat; else accept.

The structure's own Newton/contact loop converges the rest of the system exactly for each law,
and the law is the exact linearisation of the bearings at the current iterate (Eq. 14, 16), so
the outer loop is Newton-Raphson on the bearing nonlinearity: a converged co-simulated step is
the monolithic step to ``tol``, and an affine bearing (linear, lumped) converges in one pass.

A bearing force can be continuous with a slope that jumps: the hybrid model's is where a node
of its film enters or leaves the pressurised zone. Near such a kink Newton can fall into a
two-cycle between iterates on either side (the paper's case at 300, 400, 800 and 900 rad/s:
the mismatch alternating between two values above ``tol`` until the step fails). When the
mismatch has not halved over two iterations, the rest of the step is relaxed: each new law is
the mean of the linearisation at the new iterate and the law just used
(:data:`RELAXATION`). The acceptance test is unchanged (the law used against the bearings at
the new iterate), so a relaxed step is still the monolithic step to ``tol``.

The static solution X0 is the same iteration with the structure's static solve and the
velocities zero. Its first linearisation point comes from a per-bearing static equilibrium
under the loads a stiff support would carry (so no iterate starts outside the clearance),
solved by :meth:`BearingSet.static_position` through the bearings' own ``evaluate``, the same
calls whatever the transport.

The slaves are reached only through :class:`StructureSlave` and :class:`BearingSet`, which
declare everything the master and the runner use; :mod:`orchestrator.coupling.inprocess` (the
physics objects directly) and :mod:`orchestrator.coupling.fmi` (the FMUs through fmpy)
implement them. In-process, with hybrid or linear bearings, :meth:`Master.step` hands the
whole iteration to one compiled call (:mod:`orchestrator.coupling.fused`, the ``fused``
attribute that :func:`orchestrator.coupling.system.build_master` sets): the same kernels in
the same order, so the same bits as the loop below, which stays the reference and serves the
FMUs and the other bearing models.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from bearing_fmu.affine import AffineLaws
from bearing_fmu.blas_threads import one_blas_thread
from bearing_fmu.static import newton_equilibrium
from fmu_src.state_codec import StateArrays, decode, encode, nest
from fmu_src.states import laws_arrays, laws_from_arrays

__all__ = [
    "CHECKPOINT_KIND",
    "BearingSet",
    "CompiledSteps",
    "CouplingError",
    "Master",
    "StepBlock",
    "StepReport",
    "StructureSlave",
    "decode_checkpoint",
    "relaxed_law",
]

#: weight of the new linearisation in a relaxed iteration (module docstring): the law used next
#: is ``RELAXATION * new + (1 - RELAXATION) * last used``
RELAXATION = 0.5
#: a step is relaxed from the iteration whose mismatch exceeds STALL times the one two
#: iterations earlier (Newton's mismatch falls quadratically; a two-cycle's repeats)
STALL = 0.5
#: the kind tag of :meth:`Master.checkpoint` states (:mod:`fmu_src.state_codec`)
CHECKPOINT_KIND = "gsb.master_checkpoint"


@njit(cache=True)
def relaxed_law(it, mismatch, mismatches, relaxed, stall, relaxation, f0_new, kb_new, cb_new,
                f0, kb, cb):
    """:meth:`Master.step`'s rule after iteration ``it`` (1-based) of a step, for the compiled
    steps (:class:`CompiledSteps`): its ``mismatch`` goes into ``mismatches[it - 1]``; the step
    is relaxed from the iteration whose mismatch exceeds ``stall`` times the one two iterations
    earlier (or stays so); the next law is the new linearisation ``f0_new, kb_new, cb_new``,
    or once relaxed :meth:`bearing_fmu.affine.AffineLaws.blend` of it with the law used
    ``f0, kb, cb`` (weight ``relaxation``), in its order. Returns ``(relaxed, f0, kb, cb)``."""
    mismatches[it - 1] = mismatch
    if not relaxed and it >= 3 and mismatch > stall * mismatches[it - 3]:
        relaxed = True
    if not relaxed:
        return relaxed, f0_new, kb_new, cb_new
    r = 1.0 - relaxation
    return (relaxed, relaxation * f0_new + r * f0, relaxation * kb_new + r * kb,
            relaxation * cb_new + r * cb)


class CouplingError(RuntimeError):
    """The coupled iteration did not converge (step, time and mismatch in the message)."""


class StructureSlave(ABC):
    """What the master and the runner need from the gear-shaft slave (in-process or FMU).

    Life cycle: laws + :meth:`solve_static` (repeated: the static iteration), then
    :meth:`exit_initialization` once, then :meth:`do_step` with :meth:`get_state` /
    :meth:`set_state` around it (rollback), then :meth:`close`.
    """

    n_bearings: int
    #: the in-process physics object (:class:`gear_fmu.structure.Structure`) where there is
    #: one, so that checks reuse its damping instead of building it again; None through FMUs
    physics = None

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
        """One Newmark step from t to t + dt; raises on non-convergence."""

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
    def mesh_force(self) -> float:
        """Total normal mesh force of the current state [N]."""

    @abstractmethod
    def transmission_error(self) -> float:
        """Transmission error r_b1 theta_1 + r_b2 theta_2 of the current state [m]."""

    @abstractmethod
    def gear_displacements(self) -> np.ndarray:
        """(2, 2) [u, v] of the pinion and gear nodes [m], global frame."""

    def step_outputs(self) -> tuple[float, float, np.ndarray]:
        """What the runner records after each step: :meth:`mesh_force`,
        :meth:`transmission_error` and :meth:`gear_displacements` (one FMI call through the
        FMU)."""
        return self.mesh_force(), self.transmission_error(), self.gear_displacements()

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

    @abstractmethod
    def evaluate(self, states: np.ndarray):
        """Film force (nb, 2), Kb (nb, 2, 2), Cb (nb, 2, 2) at journal states (nb, 4)."""

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
class StepBlock:
    """Steps taken by one call of :meth:`Master.steps`: what the runner records of each
    accepted step, rows in step order, and the error of the step that ended the block early
    (None when all were accepted)."""

    count: int
    states: np.ndarray  # (count, nb, 4) accepted journal states [m, m/s]
    bearing_force: np.ndarray  # (count, nb, 2) [N]
    mesh_force: np.ndarray  # (count,) [N]
    transmission_error: np.ndarray  # (count,) [m]
    gear_nodes: np.ndarray  # (count, 2, 2) u, v of the pinion and gear nodes [m]
    iterations: np.ndarray  # (count,)
    mismatch: float  # the last step's relative mismatch (at its acceptance, or failure)
    error: Exception | None = None


class CompiledSteps(ABC):
    """The master's steps as one compiled call per block of steps where the slaves allow it
    (the master's ``fused``; :func:`orchestrator.coupling.system.build_master` gives it):
    in-process (:class:`orchestrator.coupling.fused.FusedStep`) and through the FMUs
    (:class:`orchestrator.coupling.fmi.steps.FmuSteps`). Each gives the bits, counters and
    errors of the master's Python loop. A subclass says which slaves it takes (:meth:`fits`)
    and takes a block (``_block``); the entry points are the master's."""

    @staticmethod
    @abstractmethod
    def fits(structure, bearings) -> bool:
        """Whether these slaves can take the compiled steps."""

    @abstractmethod
    def _block(self, master: Master, t: float, dt: float, n: int,
               time_of) -> StepBlock | None:
        """Up to ``n`` steps of dt from t [s] (the structure's time) until one fails (its
        error in the block, after the steps before it are taken); ``time_of(k)``: the time
        [s] of the block's step k, as the caller's messages give it. None when the next step
        takes the Python loop."""

    def step(self, master: Master, t: float, dt: float) -> StepReport | None:
        """The master's step from t to t + dt [s] (same arguments, counters and errors), or
        None for a step the compiled loop does not take: a block of one step."""
        block = self._block(master, t, dt, 1, lambda k: t)
        if block is None:
            return None
        if block.error is not None:
            raise block.error
        return StepReport(int(block.iterations[0]), block.mismatch, block.bearing_force[0],
                          master.laws, block.states[0])

    def steps(self, master: Master, first: int, dt: float, n: int) -> StepBlock | None:
        """Up to ``n`` of the master's steps of dt from step ``first`` (t = first dt [s]) in
        one compiled call (:meth:`Master.steps`)."""
        return self._block(master, first * dt, dt, n, lambda k: (first + k) * dt)

    def steps_from(self, master: Master, t: float, dt: float, n: int) -> StepBlock | None:
        """:meth:`steps` from the time ``t`` [s] (the structure's), step k's time t + k dt."""
        return self._block(master, t, dt, n, lambda k: t + k * dt)


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
    relaxed_steps: int = 0  # steps that needed the relaxation (module docstring)
    #: the same steps as one compiled call where the slaves allow it
    #: (:class:`CompiledSteps`, given by :func:`orchestrator.coupling.system.build_master`):
    #: ``fused.step(master, t, dt)`` returns the step's report, or None for a step this loop
    #: takes
    fused: CompiledSteps | None = field(default=None, repr=False)

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

    @one_blas_thread
    def step(self, t: float, dt: float) -> StepReport:
        """One coupled Newmark step from t to t + dt: Newton on the bearings' forces through
        their affine laws (Eq. 17), linearised at each iterate (module docstring)."""
        if self.laws is None:
            raise CouplingError("call solve_static() (or set laws) before the first step")
        if self.fused is not None:
            report = self.fused.step(self, t, dt)
            if report is not None:
                return report
        saved = self.structure.get_state()
        laws = self.laws
        mismatch = math.inf
        history = []
        relaxed = False
        for it in range(1, self.max_iterations + 1):
            self.structure.set_bearing_laws(laws)
            self.structure.do_step(t, dt)
            states = self.structure.journal_states()
            force, kb, cb = self._evaluate(states)
            mismatch, new = laws.relinearise(states, force, kb, cb)
            self.total_iterations += 1
            if mismatch <= self.tol:
                self.laws = new
                return StepReport(it, mismatch, force, new, states)
            history.append(mismatch)
            if not relaxed and it >= 3 and mismatch > STALL * history[-3]:
                relaxed = True
                self.relaxed_steps += 1
            laws = laws.blend(new, RELAXATION) if relaxed else new
            self.structure.set_state(saved)
        raise CouplingError(not_converged(t, dt, self.max_iterations, mismatch, self.tol))

    @one_blas_thread
    def steps(self, first: int, dt: float, n: int) -> StepBlock | None:
        """Up to ``n`` steps of dt from step ``first`` (t = first dt [s]): the same steps as
        ``n`` calls of :meth:`step`, in one compiled call where the slaves allow it
        (:meth:`CompiledSteps.steps`), else by :meth:`step` in a loop
        that gathers the structure's outputs of each step for the block. A
        :class:`StepBlock` of the steps taken and the error of a step that failed (the steps
        before it taken), or None: take the next step with :meth:`step`."""
        if self.laws is None:
            raise CouplingError("call solve_static() (or set laws) before the first step")
        if n < 1:
            return None
        if self.fused is None:
            return self._loop_steps(dt, n, lambda k: (first + k) * dt)
        return self.fused.steps(self, first, dt, n)

    @one_blas_thread
    def steps_from(self, t: float, dt: float, n: int) -> StepBlock | None:
        """:meth:`steps` from the time ``t`` [s] (the structure's) for a caller whose times
        are not whole multiples of dt (an FMU's communication steps cut into equal steps):
        the messages of a failed step k give t + k dt."""
        if self.laws is None:
            raise CouplingError("call solve_static() (or set laws) before the first step")
        if n < 1:
            return None
        if self.fused is None:
            return self._loop_steps(dt, n, lambda k: t + k * dt)
        return self.fused.steps_from(self, t, dt, n)

    def _loop_steps(self, dt: float, n: int, time_of) -> StepBlock:
        """``n`` steps of :meth:`step` (step k from ``time_of(k)`` [s]) with the structure's
        outputs after each (:meth:`StructureSlave.step_outputs`), as a block: the caller's
        work between steps (recording a row, checking for signals) is paid once per block.
        The first step that fails ends the block, its error in it."""
        states, forces, mesh, te, gear, its = [], [], [], [], [], []
        mismatch, error = math.nan, None
        for k in range(n):
            try:
                report = self.step(time_of(k), dt)
            except Exception as exc:  # handed to the caller with the rows (as FusedStep)
                error = exc
                break
            mesh_force, transmission_error, gear_nodes = self.structure.step_outputs()
            states.append(report.states.copy())  # a slave may reuse its buffers
            forces.append(report.bearing_force.copy())
            mesh.append(mesh_force)
            te.append(transmission_error)
            gear.append(gear_nodes)
            its.append(report.iterations)
            mismatch = report.mismatch
        count, nb = len(its), self.structure.n_bearings
        return StepBlock(count, np.array(states).reshape(count, nb, 4),
                         np.array(forces).reshape(count, nb, 2), np.array(mesh, dtype=float),
                         np.array(te, dtype=float), np.array(gear).reshape(count, 2, 2),
                         np.array(its, dtype=np.int64), mismatch, error)


def not_converged(t, dt, max_iterations, mismatch, tol) -> str:
    """The message of a step from t [s] that did not converge."""
    return (f"step at t = {t:.6e} s (dt = {dt:.3e} s) did not converge in {max_iterations} "
            f"iterations: relative bearing-force mismatch {mismatch:.3e} > tol {tol:.1e}")


def decode_checkpoint(data, what: str = "the checkpoint") -> StateArrays:
    """The arrays of :meth:`Master.checkpoint` bytes; a
    :class:`~fmu_src.state_codec.StateFormatError` starting with ``what`` for anything else
    (a pickle, another format, version or kind): what a resumed run checks before it starts."""
    return decode(data, CHECKPOINT_KIND, what)
