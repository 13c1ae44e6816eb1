"""Checks of a run before its transient: what the time step resolves, what the films carry.

:func:`unbalance_warnings` compares each shaft's unbalance force ``M e_mu omega^2`` (Eq. 10)
with the static load capacity of its two bearings (:func:`film_capacities`, the film force at
the eccentricity limit); :func:`overload_message` explains a static solution that fails because
a bearing's static load exceeds that capacity, in newtons and case fields.

:func:`time_step_warnings` linearises the case about its static solution X0 (the bearings' Kb
and Cb there, the damping the transient uses, the exact mean mesh stiffness, as ``gsb modal``)
and flags the damped mesh modes that get fewer than
:data:`gear_fmu.modal.damped_modes.MIN_STEPS_PER_PERIOD` steps per period
(:func:`gear_fmu.modal.damped_modes.under_resolved`). ``gsb run`` prints the warnings and stores
them in the results file.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import FilmBearingModel
from fmu_src import description
from fmu_src.case import Case
from gear_fmu.modal.analyses import exact_mean_mesh_stiffness
from gear_fmu.modal.damped_modes import MIN_STEPS_PER_PERIOD, damped_modes, under_resolved

__all__ = ["EPS_LIMIT", "film_capacities", "overload_message", "time_step_warnings",
           "unbalance_warnings"]

#: eccentricity ratio up to which the static solution searches (bearing_fmu.static)
EPS_LIMIT = 0.995
#: eccentricity ratio of the load capacity the unbalance warning compares with (minimum film
#: thickness 0.1 C, a common design limit; the film force grows without bound towards 1)
EPS_DESIGN = 0.9
#: the case fields that raise a film's load capacity, and those that lower the load
RAISE_CAPACITY = ("bearings.length", "bearings.diameter", "bearings.viscosity",
                  "operation.speed", "a smaller bearings.clearance")
LOWER_LOAD = "operation.torque"


def film_capacities(case: Case, eps: float = EPS_LIMIT) -> tuple[np.ndarray, str]:
    """The static load capacity of each bearing's film [N] (4,): the film force at the
    eccentricity ratio ``eps``, zero velocity, at the bearing's speed; and the model that gave
    it (the case's model if it is a film model, else the hybrid film)."""
    name = case["bearings.model"]
    models = description.bearing_models(case)
    if not all(isinstance(m, FilmBearingModel) for m in models):
        name = "hybrid"
        models = description.bearing_models(case.with_overrides({"bearings.model": name}))
    out = np.empty(len(models))
    for b, (m, w) in enumerate(zip(models, description.bearing_speeds(case), strict=True)):
        fbar = m.dimensionless(eps, 0.0, jacobian=False).force
        out[b] = m.bearing.force_scale(w) * math.hypot(*fbar)
    return out, name


def unbalance_warnings(case: Case) -> list[str]:
    """One sentence per shaft whose unbalance force ``M e_mu omega^2`` exceeds the static load
    capacity of its two bearings at the eccentricity ratio :data:`EPS_DESIGN` (the journals
    then orbit closer to the wall than a minimum film thickness of 0.1 C)."""
    system = description.gear_shaft_system(case)
    speeds = description.bearing_speeds(case)
    unbalance = case["operation.unbalance"]
    capacity, model = film_capacities(case, EPS_DESIGN)
    out = []
    for i, shaft in enumerate(("pinion", "gear")):
        force = system.shaft_masses[i] * unbalance[i] * speeds[2 * i] ** 2
        cap = capacity[2 * i] + capacity[2 * i + 1]
        if force > cap:
            out.append(
                f"the unbalance force of the {shaft} shaft, M e_mu omega^2 = "
                f"{system.shaft_masses[i]:.3g} kg x {unbalance[i] * 1e3:g} mm x "
                f"({speeds[2 * i]:.4g} rad/s)^2 = {force:.4g} N, exceeds the static load "
                f"capacity of bearings {2 * i + 1} and {2 * i + 2}, {cap:.4g} N ({model} film at "
                f"eccentricity {EPS_DESIGN}): the journals will orbit near the bearing wall "
                f"(or the run fail); lower operation.unbalance[{i}] or operation.speed")
    return out


def overload_message(case: Case) -> str | None:
    """Why a static solution cannot exist, in the case's terms, if a bearing's static load
    (the structure on stiff supports) exceeds its film's capacity; None otherwise."""
    from gear_fmu.modal.analyses import support_loads

    loads = np.hypot(*support_loads(description.structure(case)).T)
    capacity, model = film_capacities(case)
    over = [b for b in range(len(loads)) if loads[b] > capacity[b]]
    if not over:
        return None
    what = "; ".join(f"bearing {b + 1} carries {loads[b]:.4g} N, its film at most "
                     f"{capacity[b]:.4g} N" for b in over)
    return (f"{what} (static loads with T = {case['operation.torque']:g} N m, {model} film at "
            f"eccentricity {EPS_LIMIT}, {case['operation.speed']:g} rad/s): raise "
            f"{', '.join(RAISE_CAPACITY)}, or lower {LOWER_LOAD}")


def time_step_warnings(case: Case, laws: AffineLaws, dt: float, structure=None) -> list[str]:
    """One sentence per damped mesh mode resolved by fewer than 10 steps per period.

    Parameters
    ----------
    case : Case
    laws : AffineLaws
        The bearings' laws at X0 (Kb [N/m], Cb [N s/m], global frame).
    dt : float
        The run's time step [s].
    structure : gear_fmu.structure.Structure, optional
        The in-process structure after the end of initialisation (its damping is reused);
        default: one built from the case (runs through FMUs).
    """
    kb = np.asarray(laws.kb, dtype=float)
    cb = np.asarray(laws.cb, dtype=float)
    sym = 0.5 * (kb + np.transpose(kb, (0, 2, 1)))
    st = structure
    if st is None:
        st = description.structure(case, damping_bearing_stiffness=sym)
    k_mesh = exact_mean_mesh_stiffness(st, sym)  # as gsb modal: the same modes
    modes = damped_modes(st.system, st.damping_full, k_mesh, kb, cb)
    steps = case["simulation.steps_per_mesh_period"]
    out = []
    for m in under_resolved(modes, dt):
        need = int(np.ceil(MIN_STEPS_PER_PERIOD * m["frequency_hz"] * dt * steps))
        out.append(
            f"the damped mesh mode at {m['frequency_hz']:.0f} Hz (damping ratio "
            f"{m['damping_ratio']:.3f}, {100 * m['mesh_energy_fraction']:.0f} % of its strain "
            f"energy in the mesh) gets {m['steps_per_period']:.1f} time steps per period "
            f"(dt = {dt:.3e} s): its response is not resolved; set "
            f"simulation.steps_per_mesh_period >= {need} (now {steps}) for "
            f"{MIN_STEPS_PER_PERIOD} steps per period")
    return out
