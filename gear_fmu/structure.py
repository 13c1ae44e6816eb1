"""The gear-shaft structure as a time stepper: Eq. (9) with Newmark, Newton and contact (Sec. 3).

``Structure`` owns the structural state (t, X, Xdot, Xddot, mesh contact set). One call of
:meth:`Structure.step` is a full Newmark step (Eq. 11-16) of

    M Xdd + C Xd + K_shaft X = F0(t) + F_mesh(t, X) + sum_j B_j^T (F0_j - Kb_j X_j - Cb_j Xd_j)

where the bearings enter as affine laws (Eq. 17, :class:`bearing_fmu.affine.AffineLaws`) given
by the caller in the global (s, t) frame at the four bearing nodes (X_j = (u, v) of bearing node
j), re-set by the master at every iteration: the Newton tangent is
``c0 M + c1 C + K + K_mesh + Kb + c1 Cb`` (Eq. 14, 16; c0 = 4/dt^2, c1 = 2/dt). External loads
``F0(t)`` (:mod:`gear_fmu.loads`): input torque, mass unbalance of Eq. (10), optional gravity.

Time integration refinements (switched on by the case file, :mod:`fmu_src.description`):

* ``consistent_start``: the static solution X0 balances the constant loads only, so at t = 0
  the unbalance of Eq. (10) is the one force not in equilibrium; the transient starts from
  ``Xdd_0 = M^-1 F_unb(0)`` instead of zero (Newmark's update carries Xdd_n forward, and a
  wrong Xdd_0 leaves a first-order error).
* ``locate_contact``: the mesh stiffness jumps when a contact line enters or leaves the path
  of contact (:meth:`gear_fmu.mesh.element.MeshElement.event_angles`, known from the rigid-body
  kinematics). A step containing such angles is cut into sub-steps ending on them; a sub-step
  ending on an event is solved with the contact set before it (mesh evaluated
  ``EVENT_SIDE`` base pitch earlier, :mod:`gear_fmu.step.events`), then the acceleration is
  reset to the one after it, ``Xdd+ = Xdd- + M^-1 (F_mesh+ - F_mesh-)`` at the same X and Xd.
  Each sub-step then integrates a smooth problem and the scheme keeps its order 2. The bearing
  laws of the step serve every sub-step (they are affine in X and Xd). No sub-step is shorter
  than ``EVENT_SNAP`` dt: an event that close to the step's end is taken at the end, and events
  that close to each other as one (a step slightly off the mesh period's divisor brings the
  events back towards the step's end a little every step). Contact changes that are not
  kinematic (a tooth pair separating under dynamic load) are not located.

Solution method: the constant part of the tangent is condensed onto the 20 gear and bearing DOFs
once per dt (:mod:`gear_fmu.step.condensation`); each step costs one matrix-vector product for the
right-hand side and, per Newton/contact iteration, a mesh evaluation and a 20 x 20 solve
(:mod:`gear_fmu.step.contact_loop`), then ``X_r = A_rr^-1 b_r - W X_c`` and the Newmark update
(Eq. 12, :mod:`gear_fmu.step.newmark`). Analyses without dynamics (modes, quasi-static transmission
error, support loads) are in :mod:`gear_fmu.modal.analyses`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.dofs import THETA
from gear_fmu.loads import (
    StructureLoads,
    constant_loads,
    shaft_speeds,
    unbalance_amplitudes,
    unbalance_force,
)
from gear_fmu.mesh.element import MeshElement, MeshState, transmission_error
from gear_fmu.modal.analyses import reference_damping
from gear_fmu.modal.damping import DampingModel
from gear_fmu.step.assembly import (
    check_laws,
    check_laws_fast,
    finish_step,
    history_memo,
    prepare_step,
)
from gear_fmu.step.condensation import (
    N_BEARING,
    N_GEAR,
    NC,
    Condensation,
    CondensationSlots,
)
from gear_fmu.step.contact_loop import StepInfo, solve_condensed
from gear_fmu.step.events import ContactEvents
from gear_fmu.step.kernel import CONVERGED, SINGULAR, advance, contact_event
from gear_fmu.step.newmark import NewmarkConvergenceError, newmark_coefficients
from gear_fmu.system import GearShaftSystem

__all__ = ["StepInfo", "StepsPlan", "Structure", "StructureLoads", "StructureState",
           "check_laws"]

#: first static iterate: pinion torsion [rad] that closes every potential contact
INITIAL_APPROACH_ROTATION = 1e-3
_NO_ERROR = np.zeros(12)  # no runout or mounting error
_NO_SET = np.zeros(0, dtype=np.bool_)  # no contact set known
_NO_MEMO = np.zeros(0)  # no memo of the history products (a sub-step after the first)
#: sub-steps of one step that :meth:`Structure.steps_plan` takes (a spur step of the paper's
#: case has at most 2, a helical one 3); a step with more takes the Python path
MAX_PIECES = 4
_SLOTS = 4  # the sub-step slots of the compiled call (orchestrator.coupling.fused)
_NO_ERRORS = np.zeros((_SLOTS, 12))
#: where :meth:`Structure.state_outputs` takes its values in ``[x[:NC], v[:NC]]``: at each
#: bearing node 1-4 u, v, udot, vdot (global s, t), then u, v of the pinion and gear nodes
_STATE_OUTPUTS = np.array([*(k for j in range(4) for k in (N_GEAR + 2 * j, N_GEAR + 2 * j + 1,
                                                          NC + N_GEAR + 2 * j,
                                                          NC + N_GEAR + 2 * j + 1)),
                           0, 1, 6, 7])


@dataclass(frozen=True)
class StepsPlan:
    """The structure's arguments of the compiled loop over steps
    (:func:`orchestrator.coupling.fused.coupled_steps`) for m steps planned ahead
    (:meth:`Structure.steps_plan`), in the kernel's order: ``head``, per step its sub-step
    count, the condensation slot of each sub-step, the condensations
    (:class:`gear_fmu.step.condensation.CondensationSlots`), piece tables, events and error
    displacements (one row of these for a mesh without errors); ``state``, copies of X, Xd,
    Xdd the kernel advances; ``tail``, the mesh and the solver's settings; ``work``, the
    iterations' buffers; ``kept``, the mesh evaluation the last accepted step ended on (its
    contact set the next step's); ``ends``, the end times [s] of each step's sub-steps."""

    head: tuple
    state: tuple
    tail: tuple
    work: tuple
    kept: tuple
    ends: list


@dataclass(frozen=True)
class StructureState:
    """Everything needed to roll a step back exactly (copies)."""

    t: float
    n_steps: int
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    active: object
    mesh_state: object


class Structure:
    """Gear-shaft structure stepping one Newmark step at a time (module docstring).

    Parameters
    ----------
    system : GearShaftSystem
        Assembled shafts and discs.
    mesh : object
        Mesh element with ``evaluate(pinion_angle, q12)`` (:mod:`gear_fmu.step.contact_loop`).
    loads : StructureLoads
    zeta : float or DampingModel
        The damping model (:mod:`gear_fmu.modal.damping`); a float is the modal damping factor on
        the ``"bearings"`` basis (paper 0.03).
    damping_bearing_stiffness : float or (4, 2, 2)
        Bearing stiffness of the reference configuration of the modal damping
        (:mod:`gear_fmu.modal.modes`) [N/m]; :meth:`set_damping_reference` replaces it.
    damping : (n_dof, n_dof) array, optional
        Explicit damping matrix (full numbering) replacing the modal one.
    tol : float
        Relative residual limit l (paper 1e-5).
    max_iter : int
        Newton/contact iterations per step.
    consistent_start, locate_contact : bool
        Time integration refinements (module docstring); off by default here, on by default
        in case files.

    Attributes
    ----------
    timing : dict or None
        Set to ``{"mesh": 0.0, "assembly": 0.0, "solve": 0.0}`` to accumulate seconds per part
        of a step (benchmarks); None (default) for no timers.
    """

    n_bearings = N_BEARING

    @one_blas_thread
    def __init__(
        self,
        system: GearShaftSystem,
        mesh,
        loads: StructureLoads | None = None,
        zeta: float | DampingModel = 0.03,
        damping_bearing_stiffness=1e8,
        damping: np.ndarray | None = None,
        tol: float = 1e-5,
        max_iter: int = 30,
        consistent_start: bool = False,
        locate_contact: bool = False,
    ):
        if not (tol > 0.0 and math.isfinite(tol)):
            raise ValueError(f"tol = {tol!r} must be finite and > 0")
        self.system = system
        self.mesh = mesh
        self.loads = StructureLoads() if loads is None else loads
        self.tol = tol
        self.max_iter = int(max_iter)
        self.timing: dict | None = None
        self._ordering()
        self._m = self._permute(system.mass)
        self._k = self._permute(system.stiffness)
        k_static = self._k
        if system.load_dof is not None:  # fix the free torsional rotation (gear_fmu.drivetrain)
            k_static = k_static.copy()
            i = int(np.flatnonzero(self._full_of_internal == system.load_dof)[0])
            k_static[i, i] += system.static_ground
        self._static = Condensation(k_static)
        self.consistent_start = bool(consistent_start)
        self.locate_contact = bool(locate_contact) and hasattr(mesh, "event_angles")
        self._m_gear = None  # M^-1 restricted to the gear-node columns, when first needed
        self._events = None  # the contact events (gear_fmu.step.events), when first needed
        self._last_pieces = None  # (t, dt, pieces) of the last step (_pieces)
        #: the mesh's constant arrays for the compiled step (gear_fmu.step.kernel), or None:
        #: the Python loop of gear_fmu.step.contact_loop serves any other mesh object
        self._mesh_arrays = mesh.kernel_arrays() if isinstance(mesh, MeshElement) else None
        self._forces()
        # the state: at rest at t = 0, no contact known yet
        n = self._perm.size
        self.t = 0.0
        self.n_steps = 0
        self.x = np.zeros(n)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.active = None
        self.mesh_state = None
        self._dyn_cache: dict[float, tuple] = {}
        #: the history products of the last step's start (gear_fmu.step.assembly), reused
        #: when the master takes that step again; emptied with C (set_damping)
        self._memo = history_memo(self._m.shape[0])
        # the compiled steps' condensations, by sub-step length
        self._condensations = CondensationSlots()
        self.damping_model = zeta if isinstance(zeta, DampingModel) else DampingModel(
            ratio=float(zeta))
        self._reference_modes = None
        self._reference_mesh_stiffness = None
        self._pending_reference = None
        if damping is not None:
            damping = np.asarray(damping, dtype=float)
            if damping.shape != (system.n_dof, system.n_dof):
                raise ValueError(
                    f"damping shape {damping.shape} must be "
                    f"({system.n_dof}, {system.n_dof})"
                )
            self.set_damping(damping)
        else:
            # built when first needed (a step, the damping matrix): a runner replaces it by
            # the static solution's reference before the first step, so it is never computed
            self._pending_reference = damping_bearing_stiffness
            self._c = None

    # ------------------------------------------------------------------ damping
    @one_blas_thread
    def set_damping(self, damping_full: np.ndarray) -> None:
        """Use the damping matrix C (full numbering) [N s/m] from now on."""
        self._pending_reference = None
        self._damping_full = damping_full
        self._c = self._permute(damping_full)
        self._mc = np.hstack([self._m, self._c])  # b = [M C] @ [p; q] (prepare_step)
        self._memo = history_memo(self._m.shape[0])
        self._dyn_cache.clear()
        self._condensations.clear()

    def _require_damping(self) -> None:
        """Build the damping of the constructor's reference if nothing replaced it (at the
        construction time t = 0, as if built then)."""
        if self._pending_reference is not None:
            t, self.t = self.t, 0.0
            try:
                self.set_damping_reference(self._pending_reference)
            finally:
                self.t = t

    @property
    def damping_full(self) -> np.ndarray:
        """The damping matrix C (full numbering) [N s/m]."""
        self._require_damping()
        return self._damping_full

    @property
    def reference_modes(self):
        """The modes of the modal damping's reference configuration (None if not modal)."""
        self._require_damping()
        return self._reference_modes

    @property
    def reference_mesh_stiffness(self):
        """Mean mesh stiffness (12, 12) of the damping's reference configuration, or None."""
        self._require_damping()
        return self._reference_mesh_stiffness

    @one_blas_thread
    def set_damping_reference(self, bearing_stiffness) -> None:
        """(Re)build the modal damping C on the modes of the reference configuration.

        ``bearing_stiffness``: isotropic [N/m] or (4, 2, 2) bearing stiffness (symmetric part
        used) of the reference configuration (:func:`gear_fmu.modal.analyses.reference_damping`).
        The master calls this with the bearings' stiffness at the static solution X0 before
        the transient.
        """
        self._pending_reference = None
        c, modes, k_mesh = reference_damping(self, self.damping_model, bearing_stiffness)
        self.set_damping(c)
        self._reference_modes, self._reference_mesh_stiffness = modes, k_mesh

    # ------------------------------------------------------------------ set-up
    def _ordering(self) -> None:
        sys_ = self.system
        red = sys_.reduced_index
        c_full = np.concatenate([sys_.gear_dofs, sys_.bearing_dofs.ravel()])
        c = red[c_full]
        if np.any(c < 0):
            raise ValueError("a gear or bearing DOF is clamped")
        r = np.setdiff1d(np.arange(sys_.free.size), c)
        self._perm = np.concatenate([c, r])  # position in reduced vector of internal index i
        self._full_of_internal = sys_.free[self._perm]

    def _permute(self, a: np.ndarray) -> np.ndarray:
        idx = self._full_of_internal
        return a[np.ix_(idx, idx)] if a.ndim == 2 else a[idx]

    def _forces(self) -> None:
        sys_, ld = self.system, self.loads
        f = self._permute(constant_loads(sys_, ld))
        self._f_const = f  # static part of F0(t)
        self._f_c = np.ascontiguousarray(f[:NC])
        self._omega = shaft_speeds(ld, sys_.teeth)
        self._last_pieces = None  # the mesh angles move with the speeds
        self._unb = unbalance_amplitudes(sys_.shaft_masses, ld.unbalance, self._omega)
        # [M1 e1 omega^2, M2 e2 omega_2^2, omega, omega_2]: Eq. (10) inside the compiled step
        self._unb_coef = np.array([*self._unb, *self._omega], dtype=float)
        # residual scale: the largest external load (torque, gravity, unbalance)
        self._f_scale = max(float(np.linalg.norm(f)), *self._unb)

    @one_blas_thread
    def set_torque(self, torque: float) -> None:
        """Input torque T [N m] from the next static solution or step on.

        The constant part of F0(t) (:func:`gear_fmu.loads.constant_loads`: T on the input
        torsion DOF, ``T z2 / z1`` on a free load) and what is derived from it are recomputed
        exactly as if the structure had been built with ``loads.torque = torque``; the
        factorisations, which do not depend on the loads, are kept. The mesh element's contact
        compliance stays linearised at the torque it was built for.
        """
        torque = float(torque)
        if torque == self.loads.torque:
            return
        self.loads = replace(self.loads, torque=torque)  # checked: finite
        self._forces()
        f = self._f_const[NC:]
        self._dyn_cache = {dt: (cond, cond.g @ f) for dt, (cond, _) in self._dyn_cache.items()}
        self._condensations.clear()

    def pinion_angle(self, t: float) -> float:
        """Rigid-body pinion angle at t [rad]."""
        return self.loads.pinion_angle0 + self._omega[0] * t

    @property
    def mesh_period(self) -> float:
        """Mesh period 2 pi / (omega z1) [s] (inf at zero speed)."""
        w = self._omega[0]
        return math.inf if w == 0.0 else 2.0 * math.pi / (w * self.system.teeth[0])

    def _dynamic(self, dt: float):
        hit = self._dyn_cache.get(dt)
        if hit is not None:
            return hit
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"time step dt = {dt!r} s must be finite and > 0")
        self._require_damping()
        c0, c1, _ = newmark_coefficients(dt)
        cond = Condensation(c0 * self._m + c1 * self._c + self._k)
        entry = (cond, cond.g @ self._f_const[NC:])
        if len(self._dyn_cache) > 256:
            self._dyn_cache.clear()
        self._dyn_cache[dt] = entry
        return entry

    check_laws = staticmethod(check_laws)

    # ------------------------------------------------------------------ solves
    @one_blas_thread
    def static(self, F0, Kb, Cb=None) -> StepInfo:
        """Static solution X0 at the current time with the given affine bearing laws.

        Velocities and accelerations are set to zero (paper Sec. 3.2); the loads are the constant
        ones (torque, gravity) without the rotating unbalance. ``Cb`` is ignored (zero velocity).
        """
        f0, kb, _ = check_laws(F0, Kb, np.zeros((4, 2, 2)) if Cb is None else Cb)
        info = self.static_at(f0, kb, self.pinion_angle(self.t))
        if self.consistent_start:
            f = np.zeros(N_GEAR)
            f[[0, 1, 6, 7]] = unbalance_force(self._unb, self._omega, self.t)  # Eq. (10)
            self.a = self._gear_compliance() @ f
        return info

    def _gear_compliance(self) -> np.ndarray:
        """``M^-1`` restricted to the gear-node columns, (n, 12) (internal order)."""
        if self._m_gear is None:
            cho = scipy.linalg.cho_factor(self._m)
            self._m_gear = np.ascontiguousarray(
                scipy.linalg.cho_solve(cho, np.eye(self._m.shape[0])[:, :N_GEAR]))
        return self._m_gear

    @one_blas_thread
    def static_at(self, f0, kb, angle) -> StepInfo:
        """Static solution at a given rigid-body pinion angle [rad] (checked laws)."""
        cond = self._static
        b = self._f_const
        out = cond.g @ b[NC:]
        z0 = b[:NC] + out[:NC]
        z0[N_GEAR:] += f0.ravel()
        y = out[NC:]
        s_lin = cond.s0.copy()
        for j in range(4):
            sl = slice(N_GEAR + 2 * j, N_GEAR + 2 * j + 2)
            s_lin[sl, sl] += kb[j]
        xc = np.zeros(NC)
        xc[THETA] = INITIAL_APPROACH_ROTATION  # close every potential contact first
        f_scale = max(float(np.linalg.norm(b)), float(np.linalg.norm(f0)))
        xc, ms, info = solve_condensed(self.mesh, s_lin, z0, xc, angle, None, f_scale, self.t,
                                       "static solution", self.tol, self.max_iter)
        self.x = np.concatenate([xc, y - cond.w @ xc])
        self.v = np.zeros_like(self.x)
        self.a = np.zeros_like(self.x)
        self.active = np.array(ms.active, copy=True)
        self.mesh_state = ms
        return info

    @one_blas_thread
    def step(self, dt: float, F0, Kb, Cb) -> StepInfo:
        """One Newmark step t -> t + dt with affine bearing laws F0 - Kb X - Cb Xdot.

        Parameters
        ----------
        dt : float
            Time step [s].
        F0 : (4, 2) array
            Bearing force at X = 0, Xdot = 0 [N] (global s, t).
        Kb, Cb : (4, 2, 2) arrays
            Bearing stiffness [N/m] and damping [N s/m] (global s, t).

        Raises
        ------
        NewmarkConvergenceError
            With the step number, the time and the residual.
        """
        f0, kb, cb = check_laws_fast(F0, Kb, Cb)
        self._check_step(dt)
        t1 = self.t + dt
        what = f"Newmark step {self.n_steps + 1}"
        pieces = self._pieces(dt)
        if len(pieces) == 1 and pieces[0][3] is None:
            info = self._advance(dt, t1, pieces[0][2], f0, kb, cb, what, self._memo)
        else:
            info = StepInfo(t1, 0, 0.0)
            for p, (h, te, before, after) in enumerate(pieces):
                # only the first starts from the step's state (advance_pieces)
                memo = self._memo if p == 0 else _NO_MEMO
                sub = self._advance(h, te, before, f0, kb, cb, what, memo)
                info.iterations += sub.iterations
                info.residual = max(info.residual, sub.residual)
                info.residuals += sub.residuals
                if after is not None:
                    self._contact_event(after)
        self.t = t1
        self.n_steps += 1
        return info

    def _pieces(self, dt: float, t: float | None = None) -> list:
        """``[(h [s], end time [s], mesh angle of the sub-step [rad], angle after its event
        [rad] or None)]`` of a step of dt from ``t`` [s] (default: the structure's time)
        (:meth:`gear_fmu.step.events.ContactEvents.pieces`; one piece without contact
        location). The last step's are kept: a coupled step is computed again from the same
        t at each iteration of the master."""
        t = self.t if t is None else t
        last = self._last_pieces
        if last is not None and last[0] == t and last[1] == dt:
            return last[2]
        if not self.locate_contact:
            t1 = t + dt
            pieces = [(dt, t1, self.pinion_angle(t1), None)]
        else:
            if self._events is None:
                self._events = ContactEvents(self.mesh, self.pinion_angle)
            pieces = self._events.pieces(t, dt)
        self._last_pieces = (t, dt, pieces)
        return pieces

    def _contact_event(self, angle: float) -> None:
        """Xdd, contact set and mesh state after a contact event: the mesh evaluated at pinion
        ``angle`` [rad] after it, ``Xdd+ = Xdd- + M^-1 (F_mesh+ - F_mesh-)`` at the same X and
        Xd (module docstring; :func:`gear_fmu.step.kernel.contact_event`)."""
        mesh = self.mesh
        buffers = self._mesh_buffers()
        a = self.a.copy()
        err = mesh.error_displacement(angle) if mesh.has_errors else _NO_ERROR
        total, length = contact_event(angle, self.x, err, mesh.has_errors, *self._mesh_arrays,
                                      self._gear_compliance(), self.mesh_state.force, a,
                                      *buffers)
        self.a = a
        self._take_mesh_state(buffers, total, length, self.x)

    def _check_step(self, dt: float) -> None:
        if self.active is None:
            raise RuntimeError("call static() before the first step (initial state X0)")
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"time step dt = {dt!r} s must be finite and > 0")

    def _advance(self, h, t1, angle, f0, kb, cb, what, memo) -> StepInfo:
        """One Newmark step of length h to t1 (mesh at ``angle``); updates X, Xd, Xdd and the
        contact state, not the time. ``memo``: of the history products
        (:func:`gear_fmu.step.assembly.history_products`), or empty."""
        timing = self.timing
        if self._mesh_arrays is not None and timing is None:
            return self._advance_compiled(h, t1, angle, f0, kb, cb, what, memo)
        t0 = time.perf_counter() if timing is not None else 0.0
        cond, g_const = self._dynamic(h)
        x, v, a = self.x, self.v, self.a
        unb = unbalance_force(self._unb, self._omega, t1)  # Eq. (10)
        s_lin, z0, y = prepare_step(self._mc, cond.g, g_const, x, v, a, self._f_c, unb, f0, kb,
                                     cb, cond.s0, h, N_GEAR, memo)
        f_scale = max(self._f_scale, math.sqrt(float(np.sum(f0 * f0))))
        if timing is not None:
            timing["assembly"] += time.perf_counter() - t0
        xc0 = x[:NC] + h * v[:NC]
        xc, ms, info = solve_condensed(self.mesh, s_lin, z0, xc0, angle, self.active, f_scale,
                                       t1, what, self.tol, self.max_iter, timing)
        t0 = time.perf_counter() if timing is not None else 0.0
        self.x, self.v, self.a = finish_step(x, v, a, xc, y, cond.w, h)
        self.active = ms.active
        self.mesh_state = ms
        if timing is not None:
            timing["assembly"] += time.perf_counter() - t0
        return info

    def _advance_compiled(self, h, t1, angle, f0, kb, cb, what, memo) -> StepInfo:
        """:meth:`_advance` in one compiled call (:func:`gear_fmu.step.kernel.advance`, the
        same arithmetic as the Python loop)."""
        head, tail, outputs = self._advance_inputs(h, t1, angle)
        status, k, total, length = advance(*head, f0, kb, cb, *tail, *outputs, memo)
        return self._advance_result(status, k, total, length, outputs, t1, what)

    def _advance_inputs(self, h, t1, angle):
        """The arguments of :func:`gear_fmu.step.kernel.advance` for a step of length h to t1
        (mesh at ``angle``): those before the bearing laws, those after them, and the output
        buffers it writes (:meth:`_advance_result` reads them)."""
        cond, g_const = self._dynamic(h)
        mesh = self.mesh
        outputs = self._advance_outputs()
        err = mesh.error_displacement(angle) if mesh.has_errors else _NO_ERROR
        used = _NO_SET if self.active is None else self.active
        head = (self._mc, cond.g, g_const, cond.s0, cond.w, self.x, self.v, self.a, self._f_c,
                self._unb_coef, t1)
        tail = (h, angle, err, mesh.has_errors, *self._mesh_arrays, used,
                self.active is not None, self._f_scale, self.tol, self.max_iter)
        return head, tail, outputs

    def _mesh_buffers(self) -> tuple:
        """New buffers for a mesh evaluation of the compiled kernels: force, tangent, contact
        set, slices inside the path of contact, approach, load, abscissa, axial position."""
        n = self.mesh.n_lines * self.mesh.n_slices
        return (np.empty(12), np.empty((12, 12)), np.empty(n, dtype=np.bool_),
                np.empty(n, dtype=np.bool_), np.empty(n), np.empty(n), np.empty(n),
                np.empty(n))

    def _take_mesh_state(self, buffers, total, length, x) -> None:
        """The mesh evaluation in ``buffers`` (:meth:`_mesh_buffers`), of total load
        ``total`` [N] and contact length ``length`` [m] at the state ``x``, as the current
        mesh state and contact set."""
        force, stiff, active, inside, delta, load, xi, z = buffers
        te = transmission_error(self.mesh.pair.base_radius, x[:N_GEAR])
        self.mesh_state = MeshState(force, stiff, active, delta, load, inside, xi, z, total, te,
                                    {"contact_length": length})
        self.active = active

    def _advance_outputs(self) -> tuple:
        """New buffers for what :func:`gear_fmu.step.kernel.advance` writes: the mesh
        evaluation (:meth:`_mesh_buffers`), the residuals and the new X, Xd, Xdd."""
        size = self.x.size
        return (*self._mesh_buffers(), np.empty(self.max_iter + 1), np.empty(size),
                np.empty(size), np.empty(size))

    def _advance_result(self, status, k, total, length, outputs, t1, what) -> StepInfo:
        """Raise the error of a failed :func:`gear_fmu.step.kernel.advance`, or take its new
        state and mesh evaluation from ``outputs`` (:meth:`_advance_inputs`)."""
        mesh_buffers, (residuals, x1, v1, a1) = outputs[:-4], outputs[-4:]
        history = residuals[:k + 1].tolist()
        if status == SINGULAR:
            raise NewmarkConvergenceError(
                f"{what} at t = {t1:.9g} s: singular tangent at iteration {k} "
                f"({int(np.count_nonzero(mesh_buffers[2]))} mesh slices in contact; with no tooth "
                "contact the pinion is free in torsion - check the torque sign)")
        if status != CONVERGED:
            raise NewmarkConvergenceError(
                f"{what} at t = {t1:.9g} s did not converge: relative residual "
                f"{history[-1]:.3e} (tol {self.tol:.1e}) after {self.max_iter} iterations; "
                f"last residuals {', '.join(f'{v:.2e}' for v in history[-5:])}")
        self._take_mesh_state(mesh_buffers, total, length, x1)
        self.x, self.v, self.a = x1, v1, a1
        return StepInfo(t1, k, history[-1], history)

    def steps_plan(self, dt: float, n: int):
        """The next steps of dt, at most ``n``, as the inputs of the compiled loop over steps
        (:func:`orchestrator.coupling.fused.coupled_steps`), a :class:`StepsPlan`; it stops
        before a step of more than :data:`MAX_PIECES` sub-steps. None when the next step takes
        the Python path (timing on, more than :data:`MAX_PIECES` sub-steps). Finish it with
        :meth:`end_steps`."""
        self._check_step(dt)
        if self._mesh_arrays is None or self.timing is not None:
            return None
        t, steps, slotted = self.t, [], []
        slots = self._condensations
        while len(steps) < n:
            pieces = self._pieces(dt, t)
            lengths = [h for h, _, _, _ in pieces]
            if len(pieces) > MAX_PIECES or not slots.make_room(lengths, first=not steps):
                break
            steps.append(pieces)
            slotted.append([slots.slot(h, self._dynamic) for h in lengths])
            t = pieces[-1][1]
        if not steps:
            return None
        m, mesh = len(steps), self.mesh
        counts = np.empty(m, dtype=np.int64)
        index = np.empty((m, _SLOTS), dtype=np.int64)
        tables = np.zeros((m, _SLOTS, 4))
        events = np.zeros((m, _SLOTS), dtype=np.bool_)
        err = err_after = _NO_ERRORS[None]
        if mesh.has_errors:
            err, err_after = np.zeros((m, _SLOTS, 12)), np.zeros((m, _SLOTS, 12))
        for i, pieces in enumerate(steps):
            counts[i] = len(pieces)
            index[i] = slotted[i][0]  # the unused slots: the first's
            index[i, :len(pieces)] = slotted[i]
            for p, (h, te, before, after) in enumerate(pieces):
                tables[i, p] = h, te, before, math.nan if after is None else after
                events[i, p] = after is not None
                if mesh.has_errors:
                    err[i, p] = mesh.error_displacement(before)
                    if after is not None:
                        err_after[i, p] = mesh.error_displacement(after)
        kept = self._mesh_buffers()
        kept[2][:] = self.active  # the contact set the first step starts from
        return StepsPlan(
            (counts, index, self._mc, *slots.arrays(), tables, events, err, err_after),
            (self.x.copy(), self.v.copy(), self.a.copy()),
            (self._f_c, self._unb_coef, mesh.has_errors, *self._mesh_arrays, self._f_scale,
             self.tol, self.max_iter, self._gear_compliance(), self._memo),
            self._advance_outputs(), kept, [[te for _, te, _, _ in p] for p in steps])

    def end_steps(self, plan: StepsPlan, count: int, total: float, length: float) -> None:
        """Take the state after the first ``count`` steps of ``plan`` (:meth:`steps_plan`):
        X, Xd, Xdd, and the mesh evaluation the last of them ended on, of total load
        ``total`` [N] and contact length ``length`` [m]; the time and step count advance as
        ``count`` calls of :meth:`step` would."""
        if count:
            x, v, a = plan.state
            self._take_mesh_state(plan.kept, total, length, x)
            self.x, self.v, self.a = x, v, a
            self.t = plan.ends[count - 1][-1]
            self.n_steps += count

    def raise_failed_step(self, status, k, outputs, t1) -> None:
        """Raise the error of the sub-step to ``t1`` [s] of a compiled step
        (:func:`orchestrator.coupling.fused.coupled_steps`) that returned ``status`` after
        ``k`` passes, its residuals and mesh evaluation in ``outputs``
        (``_advance_outputs``): the error of the Python path."""
        if status == CONVERGED:
            raise ValueError("raise_failed_step: the step converged")
        self._advance_result(status, k, 0.0, 0.0, outputs, t1, f"Newmark step {self.n_steps + 1}")

    # ------------------------------------------------------------------ state
    def get_state(self) -> StructureState:
        """A copy of everything a step changes (for the master's rollback)."""
        return StructureState(self.t, self.n_steps, self.x.copy(), self.v.copy(), self.a.copy(),
                              None if self.active is None else np.array(self.active, copy=True),
                              self.mesh_state)

    def set_state(self, state: StructureState) -> None:
        """Restore a state from :meth:`get_state` exactly."""
        self.t, self.n_steps = state.t, state.n_steps
        self.x, self.v, self.a = state.x.copy(), state.v.copy(), state.a.copy()
        self.active = None if state.active is None else np.array(state.active, copy=True)
        self.mesh_state = state.mesh_state

    # ------------------------------------------------------------------ outputs
    def journal_states(self) -> np.ndarray:
        """(4, 4) [u, v, udot, vdot] at bearing nodes 1-4, global (s, t) frame [m, m/s]."""
        xv = np.concatenate((self.x[:NC], self.v[:NC]))
        return xv.take(_STATE_OUTPUTS[:16]).reshape(4, 4)

    def gear_displacements(self) -> np.ndarray:
        """(2, 6) DOFs (u, v, w, phi, psi, theta) of the pinion and gear nodes."""
        return self.x[:N_GEAR].reshape(2, 6).copy()

    def state_outputs(self) -> list[float]:
        """:meth:`journal_states` (16, row by row) then u, v of the pinion and gear nodes (4,
        :meth:`gear_displacements`) as a list: what an FMU outputs at every step, in one
        gather [m, m/s]."""
        return np.concatenate((self.x[:NC], self.v[:NC])).take(_STATE_OUTPUTS).tolist()

    def mesh_force(self) -> float:
        """Total normal mesh force of the current state [N]."""
        return float(self.mesh_state.total_load)

    def transmission_error(self) -> float:
        """r_b1 theta1 + r_b2 theta2 of the current state [m]
        (:class:`gear_fmu.mesh.element.MeshState`)."""
        return float(self.mesh_state.transmission_error)

    def full_vector(self, which: str = "x") -> np.ndarray:
        """Displacement / velocity / acceleration in the full numbering of the system."""
        vec = {"x": self.x, "v": self.v, "a": self.a}[which]
        out = np.zeros(self.system.n_dof)
        out[self._full_of_internal] = vec
        return out
