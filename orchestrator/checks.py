"""Checks of a run before its transient: what the time step resolves.

:func:`time_step_warnings` linearises the case about its static solution X0 (the bearings' Kb
and Cb there, the damping the transient uses, the exact mean mesh stiffness, as ``gsb modal``)
and flags the damped mesh modes that get fewer than
:data:`gear_fmu.damped_modes.MIN_STEPS_PER_PERIOD` steps per period
(:func:`gear_fmu.damped_modes.under_resolved`). ``gsb run`` prints the warnings and stores them
in the results file.
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.affine import AffineLaws
from fmu_src import description
from fmu_src.case import Case
from gear_fmu.analyses import exact_mean_mesh_stiffness
from gear_fmu.damped_modes import MIN_STEPS_PER_PERIOD, damped_modes, under_resolved

__all__ = ["time_step_warnings"]


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
