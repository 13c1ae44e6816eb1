"""The gear-shaft structure as a time stepper: Eq. (9) with Newmark, Newton and contact (Sec. 3).

``Structure`` owns the structural state (t, X, Xdot, Xddot, the meshes' contact sets) of a gear
train (:class:`gear_fmu.system.GearShaftSystem`, built from a :class:`gear_fmu.layout.Layout`).
One call of :meth:`Structure.step` is a full Newmark step (Eq. 11-16) of

    M Xdd + (C + G(Omega)) Xd + K_shaft X
        = F0(t) + sum_m F_mesh,m(t, X) + sum_j B_j^T (F0_j - Kb_j X_j - Cb_j Xd_j)

where the bearings enter as affine laws (Eq. 17, :class:`bearing_fmu.affine.AffineLaws`) given
by the caller in the global (s, t) frame at the bearing nodes (X_j = (u, v) of bearing j's node,
the layout's order), re-set by the master at every iteration: the Newton tangent is
``c0 M + c1 C + K + sum K_mesh + Kb + c1 Cb`` (Eq. 14, 16; c0 = 4/dt^2, c1 = 2/dt). The
gyroscopic matrix ``G(Omega)`` of the shafts, gears and discs at their speeds
(:meth:`gear_fmu.system.GearShaftSystem.gyroscopic`; not in the paper; in a run-up at the
speed of each step's end) is on when asked (``gyroscopic``): it joins C wherever C acts, and
makes the tangent unsymmetric. External
loads ``F0(t)`` (:mod:`gear_fmu.loads`): input torque, mass unbalances of Eq. (10), optional
gravity. Each mesh element works in its pair's own frame
(:func:`gear_fmu.mesh.element.pair_frame`) and is driven by the rigid-body angle of its
driver's shaft, the input angle times that shaft's speed ratio.

Time integration refinements (switched on by the case file, :mod:`fmu_src.description`):

* ``consistent_start``: the static solution X0 balances the constant loads only, so at t = 0
  the unbalances of Eq. (10) are the forces not in equilibrium; the transient starts from
  ``Xdd_0 = M^-1 F_unb(0)`` instead of zero (Newmark's update carries Xdd_n forward, and a
  wrong Xdd_0 leaves a first-order error).
* ``locate_contact``: a mesh's stiffness jumps when a contact line enters or leaves the path
  of contact (:meth:`gear_fmu.mesh.element.MeshElement.event_angles`, known from the
  rigid-body kinematics). A step containing such angles of any mesh is cut into sub-steps
  ending on them (:func:`gear_fmu.step.events.train_pieces`); a sub-step ending on an event is
  solved with the contact set before it (the mesh evaluated ``EVENT_SIDE`` base pitch
  earlier), then the acceleration is reset to the one after it,
  ``Xdd+ = Xdd- + M^-1 (F_mesh+ - F_mesh-)`` at the same X and Xd. Each sub-step then
  integrates a smooth problem and the scheme keeps its order 2. The bearing laws of the step
  serve every sub-step (they are affine in X and Xd). Contact changes that are not kinematic
  (a tooth pair separating under dynamic load) are not located.

Solution method: the constant part of the tangent is condensed onto the gear-node, bearing and
unbalanced-disc DOFs once per sub-step length (:mod:`gear_fmu.step.condensation`); each step
costs one matrix-vector product for the right-hand side and, per Newton/contact iteration, an
evaluation of every mesh and an nc x nc solve (:mod:`gear_fmu.step.contact_loop`), then
``X_r = A_rr^-1 b_r - W X_c`` and the Newmark update (Eq. 12, :mod:`gear_fmu.step.newmark`),
all in one compiled call (:func:`gear_fmu.step.kernel.advance_pieces`). Analyses without
dynamics (modes, quasi-static transmission error, support loads) are in
:mod:`gear_fmu.modal.analyses`.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg

from bearing_fmu.blas_threads import one_blas_thread
from bearing_fmu.borrowed import held
from gear_fmu.dofs import DOF_PER_NODE, THETA, U, V, dof
from gear_fmu.loads import (
    StructureLoads,
    accelerated_unbalance_coefficients,
    bearing_ratios,
    constant_loads,
    shaft_speeds,
    unbalance_coefficients,
    unbalance_force,
)
from gear_fmu.mesh.element import MeshElement, MeshState
from gear_fmu.modal.analyses import reference_damping
from gear_fmu.modal.damping import DampingModel
from gear_fmu.speed_profile import SpeedProfile
from gear_fmu.step.assembly import check_laws, check_laws_fast, column_nonzeros, history_memo
from gear_fmu.step.condensation import Condensation, CondensationSlots
from gear_fmu.step.contact_loop import (
    CONVERGED,
    SINGULAR,
    MeshWork,
    StepInfo,
    contact_newton,
    kept_views,
)
from gear_fmu.step.events import ContactEvents, quiet_steps, step_times, train_pieces
from gear_fmu.step.kernel import advance_step, keep_evaluation
from gear_fmu.step.newmark import NewmarkConvergenceError
from gear_fmu.system import GearShaftSystem

__all__ = ["StepInfo", "StepsPlan", "Structure", "StructureLoads", "StructureState",
           "check_laws"]

#: first static iterate: rotation [rad] of every mesh's driver node that closes every potential
#: contact of the mesh
INITIAL_APPROACH_ROTATION = 1e-3


@dataclass(frozen=True)
class StepsPlan:
    """The structure's arguments of the compiled loop over steps (:meth:`Structure.steps_plan`,
    :func:`orchestrator.coupling.step.coupled_steps`) for m steps planned ahead, in the
    kernel's order: ``head``, per step its sub-step count, the condensation slot of each
    sub-step, [M C] and the condensations
    (:class:`gear_fmu.step.condensation.CondensationSlots`), the sub-steps' lengths and end
    times, the meshes' angles before and after their events, their error displacements (one
    row of these for meshes without errors); ``state``, copies of X, Xd, Xdd the kernel
    advances; ``tail``, the loads, the meshes and the solver's settings; ``work``, the
    iterations' buffers; ``ends``, the end times [s] of each step's sub-steps."""

    head: tuple
    state: tuple
    tail: tuple
    work: tuple
    ends: list


@dataclass(frozen=True)
class StructureState:
    """Everything needed to roll a step back exactly (copies): the time and step count, X,
    Xd, Xdd (internal order), and each mesh's evaluation at that state (None before a
    solution): per mesh its force, stiffness, approach, load, abscissa and z arrays in one
    float block and its contact set and inside flags in one bool block
    (:func:`gear_fmu.step.contact_loop.kept_views`), then its total load [N], contact
    length [m] and transmission error [m] (the fields of
    :class:`gear_fmu.mesh.element.MeshState`, kept as two blocks: a master saves a state at
    every step)."""

    t: float
    n_steps: int
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    meshes: tuple | None

    @property
    def mesh_states(self) -> tuple[MeshState, ...] | None:
        """Each mesh's evaluation as a :class:`gear_fmu.mesh.element.MeshState` (views)."""
        if self.meshes is None:
            return None
        states = []
        for floats, bools, total, length, te in self.meshes:
            f, k, act, inside, delta, load, xi, z = kept_views(floats, bools)
            states.append(MeshState(f, k, act, delta, load, inside, xi, z, total, te,
                                    {"contact_length": length}))
        return tuple(states)

    @classmethod
    def of(cls, t, n_steps, x, v, a, mesh_states) -> StructureState:
        """The state of these arrays and :class:`~gear_fmu.mesh.element.MeshState` s (None
        before a solution)."""
        meshes = None if mesh_states is None else tuple(
            (np.concatenate([np.ravel(b) for b in (ms.force, ms.stiffness, ms.delta, ms.load,
                                                    ms.xi, ms.z)]).astype(float),
             np.concatenate((ms.active, ms.inside)).astype(np.bool_),
             float(ms.total_load), float(ms.contact_length), float(ms.transmission_error))
            for ms in mesh_states)
        return cls(t, n_steps, x, v, a, meshes)


class Structure:
    """Gear-shaft structure stepping one Newmark step at a time (module docstring).

    Parameters
    ----------
    system : GearShaftSystem
        Assembled shafts and discs of a layout.
    meshes : sequence of MeshElement
        One per mesh of the layout (its order), each in its pair's own frame
        (:func:`fmu_src.description.mesh_elements_of`).
    loads : StructureLoads
    zeta : float or DampingModel
        The damping model (:mod:`gear_fmu.modal.damping`); a float is the modal damping factor on
        the ``"bearings"`` basis (paper 0.03).
    damping_bearing_stiffness : float or (nb, 2, 2)
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
    gyroscopic : bool
        Add the gyroscopic matrix ``G(Omega)`` at the shafts' speeds to C (module docstring);
        off by default here, on by default in case files (off in the paper's).
    """

    @one_blas_thread
    def __init__(
        self,
        system: GearShaftSystem,
        meshes,
        loads: StructureLoads | None = None,
        zeta: float | DampingModel = 0.03,
        damping_bearing_stiffness=1e8,
        damping: np.ndarray | None = None,
        tol: float = 1e-5,
        max_iter: int = 30,
        consistent_start: bool = False,
        locate_contact: bool = False,
        gyroscopic: bool = False,
    ):
        if not (tol > 0.0 and math.isfinite(tol)):
            raise ValueError(f"tol = {tol!r} must be finite and > 0")
        self.system = system
        self.layout = system.layout
        if isinstance(meshes, MeshElement):
            meshes = (meshes,)
        self.meshes = tuple(meshes)
        if len(self.meshes) != len(self.layout.meshes) or not all(
                isinstance(m, MeshElement) for m in self.meshes):
            raise ValueError(f"meshes: one MeshElement per mesh of the layout "
                             f"({len(self.layout.meshes)}), got {len(self.meshes)}")
        self.nb = len(self.layout.bearings)
        self.loads = StructureLoads() if loads is None else loads
        self.tol = tol
        self.max_iter = int(max_iter)
        self._ordering()
        self._m = self._permute(system.mass)
        self._k = self._permute(system.stiffness)
        k_static = self._k
        if system.load_dof is not None:  # fix the free torsional rotation (gear_fmu.drivetrain)
            k_static = k_static.copy()
            i = int(np.flatnonzero(self._full_of_internal == system.load_dof)[0])
            k_static[i, i] += system.static_ground
        self._static = Condensation(k_static, self.nc)
        self.consistent_start = bool(consistent_start)
        self.locate_contact = bool(locate_contact)
        self.gyroscopic = bool(gyroscopic)
        self._m_inv = None  # M^-1 restricted to the condensed columns, when first needed
        self._m_inv_g = None  # ... to the gear-node columns
        self._one = None  # the arguments of the last single step (_one_step)
        self._one_buf = None  # their arrays
        self._ahead = None  # the next steps of a step alone looked ahead (_quiet_step)
        self._step_work = None  # its buffers
        self._held = None  # (arrays, the same held for the compiled step: _held_arrays)
        self._events = None  # the contact events of each mesh, when first needed
        self._work = [MeshWork(m, idx) for m, idx in zip(self.meshes, self._mesh_idx,
                                                          strict=True)]
        self._mesh_tuple = tuple(w.arrays() for w in self._work)
        self._has_err = any(m.has_errors for m in self.meshes)
        self._signed_ratios = self.layout.ratios * self.layout.directions
        self._bearing_ratios = bearing_ratios(self.layout)
        self._ramp = None  # a run-up's rigid-body inertia load (_at_time), when first needed
        self._forces()
        # the state: at rest at t = 0, no solution yet
        n = self._perm.size
        self.t = 0.0
        self.n_steps = 0
        self.x = np.zeros(n)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.solved = False  # a static solution or a step has set the meshes' evaluations
        self._totals = np.zeros(len(self.meshes))
        self._lengths = np.zeros(len(self.meshes))
        self._dyn_cache: dict[float, tuple] = {}
        #: the history products of the last step's start (gear_fmu.step.assembly), reused
        #: when the master takes that step again; emptied with C (set_damping)
        self._memo = history_memo(n)
        # the condensations of the sub-step lengths of the run
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
        self._c_damping = self._permute(damping_full)
        self._set_c(self.loads.input_speed)

    def _set_c(self, input_speed: float) -> None:
        """C = the damping plus, with gyroscopic terms, ``G(Omega)`` at ``input_speed``
        [rad/s]; what is built on C is forgotten."""
        self._c = self._c_damping
        self._gyroscopic_speed = float(input_speed)
        if self.gyroscopic:
            self._c = self._c + self._permute(self.gyroscopic_at(input_speed))
        # b = [M C] [p; q] (prepare_step), transposed for the compiled step's products, with
        # the nonzero rows of M's columns (M's half taken at them only: history_products)
        self._mc = (np.ascontiguousarray(np.hstack([self._m, self._c]).T),
                    *column_nonzeros(self._m))
        self._memo = history_memo(self._m.shape[0])
        self._dyn_cache.clear()
        self._condensations.clear()
        if self._ramp is not None:
            self._ramp[1].clear()

    def _follow_gyroscopic(self, t1: float) -> None:
        """A varying speed's gyroscopic matrix for the step ending at t1 [s]: ``G(Omega(t1))``
        in C (Eq. 11 at t1, as the bearings' speed and the unbalances; its sub-steps take it
        too), the condensations rebuilt for it (docs/equations.md "Run-ups"). Nothing at
        constant speed, without gyroscopic terms, or when the speed is the one C has (a step
        taken again)."""
        if self.gyroscopic and self.loads.profile is not None:  # (checked first: a hot path)
            self._follow_speed(t1)

    @one_blas_thread
    def _follow_speed(self, t1: float) -> None:
        self._require_damping()
        speed = self.input_speed_at(t1)
        if speed != self._gyroscopic_speed:
            self._set_c(speed)

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
    def gyroscopic_full(self) -> np.ndarray:
        """``G(Omega)`` (full numbering) [N m s] at the shafts' speeds, zero when the
        structure has no gyroscopic terms (``gyroscopic`` False)."""
        return self.gyroscopic_at(self.loads.input_speed)

    def gyroscopic_at(self, input_speed: float) -> np.ndarray:
        """``G(Omega)`` (full numbering) [N m s] with the input shaft at ``input_speed``
        [rad/s] and the others at their ratios (a linearisation at another speed); zero when
        the structure has no gyroscopic terms."""
        if not self.gyroscopic:
            return np.zeros((self.system.n_dof, self.system.n_dof))
        return self.system.gyroscopic(shaft_speeds(self.layout, float(input_speed)))

    @property
    def reference_modes(self):
        """The modes of the modal damping's reference configuration (None if not modal)."""
        self._require_damping()
        return self._reference_modes

    @property
    def reference_mesh_stiffness(self):
        """Mean stiffness (n_meshes, 12, 12) of each mesh in the damping's reference
        configuration, or None."""
        self._require_damping()
        return self._reference_mesh_stiffness

    @one_blas_thread
    def set_damping_reference(self, bearing_stiffness) -> None:
        """(Re)build the modal damping C on the modes of the reference configuration.

        ``bearing_stiffness``: isotropic [N/m] or (nb, 2, 2) bearing stiffness (symmetric
        part used) of the reference configuration
        (:func:`gear_fmu.modal.analyses.reference_damping`). The master calls this with the
        bearings' stiffness at the static solution X0 before the transient.
        """
        self._pending_reference = None
        c, modes, k_mesh = reference_damping(self, self.damping_model, bearing_stiffness)
        self.set_damping(c)
        self._reference_modes, self._reference_mesh_stiffness = modes, k_mesh

    # ------------------------------------------------------------------ set-up
    def _ordering(self) -> None:
        """The condensed DOFs ``c`` (gear nodes' six DOFs, the bearings' u, v, the u, v of
        unbalanced discs) first, then the rest; each mesh's and unbalance's condensed
        indices."""
        sys_ = self.system
        gear_nodes: list[int] = []
        for pair in sys_.mesh_nodes:
            for node in pair:
                if int(node) not in gear_nodes:
                    gear_nodes.append(int(node))
        c_full = [DOF_PER_NODE * n + i for n in gear_nodes for i in range(DOF_PER_NODE)]
        self.ng = len(c_full)
        c_full += [int(d) for d in sys_.bearing_dofs.ravel()]
        for node in sys_.unbalances.node:
            if int(node) not in gear_nodes and dof(int(node), U) not in c_full:
                c_full += [dof(int(node), U), dof(int(node), V)]
        red = sys_.reduced_index
        c = red[np.array(c_full, dtype=int)]
        if np.any(c < 0):
            raise ValueError("a gear, bearing or unbalance DOF is clamped")
        self.nc = c.size
        r = np.setdiff1d(np.arange(sys_.free.size), c)
        self._perm = np.concatenate([c, r])  # position in reduced vector of internal index i
        self._full_of_internal = sys_.free[self._perm]
        where = {int(f): i for i, f in enumerate(c_full)}
        self._mesh_idx = [np.array([where[DOF_PER_NODE * int(n) + i] for n in pair
                                    for i in range(DOF_PER_NODE)], dtype=np.int64)
                          for pair in sys_.mesh_nodes]
        self._unb_idx = np.array([[where[dof(int(n), U)], where[dof(int(n), V)]]
                                  for n in sys_.unbalances.node], dtype=np.int64).reshape(-1, 2)
        self._gear_uv = np.array([[where[dof(int(n), U)], where[dof(int(n), V)]]
                                  for n in sys_.gear_nodes], dtype=np.int64).reshape(-1, 2)
        # per bearing u, v, udot, vdot in [x[:nc], v[:nc]], then u, v of every gear node
        ng, nc = self.ng, self.nc
        journals = [k for j in range(self.nb) for k in (ng + 2 * j, ng + 2 * j + 1,
                                                         nc + ng + 2 * j, nc + ng + 2 * j + 1)]
        self._state_outputs = np.array([*journals, *self._gear_uv.ravel()], dtype=np.int64)
        # the driver node's torsion of each mesh, turned to close its contacts (static_at)
        lay = self.layout
        self._approach = np.zeros(self.nc)
        for m, (driver, _) in enumerate(lay.drivers):
            sign = lay.directions[lay.shaft_index[lay.gear(driver).shaft]]
            self._approach[self._mesh_idx[m][THETA]] = sign * INITIAL_APPROACH_ROTATION
        self._driver_ratio = np.array([lay.ratios[lay.shaft_index[lay.gear(d).shaft]]
                                       for d, _ in lay.drivers])

    def _permute(self, a: np.ndarray) -> np.ndarray:
        idx = self._full_of_internal
        return a[np.ix_(idx, idx)] if a.ndim == 2 else a[idx]

    def _forces(self) -> None:
        sys_, ld = self.system, self.loads
        f = self._permute(constant_loads(sys_, ld))
        self._f_const = f  # static part of F0(t)
        self._f_c = self._f_c_const = np.ascontiguousarray(f[:self.nc])
        self._speeds = shaft_speeds(self.layout, ld.input_speed)
        w = ld.input_speed * self._driver_ratio
        z = np.array([m.pair.teeth[0] for m in self.meshes], dtype=float)
        with np.errstate(divide="ignore"):
            self._mesh_periods = np.where(w > 0.0, 2.0 * math.pi / (w * z), math.inf)
        self._mesh_period = float(np.min(self._mesh_periods))
        self._events = None  # the mesh angles move with the speeds
        # [M e omega^2, signed omega, phase] per unbalance: Eq. (10) inside the compiled step
        self._unb_coef = unbalance_coefficients(sys_.unbalances, self._speeds)
        # residual scale: the largest external load (torque, gravity, unbalance)
        self._f_scale = max(float(np.linalg.norm(f)), *np.abs(self._unb_coef[:, 0]), 0.0)

    @one_blas_thread
    def set_torque(self, torque: float) -> None:
        """Input torque T [N m] from the next static solution or step on.

        The constant part of F0(t) (:func:`gear_fmu.loads.constant_loads`: T on the input
        torsion DOF, the balancing torque on a free load) and what is derived from it are
        recomputed exactly as if the structure had been built with ``loads.torque = torque``;
        the factorisations, which do not depend on the loads, are kept. The mesh elements'
        contact compliance stays linearised at the torque they were built for.
        """
        torque = float(torque)
        if torque == self.loads.torque:
            return
        self.loads = replace(self.loads, torque=torque)  # checked: finite
        self._forces()
        f = self._f_const[self.nc:]
        self._dyn_cache = {dt: (cond, cond.g @ f) for dt, (cond, _) in self._dyn_cache.items()}
        self._condensations.clear()

    def input_angle(self, t: float) -> float:
        """Rigid-body angle of the input shaft at t [rad] (in a run-up the integral of its
        speed, :class:`gear_fmu.speed_profile.SpeedProfile`)."""
        if self.loads.profile is not None:
            return self.loads.input_angle0 + self.loads.profile.angle(t)
        return self.loads.input_angle0 + self.loads.input_speed * t

    def input_speed_at(self, t: float) -> float:
        """Speed of the input shaft at t [rad/s]."""
        p = self.loads.profile
        return self.loads.input_speed if p is None else p.speed(t)

    def bearing_speeds_at(self, t: float) -> np.ndarray | None:
        """The speed magnitude of each bearing's shaft at t [rad/s] in a run-up (the layout's
        bearing order), None at constant speed."""
        if self.loads.profile is None:
            return None
        return self.input_speed_at(t) * self._bearing_ratios

    def follow_speed(self, t1: float, speed: float) -> None:
        """From the structure's time t on, the input speed goes linearly to ``speed`` [rad/s]
        at ``t1`` [s] (> t) and stays there: the speed profile continued
        (:meth:`gear_fmu.speed_profile.SpeedProfile.continued`, the angle and the speed at t
        kept), with a run-up's loads, bearing speeds, gyroscopic matrix and one step per plan
        from now on (a host's speed input,
        :class:`orchestrator.coupling.transmission.TransmissionSlave`). Nothing changes where
        the speed is ``speed`` and stays so: a constant speed that has not varied, or a
        profile whose last point is past. ValueError for a speed that is not finite and > 0."""
        now = self.loads.profile
        if (now is None and speed == self.loads.input_speed) or (
                now is not None and now.speeds[-1] == speed and now.times[-1] <= self.t):
            return
        if not (math.isfinite(speed) and speed > 0.0):
            raise ValueError(f"speed = {speed!r} rad/s: must be finite and > 0")
        if now is None:
            now = SpeedProfile((0.0,), (self.loads.input_speed,))
        self.set_profile(now.continued(self.t, t1, float(speed)))

    def set_profile(self, profile) -> None:
        """The input speed's profile from now on (:class:`gear_fmu.speed_profile.SpeedProfile`,
        its angle continuing the current one: :meth:`follow_speed`, or a restored state's)."""
        if (profile is None) != (self.loads.profile is None):
            self._events = None  # (at constant speed their angle is inlined, else the profile's)
        self.loads = replace(self.loads, profile=profile)
        self._one = None

    def _at_time(self, t1: float, slotted) -> None:
        """A run-up's speed-dependent loads for the step ending at t1 [s] (nothing at constant
        speed; docs/equations.md "Run-ups"): the unbalances at the speed and angular
        acceleration of t1 (:func:`gear_fmu.loads.accelerated_unbalance_coefficients`), and
        the rigid-body inertia of the ramp ``-M u_rb dOmega/dt`` (``u_rb`` the rigid rotation
        per unit input angle, :meth:`gear_fmu.system.GearShaftSystem.rigid_rotation`) on the
        constant loads: on the condensed DOFs directly, on the others through the condensation
        of each sub-step length ``h`` of ``slotted`` ([(slot, h)]) the step uses (the ramp's
        acceleration of t1 for all of them)."""
        p = self.loads.profile
        if p is None:
            return
        alpha = p.acceleration(t1)
        self._unb_coef = accelerated_unbalance_coefficients(
            self.system.unbalances, self._signed_ratios, p, t1)
        if self._ramp is None:
            u_rb = self.system.rigid_rotation(self._signed_ratios)
            self._ramp = (self._permute(-(self.system.mass @ u_rb)), {})
        load, condensed = self._ramp
        self._f_c = self._f_c_const + alpha * load[:self.nc]
        g_const = self._condensations.arrays()[1]
        if len(condensed) > 256:
            condensed.clear()
        for k, h in slotted:
            cond, g_f = self._dynamic(h)
            if h not in condensed:
                condensed[h] = cond.g @ load[self.nc:]
            g_const[k] = g_f + alpha * condensed[h]

    def mesh_angles(self, input_angle: float) -> np.ndarray:
        """Each mesh's pinion (driver) angle [rad] at the input shaft's angle
        ``input_angle`` [rad]: the angle of the driver's shaft, turned into the pair's own
        frame (where the driver turns about +z)."""
        return self._driver_ratio * input_angle

    @property
    def mesh_periods(self) -> np.ndarray:
        """Each mesh's period ``2 pi / (omega_driver z_driver)`` [s] (inf at zero speed)."""
        return self._mesh_periods.copy()

    @property
    def mesh_period(self) -> float:
        """The shortest mesh period [s]: the case's time step is a fraction of it."""
        return self._mesh_period

    def _dynamic(self, dt: float):
        hit = self._dyn_cache.get(dt)
        if hit is not None:
            return hit
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"time step dt = {dt!r} s must be finite and > 0")
        self._require_damping()
        entry = self._condensation(dt)
        if len(self._dyn_cache) > 256:
            self._dyn_cache.clear()
        self._dyn_cache[dt] = entry
        return entry

    @one_blas_thread
    def _condensation(self, dt: float) -> tuple:
        """``(Condensation, g f_const_r)`` of the Newmark tangent at dt [s] (Eq. 12, 14).
        On one BLAS thread whoever asks (a step alone, a plan of steps, a test): LAPACK's
        factors and BLAS's products change their last bits with the thread count, and a
        step alone once differed from the same step of a plan by them (numpy 1.26's
        OpenBLAS here, the CI machine with the newest)."""
        c0, c1 = 4.0 / dt**2, 2.0 / dt
        cond = Condensation(c0 * self._m + c1 * self._c + self._k, self.nc,
                            symmetric=not self.gyroscopic)
        return cond, cond.g @ self._f_const[self.nc:]

    def check_laws(self, f0, kb, cb):
        """The laws as checked arrays of this structure's bearings
        (:func:`gear_fmu.step.assembly.check_laws`)."""
        return check_laws(f0, kb, cb, self.nb)

    @one_blas_thread
    def _m_inv_columns(self) -> np.ndarray:
        """``M^-1`` restricted to the condensed columns, (n, nc) (internal order; on one
        BLAS thread, as :meth:`_condensation`)."""
        if self._m_inv is None:
            cho = scipy.linalg.cho_factor(self._m)
            self._m_inv = np.ascontiguousarray(
                scipy.linalg.cho_solve(cho, np.eye(self._m.shape[0])[:, :self.nc]))
        return self._m_inv

    def _m_inv_gear_columns(self) -> np.ndarray:
        """``M^-1`` restricted to the condensed gear-node columns, (n, ng), contiguous."""
        if self._m_inv_g is None:
            self._m_inv_g = np.ascontiguousarray(self._m_inv_columns()[:, :self.ng])
        return self._m_inv_g

    def _errors(self, angles) -> np.ndarray:
        """(n_meshes, 12) error displacements at the meshes' ``angles`` [rad]."""
        out = np.zeros((len(self.meshes), 12))
        if self._has_err:
            for m, (mesh, angle) in enumerate(zip(self.meshes, angles, strict=True)):
                if mesh.has_errors:
                    out[m] = mesh.error_displacement(float(angle))
        return out

    # ------------------------------------------------------------------ solves
    @one_blas_thread
    def static(self, F0, Kb, Cb=None) -> StepInfo:
        """Static solution X0 at the current time with the given affine bearing laws.

        Velocities and accelerations are set to zero (paper Sec. 3.2); the loads are the constant
        ones (torque, gravity) without the rotating unbalance. ``Cb`` is ignored (zero velocity).
        """
        zeros = np.zeros((self.nb, 2, 2))
        f0, kb, _ = self.check_laws(F0, Kb, zeros if Cb is None else Cb)
        info = self.static_at(f0, kb, self.input_angle(self.t))
        if self.consistent_start and self._unb_idx.size:
            f = np.zeros(self.nc)
            unb = unbalance_force(self._unb_coef, self.t)  # Eq. (10)
            for (iu, iv), (fu, fv) in zip(self._unb_idx, unb, strict=True):
                f[iu] += fu
                f[iv] += fv
            self.a = self._m_inv_columns() @ f
        return info

    @one_blas_thread
    def static_at(self, f0, kb, input_angle: float) -> StepInfo:
        """Static solution with the input shaft at the rigid-body angle ``input_angle`` [rad]
        (checked laws ``f0`` (nb, 2) [N], ``kb`` (nb, 2, 2) [N/m])."""
        cond, nc, ng = self._static, self.nc, self.ng
        b = self._f_const
        out = cond.g @ b[nc:]
        z0 = b[:nc] + out[:nc]
        z0[ng:ng + 2 * self.nb] += f0.ravel()
        y = out[nc:]
        s_lin = cond.s0.copy()
        for j in range(self.nb):
            sl = slice(ng + 2 * j, ng + 2 * j + 2)
            s_lin[sl, sl] += kb[j]
        angles = self.mesh_angles(input_angle)
        f_scale = max(float(np.linalg.norm(b)), float(np.linalg.norm(f0)))
        residuals = np.empty(self.max_iter + 1)
        fc, kc = np.empty(ng), np.empty((ng, ng))
        status, k, xc = contact_newton(
            s_lin, z0, self._approach.copy(), angles, self._errors(angles), self._has_err,
            self._mesh_tuple, fc, kc, self._totals, self._lengths, False, f_scale, self.tol,
            self.max_iter, residuals)
        self._raise(status, k, residuals, self.t, "static solution")
        keep_evaluation(self._mesh_tuple)
        self.x = np.concatenate([xc, y - cond.w @ xc])
        self.v = np.zeros_like(self.x)
        self.a = np.zeros_like(self.x)
        self.solved = True
        return StepInfo(self.t, k, float(residuals[k]), residuals[:k + 1].tolist())

    def _raise(self, status, k, residuals, t, what) -> None:
        """The error of a structural solve that returned ``status`` after ``k`` passes."""
        if status == CONVERGED:
            return
        history = residuals[:k + 1].tolist()
        if status == SINGULAR:
            slices = ", ".join(f"{m.name} {int(np.count_nonzero(w.out[2]))}"
                               for m, w in zip(self.layout.meshes, self._work, strict=True))
            raise NewmarkConvergenceError(
                f"{what} at t = {t:.9g} s: singular tangent at iteration {k} (mesh slices in "
                f"contact: {slices}; a mesh without tooth contact leaves its shafts free in "
                "torsion - check the torque sign)")
        raise NewmarkConvergenceError(
            f"{what} at t = {t:.9g} s did not converge: relative residual "
            f"{history[-1]:.3e} (tol {self.tol:.1e}) after {self.max_iter} iterations; "
            f"last residuals {', '.join(f'{v:.2e}' for v in history[-5:])}")

    @one_blas_thread
    def step(self, dt: float, F0, Kb, Cb) -> StepInfo:
        """One Newmark step t -> t + dt with affine bearing laws F0 - Kb X - Cb Xdot.

        Parameters
        ----------
        dt : float
            Time step [s].
        F0 : (nb, 2) array
            Bearing force at X = 0, Xdot = 0 [N] (global s, t).
        Kb, Cb : (nb, 2, 2) arrays
            Bearing stiffness [N/m] and damping [N s/m] (global s, t).

        Raises
        ------
        NewmarkConvergenceError
            With the step number, the time and the residual.
        """
        f0, kb, cb = check_laws_fast(F0, Kb, Cb, self.nb)
        counts, slots, table, angles, after, errs, errs_a, end = self._one_step(dt)
        residuals, x1, v1, a1 = self._step_work[4:]
        status, piece, k = advance_step(
            counts, self._held_arrays((slots, table, angles, after, errs, errs_a)), self.x,
            self.v, self.a, self._f_c, self._unb_coef, f0, kb, cb, self._has_err,
            self._f_scale, self.tol, self.max_iter, x1, v1, a1)
        if status != CONVERGED:
            self._raise(status, k, residuals, float(table[piece, 1]),
                        f"Newmark step {self.n_steps + 1}")
        # the new state in the work buffers, the old state's arrays the next step's buffers
        self._step_work[5:] = [self.x, self.v, self.a]
        self.x, self.v, self.a = x1, v1, a1
        self.t = end
        self.n_steps += 1
        return StepInfo(self.t, k, float(residuals[k]), residuals[:k + 1].tolist())

    def _held_arrays(self, plan: tuple):
        """The arrays of :func:`gear_fmu.step.kernel.advance_step` that stay from step to
        step, held in one numba object (:func:`bearing_fmu.borrowed.held`) with the step's
        ``plan`` (its slots ... contact-event error displacements, :meth:`_one_step`'s
        buffers): built again when one of them is another array than the held one (a
        longer plan, another damping, new condensations)."""
        arrays = (*plan, self._mc, *self._condensations.arrays(), self._unb_idx,
                  self._mesh_tuple, *self._step_work[:5], self._m_inv_g, self._memo,
                  self._totals, self._lengths)
        kept = self._held
        if kept is None or len(kept[0]) != len(arrays) or not all(
                map(operator.is_, kept[0], arrays)):
            kept = self._held = (arrays, held(arrays))
        return kept[1]

    def _one_step(self, dt: float) -> tuple:
        """The arguments of :func:`gear_fmu.step.kernel.advance_pieces` for the step of dt
        from the structure's time (:meth:`steps_plan`'s for one step, built lean: a step alone
        is on an FMU's hot path), kept for the next call from the same time: a master takes a
        step again at each of its iterations."""
        self._follow_gyroscopic(self.t + dt)
        key = (self.t, dt, self._condensations.generation)
        if self._one is not None and self._one[0] == key:
            if self.loads.profile is not None:  # (a plan of another step may have set them)
                n, index, table = self._one[1][0], self._one[1][1], self._one[1][2]
                self._at_time(self._one[1][7], [(index[p], table[p, 0]) for p in range(n)])
            return self._one[1]
        self._check_step(dt)
        quiet = self._quiet_step(dt)
        pieces = self._pieces(dt, self.t) if quiet is None else [quiet]
        slots = self._condensations
        slots.make_room([h for h, _, _, _ in pieces], first=True)
        n, n_meshes = len(pieces), len(self.meshes)
        buf = self._one_buf
        if buf is None or buf[0].size < n:  # (filled in place: arrays per step cost more)
            size = max(n, 4)
            buf = self._one_buf = (np.zeros(size, dtype=np.int64), np.zeros((size, 2)),
                                   np.zeros((size, n_meshes)), np.zeros((size, n_meshes)),
                                   np.zeros((size, n_meshes, 12)),
                                   np.zeros((size, n_meshes, 12)))
        index, table, angles, after, errs, errs_after = buf
        for p, (h, te, before, aft) in enumerate(pieces):
            index[p] = slots.slot(h, self._dynamic)
            table[p, 0], table[p, 1] = h, te
            for m in range(n_meshes):
                angles[p, m], after[p, m] = before[m], aft[m]
            if self._has_err:
                errs[p] = self._errors(before)
                errs_after[p] = self._errors(np.where(np.isnan(aft), before, aft))
        if self.loads.profile is not None:
            self._at_time(pieces[-1][1], [(index[p], table[p, 0]) for p in range(n)])
        key = (self.t, dt, slots.generation)
        self._one = (key, (n, index, table, angles, after, errs, errs_after, pieces[-1][1]))
        self._m_inv_gear_columns()
        if self._step_work is None:
            ng, size = self.ng, self.x.size
            self._step_work = [np.empty(ng), np.empty((ng, ng)), self._totals.copy(),
                               self._lengths.copy(), np.empty(self.max_iter + 1),
                               np.empty(size), np.empty(size), np.empty(size)]
        return self._one[1]

    # how many steps a step alone looks ahead for contact events (_quiet_step)
    _AHEAD = 64

    def _quiet_step(self, dt: float):
        """The step of dt from the structure's time as its one piece ``(dt, end time [s],
        mesh angles, NaN)`` when it surely has no contact event, else None: looked up in the
        next ``_AHEAD`` steps from a time, each starting where the last ends
        (:meth:`_quiet_steps`, their angles at once), made again when the step, the speed or
        the time is another (a rollback, a new run)."""
        ld = self.loads
        key = (dt, ld.input_angle0, ld.input_speed, ld.profile is None, self.locate_contact)
        ahead = self._ahead
        if ahead is None or ahead[0] != key or ahead[1][ahead[4]] != self.t:
            times = step_times(self.t, dt, self._AHEAD)
            quiet = self._quiet_steps(times)
            angles = self._plain_angles(times[1:]) if quiet.any() else None
            ahead = self._ahead = [key, times, quiet, angles, 0]
        j = ahead[4]
        ahead[4] = min(j + 1, self._AHEAD - 1)  # (the last is looked up from its own time)
        if not ahead[2][j]:
            return None
        return dt, float(ahead[1][j + 1]), ahead[3][j], self._no_after()

    def _plain_angles(self, ends: np.ndarray) -> np.ndarray:
        """(len(ends), n_meshes) angles [rad] of the meshes at the ends [s] of steps of one
        piece, as :meth:`_pieces` computes them (the contact events' pinion angles, at once;
        without contact location :meth:`mesh_angles`, step by step)."""
        if not self.locate_contact:
            return np.array([self.mesh_angles(self.input_angle(te)) for te in ends.tolist()],
                            dtype=float).reshape(len(ends), len(self.meshes))
        out = np.empty((len(ends), len(self.meshes)))
        for m, ev in enumerate(self._contact_events()):
            out[:, m] = ev.pinion_angle(ends)
        return out

    def _no_after(self) -> np.ndarray:
        """The angles after events of a piece without any: NaN per mesh."""
        return np.full(len(self.meshes), math.nan)

    def _pieces(self, dt: float, t: float) -> list:
        """``[(h [s], end time [s], angles before, angles after or NaN)]`` of a step of dt
        from ``t`` [s] (:func:`gear_fmu.step.events.train_pieces`; one piece without contact
        location)."""
        if not self.locate_contact:
            t1 = t + dt
            return [(dt, t1, self.mesh_angles(self.input_angle(t1)),
                     np.full(len(self.meshes), math.nan))]
        return train_pieces(self._contact_events(), t, dt)

    def _contact_events(self) -> list:
        """Each mesh's :class:`gear_fmu.step.events.ContactEvents`, made when first needed."""
        if self._events is None and self.loads.profile is not None:
            self._events = [ContactEvents(mesh, lambda t, r=float(r): r * self.input_angle(t))
                            for mesh, r in zip(self.meshes, self._driver_ratio, strict=True)]
        if self._events is None:  # (input_angle inlined: a call per angle on the hot path)
            a0, w = self.loads.input_angle0, self.loads.input_speed
            self._events = [ContactEvents(mesh, lambda t, r=float(r): r * (a0 + w * t))
                            for mesh, r in zip(self.meshes, self._driver_ratio, strict=True)]
        return self._events

    def _quiet_steps(self, times: np.ndarray) -> np.ndarray:
        """Whether each step from ``times[k]`` to ``times[k + 1]`` [s] is one piece of dt for
        sure (:func:`gear_fmu.step.events.quiet_steps`): none under a speed profile (each
        step planned alone), all without contact location."""
        n = len(times) - 1
        if self.loads.profile is not None:
            return np.zeros(n, dtype=bool)
        if not self.locate_contact:
            return np.ones(n, dtype=bool)
        return quiet_steps(self._contact_events(), times)

    def _check_step(self, dt: float) -> None:
        if not self.solved:
            raise RuntimeError("call static() before the first step (initial state X0)")
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"time step dt = {dt!r} s must be finite and > 0")

    def steps_plan(self, dt: float, n: int) -> StepsPlan:
        """The next steps of dt, at most ``n`` (fewer when the condensations of their
        sub-steps would not fit the slots together), as the inputs of the compiled loop over
        steps (:func:`gear_fmu.step.kernel.advance_pieces` per step), a :class:`StepsPlan`.
        Finish it with :meth:`end_steps`.

        The steps follow each other as :meth:`step` takes them (each starts where the last
        ended, ``t + dt``); those without a contact event
        (:func:`gear_fmu.step.events.quiet_steps`, most of them) are one piece of dt filled
        in at once, the others cut at their events
        (:func:`gear_fmu.step.events.train_pieces`)."""
        self._check_step(dt)
        slots = self._condensations
        if self.loads.profile is not None:  # the loads of each step: one step per plan
            n = min(n, 1)
            self._follow_gyroscopic(self.t + dt)
        times = step_times(self.t, dt, n)
        quiet = self._quiet_steps(times)
        cut = {}  # step -> (pieces, slots) of the steps cut at their events
        plain, m = None, n  # the slot of a quiet step's one piece; the steps that fit
        first_quiet = int(np.argmax(quiet)) if quiet.any() else n
        for k in sorted([*np.flatnonzero(~quiet).tolist(), first_quiet])[:n]:
            if k == first_quiet:
                lengths, pieces = [dt], None
            else:
                pieces = self._pieces(dt, float(times[k]))
                lengths = [h for h, _, _, _ in pieces]
            if not slots.make_room(lengths, first=k == 0):
                m = k
                break
            slotted = [slots.slot(h, self._dynamic) for h in lengths]
            if pieces is None:
                plain = slotted[0]
            else:
                cut[k] = (pieces, slotted)
                self._at_time(pieces[-1][1], zip(slotted, lengths, strict=True))
        ends = times[1:m + 1]
        n_meshes = len(self.meshes)
        width = max((len(pieces) for pieces, _ in cut.values()), default=1)
        counts = np.ones(m, dtype=np.int64)
        index = np.zeros((m, width), dtype=np.int64)
        index[:, 0] = plain if plain is not None else 0
        table = np.zeros((m, width, 2))
        table[:, 0, 0], table[:, 0, 1] = dt, ends
        angles = np.zeros((m, width, n_meshes))
        if plain is not None:
            angles[:, 0] = self._plain_angles(ends)
        after = np.full((m, width, n_meshes), math.nan)
        end_times = [[te] for te in ends.tolist()]
        for i, (pieces, slotted) in cut.items():  # (all before m: the loop stopped there)
            counts[i] = len(pieces)
            index[i, :len(pieces)] = slotted
            end_times[i] = [te for _, te, _, _ in pieces]
            for p, (h, te, before, aft) in enumerate(pieces):
                table[i, p] = h, te
                angles[i, p] = before
                after[i, p] = aft
        rows = m if self._has_err else 1
        errs, errs_after = np.zeros((rows, width, n_meshes, 12)), np.zeros(
            (rows, width, n_meshes, 12))
        if self._has_err:
            for i in range(m):
                for p in range(counts[i]):
                    errs[i, p] = self._errors(angles[i, p])
                    errs_after[i, p] = self._errors(
                        np.where(np.isnan(after[i, p]), angles[i, p], after[i, p]))
        ng, size = self.ng, self.x.size
        return StepsPlan(
            (counts, index, self._mc, *slots.arrays(), table, angles, after, errs, errs_after),
            (self.x.copy(), self.v.copy(), self.a.copy()),
            (self._unb_coef, self._unb_idx, self._f_c, self._has_err, self._mesh_tuple,
             self._f_scale, self.tol, self.max_iter,
             self._m_inv_gear_columns(), self._memo),
            (np.empty(ng), np.empty((ng, ng)), self._totals.copy(), self._lengths.copy(),
             np.empty(self.max_iter + 1), np.empty(size), np.empty(size), np.empty(size)),
            end_times)

    def end_steps(self, plan: StepsPlan, count: int, totals, lengths) -> None:
        """Take the state after the first ``count`` steps of ``plan`` (:meth:`steps_plan`):
        X, Xd, Xdd from its ``state`` and the meshes' kept evaluations (the kernel keeps
        them), of total loads ``totals`` [N] and contact lengths ``lengths`` [m]; the time
        and step count advance as ``count`` calls of :meth:`step` would."""
        if count:
            self.x, self.v, self.a = (s.copy() for s in plan.state)
            self._totals[:], self._lengths[:] = totals, lengths
            self.t = plan.ends[count - 1][-1]
            self.n_steps += count

    def raise_failed_step(self, status, k, residuals, t1) -> None:
        """Raise the error of the sub-step to ``t1`` [s] of a compiled step that returned
        ``status`` after ``k`` passes with these ``residuals``: the error of :meth:`step`."""
        if status == CONVERGED:
            raise ValueError("raise_failed_step: the step converged")
        self._raise(status, k, residuals, t1, f"Newmark step {self.n_steps + 1}")

    # ------------------------------------------------------------------ state
    @property
    def mesh_states(self) -> tuple[MeshState, ...] | None:
        """Each mesh's evaluation at the current state (copies; None before a solution)."""
        if not self.solved:
            return None
        return tuple(w.state(w.kept, total, length, self.x[w.idx]) for w, total, length in
                     zip(self._work, self._totals, self._lengths, strict=True))

    def get_state(self) -> StructureState:
        """A copy of everything a step changes (for the master's rollback)."""
        meshes = None
        if self.solved:  # (a plain loop: a master saves a state at every step)
            x, totals, lengths = self.x, self._totals.tolist(), self._lengths.tolist()
            meshes = tuple([(w.kept_f.copy(), w.kept_b.copy(), totals[m], lengths[m],
                             w.mesh.transmission_error(x[w.idx]))
                            for m, w in enumerate(self._work)])
        return StructureState(self.t, self.n_steps, self.x.copy(), self.v.copy(), self.a.copy(),
                              meshes)

    def set_state(self, state: StructureState) -> None:
        """Restore a state from :meth:`get_state` exactly."""
        self.t, self.n_steps = state.t, state.n_steps
        self.x, self.v, self.a = state.x.copy(), state.v.copy(), state.a.copy()
        self.solved = state.meshes is not None
        if self.solved:
            if len(state.meshes) != len(self._work):
                raise ValueError(f"a state of {len(state.meshes)} meshes for a structure of "
                                 f"{len(self._work)}")
            for m, w in enumerate(self._work):
                saved = state.meshes[m]
                w.kept_f[:] = saved[0]
                w.kept_b[:] = saved[1]
                self._totals[m], self._lengths[m] = saved[2], saved[3]

    # ------------------------------------------------------------------ outputs
    def journal_states(self) -> np.ndarray:
        """(nb, 4) [u, v, udot, vdot] at the bearing nodes, global (s, t) frame [m, m/s]."""
        xv = np.concatenate((self.x[:self.nc], self.v[:self.nc]))
        return xv.take(self._state_outputs[:4 * self.nb]).reshape(self.nb, 4)

    def gear_displacements(self) -> np.ndarray:
        """(n_gears, 6) DOFs (u, v, w, phi, psi, theta) of each gear's node (layout order)."""
        return np.array([self.x[self._gear_uv[g, 0]:self._gear_uv[g, 0] + DOF_PER_NODE]
                         for g in range(len(self.layout.gears))]).reshape(-1, DOF_PER_NODE)

    def state_outputs(self) -> list[float]:
        """:meth:`journal_states` (row by row) then u, v of each gear's node as a list: what
        an FMU outputs at every step, in one gather [m, m/s]."""
        xv = np.concatenate((self.x[:self.nc], self.v[:self.nc]))
        return xv.take(self._state_outputs).tolist()

    def mesh_forces(self) -> np.ndarray:
        """Total normal force of each mesh in the current state [N]."""
        return self._totals.copy()

    def transmission_errors(self) -> np.ndarray:
        """Each mesh's ``r_b1 theta1 + r_b2 theta2`` in the current state [m]
        (:meth:`gear_fmu.mesh.element.MeshElement.transmission_error`)."""
        return np.array([w.mesh.transmission_error(self.x[w.idx]) for w in self._work])

    def full_vector(self, which: str = "x") -> np.ndarray:
        """Displacement / velocity / acceleration in the full numbering of the system."""
        vec = {"x": self.x, "v": self.v, "a": self.a}[which]
        out = np.zeros(self.system.n_dof)
        out[self._full_of_internal] = vec
        return out
