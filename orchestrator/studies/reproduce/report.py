"""``report.md`` of ``gsb reproduce``: every figure next to what the paper states, with the
checks of the paper's claims (pass/fail, never tuned) and where the results depart from it."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np

from orchestrator.studies.reproduce.plan import window_text
from orchestrator.sweeps.runner import stopped_on_physics

__all__ = ["json_default", "write_report"]


def json_default(o):
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def _check(ok: bool) -> str:
    return "PASS" if ok else "FAIL"


def bearing_force_departure(ptp_bearing1: float, r_300: float, r_max: float) -> str:
    """The paragraph on the bearing forces (the departure from the paper), with the damped
    modes, the film damping and the tooth critical speeds of the spur case computed here
    (:func:`orchestrator.analysis.campbell.linearise`); the sensitivity to the drivetrain, the
    damping and the time step is in ``docs/drivetrain.md``."""
    from fmu_src.case import load_case
    from gear_fmu.modal.damped_modes import tooth_critical_speeds
    from orchestrator.analysis.campbell import linearise

    lin = linearise(load_case("baguet2010_spur"))
    d = lin.damped
    mesh = [i for i in range(d.frequency_hz.size)
            if not d.overdamped[i] and d.mesh_energy_fraction[i] >= 0.25]
    undamped = lin.modes
    top = int(np.argmax(undamped.mesh_energy_fraction))
    crit = tooth_critical_speeds(d.frequency_hz, d.damping_ratio, d.mesh_energy_fraction,
                                 lin.z1, (100.0, 1200.0), min_mesh_fraction=0.25)
    return (
        f"Bearing forces. The paper finds the bearing-force amplitudes dominated by the "
        f"unbalance, with the mesh excitation superimposed. Here the mesh-order lines dominate "
        f"the force (bearing-1 peak-to-peak {ptp_bearing1:.0f} N at 325 rad/s; the largest "
        f"lines are the 2nd and 3rd mesh harmonics), although the orbits are unbalance "
        f"ellipses with small mesh ripples, as in the paper's Fig. 6: the mesh-order force is "
        f"the film damping acting on sub-micrometre journal motion (direct damping Cb_tt at "
        f"X0: " + ", ".join(f"{lin.cb[j][1, 1]:.3g}" for j in range(4)) + " N s/m at "
        f"bearings 1-4), the film stiffness contributing little. The resonances that set R "
        f"(R = {r_300:.2f} at 300 rad/s, up to {r_max:.2f} over 100-1200 rad/s) are the damped "
        f"modes of the linearised system with the film damping, "
        + ", ".join(f"{d.frequency_hz[i]:.0f} Hz (damping ratio {d.damping_ratio[i]:.3f})"
                    for i in mesh)
        + f" (`gsb modal`), not the undamped mesh mode ({undamped.frequency_hz[top]:.0f} Hz): "
        f"their tooth critical speeds in 100-1200 rad/s are "
        + ", ".join(f"{c['speed_rad_s']:.0f}" for c in crit) + " rad/s. "
        "What moves the result most is the drivetrain, which the paper does not state: a "
        "motor inertia on the free input end lowers R and the bearing-1 peak-to-peak markedly, "
        "while the output condition (clamped, or a load inertia) barely matters; the damping "
        "model and the time step move the mesh lines too (generated figures in "
        "`docs/drivetrain.md`). Other choices the paper leaves open (tooth stiffness of "
        "Weber-Banaschek checked against ISO 6336, modal damping 0.03 on the modes with the "
        "bearings' static stiffness) bear on it as well.")


def write_report(out, plan, meta, figs) -> Path:
    table4, timings = meta["table4"], meta["timings"]
    rel = {k: v[0].relative_to(out) for k, v in figs.items()}
    f8 = figs["fig8"][1]
    f9 = figs["fig9"][1]
    f10 = figs["fig10"][1]
    f11 = figs["fig11"][1]
    f7 = figs["fig7"][1]
    tr = figs["transients"][1]
    orb = figs["orbits"][1]

    def rel_diff(a, b):
        """Largest relative difference over the common speeds and the speed where it is."""
        keys = sorted(set(a) & set(b))
        if not keys:
            return math.nan, math.nan
        d = {k: abs(a[k] - b[k]) / max(abs(b[k]), 1e-300) for k in keys}
        worst = max(d, key=d.get)
        return d[worst], float(worst)

    lin_vs_nl, at_speed = rel_diff(f8["ptp1_linear"], f8["ptp1_hybrid"])
    big = max(plan.unbalances)
    lin_big, big_speed = rel_diff(f10[f"ptp1_linear_{big * 1e3:g}mm"],
                                  f10[f"ptp1_hybrid_{big * 1e3:g}mm"])
    fig7_diff = abs(f7["bearing1_linear_ptp"] / f7["bearing1_hybrid_ptp"] - 1)
    ecc = list(f9["mean_eccentricity"].values())
    r_max = {b: max(v.values()) for b, v in f11["R"].items() if v}
    betas = sorted(r_max)
    t4 = {r["case"]: r for r in table4}
    ratio = {c: r["time_full_run"] / t4["2"]["time_full_run"] for c, r in t4.items()}
    checks = [
        ("bearing 1 spectrum: lines at 1 and 26 and 52 (pinion units)",
         all(f7["bearing1_lines"].values())),
        ("bearing 3 spectrum: lines at 1, 157/26 and 157 (gear units)",
         all(f7["bearing3_lines"].values())),
        ("spur: orbits 1 = 2 and 3 = 4", orb["symmetry"] < 1e-8),
        ("spur: steady orbits centred on X0 (centre within 5 % of C)",
         max(math.hypot(*s) for s in tr["spur_hybrid"]) < 0.05),
        ("helical: orbits 1 and 2 shifted to either side of X0",
         np.dot(tr["helical_hybrid"][0], tr["helical_hybrid"][1]) < 0
         or np.dot(tr["helical_hybrid"][2], tr["helical_hybrid"][3]) < 0),
        (f"Fig. 7, spur e_mu 0.6 mm at 325 rad/s: linear and nonlinear bearing-1 "
         f"peak-to-peak agree within 5 % ({100 * fig7_diff:.1f} %)", fig7_diff < 0.05),
        (f"Fig. 8, spur e_mu 0.6 mm, every speed: linear and nonlinear within 10 % (largest "
         f"difference {100 * lin_vs_nl:.1f} % at {at_speed:g} rad/s)", lin_vs_nl < 0.1),
        (f"Fig. 10, e_mu {big * 1e3:g} mm: linear and nonlinear part further than at 0.6 mm "
         f"({100 * lin_big:.1f} % at {big_speed:g} rad/s)", lin_big > lin_vs_nl),
        ("R falls as the helix angle grows (max of R over speed per beta: "
         + ", ".join(f"{b:g} deg {r_max[b]:.2f}" for b in betas) + ")",
         all(r_max[a] >= r_max[b] for a, b in itertools.pairwise(betas))),
        ("mean shaft eccentricity grows with torque ("
         + ", ".join(f"{t:g} N m {e:.3f}" for t, e in f9["mean_eccentricity"].items()) + ")",
         all(a < b for a, b in itertools.pairwise(ecc))),
        ("Table 4: time linear < hybrid < FD/multigrid",
         t4["0"]["time_full_run"] < t4["2"]["time_full_run"] < t4["4"]["time_full_run"]),
        (f"Table 4: short-bearing theory far off in X0 ({100 * t4['1']['error']:+.2f} %)",
         abs(t4["1"]["error"]) > 0.05),
    ]
    lines = [
        "# Baguet & Jacquenot (2010), section 4, regenerated",
        "",
        f"Plan: **{plan.label}** ({plan.periods} mesh periods per run, speeds "
        f"{', '.join(f'{w:g}' for w in plan.speeds)} rad/s, steady-state window of every "
        f"run and sweep point: {window_text(plan)})."
        + (" Quick runs are not steady state: compare trends only." if plan.label == "quick"
           else ""),
        f"Wall time: {timings['total']:.0f} s (base runs {timings['base runs']:.0f} s, Table 4 "
        f"{timings['Table 4']:.0f} s, sweeps {timings['sweeps']:.0f} s).",
        "",
        "## Checks of the paper's claims (pass/fail, never tuned)",
        "",
        "| check | result |",
        "| --- | --- |",
        *[f"| {text} | {_check(ok)} |" for text, ok in checks],
        "",
        "## Table 4: methods compared",
        "",
        "Paper: errors 0.02 % (hybrid 192), 0.005 % (hybrid 384), 12.40 % (short bearing); "
        "times relative to case 2: 0.60, 0.69, 1, 1.36, 130 (8 min for case 2 in 2010).",
        "",
        "| case | method | mesh | eccentricity bearing 1 | error vs M.M. | coupled it/step | "
        "bearing evaluations (full run) | time, full run [s] | relative time |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in table4:
        err = "Ref." if r["case"] == "4" else f"{100 * r['error']:+.3f} %"
        proj = f" (projected from {r['periods_timed']} periods)" if r["projected"] else ""
        lines.append(
            f"| {r['case']} | {r['method']} | {r['mesh']} | {r['eccentricity']:.5f} | {err} | "
            f"{r['iterations_per_step']:.2f} | {r['evaluations_full_run']:.3g} | "
            f"{r['time_full_run']:.1f}{proj} | "
            f"{r['time_full_run'] / t4['2']['time_full_run']:.2f} |")
    lines += [
        "",
        "## Figures",
        "",
        f"![orbits]({rel['orbits']})",
        "",
        "Paper (Figs. 5-6): orbits of bearings 1 and 2 identical, 3 and 4 identical; bending in "
        "the base plane, largest at the gear nodes; 26 oscillations per orbit in bearing 1. "
        f"Here: symmetry to {orb['symmetry']:.1e}; pinion-node / bearing-1 peak-to-peak ratios "
        f"(s, t) {orb['pinion_over_bearing_ptp'][0]:.2f}, {orb['pinion_over_bearing_ptp'][1]:.2f}.",
        "",
        f"![Fig. 7]({rel['fig7']})",
        "",
        "Paper (Fig. 7): linear and nonlinear forces identical in bearings 1 and 3; lines at "
        "f_p = 1, f_m = 26 and harmonics (bearing 1), f_g = 1, f_p = 6.03, f_m = 157 (bearing 3); "
        "unbalance dominates the bearing forces. Here: bearing 1 mean "
        f"{f7['bearing1_hybrid_mean']:.0f} N, peak-to-peak {f7['bearing1_hybrid_ptp']:.0f} N "
        f"(hybrid) vs {f7['bearing1_linear_ptp']:.0f} N (linear); bearing 3 peak-to-peak "
        f"{f7['bearing3_hybrid_ptp']:.0f} N vs {f7['bearing3_linear_ptp']:.0f} N. The unbalance "
        "force alone is about M e_mu omega^2 / 2 = 190 N per pinion bearing: where the "
        "peak-to-peak is far larger, the mesh excitation dominates instead (see 'Where this "
        "departs from the paper').",
        "",
        f"![Fig. 8]({rel['fig8']})",
        "",
        "Paper (Fig. 8): R and the bearing forces show amplitude jumps at critical speeds; "
        f"linear and nonlinear similar. Here: largest linear/nonlinear difference in bearing-1 "
        f"peak-to-peak {100 * lin_vs_nl:.1f} % (at {at_speed:g} rad/s).",
        "",
        f"![Fig. 9]({rel['fig9']})",
        "",
        "Paper (Fig. 9): the ellipse centre moves out (mean eccentricity grows) with torque; "
        "orbit size set by the unbalance. Here, centre eccentricity per torque: "
        + ", ".join(f"{t:g} N m: {e:.3f}" for t, e in f9["mean_eccentricity"].items()) + ".",
        "",
        f"![Fig. 10]({rel['fig10']})",
        "",
        "Paper (Fig. 10): linear and nonlinear part at high speed, more so with larger unbalance; "
        f"R barely affected. Here: largest difference at e_mu {big * 1e3:g} mm "
        f"{100 * lin_big:.1f} % at {big_speed:g} rad/s (0.6 mm: {100 * lin_vs_nl:.1f} %).",
        "",
        f"![Figs. 11, 14]({rel['fig11']})",
        "",
        "Paper (Figs. 11, 14): peaks of R at critical speeds, falling with the helix angle; orbit "
        "centres move away from X0 as beta grows, orbit size unchanged. Here, max R over the "
        "speeds: " + ", ".join(f"beta {b:g}: {r_max[b]:.2f}" for b in betas) + "; centres "
        + ", ".join(f"{b:g} deg: ({c[0]:+.3f}, {c[1]:+.3f})" for b, c in f11["centres"].items())
        + ".",
        "",
        f"![Figs. 12, 17]({rel['transients']})",
        "",
        "Paper (Figs. 12, 17): spur orbits centred on X0; helical ones shifted to either side; "
        "the helical gear-shaft orbit moves away from X0 and the linear model misses it. "
        "Here, steady orbit centre minus X0 (units of C), bearings 1-4: "
        + "; ".join(f"{k}: {v}" for k, v in tr.items()) + ".",
        "",
        f"![Fig. 13]({rel['fig13']})",
        "",
        "Paper (Fig. 13): load uniform along the face width for spur, not for helical. Here, "
        "relative spread of the load along each line in contact: spur "
        + ", ".join(f"{v:.2e}" for v in figs["fig13"][1]["spur"]) + "; helical "
        + ", ".join(f"{v:.2f}" for v in figs["fig13"][1]["helical"]) + ".",
        "",
        f"![Fig. 15]({rel['fig15']})",
        "",
        f"![Fig. 16]({rel['fig16']})",
        "",
        "Paper (Figs. 15-16): the helical gear filters the mesh harmonics; the lumped spring "
        "cannot predict the bearing loads; the linear model is fine in bearing 1 but not in "
        "bearing 3.",
        "",
        "## Where this departs from the paper",
        "",
        "Stated with the numbers, not tuned away (the paper gives its results as curves; its "
        "text has few values to compare with):",
        "",
        "- " + bearing_force_departure(
            f7["bearing1_hybrid_ptp"], f8["R_hybrid"].get(300.0, math.nan),
            max(f8["R_hybrid"].values())),
        f"- Linear vs nonlinear at e_mu 0.6 mm: equal at the paper's 325 rad/s "
        f"({100 * fig7_diff:.1f} %), but they part by up to {100 * lin_vs_nl:.1f} % at "
        f"{at_speed:g} rad/s, where the paper reports them similar over the whole range.",
        f"- Table 4 time ratios: FD/multigrid {ratio['4']:.0f} x the hybrid case (paper "
        f"130 x), linear {ratio['0']:.2f} (paper 0.60), short bearing {ratio['1']:.2f} "
        f"(paper 0.69), hybrid n = 384 {ratio['3']:.2f} "
        f"(paper 1.36); the hybrid case itself runs in {t4['2']['time_full_run']:.0f} s "
        f"(paper: 8 minutes in 2010).",
        "",
        "## Failed sweep points",
        "",
    ]
    failed = [(k, i, m) for k, v in meta["failed"].items() for i, m in v]
    lines += [f"- {k} point {i}: {m}" for k, i, m in failed
              if not stopped_on_physics(m)] or ["none"]
    lines += ["", "## Sweep points stopped on physics (a journal touching its bearing)", ""]
    lines += [f"- {k} point {i}: {m}" for k, i, m in failed
              if stopped_on_physics(m)] or ["none"]
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path
