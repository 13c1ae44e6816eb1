"""The gear-shaft structure as a time stepper: Eq. (9) with Newmark, Newton and contact (Sec. 3).

``Structure`` owns the structural state (t, X, Xdot, Xddot, mesh contact set). One call of
:meth:`Structure.step` is a full Newmark step (Eq. 11-16) of

    M Xdd + C Xd + K_shaft X = F0(t) + F_mesh(t, X) + sum_j B_j^T (F0_j - Kb_j X_j - Cb_j Xd_j)

where the bearings enter as affine laws given by the caller in the global (s, t) frame at the
four bearing nodes (X_j = (u, v) of bearing node j), exactly as Eq. (17) but re-set by the master
at every iteration: the Newton tangent is ``4/dt^2 M + 2/dt C + K + K_mesh + Kb + 2/dt Cb``
(Eq. 14, 16). External loads ``F0(t)``: input torque T on the pinion shaft's torsion DOF at its
input end, mass unbalance of Eq. (10) on each shaft, optional gravity; the resisting torque is the
reaction of the clamped output torsion DOF (see :mod:`gear_fmu.system`).

Solution method
---------------
Within a step only the mesh (12 gear-node DOFs) and the bearing laws (8 bearing DOFs) change the
tangent; the rest of ``A = 4/dt^2 M + 2/dt C + K_shaft`` is constant at fixed dt. The free DOFs are
ordered ``[c; r]`` with c = (pinion node, gear node, bearings 1-4 (u, v)) and the r block is
eliminated once per dt (dense inverse of A_rr, W = A_rr^-1 A_rc, Schur complement
S0 = A_cc - A_cr W). Each step then costs one matrix-vector product for the right-hand side and,
per Newton/contact iteration, a mesh evaluation and a 20 x 20 solve of

    (S0 + Kb + 2/dt Cb + K_mesh) X_c = z,      X_r = A_rr^-1 b_r - W X_c.

The mesh force is piecewise linear in X (fixed active set), so Newton converges in one solve
once the contact set is right; the contact loop ends when the set is stable and the relative
residual ``||G_c|| / max(||F_ext||, ||F_mesh||, ||F_bearing||)`` is below ``tol`` (the r rows of G
vanish by construction, to round-off).

Mesh element API consumed: ``mesh.evaluate(pinion_angle, q12) -> state`` with ``state.force``
(12,) the generalised mesh force on the gear-node DOFs, ``state.stiffness`` (12, 12) its tangent
``-dforce/dq`` for the current active set, ``state.active`` the contact set (compared between
iterates), and for outputs ``total_load``, ``transmission_error``, ``load``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from numba import njit

from .dofs import DOF_PER_NODE, THETA, U, V
from .modal import modal_damping_matrix, natural_modes
from .newmark import NewmarkConvergenceError
from .system import GearShaftSystem

__all__ = ["StepInfo", "Structure", "StructureLoads", "StructureState"]

N_GEAR = 12  # gear-node DOFs in the condensed block
N_BEARING = 4
NC = N_GEAR + 2 * N_BEARING
#: first static iterate: pinion torsion [rad] that closes every potential contact
INITIAL_APPROACH_ROTATION = 1e-3


@dataclass(frozen=True)
class StructureLoads:
    """External loads and kinematics (paper Sec. 3.1 and 4.1).

    Parameters
    ----------
    torque : float
        Input torque T on the pinion shaft [N m] (> 0 drives the pinion about +z).
    input_speed : float
        Pinion speed omega [rad/s] (>= 0); the gear turns at omega z1/z2 about -z.
    unbalance : (float, float)
        e_mu of the pinion shaft and of the gear shaft [m] (Eq. 10), applied at the gear nodes
        with M = shaft + gear mass.
    gravity : (float, float) or None
        Gravity acceleration components (g_s, g_t) [m/s^2]; None = no gravity.
    pinion_angle0 : float
        Rigid-body pinion angle at t = 0 [rad].
    """

    torque: float = 220.0
    input_speed: float = 325.0
    unbalance: tuple[float, float] = (0.0, 0.0)
    gravity: tuple[float, float] | None = None
    pinion_angle0: float = 0.0

    def __post_init__(self) -> None:
        if not math.isfinite(self.torque):
            raise ValueError(f"torque = {self.torque!r} N m is not finite")
        if not (math.isfinite(self.input_speed) and self.input_speed >= 0.0):
            raise ValueError(f"input_speed = {self.input_speed!r} rad/s must be finite and >= 0")
        if len(self.unbalance) != 2 or not all(
            math.isfinite(e) and e >= 0.0 for e in self.unbalance
        ):
            raise ValueError(f"unbalance = {self.unbalance!r} m: two finite values >= 0")


@dataclass
class StepInfo:
    """Outcome of one step or static solve."""

    t: float
    iterations: int  # linear solves of the Newton/contact loop
    residual: float
    residuals: list = field(default_factory=list)


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


@njit(cache=True)
def _prepare_step(h, g_const, x, v, a, f_c, unb, f0, kb, cb, s0, dt, ng):
    """Right-hand side and condensed tangent of one Newmark step (Eq. 12, 14, 16).

    Returns ``s_lin`` (nc, nc) = S0 + Kb + 2/dt Cb, ``z0`` (nc,) and ``y`` = A_rr^-1 b_r.
    """
    n = x.size
    nc = s0.shape[0]
    c0 = 4.0 / dt**2
    c1 = 2.0 / dt
    c2 = 4.0 / dt
    pq = np.empty(2 * n)
    for i in range(n):
        pq[i] = c0 * x[i] + c2 * v[i] + a[i]
        pq[n + i] = c1 * x[i] + v[i]
    out = h @ pq
    z0 = np.empty(nc)
    for i in range(nc):
        z0[i] = out[i] + out[nc + i] + g_const[i] + f_c[i]
    z0[0] += unb[0]  # pinion node (u, v)
    z0[1] += unb[1]
    z0[6] += unb[2]  # gear node (u, v)
    z0[7] += unb[3]
    y = out[2 * nc:] + g_const[nc:]
    s_lin = s0.copy()
    for j in range(4):
        o = ng + 2 * j
        for r in range(2):
            acc = f0[j, r]
            for c in range(2):
                acc += cb[j, r, c] * (c1 * x[o + c] + v[o + c])
                s_lin[o + r, o + c] += kb[j, r, c] + c1 * cb[j, r, c]
            z0[o + r] += acc
    return s_lin, z0, y


@njit(cache=True)
def _all_finite(f0, kb, cb):
    """True when every entry of the bearing laws is finite."""
    return np.isfinite(f0).all() and np.isfinite(kb).all() and np.isfinite(cb).all()


@njit(cache=True)
def _same_set(a, b):
    """Equality of two boolean contact sets (False if the sizes differ)."""
    if a.shape != b.shape:
        return False
    for i in range(a.size):
        if a.flat[i] != b.flat[i]:
            return False
    return True


@njit(cache=True)
def _residual_norm(s_lin, z0, xc, mesh_force):
    """2-norm of the condensed residual G_c = S X_c - z0 - F_mesh (mesh rows first)."""
    nc = z0.size
    ng = mesh_force.size
    acc = 0.0
    for i in range(nc):
        g = -z0[i]
        for j in range(nc):
            g += s_lin[i, j] * xc[j]
        if i < ng:
            g -= mesh_force[i]
        acc += g * g
    return np.sqrt(acc)


@njit(cache=True)
def _newton_solve(s_lin, z0, xc, mesh_force, mesh_stiffness):
    """Solve (S + K_mesh) X_c = z0 + F_mesh + K_mesh X_c (fixed active set), Eq. (13)."""
    nc = z0.size
    ng = mesh_force.size
    s = s_lin.copy()
    rhs = z0.copy()
    for i in range(ng):
        acc = mesh_force[i]
        for j in range(ng):
            s[i, j] += mesh_stiffness[i, j]
            acc += mesh_stiffness[i, j] * xc[j]
        rhs[i] += acc
    # Gaussian elimination with partial pivoting (nc = 20)
    for k in range(nc):
        p = k
        big = abs(s[k, k])
        for i in range(k + 1, nc):
            if abs(s[i, k]) > big:
                big = abs(s[i, k])
                p = i
        if big == 0.0:
            return rhs, False
        if p != k:
            for j in range(nc):
                tmp = s[k, j]
                s[k, j] = s[p, j]
                s[p, j] = tmp
            tmp = rhs[k]
            rhs[k] = rhs[p]
            rhs[p] = tmp
        piv = s[k, k]
        for i in range(k + 1, nc):
            f = s[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, nc):
                    s[i, j] -= f * s[k, j]
                rhs[i] -= f * rhs[k]
    for i in range(nc - 1, -1, -1):
        acc = rhs[i]
        for j in range(i + 1, nc):
            acc -= s[i, j] * rhs[j]
        rhs[i] = acc / s[i, i]
    ok = True
    for i in range(nc):
        if not np.isfinite(rhs[i]):
            ok = False
    return rhs, ok


@njit(cache=True)
def _finish_step(x, v, a, xc, y, w, dt):
    """X_r = y - W X_c, then Newmark velocities and accelerations (Eq. 12)."""
    n = x.size
    nc = xc.size
    x1 = np.empty(n)
    x1[:nc] = xc
    x1[nc:] = y - w @ xc
    c0 = 4.0 / dt**2
    c1 = 2.0 / dt
    c2 = 4.0 / dt
    v1 = np.empty(n)
    a1 = np.empty(n)
    for i in range(n):
        dx = x1[i] - x[i]
        v1[i] = c1 * dx - v[i]
        a1[i] = c0 * dx - c2 * v[i] - a[i]
    return x1, v1, a1


class _Condensation:
    """Static condensation of a constant symmetric matrix A (ordered [c; r]) onto c."""

    def __init__(self, a: np.ndarray, nc: int = NC):
        acc, acr, arr = a[:nc, :nc], a[:nc, nc:], a[nc:, nc:]
        cho = scipy.linalg.cho_factor(arr)
        arr_inv = scipy.linalg.cho_solve(cho, np.eye(arr.shape[0]))
        self.w = arr_inv @ acr.T  # A_rr^-1 A_rc
        self.s0 = acc - acr @ self.w
        # rows: (-W^T, A_rr^-1) applied to b_r gives (z correction, y)
        self.g = np.vstack([-self.w.T, arr_inv])


class Structure:
    """Gear-shaft structure stepping one Newmark step at a time (module docstring).

    Parameters
    ----------
    system : GearShaftSystem
        Assembled shafts and discs (:func:`gear_fmu.system.paper_system_example`).
    mesh : object
        Mesh element with ``evaluate(pinion_angle, q12)`` (module docstring).
    loads : StructureLoads
    zeta : float
        Modal damping factor (paper 0.03).
    damping_bearing_stiffness : float or (4, 2, 2)
        Bearing stiffness of the reference configuration of the modal damping
        (:mod:`gear_fmu.modal`) [N/m].
    damping : (n_dof, n_dof) array, optional
        Explicit damping matrix (full numbering) replacing the modal one.
    tol : float
        Relative residual limit l (paper 1e-5).
    max_iter : int
        Newton/contact iterations per step.
    """

    n_bearings = N_BEARING

    def __init__(
        self,
        system: GearShaftSystem,
        mesh,
        loads: StructureLoads | None = None,
        zeta: float = 0.03,
        damping_bearing_stiffness=1e8,
        damping: np.ndarray | None = None,
        tol: float = 1e-5,
        max_iter: int = 30,
    ):
        if not (tol > 0.0 and math.isfinite(tol)):
            raise ValueError(f"tol = {tol!r} must be finite and > 0")
        self.system = system
        self.mesh = mesh
        self.loads = StructureLoads() if loads is None else loads
        self.tol = tol
        self.max_iter = int(max_iter)
        self.profile = False
        self.timing = {"mesh": 0.0, "assembly": 0.0, "solve": 0.0}
        self._ordering()
        mp = self._permute(system.mass)
        kp = self._permute(system.stiffness)
        self._m, self._k = mp, kp
        self._static = _Condensation(kp)
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
        self._laws = None
        self._dyn_cache: dict[float, tuple] = {}
        self.zeta = float(zeta)
        if damping is not None:
            self.damping_full = np.asarray(damping, dtype=float)
            if self.damping_full.shape != (system.n_dof, system.n_dof):
                raise ValueError(
                    f"damping shape {self.damping_full.shape} must be "
                    f"({system.n_dof}, {system.n_dof})"
                )
            self._c = self._permute(self.damping_full)
        else:
            self.set_damping_reference(damping_bearing_stiffness)

    def set_damping_reference(self, bearing_stiffness) -> None:
        """(Re)build the modal damping C on the modes of the reference configuration.

        ``bearing_stiffness``: isotropic [N/m] or (4, 2, 2) bearing stiffness (symmetric part
        used) of the reference configuration, :mod:`gear_fmu.modal`; the mean mesh stiffness is
        taken at the static load with these bearings. The master calls this with the bearings'
        stiffness at the static solution X0 before the transient.
        """
        system = self.system
        if self.zeta == 0.0:
            self.damping_full = np.zeros((system.n_dof, system.n_dof))
        else:
            k_mesh = self.mean_mesh_stiffness(bearing_stiffness)
            self.reference_modes = natural_modes(system, bearing_stiffness, k_mesh)
            self.damping_full = modal_damping_matrix(system, self.reference_modes, self.zeta)
            self.reference_mesh_stiffness = k_mesh
        self._c = self._permute(self.damping_full)
        self._dyn_cache.clear()

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

    def _internal(self, full_dof: int) -> int:
        pos = np.flatnonzero(self._full_of_internal == full_dof)
        if pos.size != 1:
            raise ValueError(f"DOF {full_dof} is not a free DOF")
        return int(pos[0])

    def _forces(self) -> None:
        sys_, ld = self.system, self.loads
        n = self._full_of_internal.size
        f = np.zeros(n)
        f[self._internal(sys_.input_dof)] += ld.torque
        if ld.gravity is not None:
            g = np.zeros(sys_.n_dof)
            nodes = np.arange(sys_.n_nodes)
            g[DOF_PER_NODE * nodes + U] = ld.gravity[0]
            g[DOF_PER_NODE * nodes + V] = ld.gravity[1]
            f += self._permute(sys_.mass @ g)
        self._f_const = f  # static part of F0(t)
        self._f_c = np.ascontiguousarray(f[:NC])
        z1, z2 = sys_.teeth
        self._omega = (ld.input_speed, ld.input_speed * z1 / z2)
        self._unb = [
            sys_.shaft_masses[i] * ld.unbalance[i] * self._omega[i] ** 2 for i in range(2)
        ]
        # residual scale: the largest external load (torque, gravity, unbalance)
        self._f_scale = max(float(np.linalg.norm(f)), *self._unb)

    def external_force(self, t: float) -> np.ndarray:
        """F0(t) in internal ordering [N]: torque, gravity, unbalance (Eq. 10)."""
        f = self._f_const.copy()
        self._add_unbalance(f, t)
        return f

    def _add_unbalance(self, f: np.ndarray, t: float) -> None:
        w1, w2 = self._omega
        a1, a2 = self._unb
        # pinion shaft rotates about +z, gear shaft about -z
        f[U] += a1 * math.cos(w1 * t)
        f[V] += a1 * math.sin(w1 * t)
        f[DOF_PER_NODE + U] += a2 * math.cos(w2 * t)
        f[DOF_PER_NODE + V] -= a2 * math.sin(w2 * t)

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
        c0, c1 = 4.0 / dt**2, 2.0 / dt
        cond = _Condensation(c0 * self._m + c1 * self._c + self._k)
        mc = np.hstack([self._m, self._c])  # b = [M C] @ [p; q]
        h = np.vstack([mc[:NC], cond.g @ mc[NC:]])
        g_const = cond.g @ self._f_const[NC:]
        entry = (cond, h, g_const)
        if len(self._dyn_cache) > 8:
            self._dyn_cache.clear()
        self._dyn_cache[dt] = entry
        return entry

    # ------------------------------------------------------------------ laws
    @staticmethod
    def _check_laws(f0, kb, cb):
        f0 = np.asarray(f0, dtype=float)
        kb = np.asarray(kb, dtype=float)
        cb = np.asarray(cb, dtype=float)
        if f0.shape != (4, 2) or kb.shape != (4, 2, 2) or cb.shape != (4, 2, 2):
            raise ValueError(
                f"bearing laws shapes F0 {f0.shape}, Kb {kb.shape}, Cb {cb.shape}: expected "
                "(4, 2), (4, 2, 2), (4, 2, 2)"
            )
        if not (np.all(np.isfinite(f0)) and np.all(np.isfinite(kb)) and np.all(np.isfinite(cb))):
            raise ValueError("bearing laws contain non-finite values")
        return f0, kb, cb

    @staticmethod
    def _same(a, b) -> bool:
        """Contact sets equal (numba for boolean arrays, numpy otherwise)."""
        if (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == np.bool_
                and b.dtype == np.bool_):
            return _same_set(a, b)
        return np.array_equal(a, b)

    @staticmethod
    def _check_laws_fast(f0, kb, cb):
        """Shape and finiteness check of the laws at the cost of one sum (hot path)."""
        if not all(isinstance(m, np.ndarray) for m in (f0, kb, cb)) or (
            f0.shape != (4, 2) or kb.shape != (4, 2, 2) or cb.shape != (4, 2, 2)
        ):
            return Structure._check_laws(f0, kb, cb)
        if f0.dtype != np.float64 or kb.dtype != np.float64 or cb.dtype != np.float64:
            return Structure._check_laws(f0, kb, cb)
        if not _all_finite(f0, kb, cb):
            return Structure._check_laws(f0, kb, cb)
        return f0, kb, cb

    # ------------------------------------------------------------------ Newton / contact
    def _solve_condensed(self, s_lin, z0, xc, angle, active_used, f_scale, t, what):
        """Newton/contact loop on the condensed block; returns (xc, mesh state, info)."""
        residuals = []
        prof = self.profile
        mesh = self.mesh
        for k in range(self.max_iter + 1):
            t0 = time.perf_counter() if prof else 0.0
            ms = mesh.evaluate(angle, xc[:N_GEAR])
            if prof:
                t1_ = time.perf_counter()
                self.timing["mesh"] += t1_ - t0
                t0 = t1_
            force = ms.force
            scale = max(f_scale, math.sqrt(float(force @ force)))
            r = _residual_norm(s_lin, z0, xc, force) / (scale if scale > 0.0 else 1.0)
            residuals.append(r)
            if r <= self.tol and active_used is not None and self._same(ms.active, active_used):
                if prof:
                    self.timing["solve"] += time.perf_counter() - t0
                return xc, ms, StepInfo(t, k, r, residuals)
            if k == self.max_iter:
                break
            xc, ok = _newton_solve(s_lin, z0, xc, force, ms.stiffness)
            if not ok:
                raise NewmarkConvergenceError(
                    f"{what} at t = {t:.9g} s: singular tangent at iteration {k} "
                    f"({int(np.count_nonzero(ms.active))} mesh slices in contact; with no tooth "
                    "contact the pinion is free in torsion - check the torque sign)"
                )
            active_used = ms.active
            if prof:
                self.timing["solve"] += time.perf_counter() - t0
        if what == "Newmark step":
            what = f"Newmark step {self.n_steps + 1}"
        raise NewmarkConvergenceError(
            f"{what} at t = {t:.9g} s did not converge: relative residual {residuals[-1]:.3e} "
            f"(tol {self.tol:.1e}) after {self.max_iter} iterations; last residuals "
            f"{', '.join(f'{v:.2e}' for v in residuals[-5:])}"
        )

    # ------------------------------------------------------------------ public
    def static(self, F0, Kb, Cb=None) -> StepInfo:
        """Static solution X0 at the current time with the given affine bearing laws.

        Velocities and accelerations are set to zero (paper Sec. 3.2); the loads are the constant
        ones (torque, gravity) without the rotating unbalance. ``Cb`` is ignored (zero velocity).
        """
        f0, kb, _ = self._check_laws(F0, Kb, np.zeros((4, 2, 2)) if Cb is None else Cb)
        return self._static_at(f0, kb, self.pinion_angle(self.t))

    def _static_at(self, f0, kb, angle) -> StepInfo:
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
        xc, ms, info = self._solve_condensed(
            s_lin, z0, xc, angle, None, f_scale, self.t, "static solution"
        )
        self.x = np.concatenate([xc, y - cond.w @ xc])
        self.v = np.zeros_like(self.x)
        self.a = np.zeros_like(self.x)
        self.active = np.array(ms.active, copy=True)
        self.mesh_state = ms
        return info

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
        prof = self.profile
        t0 = time.perf_counter() if prof else 0.0
        f0, kb, cb = self._check_laws_fast(F0, Kb, Cb)
        if self.active is None:
            raise RuntimeError("call static() before the first step (initial state X0)")
        cond, h, g_const = self._dynamic(dt)
        x, v, a = self.x, self.v, self.a
        t1 = self.t + dt
        w1, w2 = self._omega
        a1, a2 = self._unb
        unb = np.array([a1 * math.cos(w1 * t1), a1 * math.sin(w1 * t1),
                        a2 * math.cos(w2 * t1), -a2 * math.sin(w2 * t1)])
        s_lin, z0, y = _prepare_step(h, g_const, x, v, a, self._f_c, unb, f0, kb, cb, cond.s0,
                                     dt, N_GEAR)
        f_scale = max(self._f_scale, math.sqrt(float(np.sum(f0 * f0))))
        if prof:
            self.timing["assembly"] += time.perf_counter() - t0
        xc0 = x[:NC] + dt * v[:NC]
        xc, ms, info = self._solve_condensed(
            s_lin, z0, xc0, self.pinion_angle(t1), self.active, f_scale, t1,
            "Newmark step",
        )
        t0 = time.perf_counter() if prof else 0.0
        self.x, self.v, self.a = _finish_step(x, v, a, xc, y, cond.w, dt)
        self.t = t1
        self.n_steps += 1
        self.active = ms.active
        self.mesh_state = ms
        if prof:
            self.timing["assembly"] += time.perf_counter() - t0
        return info

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
        return np.hstack([self.x[N_GEAR:NC].reshape(4, 2), self.v[N_GEAR:NC].reshape(4, 2)])

    def gear_displacements(self) -> np.ndarray:
        """(2, 6) DOFs (u, v, w, phi, psi, theta) of the pinion and gear nodes."""
        return self.x[:N_GEAR].reshape(2, 6).copy()

    def mesh_force(self) -> float:
        """Total normal mesh force of the current state [N]."""
        return float(self.mesh_state.total_load)

    def transmission_error(self) -> float:
        """r_b1 theta1 + r_b2 theta2 of the current state [m] (:class:`gear_fmu.mesh.MeshState`)."""
        return float(self.mesh_state.transmission_error)

    def full_vector(self, which: str = "x") -> np.ndarray:
        """Displacement / velocity / acceleration in the full numbering of the system."""
        vec = {"x": self.x, "v": self.v, "a": self.a}[which]
        out = np.zeros(self.system.n_dof)
        out[self._full_of_internal] = vec
        return out

    def bearing_forces(self, F0, Kb, Cb) -> np.ndarray:
        """(4, 2) force of the affine laws on the structure at the current state [N]."""
        st = self.journal_states()
        return (np.asarray(F0) - np.einsum("bij,bj->bi", Kb, st[:, :2])
                - np.einsum("bij,bj->bi", Cb, st[:, 2:]))

    def mean_mesh_stiffness(self, bearing_stiffness=1e8, n_angles: int = 16) -> np.ndarray:
        """Mesh stiffness (12, 12) averaged over one mesh period of static solutions.

        Static solutions under the constant loads with isotropic or (4, 2, 2) bearing springs at
        ``n_angles`` pinion angles over one base pitch; the state is restored afterwards.
        """
        kb = np.asarray(bearing_stiffness, dtype=float)
        if kb.ndim == 0:
            kb = np.broadcast_to(kb * np.eye(2), (4, 2, 2)).copy()
        f0, kb, _ = self._check_laws(np.zeros((4, 2)), kb, np.zeros((4, 2, 2)))
        saved = self.get_state()
        acc = np.zeros((12, 12))
        try:
            for i in range(n_angles):
                angle = self.pinion_angle(self.t) + 2.0 * math.pi / self.system.teeth[0] * (
                    i / n_angles)
                self._static_at(f0, kb, angle)
                acc += self.mesh_state.stiffness
        finally:
            self.set_state(saved)
        return acc / n_angles

    def quasi_static(self, angles, bearing_stiffness=1e8) -> dict:
        """Static solutions under the constant loads at given pinion angles (no dynamics).

        Parameters
        ----------
        angles : array_like
            Pinion angles [rad].
        bearing_stiffness : float or (4, 2, 2)
            Isotropic [N/m] or per-bearing stiffness of the supports (global frame).

        Returns
        -------
        dict of arrays over the angles: ``transmission_error`` [m] (r_b1 theta1 + r_b2 theta2),
        ``mesh_load`` [N], ``slice_load`` (n, n_slices_total) [N], ``journal`` (n, 4, 2) [m].
        The state is restored afterwards.
        """
        kb = np.asarray(bearing_stiffness, dtype=float)
        if kb.ndim == 0:
            kb = np.broadcast_to(kb * np.eye(2), (4, 2, 2)).copy()
        f0, kb, _ = self._check_laws(np.zeros((4, 2)), kb, np.zeros((4, 2, 2)))
        saved = self.get_state()
        out = {"transmission_error": [], "mesh_load": [], "slice_load": [], "journal": []}
        try:
            for angle in np.asarray(angles, dtype=float):
                self._static_at(f0, kb, float(angle))
                ms = self.mesh_state
                out["transmission_error"].append(ms.transmission_error)
                out["mesh_load"].append(ms.total_load)
                out["slice_load"].append(np.array(ms.load, copy=True))
                out["journal"].append(self.journal_states()[:, :2].copy())
        finally:
            self.set_state(saved)
        return {k: np.array(v) for k, v in out.items()}

    def modes(self, bearing_stiffness=1e8, n_angles: int = 16):
        """Natural modes with the mean mesh stiffness at the static load (for ``gsb modal``).

        ``bearing_stiffness``: isotropic [N/m] or (4, 2, 2) (symmetric part used). Returns
        :class:`gear_fmu.modal.Modes`; format with :func:`gear_fmu.modal.mode_table`.
        """
        k_mesh = self.mean_mesh_stiffness(bearing_stiffness, n_angles)
        return natural_modes(self.system, bearing_stiffness, k_mesh)

    def support_loads(self) -> np.ndarray:
        """(4, 2) static loads of the structure on stiff bearings (1e12 N/m) [N], global frame."""
        saved = self.get_state()
        kb = np.broadcast_to(1e12 * np.eye(2), (4, 2, 2)).copy()
        try:
            self.static(np.zeros((4, 2)), kb, None)
            loads = np.einsum("bij,bj->bi", kb, self.journal_states()[:, :2])
        finally:
            self.set_state(saved)
        return loads

    # ------------------------------------------------------------------ master interface
    def set_bearing_laws(self, laws) -> None:
        """Affine laws for the next step/static solve (object with f0, kb, cb; global frame)."""
        self._laws = self._check_laws_fast(laws.f0, laws.kb, laws.cb)

    def do_step(self, t: float, dt: float) -> None:
        """Master interface: one step from t (must equal the current time) with the set laws."""
        if self._laws is None:
            raise RuntimeError("set_bearing_laws() before do_step()")
        if abs(t - self.t) > 1e-9 * max(dt, abs(t)):
            raise ValueError(f"do_step from t = {t!r} s but the structure is at t = {self.t!r} s")
        self.step(dt, *self._laws)

    def solve_static(self) -> None:
        """Master interface: static solution with the set laws."""
        if self._laws is None:
            raise RuntimeError("set_bearing_laws() before solve_static()")
        self.static(*self._laws)
