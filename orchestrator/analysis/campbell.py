"""Linearised modes of a case about its static solution and its Campbell diagram (``gsb modal``).

:func:`linearise` builds the case's master in-process, solves the static solution X0 with the
bearings (:meth:`orchestrator.coupling.master.Master.solve_static`), ends the static phase so that
the structure builds the damping C the transient uses
(:meth:`~orchestrator.coupling.master.Master.exit_initialization`), and computes at X0 (paper Eq.
20):

* the exact mean mesh stiffness (:func:`gear_fmu.modal.analyses.exact_mean_mesh_stiffness`);
* the undamped modes of K0 with the symmetric part of the bearings' Kb
  (:func:`gear_fmu.modal.analyses.modes`);
* the damped modes of M, C0 = C + Cb(X0), K0 = K_shaft + K_mesh,mean + Kb(X0), the bearings'
  Kb and Cb full 2x2 (:func:`gear_fmu.modal.damped_modes.damped_modes`).

:func:`campbell_data` repeats it over pinion speeds (the bearings' equilibrium, Kb and Cb
depend on the speed) on one structure (:class:`Linearisation`: what does not depend on the
speed is built once); :func:`crossings` finds where a mode crosses the mesh-order lines
``f = k z1 omega / (2 pi)`` and the 1x line ``f = omega / (2 pi)``, which
:func:`orchestrator.figures.campbell.plot_campbell` draws. Modes are followed from one speed to
the next by their shapes (largest modal assurance criterion ``|phi_a^H M phi_b|^2``,
one-to-one); a crossing is interpolated linearly along such a segment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from bearing_fmu import numba_cache
from bearing_fmu.base import BearingError
from fmu_src import description
from fmu_src.case import Case
from gear_fmu.modal.analyses import exact_mean_mesh_stiffness, line_of_action_stiffness, modes
from gear_fmu.modal.damped_modes import MESH_MODE_FRACTION, DampedModes, damped_modes
from gear_fmu.modal.modes import Modes
from orchestrator.coupling.master import CouplingError
from orchestrator.coupling.system import announce_compilation, build_master

__all__ = ["Linearisation", "Linearised", "campbell_data", "crossings", "linearise"]

#: mesh harmonics drawn and searched, k = 1 .. HARMONICS
HARMONICS = 4
#: a mode is followed to the next speed when the MAC of the two shapes is at least this [-]
MAC_LIMIT = 0.5


@dataclass
class Linearised:
    """The linearised system of a case at X0 (module docstring).

    Attributes
    ----------
    case : Case
    bearings : str
        Where Kb and Cb come from (for printing).
    kb, cb : (4, 2, 2) arrays
        Bearing stiffness [N/m] and damping [N s/m] at X0, global frame.
    mesh_stiffness : (12, 12) array
        Exact mean mesh stiffness [N/m, N, N m].
    mesh_stiffness_loa : float
        Its value along the line of action [N/m]
        (:func:`gear_fmu.modal.analyses.line_of_action_stiffness`).
    reference_mesh_stiffness_loa : float or None
        The same of the 16-angle mean the damping C was built on [N/m] (None without).
    contact_width : float
        Common face width [m] (stiffness per unit width = ``mesh_stiffness_loa / width``).
    mass : (n_dof, n_dof) array
        M (to compare mode shapes).
    modes : Modes or None
        Undamped modes of K0 (symmetric part of Kb).
    damped : DampedModes
    z1 : int
        Pinion teeth.
    """

    case: Case
    bearings: str
    kb: np.ndarray
    cb: np.ndarray
    mesh_stiffness: np.ndarray
    mesh_stiffness_loa: float
    reference_mesh_stiffness_loa: float | None
    contact_width: float
    mass: np.ndarray
    modes: Modes | None
    damped: DampedModes
    z1: int


class Linearisation:
    """A case linearised about X0 at any pinion speed (module docstring), what does not depend
    on the speed built once.

    Built once: the structure (shaft and gear matrices, mesh element and its tooth stiffness
    table, the condensed static stiffness) and its loads on stiff supports, from which the
    bearings' first guess of X0 starts (:meth:`orchestrator.coupling.master.Master.first_guess`).
    A static solution overwrites the whole state of the structure and the damping is rebuilt
    from the Kb of each X0, so the structure carries nothing from one speed to the next; its
    own speed enters only the unbalance and the transient, which a linearisation does not use.

    Per speed, with the case at that speed (:meth:`at`): new bearing models (the hybrid film's
    warm start remembers the states it was evaluated at, so new models evaluate the same
    sequence as a master built for that speed alone), X0, the damping C on the modes with
    Kb(X0) (its modal reference depends on Kb), the exact mean mesh stiffness and the damped
    modes. The mean mesh stiffness depends on Kb only through the contact set of the static
    solution at each angle (the slice springs ``k(xi) dl V V^T`` are fixed by the angle); the
    gear tilts under the bearings' compliance can open an edge of the face (the helical case's
    mean moves with the speed, most at a light torque, the spur case's not at all), so it is
    computed again at every speed.

    Parameters
    ----------
    case : Case
    bearing_stiffness : float, optional
        Isotropic bearing stiffness [N/m] instead of the bearings' film at X0 (:func:`linearise`);
        then nothing depends on the speed.
    n_gauss : int
        Gauss-Legendre points per event-free interval of the mean mesh stiffness.
    """

    def __init__(self, case: Case, bearing_stiffness: float | None = None, n_gauss: int = 8):
        self.case = case
        self.bearing_stiffness = None if bearing_stiffness is None else float(bearing_stiffness)
        self.n_gauss = n_gauss
        cold = numba_cache.cold()
        self.structure = description.structure(case)
        announce_compilation(cold)
        self._support_loads = None  # (4, 2) [N], when the first X0 needs them

    def at(self, speed: float | None = None, undamped: bool = True) -> Linearised:
        """The case linearised about its X0 at a pinion speed [rad/s] (default the case's).

        Raises the static solution's :class:`~bearing_fmu.base.BearingError` or
        :class:`~orchestrator.coupling.master.CouplingError`.
        """
        case = self.case if speed is None else self.case.with_overrides(
            {"drive.speed": float(speed)})
        st = self.structure
        if self.bearing_stiffness is None:
            master = build_master(case, in_process=True, structure=st)
            try:
                if self._support_loads is None:
                    self._support_loads = master.structure.support_loads()
                # its own first guess, not the previous speed's X0: X0 converges to the
                # coupling tolerance only, so another start moves it and the modes (by 1e-6
                # relative on the spur case) and the diagram would depend on the speed order
                master.solve_static(master.first_guess(self._support_loads))
                master.exit_initialization()  # C as in the transient: built with the static Kb
                kb = np.array(master.laws.kb, dtype=float)
                cb = np.array(master.laws.cb, dtype=float)
            finally:
                master.close()
            kb_ref = 0.5 * (kb + np.transpose(kb, (0, 2, 1)))
            model = description.shared_bearing_model(case) or "each bearing's own"
            source = (f"{model} film at the static solution X0 (damped modes: "
                      "Kb and Cb full 2x2; undamped modes: symmetric part of Kb)")
        else:
            k = self.bearing_stiffness
            kb = np.broadcast_to(k * np.eye(2), (4, 2, 2)).copy()
            cb = np.zeros((4, 2, 2))
            kb_ref = k
            st.set_damping_reference(k)
            source = f"isotropic {k:g} N/m, no bearing damping (Cb = 0)"
        k_mesh = exact_mean_mesh_stiffness(st, kb_ref, self.n_gauss)
        ref = st.reference_mesh_stiffness
        found = modes(st, kb_ref, mesh_stiffness=k_mesh) if undamped else None
        damped = damped_modes(st.system, st.damping_full, k_mesh, kb, cb)
        return Linearised(
            case, source, kb, cb, k_mesh, line_of_action_stiffness(st, k_mesh),
            None if ref is None else line_of_action_stiffness(st, ref),
            st.mesh.pair.contact_width, st.system.mass, found, damped,
            int(st.system.teeth[0]))

    def campbell(self, speeds, max_frequency: float = 6000.0) -> dict:
        """:func:`campbell_data` on this linearisation."""
        kept, per_speed, skipped = [], [], []
        mass, z1 = None, None
        fixed = None  # isotropic bearings: the modes of every speed
        for w in np.asarray(speeds, dtype=float):
            if fixed is None:
                try:
                    lin = self.at(float(w), undamped=False)
                except (BearingError, CouplingError) as exc:
                    skipped.append((float(w), str(exc)))
                    continue
                d = lin.damped
                f = d.frequency_hz
                sel = (~d.overdamped) & (f <= 1.5 * max_frequency)
                modes_w = {"frequency_hz": f[sel], "damping_ratio": d.damping_ratio[sel],
                           "mesh_energy_fraction": d.mesh_energy_fraction[sel],
                           "shapes": d.shapes[:, sel]}
                mass, z1 = lin.mass, lin.z1
                if self.bearing_stiffness is not None:
                    fixed = modes_w
            else:
                modes_w = {key: v.copy() for key, v in fixed.items()}
            per_speed.append(modes_w)
            kept.append(float(w))
        data = {"speeds": np.array(kept), "modes": per_speed, "mass": mass, "z1": z1,
                "skipped": skipped, "max_frequency": float(max_frequency)}
        data["segments"] = _segments(data)
        return data


def linearise(case: Case, bearing_stiffness: float | None = None, n_gauss: int = 8,
              undamped: bool = True) -> Linearised:
    """Modes of a case linearised about X0 (module docstring).

    Parameters
    ----------
    case : Case
    bearing_stiffness : float, optional
        Isotropic bearing stiffness [N/m] instead of the bearings' film at X0; then Cb = 0
        and the damping C is built on the reference configuration with this stiffness.
    n_gauss : int
        Gauss-Legendre points per event-free interval of the mean mesh stiffness.
    undamped : bool
        Also the undamped modes (``Linearised.modes``).
    """
    return Linearisation(case, bearing_stiffness, n_gauss).at(undamped=undamped)


def campbell_data(case: Case, speeds, bearing_stiffness: float | None = None,
                  n_gauss: int = 8, max_frequency: float = 6000.0) -> dict:
    """Damped modes at each pinion speed, each with its own static solution X0.

    The structure is built once (:class:`Linearisation`); the bearings, X0, the damping and
    the modes at every speed.

    Parameters
    ----------
    case : Case
    speeds : array_like
        Pinion speeds [rad/s], > 0.
    bearing_stiffness : float, optional
        Isotropic bearings without damping (:func:`linearise`): the modes then do not depend on
        the speed (computed once).
    n_gauss : int
    max_frequency : float
        Modes above ``1.5 max_frequency`` [Hz] are not kept.

    Returns
    -------
    dict
        ``speeds`` (kept speeds, rad/s), ``modes`` (per speed: dict of ``frequency_hz``,
        ``damping_ratio``, ``mesh_energy_fraction``, ``shapes`` of the oscillating modes
        below the limit), ``mass``, ``z1``, ``skipped`` (list of (speed, message) where the
        static solution failed), ``segments`` (``(speed index a, mode at a, mode at a + 1)``:
        the same mode at neighbouring speeds).
    """
    return Linearisation(case, bearing_stiffness, n_gauss).campbell(speeds, max_frequency)


def _segments(data: dict) -> list[tuple[int, int, int]]:
    """``(speed index a, mode at a, mode at a + 1)``: the same mode at two neighbouring speeds
    (one-to-one assignment maximising the MAC, kept when MAC >= :data:`MAC_LIMIT`)."""
    out = []
    m = data["mass"]
    for a in range(len(data["modes"]) - 1):
        pa, pb = data["modes"][a]["shapes"], data["modes"][a + 1]["shapes"]
        if pa.shape[1] == 0 or pb.shape[1] == 0:
            continue
        mac = np.abs(pa.conj().T @ (m @ pb)) ** 2  # shapes have phi^H M phi = 1
        rows, cols = scipy.optimize.linear_sum_assignment(-mac)
        out += [(a, int(i), int(j)) for i, j in zip(rows, cols, strict=True)
                if mac[i, j] >= MAC_LIMIT]
    return out


def crossings(data: dict, harmonics: int = HARMONICS,
              min_mesh_fraction: float = MESH_MODE_FRACTION) -> list[dict]:
    """Where a followed mode crosses an excitation line between two speeds.

    Lines: mesh orders ``f = k z1 omega / (2 pi)``, k = 1 .. harmonics (``order`` k), for modes
    with a mesh strain energy share ``>= min_mesh_fraction`` at either speed; the 1x line
    ``f = omega / (2 pi)`` (``order`` 0) for every mode. Linear interpolation along the
    segment. Returns dicts with ``order``, ``speed_rad_s``, ``speed_rpm``, ``frequency_hz``,
    ``damping_ratio``, ``mesh_energy_fraction``, sorted by order then speed.
    """
    out = []
    w, z1 = data["speeds"], data["z1"]
    for a, i, j in data["segments"]:
        ma, mb = data["modes"][a], data["modes"][a + 1]
        fa, fb = ma["frequency_hz"][i], mb["frequency_hz"][j]
        share = max(ma["mesh_energy_fraction"][i], mb["mesh_energy_fraction"][j])
        orders = [0] + (list(range(1, harmonics + 1)) if share >= min_mesh_fraction else [])
        for k in orders:
            slope = (1.0 if k == 0 else k * z1) / (2.0 * math.pi)
            ga, gb = fa - slope * w[a], fb - slope * w[a + 1]
            if ga * gb > 0.0 or ga == gb:
                continue
            s = ga / (ga - gb)
            speed = w[a] + s * (w[a + 1] - w[a])
            zeta, mesh = ((1 - s) * ma[key][i] + s * mb[key][j]
                          for key in ("damping_ratio", "mesh_energy_fraction"))
            out.append({"order": k, "speed_rad_s": float(speed),
                        "speed_rpm": float(speed * 30.0 / math.pi),
                        "frequency_hz": float(slope * speed), "damping_ratio": float(zeta),
                        "mesh_energy_fraction": float(mesh)})
    out.sort(key=lambda c: (c["order"], c["speed_rad_s"]))
    return out
