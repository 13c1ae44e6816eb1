"""``gsb modal``: the modes of a case linearised about X0, critical speeds, Campbell diagram."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from bearing_fmu import MODELS
from fmu_src.case import CaseError
from orchestrator.cli.options import add_case_argument, case_from_args

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("modal", help="natural and damped modes, tooth critical speeds, Campbell "
                                     "diagram of a case",
                       description="Modes of the gear-shaft system linearised about the static "
                                   "solution X0 (paper Eq. 20): the exact mean mesh stiffness "
                                   "over a mesh period, the undamped modes (symmetric part of "
                                   "the bearings' Kb), the damped modes (structure damping C, "
                                   "the bearings' Kb and Cb at X0), the input speeds where a "
                                   "harmonic of a mesh meets a mode of that mesh (every mesh of "
                                   "the train), and optionally a Campbell diagram over a speed "
                                   "range.")
    add_case_argument(p)
    p.add_argument("--bearing", choices=tuple(MODELS),
                   help="bearing model of every bearing (overrides bearings.*.model)")
    p.add_argument("--bearing-stiffness", type=float, default=None,
                   help="isotropic bearing stiffness [N/m] instead of the film at X0 (then no "
                        "bearing damping, Cb = 0)")
    p.add_argument("--modes", type=int, default=20,
                   help="modes listed in each text table (default 20; --json lists all)")
    p.add_argument("--speed-range", nargs=2, type=float, default=[50.0, 1500.0],
                   metavar=("LOW", "HIGH"),
                   help="input speeds [rad/s] of the critical speeds and the Campbell diagram "
                        "(default 50 1500)")
    p.add_argument("--mesh-fraction", type=float, default=0.1,
                   help="mesh modes: share of the strain energy in the mesh >= this "
                        "(each mesh's own share; default 0.1)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object instead of the tables")
    p.add_argument("--campbell", nargs="?", const="", default=None, metavar="PNG",
                   help="draw a Campbell diagram (default file <case>_campbell.png in --out)")
    p.add_argument("--campbell-speeds", type=int, default=16,
                   help="speeds of the Campbell diagram over the speed range (default 16)")
    p.add_argument("--out", default="results", help="folder of the default Campbell file "
                                                    "(default: results, as gsb run's)")
    p.set_defaults(func=modal)


def _modal_checks(args) -> tuple[float, float]:
    """The numeric options of ``gsb modal``, checked (CaseError naming value and limit)."""
    k = args.bearing_stiffness
    if k is not None and not (math.isfinite(k) and k > 0.0):
        raise CaseError(f"--bearing-stiffness {k!r} N/m must be finite and > 0")
    low, high = args.speed_range
    if not (math.isfinite(low) and low > 0.0):
        raise CaseError(f"--speed-range LOW = {low!r} rad/s must be finite and > 0")
    if not (math.isfinite(high) and high > low):
        raise CaseError(f"--speed-range HIGH = {high!r} rad/s must be finite and > LOW = "
                        f"{low!r} rad/s")
    if args.modes < 1:
        raise CaseError(f"--modes {args.modes!r} must be >= 1")
    if not 0.0 <= args.mesh_fraction <= 1.0:
        raise CaseError(f"--mesh-fraction {args.mesh_fraction!r} must lie in [0, 1]")
    if not 3 <= args.campbell_speeds <= 200:
        raise CaseError(f"--campbell-speeds {args.campbell_speeds!r} must lie in [3, 200]")
    return low, high


def _crossing_table(rows: list[dict]) -> str:
    """The Campbell diagram's critical speeds: where a followed mode crosses an excitation
    line (:func:`orchestrator.analysis.campbell.crossings`), as a text table."""
    from orchestrator.analysis.campbell import line_name
    if not rows:
        return "campbell: no mode crosses an excitation line over the speeds computed"
    out = ["campbell critical speeds (a mode followed over speed crossing an excitation line; "
           "mesh = its strain energy share in that mesh, or in every mesh for a 1x line):",
           f"{'line':<18} {'omega [rad/s]':>13} {'N [rpm]':>8} {'f [Hz]':>9} "
           f"{'zeta [-]':>8} {'mesh [-]':>8}"]
    for c in rows:
        out.append(f"{line_name(c):<18} {c['speed_rad_s']:>13.1f} {c['speed_rpm']:>8.0f} "
                   f"{c['frequency_hz']:>9.1f} {c['damping_ratio']:>8.4f} "
                   f"{c['mesh_energy_fraction']:>8.3f}")
    return "\n".join(out)


def _threshold_text(data: dict) -> str:
    """The stability threshold of a Campbell diagram's data as a line."""
    w, th = data["speeds"], data["stability_threshold"]
    if th is None:
        return (f"campbell: stable: every mode's damping ratio is positive at every speed "
                f"{w[0]:g}-{w[-1]:g} rad/s")
    if th == w[0]:
        return (f"campbell: UNSTABLE from the lowest speed computed, {th:g} rad/s: a mode's "
                "damping ratio is negative there")
    return (f"campbell: stability threshold {th:.1f} rad/s ({th * 30 / math.pi:.0f} rpm): the "
            "lowest speed where a mode's damping ratio turns negative (interpolated between "
            "the speeds computed)")


def _finite(x):
    """A float for JSON, None for NaN or inf."""
    x = float(x)
    return x if math.isfinite(x) else None


def modal(args) -> int:
    import json

    from fmu_src import description
    from gear_fmu.modal.damped_modes import (
        critical_speed_table,
        damped_mode_table,
        tooth_critical_speeds,
    )
    from gear_fmu.modal.modes import mode_table
    from orchestrator.analysis import campbell
    from orchestrator.coupling.master import CouplingError
    from orchestrator.figures.campbell import plot_campbell
    from orchestrator.run.spec import RunError

    low, high = _modal_checks(args)
    case = case_from_args(args)
    system = campbell.Linearisation(case, args.bearing_stiffness)  # the Campbell's too
    try:
        lin = system.at()
    except CouplingError as exc:
        raise RunError(f"{case['case.name']}: {exc}") from None
    found, dm, lines = lin.modes, lin.damped, lin.lines
    critical = tooth_critical_speeds(dm.frequency_hz, dm.damping_ratio, lin.mesh_shares,
                                     lines["teeth"], (low, high), campbell.HARMONICS,
                                     args.mesh_fraction, ratios=lines["ratios"],
                                     meshes=lines["meshes"])
    per_width = lin.mesh_stiffness_loa / lin.contact_width / 1e9  # N/(mm um)
    chart = None
    if args.campbell is not None:
        path = Path(args.campbell or Path(args.out) / f"{case['case.name']}_campbell.png")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CaseError(f"--campbell {path}: cannot create its folder ({exc})") from None
        speeds = np.linspace(low, high, args.campbell_speeds)
        data = system.campbell(speeds)
        if not data["modes"]:
            raise CaseError(f"--campbell: no static solution over {low:g}-{high:g} rad/s: "
                            f"{data['skipped'][0][1]}")
        model = (f"isotropic {args.bearing_stiffness:g} N/m bearings, Cb = 0"
                 if args.bearing_stiffness
                 else f"{description.shared_bearing_model(case) or 'mixed'} bearings")
        teeth = ", ".join(f"{m} z = {z}" for m, z in zip(lines["meshes"], lines["teeth"],
                                                         strict=True))
        title = (f"{case['case.name']}: Campbell diagram of the damped modes\n"
                 f"T = {case['drive.torque']:g} N m, {model}, driver teeth: {teeth}")
        chart = {"path": str(plot_campbell(data, path, title,
                                                    min_mesh_fraction=args.mesh_fraction)),
                 "speeds_rad_s": data["speeds"].tolist(),
                 "crossings": campbell.crossings(data, min_mesh_fraction=args.mesh_fraction),
                 "stability_threshold_rad_s": data["stability_threshold"],
                 "skipped": [{"speed_rad_s": w, "error": e} for w, e in data["skipped"]]}
    if args.json:
        out = {
            "case": case["case.name"], "torque_N_m": case["drive.torque"],
            "speed_rad_s": case["drive.speed"], "bearings": lin.bearings,
            "meshes": [
                {"mesh": m, "driver_teeth": z, "speed_ratio": r,
                 "mean_mesh_stiffness_N_per_m": float(k),
                 "mean_mesh_stiffness_N_per_mm_um": float(kw)}
                for m, z, r, k, kw in zip(lines["meshes"], lines["teeth"], lines["ratios"],
                                          lin.mesh_stiffness_loa, per_width, strict=True)],
            "undamped_modes": [
                {"frequency_hz": float(f), "kind": kd, "mesh_energy_fraction": _finite(s)}
                for f, kd, s in zip(found.frequency_hz, found.kinds,
                                    found.mesh_energy_fraction, strict=True)],
            "damped_modes": [
                {"mode": i + 1, "frequency_hz": float(f), "damping_ratio": _finite(z),
                 "mesh_energy_fraction": _finite(s),
                 "mesh_shares": {m: _finite(v) for m, v in zip(lines["meshes"], per,
                                                                strict=True)},
                 "kind": kd, "overdamped": bool(o), "whirl": None if o else wd}
                for i, (f, z, s, per, kd, o, wd) in enumerate(zip(
                    dm.frequency_hz, dm.damping_ratio, dm.mesh_energy_fraction,
                    lin.mesh_shares, dm.kinds, dm.overdamped, lin.whirl_direction,
                    strict=True))],
            "gyroscopic": bool(case["simulation.gyroscopic"]),
            "critical_speeds": critical,
            "speed_range_rad_s": [low, high], "mesh_fraction": args.mesh_fraction,
            "campbell": chart}
        print(json.dumps(out, allow_nan=False))
        return 0
    print(f"{case['case.name']}: modes with the mean mesh stiffness at T = "
          f"{case['drive.torque']:g} N m; bearings: {lin.bearings}")
    print(mode_table(found, args.modes))
    refs = lin.reference_mesh_stiffness_loa
    print("\nmean mesh stiffness over a mesh period (Gauss-Legendre between the contact "
          "events), along the line of action, per mesh:")
    for m, name in enumerate(lines["meshes"]):
        ref = "" if refs is None else (f"; 16 equally spaced angles (damping reference): "
                                       f"{refs[m] / lin.contact_width[m] / 1e9:.3f} N/(mm um)")
        print(f"  {name}: {lin.mesh_stiffness_loa[m]:.5g} N/m = {per_width[m]:.3f} "
              f"N/(mm um) per unit width ({lin.contact_width[m] * 1e3:g} mm){ref}")
    gyro = ("G(Omega) the gyroscopic matrix at the case's speed" if case["simulation.gyroscopic"]
            else "no gyroscopic terms (simulation.gyroscopic = false)")
    print("\ndamped modes (Eq. 20: M, C0 = C + G(Omega) + Cb(X0), K0 = K_shaft + K_mesh,mean + "
          f"Kb(X0); {gyro}); f_d = |Im lambda| / 2 pi, zeta = -Re lambda / |lambda|, mesh = "
          "strain energy share, whirl: forward with the shaft's spin, backward against it, "
          "mixed (gear_fmu.modal.whirl)"
          + (f"; {dm.n_rigid // 2} rigid-body motion(s) left out" if dm.n_rigid else ""))
    print(damped_mode_table(dm, args.modes, lin.whirl_direction))
    excitation = "; ".join(
        f"{m}: z = {z}" + ("" if r == 1.0 else f", r = {r:.4g}")
        for m, z, r in zip(lines["meshes"], lines["teeth"], lines["ratios"], strict=True))
    print(f"\ntooth critical speeds: harmonic k z r omega / 2 pi of a mesh (k = "
          f"1..{campbell.HARMONICS}; z its driver's teeth, r the driver shaft's speed over the "
          f"input speed omega; per mesh {excitation}) = f_d of a mode with a share >= "
          f"{args.mesh_fraction:g} of its strain energy in that mesh, {low:g} <= omega <= "
          f"{high:g} rad/s")
    print(critical_speed_table(critical) if critical else "(none)")
    if chart is not None:
        for w, e in data["skipped"]:
            print(f"campbell: {w:g} rad/s skipped: {e}")
        print(_crossing_table(chart["crossings"]))
        print(_threshold_text(data))
        print(f"\ncampbell: {chart['path']} ({len(chart['speeds_rad_s'])} speeds; the "
              f"crossings it marks follow each mode with the bearings linearised at every "
              f"speed, so they differ from the table above, whose modes are those at the "
              f"case's {case['drive.speed']:g} rad/s)")
    return 0
