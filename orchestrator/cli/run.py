"""``gsb run`` and ``gsb modal``: the case-file commands of the command line."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from bearing_fmu import MODELS
from fmu_src.case import CaseError

__all__ = ["add_parsers", "case_from_args"]


def _override(text: str):
    """``section.key=value`` -> (key, value): JSON lists, numbers, else the text ("4 mm")."""
    import json

    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--set {text!r}: expected section.key=value")
    key, value = (part.strip() for part in text.split("=", 1))
    try:
        return key, json.loads(value)
    except ValueError:
        return key, value


def _common(p, case_help: str = "case file (TOML) or the name of a shipped case, e.g. "
                                 "baguet2010_spur", optional: bool = False) -> None:
    if optional:
        p.add_argument("case", nargs="?", default="baguet2010_spur", help=case_help)
    else:
        p.add_argument("case", help=case_help)
    _overrides_options(p)


def _overrides_options(p) -> None:
    p.add_argument("--speed", help="override operation.speed (e.g. '500 rad/s', '3000 rpm')")
    p.add_argument("--torque", help="override operation.torque (e.g. '300 N.m')")
    p.add_argument("--unbalance", help="override operation.unbalance of both shafts (e.g. "
                                       "'1.2 mm')")
    p.add_argument("--set", dest="overrides", action="append", type=_override, default=[],
                   metavar="SECTION.KEY=VALUE", help="override any case field (repeatable)")


def add_parsers(sub) -> None:
    p = sub.add_parser("run", help="static solution and transient of a case (FMUs by default)",
                       description="Static solution X0 and the coupled transient of a case; "
                                   "writes <out>/<case>_<model>_<hash>.h5 (the hash of the "
                                   "effective parameters: runs with other overrides keep their "
                                   "own files) and PNG figures in the folder beside it. The "
                                   "file is readable while the run writes it (HDF5 SWMR) and "
                                   "flushed every second. Ctrl-C or SIGTERM stops the run after "
                                   "the current step (exit 130 / 143), the steps computed kept; "
                                   "--resume continues it.")
    p.add_argument("case", nargs="?", default=None,
                   help="case file (TOML), the name of a shipped case (e.g. baguet2010_spur; "
                        "`gsb cases` lists them), or an SSP archive of `gsb export-ssp` (its FMUs "
                        "and values are run)")
    _overrides_options(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model (overrides the "
                                                            "case; swaps the bearing FMU)")
    p.add_argument("--periods", type=int, help="mesh periods to simulate (overrides the case; "
                                               "with --resume: the new total length)")
    p.add_argument("--in-process", action="store_true",
                   help="run the Python slaves directly, without the FMI layer")
    p.add_argument("--out", default="results", help="output folder (default results/)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing results file of the same parameters (a complete "
                        "one only once the new run is complete)")
    p.add_argument("--resume", metavar="FILE", default=None,
                   help="continue the run of this results file from its last checkpoint (its "
                        "stored case, transport and model; --periods extends it)")
    p.add_argument("--fmu-dir", default=None, help="folder of built FMUs (default: the per-user "
                                                   "cache; built there if missing)")
    p.add_argument("--bearing-fmu", default=None, metavar="FMU",
                   help="a bearing FMU of your own for all four bearings (inputs s, t, s_dot, "
                        "t_dot; outputs F_s, F_t; docs/fmu-variables.md)")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=run)

    p = sub.add_parser("cases", help="list the cases shipped with the package",
                       description="The case files installed with the package; `gsb run NAME` "
                                   "runs one from any folder, `--show NAME` prints its file.")
    p.add_argument("--show", metavar="NAME", default=None, help="print this case's file")
    p.set_defaults(func=cases)

    p = sub.add_parser("export", help="write a results file's channels as CSV",
                       description="One row per time step, one column per channel component, "
                                   "named `channel[i][j] [unit]` (e.g. journal_position[0][1] "
                                   "[m]: bearing 1, t), 17 significant digits.")
    p.add_argument("file", help="results file (.h5) of gsb run")
    p.add_argument("--csv", metavar="OUT", nargs="?", const="", default="",
                   help="CSV file to write (default: the results file with .csv)")
    p.add_argument("--channel", dest="channels", action="append", default=[],
                   help="export only this channel (repeatable; default all)")
    p.set_defaults(func=export)

    p = sub.add_parser("reproduce", help="regenerate the paper's section 4 (figures, Table 4, "
                                         "report)",
                       description="Fresh runs of the paper's spur and helical cases, the "
                                   "parametric sweeps on Dask, every figure of section 4 and a "
                                   "report putting each next to what the paper states.")
    p.add_argument("--quick", action="store_true",
                   help="fewer periods, speeds and parameter values: minutes, not hours")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address (default: a LocalCluster; 'none': serial)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster workers (default 2)")
    p.add_argument("--out", default="results/reproduce", help="output folder")
    p.add_argument("--redraw", action="store_true",
                   help="only redraw the figures and the report from the runs kept in --out")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=reproduce)

    p = sub.add_parser("build-fmus", help="build the FMUs (pythonfmu) into a folder",
                       description="Build every FMU into --dest; the gear-shaft FMU carries "
                                   "the case (its parameters start at the case's values).")
    _common(p, "case the gear-shaft FMU carries (file or shipped name; default "
               "baguet2010_spur)", optional=True)
    p.add_argument("--dest", default="build/fmus", help="output folder (default build/fmus)")
    p.add_argument("--fmu", dest="names", action="append", default=[], metavar="NAME",
                   help="build only this FMU (repeatable; e.g. GearShaft, BearingHybrid)")
    p.set_defaults(func=build_fmus)

    p = sub.add_parser("export-ssp", help="write a case's system as an SSP 1.0 archive",
                       description="Build the FMUs of a case and write DEST/<case>.ssp: the "
                                   "gear-shaft FMU, four bearing components, their "
                                   "connections and parameter values (runs in SSP tools, "
                                   "e.g. ecos, and in `gsb run`).")
    _common(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model (overrides the "
                                                            "case)")
    p.add_argument("--dest", default=".", help="output folder (default: the current folder)")
    p.set_defaults(func=export_ssp)

    p = sub.add_parser("modal", help="natural and damped modes, tooth critical speeds, Campbell "
                                     "diagram of a case",
                       description="Modes of the gear-shaft system linearised about the static "
                                   "solution X0 (paper Eq. 20): the exact mean mesh stiffness "
                                   "over a mesh period, the undamped modes (symmetric part of "
                                   "the bearings' Kb), the damped modes (structure damping C, "
                                   "the bearings' Kb and Cb at X0), the pinion speeds where a "
                                   "mesh harmonic meets a mesh mode, and optionally a Campbell "
                                   "diagram over a speed range.")
    _common(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model (overrides the case)")
    p.add_argument("--bearing-stiffness", type=float, default=None,
                   help="isotropic bearing stiffness [N/m] instead of the film at X0 (then no "
                        "bearing damping, Cb = 0)")
    p.add_argument("--modes", type=int, default=20,
                   help="modes listed in each text table (default 20; --json lists all)")
    p.add_argument("--speed-range", nargs=2, type=float, default=[50.0, 1500.0],
                   metavar=("LOW", "HIGH"),
                   help="pinion speeds [rad/s] of the critical speeds and the Campbell diagram "
                        "(default 50 1500)")
    p.add_argument("--mesh-fraction", type=float, default=0.1,
                   help="mesh modes: share of the strain energy in the mesh >= this "
                        "(default 0.1)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object instead of the tables")
    p.add_argument("--campbell", nargs="?", const="", default=None, metavar="PNG",
                   help="draw a Campbell diagram (default file <case>_campbell.png in --out)")
    p.add_argument("--campbell-speeds", type=int, default=16,
                   help="speeds of the Campbell diagram over the speed range (default 16)")
    p.add_argument("--out", default=".", help="folder of the default Campbell file "
                                              "(default: the current folder)")
    p.set_defaults(func=modal)


def _overrides(args) -> dict:
    """The command line's settings as case fields: the case is their one carrier."""
    from orchestrator.run.spec import check_periods

    overrides = dict(args.overrides)
    periods = getattr(args, "periods", None)
    for key, value in (("operation.speed", args.speed), ("operation.torque", args.torque),
                       ("operation.unbalance", args.unbalance),
                       ("bearings.model", getattr(args, "bearing", None)),
                       ("simulation.mesh_periods",
                        None if periods is None else check_periods(periods))):
        if value is not None:
            overrides[key] = value
    return overrides


def case_from_args(args):
    """The case file with the command line's overrides applied (checked again)."""
    from fmu_src.case import load_case

    return load_case(args.case, _overrides(args))


def build_fmus(args) -> int:
    from fmu_src.build.fmus import build_fmus as build

    for path in build(args.dest, args.names or None, case=case_from_args(args)):
        print(path)
    return 0


def export_ssp(args) -> int:
    from fmu_src.build.ssp import write_ssp
    from fmu_src.description import time_step
    from orchestrator.run.spec import build_master

    case = case_from_args(args)
    master = build_master(case, in_process=True)  # X0: start values for non-iterative masters
    try:
        master.solve_static()
    finally:
        master.close()
    path = write_ssp(case, args.dest, laws=master.laws)
    print(f"{path} (run: gsb run {path}; ecos simulate --path {path} --parameterSet case "
          f"--stepSize {time_step(case)!r} --stopTime <s>)")
    return 0


def cases(args) -> int:
    from fmu_src.case import load_case, shipped_cases

    shipped = shipped_cases()
    if args.show is not None:
        if args.show not in shipped:
            raise CaseError(f"--show {args.show}: no shipped case of that name; shipped: "
                            f"{', '.join(shipped)}")
        print(shipped[args.show].read_text(), end="")
        return 0
    for name, path in shipped.items():
        c = load_case(path)
        print(f"{name:<24} {c['operation.speed']:g} rad/s, T = {c['operation.torque']:g} N m, "
              f"helix {math.degrees(c['gear_pair.helix_angle']):g} deg, "
              f"{c['bearings.model']} bearings, {c['simulation.mesh_periods']} mesh periods "
              f"({path})")
    return 0


def export(args) -> int:
    from orchestrator.run.results import export_csv

    path = Path(args.file)
    from orchestrator.cli.plot import file_kind

    if file_kind(path) != "run":
        raise CaseError(f"{path}: a sweep file; gsb export writes the channels of a run's file")
    out = Path(args.csv) if args.csv else path.with_suffix(".csv")
    if out.resolve() == path.resolve():
        raise CaseError(f"--csv {out}: would overwrite the results file")
    try:
        written = export_csv(path, out, args.channels or None)
    except ValueError as exc:
        raise CaseError(f"--channel: {exc}") from None
    except OSError as exc:
        raise CaseError(f"--csv {out}: cannot write ({exc.strerror or exc})") from None
    print(written)
    return 0


def run(args) -> int:
    import shutil

    from orchestrator.run.runner import resume_run, run_case, static_report

    if args.resume is not None:
        ignored = [o for o, v in (("CASE", args.case), ("--bearing", args.bearing),
                                  ("--speed", args.speed), ("--torque", args.torque),
                                  ("--unbalance", args.unbalance), ("--set", args.overrides),
                                  ("--bearing-fmu", args.bearing_fmu),
                                  ("--in-process", args.in_process),
                                  ("--overwrite", args.overwrite)) if v]
        if ignored:
            raise CaseError(f"--resume continues the stored run as it was: drop "
                            f"{', '.join(ignored)} (only --periods, --fmu-dir, --no-figures "
                            f"and --quiet apply)")
        summary = resume_run(args.resume, periods=args.periods, fmu_dir=args.fmu_dir,
                             progress=not args.quiet, figures=not args.no_figures)
        _print_summary(summary)
        return 0
    if args.case is None:
        raise CaseError("a case is needed: a case file, a shipped case name (gsb cases) or an "
                        "SSP archive; or --resume FILE")
    fmus, folder = None, None
    if str(args.case).endswith(".ssp"):
        from fmu_src.build.ssp import read_ssp

        if args.in_process:
            raise CaseError("--in-process runs a case file, not an SSP archive's FMUs")
        system = read_ssp(args.case)
        folder = system.folder
        fmus = {"gear": system.gear_fmu, "bearings": system.bearing_fmus,
                "bearing_parameters": system.bearing_parameters}
        case = system.case.with_overrides(_overrides(args))
    else:
        case = case_from_args(args)
    if args.bearing_fmu is not None:
        if args.in_process:
            raise CaseError("--bearing-fmu needs the FMU transport (drop --in-process)")
        from orchestrator.coupling.fmi import ensure_fmus

        path = Path(args.bearing_fmu)
        if not path.is_file():
            raise CaseError(f"--bearing-fmu: no such file: {path}")
        gear = fmus["gear"] if fmus else ensure_fmus(["GearShaft"], args.fmu_dir)["GearShaft"]
        fmus = {"gear": gear, "bearings": [path] * 4}
    try:
        summary = run_case(case, in_process=args.in_process,
                           out_dir=args.out, fmu_dir=args.fmu_dir, progress=not args.quiet,
                           figures=not args.no_figures, fmus=fmus, overwrite=args.overwrite)
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
    print(f"static solution X0 ({case['case.name']}):")
    print(static_report(case, summary.static_positions))
    _print_summary(summary)
    return 0


def _print_summary(summary) -> None:
    """What ``gsb run`` prints of a finished (or resumed) run: its figures, the report and the
    files it wrote."""
    print(summary.describe())
    print(summary.report_text())
    print(f"results: {summary.results}")
    for path in summary.figures:
        print(f"figure: {path}")


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


def _finite(x):
    """A float for JSON, None for NaN or inf."""
    x = float(x)
    return x if math.isfinite(x) else None


def modal(args) -> int:
    import json

    from gear_fmu.damped_modes import (
        critical_speed_table,
        damped_mode_table,
        tooth_critical_speeds,
    )
    from gear_fmu.modal import mode_table
    from orchestrator.analysis import campbell
    from orchestrator.coupling.master import CouplingError
    from orchestrator.run.spec import RunError

    low, high = _modal_checks(args)
    case = case_from_args(args)
    try:
        lin = campbell.linearise(case, args.bearing_stiffness)
    except CouplingError as exc:
        raise RunError(f"{case['case.name']}: {exc}") from None
    found, dm = lin.modes, lin.damped
    critical = tooth_critical_speeds(dm.frequency_hz, dm.damping_ratio, dm.mesh_energy_fraction,
                                     lin.z1, (low, high), campbell.HARMONICS,
                                     args.mesh_fraction)
    per_width = lin.mesh_stiffness_loa / lin.contact_width / 1e9  # N/(mm um)
    chart = None
    if args.campbell is not None:
        path = Path(args.campbell or Path(args.out) / f"{case['case.name']}_campbell.png")
        speeds = np.linspace(low, high, args.campbell_speeds)
        data = campbell.campbell_data(case, speeds, args.bearing_stiffness)
        if not data["modes"]:
            raise CaseError(f"--campbell: no static solution over {low:g}-{high:g} rad/s: "
                            f"{data['skipped'][0][1]}")
        model = (f"isotropic {args.bearing_stiffness:g} N/m bearings, Cb = 0"
                 if args.bearing_stiffness else f"{case['bearings.model']} bearings")
        title = (f"{case['case.name']}: Campbell diagram of the damped modes\n"
                 f"T = {case['operation.torque']:g} N m, {model}, z1 = {lin.z1}")
        chart = {"path": str(campbell.plot_campbell(data, path, title,
                                                    min_mesh_fraction=args.mesh_fraction)),
                 "speeds_rad_s": data["speeds"].tolist(),
                 "crossings": campbell.crossings(data, min_mesh_fraction=args.mesh_fraction),
                 "skipped": [{"speed_rad_s": w, "error": e} for w, e in data["skipped"]]}
    if args.json:
        out = {
            "case": case["case.name"], "torque_N_m": case["operation.torque"],
            "speed_rad_s": case["operation.speed"], "bearings": lin.bearings,
            "mean_mesh_stiffness_N_per_m": lin.mesh_stiffness_loa,
            "mean_mesh_stiffness_N_per_mm_um": per_width,
            "undamped_modes": [
                {"frequency_hz": float(f), "kind": kd, "mesh_energy_fraction": _finite(s)}
                for f, kd, s in zip(found.frequency_hz, found.kinds,
                                    found.mesh_strain_fraction, strict=True)],
            "damped_modes": [
                {"mode": i + 1, "frequency_hz": float(f), "damping_ratio": _finite(z),
                 "mesh_energy_fraction": _finite(s), "kind": kd, "overdamped": bool(o)}
                for i, (f, z, s, kd, o) in enumerate(zip(
                    dm.frequency_hz, dm.damping_ratio, dm.mesh_energy_fraction, dm.kinds,
                    dm.overdamped, strict=True))],
            "critical_speeds": critical,
            "speed_range_rad_s": [low, high], "mesh_fraction": args.mesh_fraction,
            "campbell": chart}
        print(json.dumps(out, allow_nan=False))
        return 0
    print(f"{case['case.name']}: modes with the mean mesh stiffness at T = "
          f"{case['operation.torque']:g} N m; bearings: {lin.bearings}")
    print(mode_table(found, args.modes))
    ref = lin.reference_mesh_stiffness_loa
    ref = "" if ref is None else (f"; 16 equally spaced angles (damping reference): "
                                  f"{ref / lin.contact_width / 1e9:.3f} N/(mm um)")
    print(f"\nmean mesh stiffness over a mesh period (Gauss-Legendre between the contact "
          f"events), along the line of action: {lin.mesh_stiffness_loa:.5g} N/m = "
          f"{per_width:.3f} N/(mm um) per unit width ({lin.contact_width * 1e3:g} mm){ref}")
    print("\ndamped modes (Eq. 20: M, C0 = C + Cb(X0), K0 = K_shaft + K_mesh,mean + Kb(X0)); "
          "f_d = |Im lambda| / 2 pi, zeta = -Re lambda / |lambda|, mesh = strain energy share"
          + (f"; {dm.n_rigid // 2} rigid-body motion(s) left out" if dm.n_rigid else ""))
    print(damped_mode_table(dm, args.modes))
    print(f"\ntooth critical speeds: mesh harmonic k z1 omega / 2 pi (k = 1..{campbell.HARMONICS}"
          f", z1 = {lin.z1}) = f_d of a mode with mesh >= {args.mesh_fraction:g}, "
          f"{low:g} <= omega <= {high:g} rad/s")
    print(critical_speed_table(critical) if critical else "(none)")
    if chart is not None:
        for w, e in data["skipped"]:
            print(f"campbell: {w:g} rad/s skipped: {e}")
        print(f"\ncampbell: {chart['path']} ({len(chart['speeds_rad_s'])} speeds)")
    return 0


def reproduce(args) -> int:
    from orchestrator.studies.reproduce import draw
    from orchestrator.studies.reproduce import reproduce as run_all

    if args.redraw:
        report = draw(args.out)
    else:
        report = run_all(args.out, quick=args.quick, scheduler=args.scheduler,
                         workers=args.workers, progress=not args.quiet)
    print(f"report: {report}")
    return 0
