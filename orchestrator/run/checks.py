"""Checks of a run before its transient: what the time step resolves, what the films carry.

:func:`unbalance_warnings` compares each shaft's unbalance force ``M e_mu omega^2`` (Eq. 10)
with the static load capacity of its bearings (:func:`film_capacities`, the film force at
the eccentricity limit); :func:`overload_message` explains a static solution that fails because
a bearing's static load exceeds that capacity, in newtons and case fields.

:func:`time_step_findings` linearises the case about its static solution X0 (the bearings' Kb
and Cb there, the damping the transient uses, the exact mean mesh stiffness, as ``gsb modal``)
and flags the damped mesh modes whose period Newmark's rule lengthens by more than
:data:`PERIOD_ERROR_LIMIT` (:func:`newmark_period_error`), with what that costs their forced
response (:func:`newmark_resonance_response`). A shipped case keeps the step its file sets on
purpose (the paper's: :func:`reference_step`): its finding is a note of the run summary, not a
warning. ``gsb run`` prints the warnings on stderr, the notes in its summary, and stores both
in the results file.
"""

from __future__ import annotations

import cmath
import math
from pathlib import Path

import numpy as np

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import FilmBearingModel
from fmu_src import description
from fmu_src.case import Case
from gear_fmu.modal.analyses import exact_mean_mesh_stiffness
from gear_fmu.modal.damped_modes import damped_modes, under_resolved
from orchestrator.analysis.campbell import mesh_shares

__all__ = ["EPS_LIMIT", "FIRST_GUESS_EPS", "PERIOD_ERROR_LIMIT", "OverloadWarning",
           "RunWarning", "TimeStepWarning", "film_capacities", "newmark_period_error",
           "newmark_resonance_response", "overload_message", "reference_step",
           "shaft_unbalance", "steps_for_period_error", "time_step_findings",
           "unbalance_warnings"]


class RunWarning(UserWarning):
    """What a run finds about its inputs after the static solution and says once (the run
    goes on; the text is also kept in the results file's ``warnings``)."""


class TimeStepWarning(RunWarning):
    """The time step resolves a mode with the mesh's strain energy too coarsely
    (:func:`time_step_findings`)."""


class OverloadWarning(RunWarning):
    """A shaft's unbalance force exceeds its bearings' static load capacity
    (:func:`unbalance_warnings`)."""

#: eccentricity ratio up to which the static solution searches (bearing_fmu.static)
EPS_LIMIT = 0.995
#: eccentricity ratio within which the master's first guess of X0 keeps each journal
#: (:meth:`orchestrator.coupling.master.BearingSet.static_position`: 0.95 C)
FIRST_GUESS_EPS = 0.95
#: eccentricity ratio of the load capacity the unbalance warning compares with (minimum film
#: thickness 0.1 C, a common design limit; the film force grows without bound towards 1)
EPS_DESIGN = 0.9
#: the case fields that raise a film's load capacity, and those that lower the load
RAISE_CAPACITY = ("bearings.*.length", "bearings.*.diameter", "bearings.*.viscosity",
                  "drive.speed", "a smaller bearings.*.clearance")
LOWER_LOAD = "drive.torque"
#: period error of a damped mesh mode [-] above which the time step warns. The period error is
#: the error of where the mode's resonances fall (the speeds at which a mesh harmonic meets it,
#: gsb modal's tooth critical speeds), and detunes its forced response: 1 % is a third of the
#: half-power half-width of a mode damped at 3 % (the shipped cases' modal damping, which the
#: films' damping adds to), so the response at resonance stays within 5 %
#: (1 / sqrt(1 + (1/3)^2)); the paper's step gives its 4.4 kHz mesh mode 3 % period error and
#: 15 % less response at resonance (damping ratio 0.065).
PERIOD_ERROR_LIMIT = 0.01


def film_capacities(case: Case, eps: float = EPS_LIMIT) -> tuple[np.ndarray, str]:
    """The static load capacity of each bearing's film [N] (one per bearing, the case's
    order): the film force at the eccentricity ratio ``eps``, zero velocity, at the bearing's
    speed; and the model that gave it (each bearing's own if it is a film model, else the
    hybrid film; ``"each bearing's"`` for several)."""
    models = description.bearing_models(case)
    names = [case[f"bearings.{b}.model"] for b in case.names("bearings")]
    if not all(isinstance(m, FilmBearingModel) for m in models):
        hybrid = description.bearing_models(case.with_overrides({"bearings.*.model": "hybrid"}))
        film = [isinstance(m, FilmBearingModel) for m in models]
        models = [m if f else h for m, h, f in zip(models, hybrid, film, strict=True)]
        names = [n if f else "hybrid" for n, f in zip(names, film, strict=True)]
    name = names[0] if len(set(names)) == 1 else "each bearing's"
    out = np.empty(len(models))
    for b, (m, w) in enumerate(zip(models, description.bearing_speeds(case), strict=True)):
        fbar = m.dimensionless(eps, 0.0, jacobian=False).force
        out[b] = m.bearing.force_scale(w) * math.hypot(*fbar)
    return out, name


def shaft_unbalance(lay, shaft: str) -> tuple[float, list[str]]:
    """``|sum M e_mu exp(i phase)|`` of the unbalanced gears and discs on a shaft [kg m] (M
    each body's ``unbalance_mass``, Eq. 10), and their unbalance fields."""
    total, keys = 0j, []
    for kind, bodies in (("gears", lay.gears), ("discs", lay.discs)):
        for body in bodies:
            if body.shaft == shaft and body.unbalance > 0.0:
                mass = body.mass if body.unbalance_mass == "body" else lay.carried_mass(shaft)
                total += mass * body.unbalance * cmath.exp(1j * body.unbalance_phase)
                keys.append(f"{kind}.{body.name}.unbalance")
    return abs(total), keys


def unbalance_warnings(case: Case) -> list[str]:
    """One sentence per shaft whose unbalance force ``M e_mu omega^2`` exceeds the static load
    capacity of its bearings at the eccentricity ratio :data:`EPS_DESIGN` (the journals then
    orbit closer to the wall than a minimum film thickness of 0.1 C)."""
    lay = description.layout(case)
    capacity, model = film_capacities(case, EPS_DESIGN)
    out = []
    for shaft, speed in zip(lay.shafts, lay.speeds, strict=True):
        me, keys = shaft_unbalance(lay, shaft.name)
        force = me * speed**2
        on = [j for j, b in enumerate(lay.bearings) if b.shaft == shaft.name]
        cap = float(sum(capacity[j] for j in on))
        if force > cap:
            names = " and ".join(lay.bearings[j].name for j in on)
            out.append(
                f"the unbalance force of shaft {shaft.name}, M e_mu omega^2 = "
                f"{me * 1e3:.4g} kg mm x ({abs(speed):.4g} rad/s)^2 = {force:.4g} N, exceeds "
                f"the static load capacity of its bearings {names}, {cap:.4g} N ({model} film "
                f"at eccentricity {EPS_DESIGN}): the journals will orbit near the bearing wall "
                f"(or the run fail); lower {' or '.join(keys)} or drive.speed")
    return out


def overload_message(case: Case, eps: float = EPS_LIMIT) -> str | None:
    """Why a static solution cannot exist, in the case's terms, if a bearing's static load
    (the structure on stiff supports) exceeds its film's capacity at the eccentricity ratio
    ``eps`` (:data:`EPS_LIMIT`, or :data:`FIRST_GUESS_EPS` where the master's first guess of
    X0 stops); None otherwise."""
    from gear_fmu.modal.analyses import support_loads

    loads = np.hypot(*support_loads(description.structure(case)).T)
    capacity, model = film_capacities(case, eps)
    over = [b for b in range(len(loads)) if loads[b] > capacity[b]]
    if not over:
        return None
    lay = description.layout(case)
    names = lay.bearing_names
    speeds = description.bearing_speeds(case)
    what = "; ".join(f"bearing {names[b]} carries {loads[b]:.4g} N, its film at most "
                     f"{capacity[b]:.4g} N (shaft {lay.bearings[b].shaft} at {speeds[b]:.4g} "
                     "rad/s)" for b in over)
    fields = ", ".join(f.replace("*", names[over[0]] if len(over) == 1 else "*")
                       for f in RAISE_CAPACITY)
    return (f"{what} (static loads with an input torque of {case['drive.torque']:g} N m, "
            f"{model} film at eccentricity {eps:g}): raise {fields}, or lower "
            f"{LOWER_LOAD}")


def newmark_period_error(steps_per_period):
    """Relative period error ``T_h / T - 1`` [-] of Newmark's average-acceleration rule
    (gamma 1/2, beta 1/4) for an oscillator resolved by ``steps_per_period`` = ``T / dt`` steps.

    On a linear oscillator the rule is the trapezoidal rule, whose numerical frequency solves
    ``tan(omega_h dt / 2) = omega dt / 2``: the period lengthens to
    ``T_h / T = (omega dt / 2) / arctan(omega dt / 2)``, about ``(omega dt)^2 / 12``, and the
    amplitude is kept (no numerical damping).
    """
    x = np.pi / np.asarray(steps_per_period, dtype=float)  # omega dt / 2
    return x / np.arctan(x) - 1.0


def newmark_resonance_response(steps_per_period, damping_ratio):
    """The steady response of a mode to a forcing at its own frequency under Newmark's rule,
    relative to the exact one [-] (``steps_per_period`` = ``T / dt`` of the mode).

    The trapezoidal rule maps a forcing at omega onto the exact response at
    ``(2 / dt) tan(omega dt / 2)`` (the bilinear transform's frequency warping), i.e. at
    ``r = tan(x) / x`` times the mode's frequency, ``x = omega dt / 2``; a mode of damping ratio
    zeta answers there ``2 zeta / sqrt((1 - r^2)^2 + (2 zeta r)^2)`` of its resonant response.
    """
    x = np.pi / np.asarray(steps_per_period, dtype=float)
    r = np.tan(x) / x
    zeta = np.asarray(damping_ratio, dtype=float)
    return 2.0 * zeta / np.sqrt((1.0 - r * r) ** 2 + (2.0 * zeta * r) ** 2)


def steps_for_period_error(limit: float = PERIOD_ERROR_LIMIT) -> float:
    """Steps per period at which :func:`newmark_period_error` equals ``limit`` (0 < limit)."""
    from scipy.optimize import brentq

    if not limit > 0.0:
        raise ValueError(f"period error limit {limit!r} must be > 0")
    return float(brentq(lambda n: newmark_period_error(n) - limit, 2.0 + 1e-9, 1e6))


def reference_step(case: Case) -> Path | None:
    """The shipped case file whose step the case keeps (the same ``case.name`` and
    ``simulation.steps_per_mesh_period``): the shipped cases reproduce a paper and take its
    step on purpose (the comment in their files); None for any other step or case."""
    from fmu_src.case import CaseError, load_case, shipped_cases

    path = shipped_cases().get(case.name)
    if path is None:
        return None
    try:
        shipped = load_case(path)
    except CaseError:
        return None
    key = "simulation.steps_per_mesh_period"
    return path if shipped[key] == case[key] else None


def _strain_in(meshes, shares) -> str:
    """``"53 % of its strain energy in the mesh"`` (a train of one mesh) or ``"21 % of its
    strain energy in the meshes: stage1 15 %, stage2 6 %"``."""
    total = float(np.nansum(shares))
    if len(meshes) == 1:
        return f"{100 * total:.0f} % of its strain energy in the mesh"
    return (f"{100 * total:.0f} % of its strain energy in the meshes: " + ", ".join(
        f"{name} {100 * v:.0f} %" for name, v in zip(meshes, shares, strict=True)))


def time_step_findings(case: Case, laws: AffineLaws, dt: float,
                       structure=None) -> tuple[list[str], list[str]]:
    """Warnings and notes on the damped mesh modes whose period Newmark lengthens by more than
    :data:`PERIOD_ERROR_LIMIT` at the step ``dt``: one warning per mode (what it costs, the
    step that brings it under the limit); for a step a shipped case keeps on purpose
    (:func:`reference_step`) no warning, one note saying so and what it costs.

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

    Returns
    -------
    warnings, notes : list of str
    """
    kb = np.asarray(laws.kb, dtype=float)
    cb = np.asarray(laws.cb, dtype=float)
    sym = 0.5 * (kb + np.transpose(kb, (0, 2, 1)))
    st = structure
    if st is None:
        st = description.structure(case, damping_bearing_stiffness=sym)
    k_mesh = exact_mean_mesh_stiffness(st, sym)  # as gsb modal: the same modes
    modes = damped_modes(st.system, st.damping_full, k_mesh, kb, cb, st.gyroscopic_full)
    shares = mesh_shares(st.system, modes, k_mesh)
    meshes = description.layout(case).mesh_names
    steps = case["simulation.steps_per_mesh_period"]
    enough = steps_for_period_error()
    costs = []
    for m in under_resolved(modes, dt, min_steps=enough):
        n = m["steps_per_period"]
        need = int(np.ceil(steps * enough / n))
        text = (f"the damped mesh mode at {m['frequency_hz']:.0f} Hz (damping ratio "
             f"{m['damping_ratio']:.3f}, {_strain_in(meshes, shares[m['mode'] - 1])}) gets "
             f"{n:.1f} time steps per period (dt = {dt:.3e} s): "
             f"Newmark's rule lengthens its period by {100 * newmark_period_error(n):.1f} % "
             f"(it adds no numerical damping): its resonances fall as much lower and a forcing at "
             f"{m['frequency_hz']:.0f} Hz gets "
             f"{100 * newmark_resonance_response(n, m['damping_ratio']):.0f} % of the response "
             f"it should")
        costs.append((text, need))
    if not costs:
        return [], []
    limit = f"{100 * PERIOD_ERROR_LIMIT:g} %"
    shipped = reference_step(case)
    if shipped is None:
        return [f"{text}; set simulation.steps_per_mesh_period >= {need} (now {steps}) for a "
                f"period error below {limit}" for text, need in costs], []
    need = max(n for _, n in costs)
    return [], [f"time step: {steps} steps per period of the fastest mesh, which the shipped "
                f"case {case.name} keeps on purpose (its file says why): "
                + "; ".join(text for text, _ in costs)
                + f"; simulation.steps_per_mesh_period >= {need} keeps every mesh mode's period "
                f"error below {limit}"]
