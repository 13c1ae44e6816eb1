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
    p.add_argument("--speed", help="override operation.speed (e.g. '500 rad/s', '3000 rpm')")
    p.add_argument("--torque", help="override operation.torque (e.g. '300 N.m')")
    p.add_argument("--unbalance", help="override operation.unbalance of both shafts (e.g. "
                                       "'1.2 mm')")
    p.add_argument("--set", dest="overrides", action="append", type=_override, default=[],
                   metavar="SECTION.KEY=VALUE", help="override any case field (repeatable)")


def add_parsers(sub) -> None:
    p = sub.add_parser("run", help="static solution and transient of a case (FMUs by default)",
                       description="Static solution X0 and the coupled transient of a case; "
                                   "writes results/<case>_<model>.h5 and PNG figures. Ctrl-C "
                                   "or SIGTERM stops it after the current step (exit 130 / "
                                   "143), the steps computed kept.")
    _common(p, "case file (TOML), the name of a shipped case (e.g. baguet2010_spur), or an SSP "
               "archive of `gsb export-ssp` (its FMUs and values are run)")
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model (overrides the "
                                                            "case; swaps the bearing FMU)")
    p.add_argument("--periods", type=int, help="mesh periods to simulate (overrides the case)")
    p.add_argument("--in-process", action="store_true",
                   help="run the Python slaves directly, without the FMI layer")
    p.add_argument("--out", default="results", help="output folder (default results/)")
    p.add_argument("--fmu-dir", default=None, help="folder of built FMUs (default: the per-user "
                                                   "cache; built there if missing)")
    p.add_argument("--bearing-fmu", default=None, metavar="FMU",
                   help="a bearing FMU of your own for all four bearings (inputs s, t, s_dot, "
                        "t_dot; outputs F_s, F_t; docs/fmu-variables.md)")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=run)

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

    p = sub.add_parser("modal", help="natural frequencies and mode types of a case",
                       description="Natural modes of the gear-shaft system with the mean mesh "
                                   "stiffness at the static load and the bearings' stiffness "
                                   "at the static solution X0 (or a given isotropic one).")
    _common(p)
    p.add_argument("--bearing-stiffness", type=float, default=None,
                   help="isotropic bearing stiffness [N/m] instead of the static film stiffness")
    p.add_argument("--modes", type=int, default=20, help="number of modes printed (default 20)")
    p.set_defaults(func=modal)


def _overrides(args) -> dict:
    overrides = dict(args.overrides)
    for key, value in (("operation.speed", args.speed), ("operation.torque", args.torque),
                       ("operation.unbalance", args.unbalance),
                       ("bearings.model", getattr(args, "bearing", None))):
        if value is not None:
            overrides[key] = value
    return overrides


def case_from_args(args):
    """The case file with the command line's overrides applied (checked again)."""
    from fmu_src.case import load_case

    return load_case(args.case, _overrides(args))


def build_fmus(args) -> int:
    from fmu_src.build import build_fmus as build

    for path in build(args.dest, args.names or None, case=case_from_args(args)):
        print(path)
    return 0


def export_ssp(args) -> int:
    from fmu_src.description import time_step
    from fmu_src.ssp import write_ssp
    from orchestrator.run import build_master

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


def run(args) -> int:
    import shutil

    from orchestrator.run import run_case, static_report

    fmus, folder = None, None
    if str(args.case).endswith(".ssp"):
        from fmu_src.ssp import read_ssp

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
        from orchestrator.fmi import ensure_fmus

        path = Path(args.bearing_fmu)
        if not path.is_file():
            raise CaseError(f"--bearing-fmu: no such file: {path}")
        gear = fmus["gear"] if fmus else ensure_fmus(["GearShaft"], args.fmu_dir)["GearShaft"]
        fmus = {"gear": gear, "bearings": [path] * 4}
    try:
        summary = run_case(case, periods=args.periods, in_process=args.in_process,
                           out_dir=args.out, fmu_dir=args.fmu_dir, progress=not args.quiet,
                           figures=not args.no_figures, fmus=fmus)
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
    print(f"static solution X0 ({case['case.name']}):")
    print(static_report(case, summary.static_positions))
    print(summary.describe())
    print(f"results: {summary.results}")
    for path in summary.figures:
        print(f"figure: {path}")
    return 0


def modal(args) -> int:
    from gear_fmu.analyses import modes
    from gear_fmu.modal import mode_table
    from orchestrator.run import build_master

    case = case_from_args(args)
    master = build_master(case, in_process=True)
    if args.bearing_stiffness is None:
        master.solve_static()
        kb = master.laws.kb
        kb = 0.5 * (kb + np.transpose(kb, (0, 2, 1)))
        source = "film stiffness at the static solution X0 (symmetric part)"
    else:
        if not (math.isfinite(args.bearing_stiffness) and args.bearing_stiffness > 0):
            raise ValueError(f"--bearing-stiffness {args.bearing_stiffness!r} N/m must be > 0")
        kb = args.bearing_stiffness
        source = f"isotropic {args.bearing_stiffness:g} N/m"
    found = modes(master.structure.structure, kb)
    print(f"{case['case.name']}: modes with the mean mesh stiffness at T = "
          f"{case['operation.torque']:g} N m; bearings: {source}")
    print(mode_table(found, args.modes))
    return 0


def reproduce(args) -> int:
    from orchestrator.reproduce import draw
    from orchestrator.reproduce import reproduce as run_all

    if args.redraw:
        report = draw(args.out)
    else:
        report = run_all(args.out, quick=args.quick, scheduler=args.scheduler,
                         workers=args.workers, progress=not args.quiet)
    print(f"report: {report}")
    return 0
