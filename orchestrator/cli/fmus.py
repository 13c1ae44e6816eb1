"""``gsb build-fmus``, ``gsb export-ssp`` and ``gsb export-fmu``: the FMUs of a case, alone,
as an SSP archive, or the whole transmission as one FMU."""

from __future__ import annotations

import shlex
from pathlib import Path

from bearing_fmu import MODELS
from fmu_src.case import CaseError
from orchestrator.cli.options import add_case_argument, case_from_args

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("build-fmus", help="build the FMUs (pythonfmu) into a folder",
                       description="Build every FMU into --dest; the gear-shaft FMU carries "
                                   "the case (its parameters start at the case's values).")
    add_case_argument(p, "case the gear-shaft FMU carries (file or shipped name; default "
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
    add_case_argument(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model of every bearing "
                                                            "(overrides bearings.*.model)")
    p.add_argument("--dest", default=".", help="output folder (default: the current folder)")
    p.set_defaults(func=export_ssp)

    p = sub.add_parser("export-fmu", help="write a case's transmission as one FMU",
                       description="Write DEST/<case>.fmu: an FMI 2.0 co-simulation FMU of "
                                   "the whole transmission (structure, four bearings and the "
                                   "iterative master inside doStep), which gives `gsb run`'s "
                                   "answer in any FMI tool, iterating or not. Parameters: the "
                                   "case's fields; input: torque [N m].")
    add_case_argument(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model of every bearing "
                                                            "(overrides bearings.*.model)")
    p.add_argument("--bearing-fmu", default=None, metavar="FMU",
                   help="a bearing FMU of your own for the four bearings, carried inside")
    p.add_argument("--dest", default=".", help="output folder (default: the current folder)")
    p.set_defaults(func=export_fmu)

def build_fmus(args) -> int:
    from fmu_src.build.fmus import build_fmus as build

    for path in build(args.dest, args.names or None, case=case_from_args(args)):
        print(path)
    return 0


def export_ssp(args) -> int:
    from fmu_src.build.ssp import write_ssp
    from fmu_src.description import time_step
    from orchestrator.coupling.system import build_master

    case = case_from_args(args)
    master = build_master(case, in_process=True)  # X0: start values for non-iterative masters
    try:
        master.solve_static()
    finally:
        master.close()
    path = write_ssp(case, args.dest, laws=master.laws)
    dt = time_step(case)
    print(f"{path} (run: gsb run {path}; ecos simulate --path {path} --parameterSet case "
          f"--stepSize {dt!r} --stopTime <s>; OMSimulator 3.0, which takes the step from its "
          f"API only: SSP('{path}').instantiate(), then .setFixedStepSize({dt!r}))")
    return 0


def export_fmu(args) -> int:
    from fmu_src.build.fmus import build_transmission_fmu
    from fmu_src.description import time_step

    case = case_from_args(args)
    if args.bearing_fmu is not None and not Path(args.bearing_fmu).is_file():
        raise CaseError(f"--bearing-fmu {args.bearing_fmu}: no such file")
    path = build_transmission_fmu(case, args.dest, args.bearing_fmu)
    dt = time_step(case)
    # fmpy steps at its output interval; 1,024 steps (32 mesh periods at the paper's step)
    print(f"{path} (step {dt!r} s or a multiple of it; e.g. python -m fmpy simulate "
          f"{shlex.quote(str(path))} --output-interval {dt!r} --stop-time {1024 * dt:.3g})")
    return 0
