"""Linearised modes of a case about its static solution and its Campbell diagram (``gsb modal``).

:func:`linearise` builds the case's master in-process, solves the static solution X0 with the
bearings (:meth:`orchestrator.coupling.master.Master.solve_static`), ends the static phase so that
the structure builds the damping C the transient uses
(:meth:`~orchestrator.coupling.master.Master.exit_initialization`), and computes at X0 (paper Eq.
20):

* the exact mean stiffness of every mesh
  (:func:`gear_fmu.modal.analyses.exact_mean_mesh_stiffness`);
* the undamped modes of K0 with the symmetric part of the bearings' Kb
  (:func:`gear_fmu.modal.analyses.modes`);
* the damped modes of M, C0 = C + G(Omega) + Cb(X0), K0 = K_shaft + K_mesh,mean + Kb(X0),
  the bearings' Kb and Cb full 2x2, the gyroscopic matrix at the speed when the case has it
  (:func:`gear_fmu.modal.damped_modes.damped_modes`), the share of each mode's strain energy
  in each mesh (:func:`mesh_shares`) and each mode's whirl direction
  (:func:`gear_fmu.modal.whirl.whirl`).

:func:`campbell_data` repeats it over input speeds (the bearings' equilibrium, Kb and Cb
depend on the speed) on one structure (:class:`Linearisation`: what does not depend on the
speed is built once); :func:`crossings` finds where a mode crosses the order lines of the
train (:func:`order_lines`): every mesh's harmonics ``f = k z r omega / (2 pi)`` (z its
driver's teeth, r the driver shaft's speed over the input speed omega) and every shaft's 1x
``f = r omega / (2 pi)``, which :func:`orchestrator.figures.campbell.plot_campbell` draws.
Modes are followed from one speed to the next by their shapes (largest modal assurance
criterion ``|phi_a^H M phi_b|^2``, one-to-one); a crossing is interpolated linearly along
such a segment. :func:`gear_fmu.modal.whirl.stability_threshold` finds the lowest speed where
a mode's damping turns negative, and :func:`campbell_dataset` labels it all (speed x mode) for
xarray.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bearing_fmu import numba_cache
from bearing_fmu.base import BearingError
from fmu_src import description
from fmu_src.case import Case
from gear_fmu.modal.analyses import exact_mean_mesh_stiffness, line_of_action_stiffness, modes
from gear_fmu.modal.damped_modes import MESH_MODE_FRACTION, DampedModes, damped_modes
from gear_fmu.modal.modes import Modes, mesh_dofs
from gear_fmu.modal.whirl import stability_threshold, whirl
from orchestrator.coupling.master import CouplingError
from orchestrator.coupling.system import announce_compilation, build_master

__all__ = ["Linearisation", "Linearised", "campbell_data", "campbell_dataset", "crossings",
           "line_name", "linearise", "mesh_shares", "order_lines"]

#: mesh harmonics drawn and searched, k = 1 .. HARMONICS
HARMONICS = 4
#: a mode is followed to the next speed when the MAC of the two shapes is at least this [-]
MAC_LIMIT = 0.5


def mesh_shares(system, modes: DampedModes, mesh_stiffness) -> np.ndarray:
    """(n_modes, n_meshes): the share of each mode's strain energy stored in each mesh,
    ``phi^H K_m phi / phi^H sym(K0) phi`` with ``K_m`` the symmetric part of mesh m's mean
    stiffness (n_meshes, 12, 12) on its gear nodes (:func:`gear_fmu.modal.modes.mesh_dofs`):
    they sum to the mode's ``mesh_energy_fraction`` (NaN where that is)."""
    k = np.asarray(mesh_stiffness, dtype=float).reshape(-1, 12, 12)
    phi = modes.shapes
    per = np.empty((phi.shape[1], k.shape[0]))
    for m in range(k.shape[0]):
        p = phi[mesh_dofs(system, m)]
        per[:, m] = np.einsum("ij,ij->j", p.conj(), 0.5 * (k[m] + k[m].T) @ p).real
    total = per.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(total != 0.0, modes.mesh_energy_fraction / total, 0.0)
    return per * scale[:, None]


def order_lines(case: Case) -> dict:
    """The excitation lines of a case's train in cycles per input revolution (the slopes of
    the Campbell diagram's lines, times 2 pi): ``meshes`` (names), ``teeth`` (each mesh's
    driver's teeth), ``ratios`` (each mesh's driver shaft speed over the input speed),
    ``mesh_orders`` (teeth x ratio: the mesh frequency per input revolution), ``shafts``
    (names) and ``shaft_ratios`` (each shaft's speed over the input speed)."""
    lay = description.layout(case)
    drivers = [lay.gear(d) for d, _ in lay.drivers]
    ratios = [float(lay.ratios[lay.shaft_index[g.shaft]]) for g in drivers]
    teeth = [int(g.teeth) for g in drivers]
    return {"meshes": list(lay.mesh_names), "teeth": teeth, "ratios": ratios,
            "mesh_orders": [z * r for z, r in zip(teeth, ratios, strict=True)],
            "shafts": [s.name for s in lay.shafts],
            "shaft_ratios": [float(r) for r in lay.ratios]}


@dataclass
class Linearised:
    """The linearised system of a case at X0 (module docstring).

    Attributes
    ----------
    case : Case
    bearings : str
        Where Kb and Cb come from (for printing).
    kb, cb : (nb, 2, 2) arrays
        Bearing stiffness [N/m] and damping [N s/m] at X0, global frame.
    mesh_stiffness : (n_meshes, 12, 12) array
        Exact mean stiffness of each mesh [N/m, N, N m].
    mesh_stiffness_loa : (n_meshes,) array
        Their values along each mesh's line of action [N/m]
        (:func:`gear_fmu.modal.analyses.line_of_action_stiffness`).
    reference_mesh_stiffness_loa : (n_meshes,) array or None
        The same of the 16-angle means the damping C was built on [N/m] (None without).
    contact_width : (n_meshes,) array
        Common face width of each mesh [m] (stiffness per unit width =
        ``mesh_stiffness_loa / contact_width``).
    mass : (n_dof, n_dof) array
        M (to compare mode shapes).
    modes : Modes or None
        Undamped modes of K0 (symmetric part of Kb).
    damped : DampedModes
    mesh_shares : (n_modes, n_meshes) array
        Share of each damped mode's strain energy in each mesh (:func:`mesh_shares`).
    whirl : (n_modes,) array
        Each damped mode's signed whirl value [-] (+1 forward circles;
        :func:`gear_fmu.modal.whirl.whirl`).
    whirl_direction : list of str
        ``"forward"``, ``"backward"``, ``"mixed"`` or ``"none"`` per damped mode.
    lines : dict
        The train's excitation lines (:func:`order_lines`).
    """

    case: Case
    bearings: str
    kb: np.ndarray
    cb: np.ndarray
    mesh_stiffness: np.ndarray
    mesh_stiffness_loa: np.ndarray
    reference_mesh_stiffness_loa: np.ndarray | None
    contact_width: np.ndarray
    mass: np.ndarray
    modes: Modes | None
    damped: DampedModes
    mesh_shares: np.ndarray
    whirl: np.ndarray
    whirl_direction: list
    lines: dict

    @property
    def mesh_names(self) -> list[str]:
        return self.lines["meshes"]

    @property
    def z1(self) -> int:
        """The first mesh's driver's teeth (the paper's pinion: 26)."""
        return self.lines["teeth"][0]


class Linearisation:
    """A case linearised about X0 at any input speed (module docstring), what does not depend
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
        self._support_loads = None  # (nb, 2) [N], when the first X0 needs them
        self.lines = order_lines(case)

    def at(self, speed: float | None = None, undamped: bool = True) -> Linearised:
        """The case linearised about its X0 at an input speed [rad/s] (default the case's).

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
            kb = np.broadcast_to(k * np.eye(2), (st.nb, 2, 2)).copy()
            cb = np.zeros((st.nb, 2, 2))
            kb_ref = k
            st.set_damping_reference(k)
            source = f"isotropic {k:g} N/m, no bearing damping (Cb = 0)"
        k_mesh = exact_mean_mesh_stiffness(st, kb_ref, self.n_gauss)
        ref = st.reference_mesh_stiffness
        found = modes(st, kb_ref, mesh_stiffness=k_mesh) if undamped else None
        damped = damped_modes(st.system, st.damping_full, k_mesh, kb, cb,
                              st.gyroscopic_at(case["drive.speed"]))
        spin, direction = whirl(st.system, damped.shapes, st.layout.directions)
        meshes = range(len(st.meshes))
        return Linearised(
            case, source, kb, cb, k_mesh,
            np.array([line_of_action_stiffness(st, k_mesh, m) for m in meshes]),
            None if ref is None else np.array([line_of_action_stiffness(st, ref, m)
                                               for m in meshes]),
            np.array([st.meshes[m].pair.contact_width for m in meshes]), st.system.mass,
            found, damped, mesh_shares(st.system, damped, k_mesh), spin, direction,
            self.lines)

    def campbell(self, speeds, max_frequency: float = 6000.0) -> dict:
        """:func:`campbell_data` on this linearisation."""
        kept, per_speed, skipped = [], [], []
        mass = None
        fixed = None  # isotropic bearings without gyroscopic terms: the modes of every speed
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
                           "mesh_shares": lin.mesh_shares[sel], "shapes": d.shapes[:, sel],
                           "whirl": lin.whirl[sel],
                           "whirl_direction": np.array(lin.whirl_direction)[sel]}
                mass = lin.mass
                if self.bearing_stiffness is not None and not self.structure.gyroscopic:
                    fixed = modes_w
            else:
                modes_w = {key: v.copy() for key, v in fixed.items()}
            per_speed.append(modes_w)
            kept.append(float(w))
        data = {"speeds": np.array(kept), "modes": per_speed, "mass": mass,
                "lines": self.lines, "skipped": skipped,
                "max_frequency": float(max_frequency)}
        data["segments"] = _segments(data)
        data["stability_threshold"] = stability_threshold(
            data["speeds"], [m["damping_ratio"] for m in per_speed])
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
    """Damped modes at each input speed, each with its own static solution X0.

    The structure is built once (:class:`Linearisation`); the bearings, X0, the damping and
    the modes at every speed.

    Parameters
    ----------
    case : Case
    speeds : array_like
        Input speeds [rad/s], > 0.
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
        ``damping_ratio``, ``mesh_energy_fraction``, ``mesh_shares`` (per mesh),
        ``shapes``, ``whirl`` (signed value) and ``whirl_direction`` (forward, backward,
        mixed, none) of the oscillating modes below the limit), ``mass``, ``lines`` (the
        train's excitation lines, :func:`order_lines`), ``skipped`` (list of (speed,
        message) where the static solution failed), ``segments`` (``(speed index a, mode at
        a, mode at a + 1)``: the same mode at neighbouring speeds), ``stability_threshold``
        (the lowest speed [rad/s] where a mode's damping ratio turns negative, None if none,
        :func:`gear_fmu.modal.whirl.stability_threshold`).
    """
    return Linearisation(case, bearing_stiffness, n_gauss).campbell(speeds, max_frequency)


def _segments(data: dict) -> list[tuple[int, int, int]]:
    """``(speed index a, mode at a, mode at a + 1)``: the same mode at two neighbouring speeds
    (one-to-one assignment maximising the MAC, kept when MAC >= :data:`MAC_LIMIT`)."""
    from scipy.optimize import linear_sum_assignment  # (here: 0.1 s of every start)

    out = []
    m = data["mass"]
    for a in range(len(data["modes"]) - 1):
        pa, pb = data["modes"][a]["shapes"], data["modes"][a + 1]["shapes"]
        if pa.shape[1] == 0 or pb.shape[1] == 0:
            continue
        mac = np.abs(pa.conj().T @ (m @ pb)) ** 2  # shapes have phi^H M phi = 1
        rows, cols = linear_sum_assignment(-mac)
        out += [(a, int(i), int(j)) for i, j in zip(rows, cols, strict=True)
                if mac[i, j] >= MAC_LIMIT]
    return out


def crossings(data: dict, harmonics: int = HARMONICS,
              min_mesh_fraction: float = MESH_MODE_FRACTION) -> list[dict]:
    """Where a followed mode crosses an excitation line between two speeds.

    Lines (:func:`order_lines`): the harmonics k = 1 .. ``harmonics`` of each mesh,
    ``f = k z r omega / (2 pi)``, for the modes with a strain energy share
    ``>= min_mesh_fraction`` in that mesh at either speed; each shaft's 1x
    ``f = r omega / (2 pi)`` for every mode. Linear interpolation along the segment. Returns
    dicts with ``harmonic`` (k; 0 for a shaft's 1x), ``mesh`` (its name; None for a 1x line),
    ``shaft`` (the 1x line's shaft; None for a mesh line), ``order`` (cycles per input
    revolution), ``speed_rad_s`` and ``speed_rpm`` (the input speed), ``frequency_hz``,
    ``damping_ratio``, ``mesh_energy_fraction`` (the share in the line's mesh; the total for
    a 1x line), sorted by mesh (1x lines first), harmonic, then speed.
    """
    out = []
    w, lines = data["speeds"], data["lines"]
    excitations = [(None, shaft, 0, r, None) for shaft, r in
                   zip(lines["shafts"], lines["shaft_ratios"], strict=True)]
    for m, (mesh, order) in enumerate(zip(lines["meshes"], lines["mesh_orders"], strict=True)):
        excitations += [(mesh, None, k, k * order, m) for k in range(1, harmonics + 1)]
    for a, i, j in data["segments"]:
        ma, mb = data["modes"][a], data["modes"][a + 1]
        fa, fb = ma["frequency_hz"][i], mb["frequency_hz"][j]
        for mesh, shaft, k, order, m in excitations:
            if m is None:
                sa, sb = ma["mesh_energy_fraction"][i], mb["mesh_energy_fraction"][j]
            else:
                sa, sb = ma["mesh_shares"][i, m], mb["mesh_shares"][j, m]
                if not max(sa, sb) >= min_mesh_fraction:
                    continue
            slope = order / (2.0 * math.pi)
            ga, gb = fa - slope * w[a], fb - slope * w[a + 1]
            if ga * gb > 0.0 or ga == gb:
                continue
            s = ga / (ga - gb)
            speed = w[a] + s * (w[a + 1] - w[a])
            zeta = (1 - s) * ma["damping_ratio"][i] + s * mb["damping_ratio"][j]
            share = (1 - s) * sa + s * sb
            out.append({"harmonic": k, "mesh": mesh, "shaft": shaft, "order": float(order),
                        "speed_rad_s": float(speed),
                        "speed_rpm": float(speed * 30.0 / math.pi),
                        "frequency_hz": float(slope * speed), "damping_ratio": float(zeta),
                        "mesh_energy_fraction": float(share)})
    rank = {name: r for r, name in enumerate(lines["meshes"])}
    out.sort(key=lambda c: (-1 if c["mesh"] is None else rank[c["mesh"]], c["harmonic"],
                            c["speed_rad_s"]))
    return out


def campbell_dataset(data: dict, harmonics: int = HARMONICS,
                     min_mesh_fraction: float = MESH_MODE_FRACTION):
    """The Campbell diagram labelled (xarray): ``speed`` x ``mode`` and the critical speeds.

    ``data`` from :func:`campbell_data`. Modes are numbered 1, 2, ... by frequency at each
    speed (rows past a speed's count are NaN, ``""`` for the direction); follow a mode across
    speeds by its shape with ``data["segments"]``.

    Returns
    -------
    xarray.Dataset
        Coordinates ``speed`` (input speed [rad/s]), ``speed_rpm``, ``mode`` (1-based),
        ``mesh``; variables ``frequency`` [Hz] (damped), ``damping_ratio`` [-],
        ``log_decrement`` [-] (``2 pi zeta / sqrt(1 - zeta^2)``), ``whirl`` [-] (signed, +1
        forward circles), ``whirl_direction`` (forward, backward, mixed, none),
        ``mesh_energy_fraction`` [-] and ``mesh_share`` (speed, mode, mesh) [-]; along
        ``crossing`` the critical speeds (:func:`crossings`): ``critical_speed`` [rad/s],
        ``critical_frequency`` [Hz], ``critical_line`` (the excitation) and
        ``critical_damping_ratio``; attributes ``stability_threshold_rad_s`` (NaN when every
        mode is damped over the speeds) and ``skipped_speeds_rad_s``.
    """
    import xarray as xr

    w = np.asarray(data["speeds"], dtype=float)
    meshes = list(data["lines"]["meshes"])
    n = max((m["frequency_hz"].size for m in data["modes"]), default=0)

    def table(key, fill=np.nan, dtype=float, extra=()):
        out = np.full((w.size, n, *extra), fill, dtype=dtype)
        for i, m in enumerate(data["modes"]):
            out[i, :m[key].shape[0]] = m[key]
        return out

    zeta = table("damping_ratio")
    with np.errstate(invalid="ignore"):
        decrement = 2.0 * np.pi * zeta / np.sqrt(1.0 - zeta**2)
    dims = ("speed", "mode")
    cross = crossings(data, harmonics, min_mesh_fraction)
    threshold = data.get("stability_threshold")
    return xr.Dataset(
        {"frequency": (dims, table("frequency_hz"), {"units": "Hz",
                                                     "long_name": "damped natural frequency"}),
         "damping_ratio": (dims, zeta, {"units": "1"}),
         "log_decrement": (dims, decrement, {"units": "1"}),
         "whirl": (dims, table("whirl"), {"units": "1", "long_name": "signed whirl (+1: "
                                          "forward circles, -1: backward)"}),
         "whirl_direction": (dims, table("whirl_direction", "", object)),
         "mesh_energy_fraction": (dims, table("mesh_energy_fraction"), {"units": "1"}),
         "mesh_share": ((*dims, "mesh"), table("mesh_shares", extra=(len(meshes),)),
                        {"units": "1", "long_name": "share of the strain energy in the mesh"}),
         "critical_speed": ("crossing", [c["speed_rad_s"] for c in cross], {"units": "rad/s"}),
         "critical_frequency": ("crossing", [c["frequency_hz"] for c in cross],
                                {"units": "Hz"}),
         "critical_line": ("crossing", [line_name(c) for c in cross]),
         "critical_damping_ratio": ("crossing", [c["damping_ratio"] for c in cross],
                                    {"units": "1"})},
        coords={"speed": ("speed", w, {"units": "rad/s", "long_name": "input speed"}),
                "speed_rpm": ("speed", w * 30.0 / math.pi, {"units": "rpm"}),
                "mode": ("mode", np.arange(1, n + 1)),
                "mesh": ("mesh", meshes)},
        attrs={"stability_threshold_rad_s": np.nan if threshold is None else threshold,
               "skipped_speeds_rad_s": [s for s, _ in data["skipped"]]})


def line_name(c: dict) -> str:
    """The excitation line of a crossing: ``"1x <shaft>"`` or ``"<mesh> k=<harmonic>"``."""
    return f"1x {c['shaft']}" if c["mesh"] is None else f"{c['mesh']} k={c['harmonic']}"
