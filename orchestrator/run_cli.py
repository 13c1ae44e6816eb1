"""``gsb run`` and ``gsb modal``: the case-file commands of the command line."""

from __future__ import annotations

import argparse
import math

import numpy as np

from bearing_fmu import MODELS

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


def _common(p) -> None:
    p.add_argument("case", help="case file (TOML) or the name of a shipped case, e.g. "
                                "baguet2010_spur")
    p.add_argument("--speed", help="override operation.speed (e.g. '500 rad/s', '3000 rpm')")
    p.add_argument("--torque", help="override operation.torque (e.g. '300 N.m')")
    p.add_argument("--unbalance", help="override operation.unbalance of both shafts (e.g. "
                                       "'1.2 mm')")
    p.add_argument("--set", dest="overrides", action="append", type=_override, default=[],
                   metavar="SECTION.KEY=VALUE", help="override any case field (repeatable)")


def add_parsers(sub) -> None:
    p = sub.add_parser("run", help="static solution and transient of a case (FMUs by default)",
                       description="Static solution X0 and the coupled transient of a case; "
                                   "writes results/<case>_<model>.h5 and PNG figures.")
    _common(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model (overrides the "
                                                            "case; swaps the bearing FMU)")
    p.add_argument("--periods", type=int, help="mesh periods to simulate (overrides the case)")
    p.add_argument("--in-process", action="store_true",
                   help="run the Python slaves directly, without the FMI layer")
    p.add_argument("--out", default="results", help="output folder (default results/)")
    p.add_argument("--fmu-dir", default=None, help="folder of built FMUs (default build/fmus; "
                                                   "built if missing)")
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

    p = sub.add_parser("modal", help="natural frequencies and mode types of a case",
                       description="Natural modes of the gear-shaft system with the mean mesh "
                                   "stiffness at the static load and the bearings' stiffness "
                                   "at the static solution X0 (or a given isotropic one).")
    _common(p)
    p.add_argument("--bearing-stiffness", type=float, default=None,
                   help="isotropic bearing stiffness [N/m] instead of the static film stiffness")
    p.add_argument("--modes", type=int, default=20, help="number of modes printed (default 20)")
    p.set_defaults(func=modal)


def case_from_args(args):
    """The case file with the command line's overrides applied (checked again)."""
    from fmu_src.case import load_case

    overrides = dict(args.overrides)
    for key, value in (("operation.speed", args.speed), ("operation.torque", args.torque),
                       ("operation.unbalance", args.unbalance),
                       ("bearings.model", getattr(args, "bearing", None))):
        if value is not None:
            overrides[key] = value
    return load_case(args.case, overrides)


def run(args) -> int:
    from orchestrator.run import run_case, static_report

    case = case_from_args(args)
    summary = run_case(case, periods=args.periods,
                       in_process=args.in_process, out_dir=args.out, fmu_dir=args.fmu_dir,
                       progress=not args.quiet, figures=not args.no_figures)
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
