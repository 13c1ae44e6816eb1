"""The figures of ``gsb reproduce`` (paper Figs. 5-17), each with the numbers its report
line needs. Every function takes the loaded runs or sweep points and the figure folder and
returns ``(png path, info dict)``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fmu_src.case import load_case
from fmu_src.examples import HELICAL, SPUR
from orchestrator.analysis.metrics import fit_ellipse, steady_window
from orchestrator.analysis.spectrum import order_spectrum, spectral_resolution
from orchestrator.coupling.system import build_master
from orchestrator.figures.base import AMPLITUDE_LABEL, order_label, pyplot
from orchestrator.studies.reproduce.plan import window_text

__all__ = ["draw_all", "force_spectrum", "has_line"]

#: the window of the base runs' steady orbits (Figs. 5, 6, 14)
GEAR_REVOLUTION = "the last gear revolution"


def _attrs(results):
    a = results["attrs"]
    return {"dt": float(a["dt"]), "speeds": np.asarray(a["speeds"], dtype=float).tolist(),
            "clearance": np.asarray(a["clearance"], dtype=float),
            "teeth": [int(z) for z in np.asarray(a["mesh_teeth"]).reshape(-1, 2)[0]],
            "static": np.asarray(a["static_journal"], dtype=float)}


def _window(results, revolutions: float, bearing: int):
    a = _attrs(results)
    period = 2 * math.pi / a["speeds"][bearing]
    return steady_window(results["time"], revolutions * period)


def _curve(points, model, key, index=None, **match):
    xs, ys = [], []
    for p in points:
        if p["error"] is not None or p["bearing"] != model:
            continue
        if any(not np.isclose(_as_float(p["overrides"].get(k)), v) for k, v in match.items()):
            continue
        x = p["overrides"]["drive.speed"]
        y = p[key] if index is None else p[key][index]
        if np.ndim(y):  # R: one per mesh, the paper's one
            y = np.asarray(y).ravel()[0]
        xs.append(float(x))
        ys.append(float(y))
    order = np.argsort(xs)
    return np.asarray(xs)[order], np.asarray(ys)[order]


def _as_float(v):
    if isinstance(v, list):
        v = v[0]
    if isinstance(v, str):
        return float(v.split()[0])
    return float(v) if v is not None else math.nan


def force_spectrum(results, bearing: int, revolutions: float = 1.0):
    """What Figs. 7 / 15 draw: the order spectrum of ||F_b|| at ``bearing`` over the last
    ``revolutions`` of its shaft, in peak amplitude [N] against orders of that shaft
    (:func:`orchestrator.analysis.spectrum.order_spectrum`): ``(orders, amplitudes,
    resolution)``, the resolution in orders (:func:`has_line`)."""
    a = _attrs(results)
    rotation_hz = a["speeds"][bearing] / (2 * np.pi)
    win = _window(results, revolutions, bearing)
    fb = np.hypot(*np.asarray(results["bearing_force"], dtype=float)[win, bearing].T)
    orders, amp = order_spectrum(fb, a["dt"], rotation_hz)
    return orders, amp, spectral_resolution(fb.size, a["dt"], rotation_hz)


def has_line(f, a, target, resolution=None, prominence=10.0, band=12):
    """A spectral line near ``target``: on the bins one ``resolution`` apart (those of the
    unpadded window, where a line on a bin of a Hann window leaks into its two neighbours
    only; by default every bin), the largest amplitude within one bin (or 2 % of the target)
    stands ``prominence`` times above the median of the ``band`` bins on either side. Order 0,
    the mean, is no line."""
    f, a = np.asarray(f, dtype=float), np.asarray(a, dtype=float)
    if resolution is not None:
        step = max(1, round(resolution / (f[1] - f[0])))
        f, a = f[::step], a[::step]
    df = f[1] - f[0]
    near = (np.abs(f - target) <= max(1.01 * df, 0.02 * target)) & (f > 0)
    if not near.any():
        return False
    i0, i1 = np.flatnonzero(near)[[0, -1]]
    side = np.r_[a[max(i0 - band, 1):i0], a[i1 + 1:i1 + 1 + band]]
    return bool(a[near].max() > prominence * max(np.median(side), 1e-12))


class _Stamped:
    """pyplot with a ``stamp``: the text :func:`_save` writes across every figure (a quick
    plan's, which is not steady state), and the ``window`` of the sweeps' points it writes
    under every figure of a steady state."""

    def __init__(self, plt, stamp: str, window: str = ""):
        self._plt, self.stamp, self.window = plt, stamp, window

    def __getattr__(self, name):
        return getattr(self._plt, name)


def _save(fig, path: Path, plt, window: str | None = None) -> Path:
    """``fig`` as ``path``, its title followed by the steady window its curves are taken over
    (``window``; None: the sweeps' points', ``plt.window``; "": none, a transient) and the
    quick plan's stamp, which is also written across it."""
    window = getattr(plt, "window", "") if window is None else window
    stamp = getattr(plt, "stamp", "")
    lines = [fig.get_suptitle()] if fig.get_suptitle() else []
    lines += [f"window: {window}"] * bool(window) + [stamp] * bool(stamp)
    if lines:
        fig.suptitle("\n".join(lines), fontsize=11)
    if stamp:
        fig.text(0.5, 0.5, stamp.split(":")[0], ha="center", va="center", rotation=25,
                 fontsize=24, color="tab:red", alpha=0.25, zorder=100)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _fig_orbits(runs, fig_dir, plt) -> tuple[Path, dict]:
    """Figs. 5-6: steady orbits of bearing and gear nodes; transient in bearings 1 and 3."""
    r = runs["spur_hybrid"]
    a = _attrs(r)
    win = _window(r, 1.0, 2)
    pos = r["journal_position"]
    fig, axes = plt.subplots(1, 4, figsize=(15, 4), constrained_layout=True)
    circle = np.linspace(0, 2 * np.pi, 361)
    for shaft, ax in enumerate(axes[:2]):
        for b in (2 * shaft, 2 * shaft + 1):
            c = a["clearance"][b]
            ax.plot(pos[win, b, 0] / c, pos[win, b, 1] / c, lw=0.7, label=f"bearing {b + 1}")
        c = a["clearance"][2 * shaft]
        ax.plot(r["gear_node"][win, shaft, 0] / c, r["gear_node"][win, shaft, 1] / c, lw=0.7,
                label="pinion" if shaft == 0 else "gear")
        ax.plot(np.cos(circle), np.sin(circle), "k-", lw=0.6)
        ax.set_aspect("equal")
        ax.set_title(f"Fig. 5{'ab'[shaft]}: shaft {shaft + 1} (units of C_{2 * shaft + 1})")
        ax.legend(fontsize=7)
    for k, b in enumerate((0, 2)):
        ax = axes[2 + k]
        c = a["clearance"][b]
        ax.plot(pos[:, b, 0] / c, pos[:, b, 1] / c, lw=0.3, color="0.6", label="transient")
        ax.plot(pos[win, b, 0] / c, pos[win, b, 1] / c, lw=0.8, color="C0",
                label="last gear revolution")
        ax.plot(*a["static"][b] / c, "k+", ms=10, label="X0")
        ax.set_aspect("equal")
        ax.set_title(f"Fig. 6{'ab'[k]}: bearing {b + 1} (s/C, t/C)")
        ax.legend(fontsize=7)
    path = _save(fig, fig_dir / "fig05_06_orbits.png", plt, GEAR_REVOLUTION)
    j = pos[win]
    sym = max(np.abs(j[:, 0] - j[:, 1]).max(), np.abs(j[:, 2] - j[:, 3]).max()) / np.abs(j).max()
    bend = [np.ptp(r["gear_node"][win, 0, k]) / np.ptp(j[:, 0, k]) for k in (0, 1)]
    return path, {"symmetry": sym, "pinion_over_bearing_ptp": bend}


def _fig_forces(runs, prefix, fig_dir, plt, name, title) -> tuple[Path, dict]:
    """Figs. 7 / 15: ||F_b|| over the last orbit and its order spectrum in peak amplitude
    (:func:`force_spectrum`; the paper normalises its own), bearings 1 and 3, nonlinear
    (hybrid) vs linear."""
    fig, axes = plt.subplots(2, 2, figsize=(13, 7), constrained_layout=True)
    info = {}
    for col, (b, revs, unit) in enumerate(((0, 1.0, "pinion"), (2, 1.0, "gear"))):
        spectra = {}
        for model, style in (("hybrid", "C0-"), ("linear", "C1--")):
            r = runs[f"{prefix}_{model}"]
            a = _attrs(r)
            win = _window(r, revs, b)
            t = r["time"][win]
            fb = np.hypot(*r["bearing_force"][win, b].T)
            axes[0, col].plot((t - t[0]) * a["speeds"][b] / (2 * np.pi), fb, style, lw=0.7,
                              label="nonlinear (hybrid)" if model == "hybrid" else "linear")
            spectra[model] = force_spectrum(r, b, revs)
            info[f"bearing{b + 1}_{model}_mean"] = float(fb.mean())
            info[f"bearing{b + 1}_{model}_ptp"] = float(np.ptp(fb))
        for model, style in (("hybrid", "C0-"), ("linear", "C1--")):
            f, amp, _ = spectra[model]
            axes[1, col].plot(f[1:], amp[1:], style, lw=0.7, label=model)  # order 0: the mean
        z1, z2 = _attrs(runs[f"{prefix}_hybrid"])["teeth"]
        fmax = 4.2 * (z1 if b == 0 else z2)
        axes[1, col].set_xlim(0, fmax)
        axes[1, col].set_xlabel(order_label(unit))
        axes[1, col].set_ylabel(f"||F_b|| bearing {b + 1}: {AMPLITUDE_LABEL}")
        axes[1, col].set_title(f"bearing {b + 1}: spectrum over the last {unit} revolution",
                               fontsize=10)
        axes[0, col].set_xlabel(f"{unit} revolutions")
        axes[0, col].set_ylabel(f"||F_b|| bearing {b + 1} [N]")
        axes[0, col].legend(fontsize=8)
        axes[1, col].legend(fontsize=8)
        f, amp, res = spectra["hybrid"]
        info[f"bearing{b + 1}_lines"] = {
            "1": has_line(f, amp, 1.0, res), "z": has_line(f, amp, z1 if b == 0 else z2, res)}
        if b == 0:
            info["bearing1_lines"]["2z"] = has_line(f, amp, 2 * z1, res)
        else:
            info["bearing3_lines"]["z2/z1"] = has_line(f, amp, z2 / z1, res)
    fig.suptitle(title)
    path = _save(fig, fig_dir / f"{name}.png", plt, "each panel's, in its title")
    return path, info


def _fig_speed(points, fig_dir, plt, name, title, models=("hybrid", "linear"),
               extra=None) -> tuple[Path, dict]:
    """Figs. 8 / 16: R and peak-to-peak ||F_b|| of bearings 1 and 3 against speed."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4), constrained_layout=True)
    info = {}
    for model in models:
        src = extra if (extra is not None and model == "hybrid") else points
        w, r = _curve(src, model, "R")
        axes[0].plot(w, r, "o-", label=model)
        info[f"R_{model}"] = dict(zip(w.tolist(), r.tolist(), strict=True))
        for k, b in enumerate((0, 2)):
            w, p = _curve(src, model, "force_ptp", b)
            axes[1 + k].plot(w, p, "o-", label=model)
            info[f"ptp{b + 1}_{model}"] = dict(zip(w.tolist(), p.tolist(), strict=True))
    axes[0].set_ylabel("R = max dynamic / static mesh load")
    axes[1].set_ylabel("peak-to-peak ||F_b|| bearing 1 [N]")
    axes[2].set_ylabel("peak-to-peak ||F_b|| bearing 3 [N]")
    for ax in axes:
        ax.set_xlabel("input speed [rad/s]")
        ax.legend(fontsize=8)
    fig.suptitle(title)
    path = _save(fig, fig_dir / f"{name}.png", plt)
    return path, info


def _fig_torque(points, fig_dir, plt, clearance) -> tuple[Path, dict]:
    """Fig. 9: orbits in bearing 1 for increasing torque, ellipse centres."""
    fig, ax = plt.subplots(figsize=(6, 6), constrained_layout=True)
    centres = {}
    for p in points:
        if p["error"] is not None:
            continue
        torque = _as_float(p["overrides"]["drive.torque"])
        o = p["orbit"][:, 0] / clearance
        ax.plot(o[:, 0], o[:, 1], lw=0.6, label=f"T = {torque:g} N m")
        c = fit_ellipse(o[:, 0], o[:, 1])["centre"]
        ax.plot(*c, "k+")
        centres[torque] = c.tolist()
    circle = np.linspace(0, 2 * np.pi, 361)
    ax.plot(np.cos(circle), np.sin(circle), "k-", lw=0.6)
    ax.set_aspect("equal")
    fig.suptitle("Fig. 9: bearing 1, omega = 325 rad/s (s/C, t/C); + ellipse centres")
    ax.legend(fontsize=8)
    path = _save(fig, fig_dir / "fig09_torque.png", plt)
    ecc = {t: math.hypot(*c) for t, c in sorted(centres.items())}
    return path, {"centres": centres, "mean_eccentricity": ecc}


def _fig_unbalance(points, base, fig_dir, plt, plan) -> tuple[Path, dict]:
    """Fig. 10: peak-to-peak ||F_b|| in bearing 1 and R against speed for several e_mu."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4), constrained_layout=True)
    info = {}
    for e in plan.unbalances:
        for model, style in (("hybrid", "-"), ("linear", "--")):
            src = base if e == 0.6e-3 else [
                p for p in points
                if np.isclose(_as_float(p["overrides"].get("gears.*.unbalance")), e)]
            w, p = _curve(src, model, "force_ptp", 0)
            w2, r = _curve(src, model, "R")
            axes[0].plot(w, p, "o" + style, label=f"{model} e_mu {e * 1e3:g} mm")
            axes[1].plot(w2, r, "o" + style, label=f"{model} e_mu {e * 1e3:g} mm")
            info[f"ptp1_{model}_{e * 1e3:g}mm"] = dict(zip(w.tolist(), p.tolist(), strict=True))
            info[f"R_{model}_{e * 1e3:g}mm"] = dict(zip(w2.tolist(), r.tolist(), strict=True))
    axes[0].set_ylabel("peak-to-peak ||F_b|| bearing 1 [N]")
    axes[1].set_ylabel("R")
    for ax in axes:
        ax.set_xlabel("input speed [rad/s]")
        ax.legend(fontsize=7)
    fig.suptitle("Fig. 10: influence of mass unbalance (spur, T = 220 N m)")
    path = _save(fig, fig_dir / "fig10_unbalance.png", plt)
    return path, info


def _fig_helix(points, base, spur_run, fig_dir, plt, plan, clearance) -> tuple[Path, dict]:
    """Figs. 11 and 14: R and peak-to-peak ||F_b|| against speed per helix angle; orbits in
    bearing 1 at 325 rad/s per helix angle with their centres."""
    fig, axes = plt.subplots(1, 4, figsize=(19, 4), constrained_layout=True)
    info = {"R": {}, "centres": {}}
    for beta in plan.helix_angles:
        if beta == 0.0:
            src = [p for p in base if p["bearing"] == "hybrid"]
        else:
            src = [p for p in points if np.isclose(
                _as_float(p["overrides"]["gears.*.helix_angle"]), beta)]
        w, r = _curve(src, "hybrid", "R")
        keep = np.isin(w, np.asarray(plan.speeds))
        axes[0].plot(w[keep], r[keep], "o-", label=f"beta {beta:g} deg")
        info["R"][beta] = dict(zip(w[keep].tolist(), r[keep].tolist(), strict=True))
        for k, b in enumerate((0, 2)):
            w, p = _curve(src, "hybrid", "force_ptp", b)
            keep = np.isin(w, np.asarray(plan.speeds))
            axes[1 + k].plot(w[keep], p[keep], "o-", label=f"beta {beta:g} deg")
        at = [p["orbit"] for p in src if p["error"] is None
              and np.isclose(_as_float(p["overrides"]["drive.speed"]), 325.0)]
        if beta == 0.0:  # the spur base run (325 rad/s)
            at = [spur_run["journal_position"][_window(spur_run, 1.0, 2), :, :2]]
        if at:
            o = at[0][:, 0] / clearance
            axes[3].plot(o[:, 0], o[:, 1], lw=0.6, label=f"beta {beta:g} deg")
            c = fit_ellipse(o[:, 0], o[:, 1])["centre"]
            axes[3].plot(*c, "k+")
            info["centres"][beta] = c.tolist()
    axes[0].set_ylabel("R")
    axes[1].set_ylabel("peak-to-peak ||F_b|| bearing 1 [N]")
    axes[2].set_ylabel("peak-to-peak ||F_b|| bearing 3 [N]")
    for ax in axes[:3]:
        ax.set_xlabel("input speed [rad/s]")
        ax.legend(fontsize=8)
    axes[3].set_aspect("equal")
    axes[3].set_title("Fig. 14: bearing 1 at 325 rad/s (s/C, t/C)")
    axes[3].legend(fontsize=7)
    fig.suptitle("Fig. 11: influence of the helix angle (hybrid bearings)")
    path = _save(fig, fig_dir / "fig11_14_helix.png", plt,
                 f"{plt.window}; Fig. 14's spur orbit: {GEAR_REVOLUTION}")
    return path, info


def _fig_transients(runs, fig_dir, plt) -> tuple[Path, dict]:
    """Figs. 12 and 17: transient from X0, spur vs helical (hybrid) and helical linear vs
    nonlinear in bearings 3 and 4."""
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.5), constrained_layout=True)
    info = {}
    for k, (shaft, bs) in enumerate(((0, (0, 1)), (1, (2, 3)))):
        ax = axes[k]
        for key, style in (("spur_hybrid", "-"), ("helical_hybrid", "-")):
            r = runs[key]
            a = _attrs(r)
            for b in bs:
                c = a["clearance"][b]
                pos = r["journal_position"][:, b] / c
                ax.plot(pos[:, 0], pos[:, 1], style, lw=0.4,
                        label=f"{key.split('_')[0]} bearing {b + 1}")
                ax.plot(*a["static"][b] / c, "k+")
        ax.set_aspect("equal")
        ax.set_title(f"Fig. 12{'ab'[k]}: shaft {shaft + 1}")
        ax.legend(fontsize=7)
    for k, b in enumerate((2, 3)):
        ax = axes[2 + k]
        for key in ("helical_hybrid", "helical_linear"):
            r = runs[key]
            a = _attrs(r)
            c = a["clearance"][b]
            ax.plot(r["journal_position"][:, b, 0] / c, r["journal_position"][:, b, 1] / c, lw=0.4,
                    label=key.split("_")[1])
            ax.plot(*a["static"][b] / c, "k+")
        ax.set_aspect("equal")
        ax.set_title(f"Fig. 17: helical, bearing {b + 1}")
        ax.legend(fontsize=7)
    path = _save(fig, fig_dir / "fig12_17_transients.png", plt, "")
    for key in ("spur_hybrid", "helical_hybrid", "helical_linear"):
        r = runs[key]
        a = _attrs(r)
        win = _window(r, 1.0, 2)
        shift = [(r["journal_position"][win, b].mean(axis=0) - a["static"][b])
                 / a["clearance"][b] for b in range(4)]
        info[key] = np.round(np.asarray(shift), 4).tolist()
    return path, info


def _fig_face_load(fig_dir, plt) -> tuple[Path, dict]:
    """Fig. 13: load per unit length along the face width, spur vs helical (quasi-static at
    the static solution, one pinion angle in the two-pair zone)."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4), constrained_layout=True)
    info = {}
    for ax, path, name in ((axes[0], SPUR, "spur"), (axes[1], HELICAL, "helical")):
        case = load_case(path)
        master = build_master(case, in_process=True)
        master.solve_static()
        st = master.structure.structure
        ms = st.mesh_states[0]  # the paper's one mesh
        mesh = st.meshes[0]
        loads = ms.load.reshape(mesh.n_lines, mesh.n_slices) / mesh.dl / 1e3  # N/mm
        z = mesh.z_slices * 1e3
        spreads = []
        for j in range(mesh.n_lines):
            on = ms.active.reshape(mesh.n_lines, -1)[j]
            if on.any():
                ax.plot(z[on], loads[j, on], "o-", ms=3, label=f"contact line {j}")
                spreads.append(float(np.ptp(loads[j, on]) / loads[j, on].mean()))
        ax.set_xlabel("z [mm]")
        ax.set_ylabel("load per unit length [N/mm]")
        ax.set_title(f"Fig. 13{'ab'[name == 'helical']}: {name}")
        ax.legend(fontsize=7)
        info[name] = spreads
    p = _save(fig, fig_dir / "fig13_face_load.png", plt, "")
    return p, info


def draw_all(runs: dict, sweeps: dict, plan, fig_dir: Path) -> dict:
    """Every figure of the reproduction: ``{key: (png path, info)}``
    (:mod:`orchestrator.studies.reproduce.report`)."""
    fig_dir = Path(fig_dir)
    fig_dir.mkdir(parents=True, exist_ok=True)
    stamp = ("gsb reproduce --quick: fewer periods, not steady state: trends only"
             if plan.label == "quick" else "")
    plt = _Stamped(pyplot(), stamp, window_text(plan))
    c1 = _attrs(runs["spur_hybrid"])["clearance"][0]  # bearing 1 (orbits in units of C_1)
    figs = {}
    figs["orbits"] = _fig_orbits(runs, fig_dir, plt)
    figs["fig7"] = _fig_forces(runs, "spur", fig_dir, plt, "fig07_forces",
                               "Fig. 7: spur, ||F_b|| over the last revolution and spectrum")
    figs["fig15"] = _fig_forces(runs, "helical", fig_dir, plt, "fig15_forces",
                                "Fig. 15: helical 12.5 deg, ||F_b|| and spectrum")
    base_speed = sweeps["fig08_speed"]
    figs["fig8"] = _fig_speed(base_speed, fig_dir, plt, "fig08_speed",
                              "Fig. 8: linear vs nonlinear bearings (spur, T 220 N m, "
                              "e_mu 0.6 mm)")
    figs["fig9"] = _fig_torque(sweeps["fig09_torque"], fig_dir, plt, c1)
    figs["fig10"] = _fig_unbalance(sweeps["fig10_unbalance"], base_speed, fig_dir, plt, plan)
    figs["fig11"] = _fig_helix(sweeps["fig11_helix"], base_speed, runs["spur_hybrid"], fig_dir,
                               plt, plan, c1)
    helical_hybrid = [p for p in sweeps["fig11_helix"]
                      if np.isclose(_as_float(p["overrides"]["gears.*.helix_angle"]), 12.5)]
    figs["fig16"] = _fig_speed(sweeps["fig16_models"], fig_dir, plt, "fig16_models",
                               "Fig. 16: helical 12.5 deg, bearing models compared",
                               models=("hybrid", "linear", "lumped"), extra=helical_hybrid)
    figs["transients"] = _fig_transients(runs, fig_dir, plt)
    figs["fig13"] = _fig_face_load(fig_dir, plt)
    return figs
