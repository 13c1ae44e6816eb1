"""Damped modes of the linearised gear-shaft-bearing system and the tooth critical speeds.

Linearised about the static solution X0 (paper Eq. 20), the free motion obeys

    M x'' + C0 x' + K0 x = 0,   C0 = C + Cb(X0),   K0 = K_shaft + K_mesh,mean + Kb(X0)

with C the structure's damping (:mod:`gear_fmu.modal.modes`), Kb and Cb the bearings' full 2x2
stiffness and damping at X0 (not symmetrised: a fluid film's Kb is not symmetric) and
``K_mesh,mean`` the mesh stiffness averaged over a mesh period
(:func:`gear_fmu.modal.analyses.exact_mean_mesh_stiffness`). With ``x = phi exp(lambda t)`` the
quadratic eigenproblem ``(lambda^2 M + lambda C0 + K0) phi = 0`` is solved in state space,

    [[0, I], [-M^-1 K0, -M^-1 C0]] [phi; lambda phi] = lambda [phi; lambda phi].

Each under-damped mode is a conjugate pair, of which the root with ``Im(lambda) > 0`` is kept:
damped frequency ``|Im(lambda)| / (2 pi)`` [Hz] and damping ratio ``-Re(lambda) / |lambda|``;
these come first, by increasing frequency. Real roots (over-damped motions) follow, flagged,
with frequency 0, by increasing ``|lambda|``. Zero roots (rigid-body motions,
``|lambda| <= zero_tol max |lambda|``) are dropped and counted.

Energy shares of a complex shape phi (displacement part, ``phi^H M phi = 1``):

* mesh strain energy share ``phi^H K_mesh phi / phi^H sym(K0) phi`` (Hermitian forms, real);
* kinetic energy shares of bending / torsion / axial DOFs, ``Re(phi_c^H (M phi)_c)``, exact
  since M does not couple DOF kinds; the mode is named by :func:`gear_fmu.modal.modes.classify`.

Tooth critical speeds (:func:`tooth_critical_speeds`): the input speeds at which a harmonic k
of a mesh frequency, ``k z1 r omega / (2 pi)`` (z1 the driver's teeth, r its shaft's speed
over the input speed), meets the damped frequency of a mode that stores a given share of its
strain energy in that mesh.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.modal.modes import KINDS, bearing_block_matrix, classify, mesh_stiffness_matrix
from gear_fmu.system import GearShaftSystem

__all__ = [
    "DampedModes",
    "critical_speed_table",
    "damped_eigen",
    "damped_mode_table",
    "damped_modes",
    "tooth_critical_speeds",
    "under_resolved",
]

#: default share of the strain energy in the mesh above which a mode is a "mesh mode" [-]
MESH_MODE_FRACTION = 0.1


@dataclass
class DampedModes:
    """Damped modes: oscillating ones by damped frequency, then over-damped roots (module
    docstring).

    Attributes
    ----------
    eigenvalues : (n,) complex
        Roots lambda [1/s], ``Im >= 0``.
    shapes : (n_dof, n) complex
        Displacement part of the eigenvectors, ``phi^H M phi = 1``.
    kinetic_fraction : (n, 3)
        Kinetic energy shares of bending / torsion / axial DOFs (NaN when the DOF kinds are not
        given).
    mesh_energy_fraction : (n,)
        Share of the strain energy stored in the mesh (NaN when ``phi^H sym(K0) phi <= 0``).
    kinds : list of str
        Mode type (:func:`gear_fmu.modal.modes.classify`), ``"unclassified"`` without DOF kinds.
    overdamped : (n,) bool
        Real roots.
    n_rigid : int
        Zero roots dropped (two per rigid-body motion).
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    kinetic_fraction: np.ndarray
    mesh_energy_fraction: np.ndarray
    kinds: list
    overdamped: np.ndarray
    n_rigid: int = 0

    @property
    def frequency_hz(self) -> np.ndarray:
        """Damped frequencies ``|Im(lambda)| / (2 pi)`` [Hz] (0 for over-damped roots)."""
        return np.abs(self.eigenvalues.imag) / (2.0 * math.pi)

    @property
    def damping_ratio(self) -> np.ndarray:
        """``-Re(lambda) / |lambda|`` [-] (1 for a stable over-damped root)."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)


def _square(a, n: int | None, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or (n is not None and a.shape[0] != n):
        want = "square" if n is None else f"({n}, {n})"
        raise ValueError(f"{name} shape {a.shape} must be {want}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has non-finite entries")
    return a


@one_blas_thread
def damped_eigen(m, c, k, k_mesh=None, dof_kind=None, zero_tol: float = 1e-6) -> DampedModes:
    """Damped modes of ``M x'' + C x' + K x = 0`` on plain arrays (module docstring).

    Parameters
    ----------
    m : (n, n) array
        Mass matrix, symmetric positive definite [kg, kg m^2].
    c : (n, n) array
        Damping matrix, any [N s/m, ...].
    k : (n, n) array
        Stiffness matrix, any (its symmetric part weighs the strain energy) [N/m, ...].
    k_mesh : (n, n) array, optional
        Symmetric part of the stiffness that is the mesh's (zero if not given).
    dof_kind : (n,) int array, optional
        0 bending, 1 torsion, 2 axial per DOF (:meth:`gear_fmu.system.GearShaftSystem.dof_kind`).
    zero_tol : float
        Roots with ``|lambda| <= zero_tol max |lambda|`` are rigid-body roots (dropped).

    Returns
    -------
    DampedModes
    """
    m = _square(m, None, "mass matrix")
    n = m.shape[0]
    c = _square(c, n, "damping matrix")
    k = _square(k, n, "stiffness matrix")
    k_mesh = np.zeros((n, n)) if k_mesh is None else _square(k_mesh, n, "mesh stiffness")
    try:
        cho = scipy.linalg.cho_factor(m)
    except np.linalg.LinAlgError as exc:
        raise ValueError("mass matrix is not positive definite") from exc
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -scipy.linalg.cho_solve(cho, k)
    a[n:, n:] = -scipy.linalg.cho_solve(cho, c)
    lam, z = scipy.linalg.eig(a)
    scale = np.abs(lam).max() if lam.size else 0.0
    zero = np.abs(lam) <= zero_tol * scale
    keep = ~zero & (lam.imag >= 0.0)  # real roots of a real matrix have Im exactly 0 (LAPACK)
    lam, phi = lam[keep], z[:n, keep]
    mphi = m @ phi
    norm = np.sqrt(np.einsum("ij,ij->j", phi.conj(), mphi).real)
    phi, mphi = phi / norm, mphi / norm
    k_sym = 0.5 * (k + k.T)
    strain = np.einsum("ij,ij->j", phi.conj(), k_sym @ phi).real
    smesh = np.einsum("ij,ij->j", phi.conj(), 0.5 * (k_mesh + k_mesh.T) @ phi).real
    with np.errstate(invalid="ignore", divide="ignore"):
        mesh_frac = np.where(strain > 0.0, smesh / strain, np.nan)
    kin = np.full((lam.size, 3), np.nan)
    kinds = ["unclassified"] * lam.size
    if dof_kind is not None:
        dof_kind = np.asarray(dof_kind)
        if dof_kind.shape != (n,):
            raise ValueError(f"dof_kind shape {dof_kind.shape} must be ({n},)")
        energy = (phi.conj() * mphi).real
        for i in range(len(KINDS)):
            kin[:, i] = energy[dof_kind == i].sum(axis=0)
        kinds = [classify(f) for f in kin]
    real = lam.imag == 0.0
    order = np.lexsort((np.abs(lam), np.abs(lam.imag), real))
    return DampedModes(lam[order], phi[:, order], kin[order], mesh_frac[order],
                       [kinds[i] for i in order], real[order], int(zero.sum()))


@one_blas_thread
def damped_modes(system: GearShaftSystem, damping_full, mesh_stiffness, kb, cb,
                 gyroscopic=None) -> DampedModes:
    """Damped modes of the gear-shaft system linearised about X0 (Eq. 20, module docstring).

    Parameters
    ----------
    system : GearShaftSystem
    damping_full : (n_dof, n_dof) array
        Structure's damping C (full numbering) [N s/m, ...], e.g. ``Structure.damping_full``.
    mesh_stiffness : (n_meshes, 12, 12) array
        Each mesh's mean stiffness on its gear nodes' DOFs (symmetric parts used,
        :func:`gear_fmu.modal.modes.mesh_stiffness_matrix`).
    kb : float or (nb, 2, 2)
        Bearings' stiffness at X0 [N/m], global frame, full 2x2.
    cb : float or (nb, 2, 2)
        Bearings' damping at X0 [N s/m], global frame, full 2x2.
    gyroscopic : (n_dof, n_dof) array, optional
        ``G(Omega)`` at the speed of the linearisation [N m s], added to C
        (``Structure.gyroscopic_at``).

    Returns
    -------
    DampedModes
        Shapes in the full numbering (zero on the clamped DOF).
    """
    n = system.n_dof
    c_full = _square(damping_full, n, "damping matrix") + bearing_block_matrix(
        system, cb, "bearing damping")
    if gyroscopic is not None:
        c_full = c_full + _square(gyroscopic, n, "gyroscopic matrix")
    k_mesh = mesh_stiffness_matrix(system, mesh_stiffness)
    k_full = system.stiffness + k_mesh + bearing_block_matrix(system, kb, "bearing stiffness")
    found = damped_eigen(system.reduce(system.mass), system.reduce(c_full),
                         system.reduce(k_full), system.reduce(k_mesh),
                         system.dof_kind()[system.free])
    shapes = np.zeros((n, found.eigenvalues.size), dtype=complex)
    shapes[system.free] = found.shapes
    return replace(found, shapes=shapes)


def tooth_critical_speeds(frequency_hz, damping_ratio, mesh_energy_fraction, z1,
                          speed_range=(50.0, 1500.0), harmonics: int = 4,
                          min_mesh_fraction: float = MESH_MODE_FRACTION, ratios=None,
                          meshes=None) -> list[dict]:
    """Input speeds at which a harmonic of a mesh frequency meets a mode of that mesh.

    Mesh m turns at ``ratios[m]`` times the input speed omega on its driver's shaft, whose
    ``z1[m]`` teeth give its mesh frequency ``z1[m] ratios[m] omega / (2 pi)``; harmonic k of
    it meets a mode of damped frequency f at ``omega = 2 pi f / (k z1[m] ratios[m])``, kept
    when the mode stores ``>= min_mesh_fraction`` of its strain energy in mesh m. A single
    pair (a scalar ``z1``, ratio 1): the pinion speeds ``2 pi f / (k z1)``.

    Parameters
    ----------
    frequency_hz, damping_ratio : (n,) array_like
        Damped frequency [Hz] and damping ratio [-] per mode (:class:`DampedModes`).
    mesh_energy_fraction : (n,) or (n, n_meshes) array_like
        Strain energy share [-] per mode in the mesh (one mesh), or in each mesh.
    z1 : int or (n_meshes,) ints
        The driver's teeth of each mesh.
    speed_range : (float, float)
        Input speeds kept, ``low <= omega <= high`` [rad/s], ``0 < low < high``.
    harmonics : int
        Mesh harmonics k = 1 .. harmonics.
    min_mesh_fraction : float
        Modes with a strain energy share ``>= min_mesh_fraction`` (in [0, 1]) in the mesh.
    ratios : (n_meshes,) floats, optional
        Speed of each mesh's driver shaft over the input speed (default 1).
    meshes : (n_meshes,) str, optional
        Names of the meshes (default "1", "2", ...).

    Returns
    -------
    list of dict
        Sorted by speed, with keys ``mode`` (1-based position in the arrays), ``mesh`` (its
        name), ``frequency_hz``, ``harmonic``, ``order`` (``k z1 ratio``, cycles per input
        revolution), ``speed_rad_s``, ``speed_rpm`` (the input speed), ``damping_ratio``,
        ``mesh_energy_fraction`` (the share in that mesh).

    Examples
    --------
    A 2 kHz mesh mode and a 26-tooth pinion: k = 1 at 483 rad/s, k = 2 at 242 rad/s.

    >>> rows = tooth_critical_speeds([2000.0], [0.1], [0.8], 26, (200.0, 500.0))
    >>> [(r["harmonic"], round(r["speed_rad_s"], 1)) for r in rows]
    [(2, 241.7), (1, 483.3)]

    Two meshes, the second's 21-tooth pinion at 23/79 of the input speed: its mode meets
    the second mesh's k = 1 at ``2 pi 2000 / (21 x 23/79)`` = 2055 rad/s.

    >>> rows = tooth_critical_speeds([2000.0], [0.1], [[0.05, 0.6]], [23, 21], (1000.0, 3000.0),
    ...                              ratios=[1.0, 23 / 79], meshes=["stage1", "stage2"])
    >>> [(r["mesh"], r["harmonic"], round(r["speed_rad_s"])) for r in rows]
    [('stage2', 2, 1028), ('stage2', 1, 2055)]
    """
    low, high = (float(v) for v in speed_range)
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 < low < high):
        raise ValueError(f"speed range ({low!r}, {high!r}) rad/s must satisfy 0 < low < high")
    teeth = np.atleast_1d(np.asarray(z1))
    if teeth.ndim != 1 or any(int(z) != z or z < 1 for z in teeth):
        raise ValueError(f"z1 = {z1!r}: need an integer >= 1 per mesh")
    if int(harmonics) != harmonics or harmonics < 1:
        raise ValueError(f"harmonics = {harmonics!r}: need an integer >= 1")
    if not 0.0 <= min_mesh_fraction <= 1.0:
        raise ValueError(f"min_mesh_fraction = {min_mesh_fraction!r} must lie in [0, 1]")
    f = np.asarray(frequency_hz, dtype=float)
    zeta = np.asarray(damping_ratio, dtype=float)
    share = np.asarray(mesh_energy_fraction, dtype=float)
    if share.ndim == 1:
        share = share[:, None]
    if not f.shape == zeta.shape == share.shape[:1] or f.ndim != 1:
        raise ValueError(f"frequency, damping ratio and mesh share shapes {f.shape}, "
                         f"{zeta.shape}, {share.shape} must be equal and 1-D (the mesh "
                         "shares (n,) or (n, n_meshes))")
    n_meshes = share.shape[1]
    ratio = np.ones(n_meshes) if ratios is None else np.asarray(ratios, dtype=float)
    names = [str(m + 1) for m in range(n_meshes)] if meshes is None else list(meshes)
    if teeth.size != n_meshes or ratio.shape != (n_meshes,) or len(names) != n_meshes:
        raise ValueError(f"{n_meshes} mesh share column(s), {teeth.size} teeth, "
                         f"{ratio.size} ratio(s) and {len(names)} name(s): one per mesh")
    rows = []
    for m in range(n_meshes):
        for i in np.flatnonzero((share[:, m] >= min_mesh_fraction) & (f > 0.0)):
            for h in range(1, int(harmonics) + 1):
                order = h * int(teeth[m]) * float(ratio[m])
                w = 2.0 * math.pi * float(f[i]) / order
                if low <= w <= high:
                    rows.append({"mode": int(i) + 1, "mesh": names[m],
                                 "frequency_hz": float(f[i]), "harmonic": h, "order": order,
                                 "speed_rad_s": w, "speed_rpm": w * 30.0 / math.pi,
                                 "damping_ratio": float(zeta[i]),
                                 "mesh_energy_fraction": float(share[i, m])})
    rows.sort(key=lambda r: (r["speed_rad_s"], r["mode"]))
    return rows


def damped_mode_table(modes: DampedModes, n_modes: int | None = None,
                      whirl: list[str] | None = None) -> str:
    """Text table: index, damped frequency [Hz], damping ratio, mesh energy share, type, the
    ``whirl`` direction of each mode if given (:func:`gear_fmu.modal.whirl.whirl`), and a
    line on the modes left out."""
    total = modes.eigenvalues.size
    n = total if n_modes is None else min(n_modes, total)
    lines = [f"{'mode':>4}  {'f_d [Hz]':>11}  {'zeta [-]':>8}  {'mesh [-]':>8}  "
             + ("whirl     " if whirl is not None else "") + "type"]
    f, zeta, share = modes.frequency_hz, modes.damping_ratio, modes.mesh_energy_fraction
    for i in range(n):
        kind = modes.kinds[i] + (" (overdamped)" if modes.overdamped[i] else "")
        spin = "" if whirl is None else f"{'-' if modes.overdamped[i] else whirl[i]:<8}  "
        lines.append(f"{i + 1:>4}  {f[i]:>11.2f}  {zeta[i]:>8.4f}  {share[i]:>8.3f}  "
                     f"{spin}{kind}")
    if n < total:
        rest = modes.overdamped[n:]
        lines.append(f"({total - n} more not listed, {int(rest.sum())} of them over-damped "
                     "real roots)")
    return "\n".join(lines)


def critical_speed_table(rows: list[dict]) -> str:
    """Text table of :func:`tooth_critical_speeds` rows (with a column naming the mesh when
    the rows carry several)."""
    several = len({r.get("mesh") for r in rows}) > 1
    width = max([9] + [len(str(r.get("mesh"))) for r in rows]) if several else 0
    head = f"{'mesh name':<{width}}  " if several else ""
    lines = [head + f"{'mode':>4}  {'f_d [Hz]':>10}  {'k [-]':>5}  {'omega [rad/s]':>13}  "
             f"{'N [rpm]':>8}  {'zeta [-]':>8}  {'mesh [-]':>8}"]
    for r in rows:
        cell = f"{r.get('mesh')!s:<{width}}  " if several else ""
        lines.append(cell + f"{r['mode']:>4}  {r['frequency_hz']:>10.2f}  {r['harmonic']:>5d}  "
                     f"{r['speed_rad_s']:>13.2f}  {r['speed_rpm']:>8.1f}  "
                     f"{r['damping_ratio']:>8.4f}  {r['mesh_energy_fraction']:>8.3f}")
    return "\n".join(lines)


#: fewest time steps per period of a mesh mode before :func:`under_resolved` flags it
MIN_STEPS_PER_PERIOD = 10


def under_resolved(modes: DampedModes, dt: float, min_steps: float = MIN_STEPS_PER_PERIOD,
                   min_mesh_fraction: float = MESH_MODE_FRACTION) -> list[dict]:
    """Mesh modes that a time step resolves with fewer than ``min_steps`` steps per period.

    Newmark (gamma 1/2, beta 1/4) keeps every mode bounded but shortens its period by about
    ``(omega dt)^2 / 12`` and smears what the mode responds to; below ~10 steps per period
    the forced response of a mode (the paper's mesh-order lines) is off by more than a few
    percent. Returns, per flagged mode, ``mode`` (1-based), ``frequency_hz``,
    ``damping_ratio``, ``mesh_energy_fraction`` and ``steps_per_period`` ``1 / (f dt)``.
    """
    if not (dt > 0.0 and math.isfinite(dt)):
        raise ValueError(f"time step dt = {dt!r} s must be finite and > 0")
    out = []
    f = modes.frequency_hz
    for i in range(f.size):
        share = modes.mesh_energy_fraction[i]
        if modes.overdamped[i] or not share >= min_mesh_fraction:
            continue
        steps = 1.0 / (f[i] * dt)
        if steps < min_steps:
            out.append({"mode": i + 1, "frequency_hz": float(f[i]),
                        "damping_ratio": float(modes.damping_ratio[i]),
                        "mesh_energy_fraction": float(share), "steps_per_period": steps})
    return out
