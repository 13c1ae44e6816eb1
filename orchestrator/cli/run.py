"""``gsb run``, ``gsb cases`` and ``gsb export``: a case's run, the shipped cases, a results
file as CSV."""

from __future__ import annotations

import math
from pathlib import Path

from bearing_fmu import MODELS
from fmu_src.case import CaseError
from orchestrator.cli.options import add_override_options, case_from_args, overrides_from_args

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="static solution and transient of a case (FMUs by default)",
                       description="Static solution X0 and the coupled transient of a case; "
                                   "writes <out>/<case>_<model>_<hash>.h5 (the hash of the "
                                   "effective parameters: runs with other overrides keep their "
                                   "own files) and PNG figures in the folder beside it. The "
                                   "same run again answers from its complete file at once "
                                   "(--overwrite computes it again). The "
                                   "file is readable while the run writes it (HDF5 SWMR) and "
                                   "flushed every second. Ctrl-C or SIGTERM stops the run after "
                                   "the current step (exit 130 / 143), the steps computed kept; "
                                   "--resume continues it.")
    p.add_argument("case", nargs="?", default=None,
                   help="case file (TOML), the name of a shipped case (e.g. baguet2010_spur; "
                        "`gsb cases` lists them), or an SSP archive of `gsb export-ssp` (its FMUs "
                        "and values are run)")
    add_override_options(p)
    p.add_argument("--bearing", choices=tuple(MODELS), help="bearing model of every bearing "
                                                            "(overrides bearings.*.model; "
                                                            "swaps the bearing FMU)")
    p.add_argument("--periods", type=int, help="mesh periods to simulate (overrides the case; "
                                               "with --resume: the new total length)")
    p.add_argument("--window", help="the last part of the run that the report and the "
                                    "figures are taken over (overrides simulation.window): "
                                    "'26 periods' (of the fastest mesh), '0.05 s' or '2 "
                                    "revolutions of <shaft>'; default: the last revolution "
                                    "of the slowest shaft")
    p.add_argument("--in-process", action="store_true",
                   help="run the Python slaves directly, without the FMI layer")
    p.add_argument("--threads", type=int, default=1,
                   help="in-process: threads that share the hybrid bearings (default 1; "
                        "2 made the paper's case 1.1-1.3 x faster with a core to spare, which "
                        "the second thread keeps busy; the same numbers, bit for bit)")
    p.add_argument("--out", default="results", help="output folder (default results/)")
    p.add_argument("--overwrite", action="store_true",
                   help="compute the run again and replace its existing results file (a "
                        "complete one only once the new run is complete); without it a "
                        "complete file of the same inputs is read, not computed")
    p.add_argument("--resume", metavar="FILE", default=None,
                   help="continue the run of this results file from its last checkpoint (its "
                        "stored case, transport and model; --periods extends it)")
    p.add_argument("--fmu-dir", default=None, help="folder of built FMUs (default: the per-user "
                                                   "cache; built there if missing)")
    p.add_argument("--bearing-fmu", default=None, metavar="FMU",
                   help="a bearing FMU of your own for every bearing (inputs s, t, s_dot, "
                        "t_dot; outputs F_s, F_t; docs/fmu-variables.md)")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true",
                   help="no progress display, no start-up messages (first-run builds)")
    p.set_defaults(func=run)

    p = sub.add_parser("cases", help="list the cases shipped with the package",
                       description="The case files installed with the package; `gsb run NAME` "
                                   "runs one from any folder, `--show NAME` prints its file.")
    p.add_argument("--show", metavar="NAME", default=None, help="print this case's file")
    p.set_defaults(func=cases)

    p = sub.add_parser("case", help="write a case file in the current schema",
                       description="Read a case file (a single-stage file of an earlier "
                                   "version included: it is translated) and print it in the "
                                   "current schema, numbers in SI units, every field given "
                                   "(comments are not carried over); docs/case-files.md.")
    p.add_argument("--upgrade", metavar="FILE", required=True,
                   help="the case file (or the name of a shipped case)")
    p.add_argument("--out", metavar="PATH", default=None,
                   help="write it there (default: stdout); an existing file is kept")
    p.set_defaults(func=upgrade_case)

    p = sub.add_parser("export", help="write a results file's channels as CSV",
                       description="One row per time step, one column per channel component, "
                                   "named by its dimensions and unit, the bearings, meshes and "
                                   "gears by the case's names and axes s, t, as in the prints "
                                   "and figures (e.g. `journal_position[bearing=1][axis=t] "
                                   "[m]`, `gear_node[gear=pinion][axis=s] [m]`, "
                                   "`mesh_force[mesh=mesh] [N]`), 17 significant digits. An "
                                   "existing CSV is kept unless --overwrite.")
    p.add_argument("file", help="results file (.h5) of gsb run")
    p.add_argument("--csv", metavar="OUT", nargs="?", const="", default="",
                   help="CSV file to write (default: the results file with .csv)")
    p.add_argument("--channel", dest="channels", action="append", default=[],
                   help="export only this channel (repeatable; default all)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing CSV file")
    p.set_defaults(func=export)



def upgrade_case(args) -> int:
    import warnings

    from fmu_src.case import LegacyCaseWarning, load_case

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LegacyCaseWarning)  # what this command is for
        case = load_case(args.upgrade)
    text = case.to_toml()
    if args.out is None:
        print(text, end="")
        return 0
    out = Path(args.out)
    if out.exists():
        raise CaseError(f"--out {out}: exists; choose another path")
    out.write_text(text)
    print(f"wrote {out}")
    return 0


def cases(args) -> int:
    from fmu_src import description
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
        helix = sorted({round(math.degrees(c[f"gears.{g}.helix_angle"]), 6)
                        for g in c.names("gears")})
        model = description.shared_bearing_model(c) or "mixed"
        meshes = len(c.names("meshes"))
        print(f"{name:<24} {c['drive.speed']:g} rad/s, T = {c['drive.torque']:g} N m, "
              f"{len(c.names('shafts'))} shafts, {meshes} mesh{'es' * (meshes != 1)} (helix "
              f"{', '.join(f'{b:g}' for b in helix)} deg), {len(c.names('bearings'))} "
              f"{model} bearings, {c['simulation.mesh_periods']} mesh periods ({path})")
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
        written = export_csv(path, out, args.channels or None, overwrite=args.overwrite)
    except FileExistsError:
        raise CaseError(f"--csv {out}: exists; --overwrite replaces it (or give another "
                        "--csv file)") from None
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
                            f"{', '.join(ignored)} (only --periods, --fmu-dir, --threads, "
                            f"--no-figures and --quiet apply)")
        summary = resume_run(args.resume, periods=args.periods, fmu_dir=args.fmu_dir,
                             progress=not args.quiet, threads=args.threads)
        _print_summary(summary, _figures(summary, args))
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
        case = system.case.with_overrides(overrides_from_args(args))
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
        fmus = {"gear": gear, "bearings": [path] * len(case.names("bearings"))}
    try:
        summary = run_case(case, in_process=args.in_process,
                           out_dir=args.out, fmu_dir=args.fmu_dir, progress=not args.quiet,
                           fmus=fmus, overwrite=args.overwrite, threads=args.threads)
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
    figures = _figures(summary, args, case["simulation.window"])
    print(f"static solution X0 ({case['case.name']}):")
    print(static_report(case, summary.static_positions))
    _print_summary(summary, figures)
    return 0


def _figures(summary, args, window: str | None = None) -> list[Path]:
    """The figures of a finished run, in the folder beside its results file
    (:func:`orchestrator.figures.run.run_figures`, over ``window``: the case's
    ``simulation.window``, None for the stored one); none with ``--no-figures``."""
    if args.no_figures:
        return []
    from orchestrator.figures.run import RUN_FIGURES, run_figures
    from orchestrator.run.results import read_attributes

    kind = None if summary.report is None else summary.report["window_kind"]
    if summary.stored:  # drawn from the same file before, unless missing or of another window
        drawn = [summary.results.with_suffix("") / name for name in RUN_FIGURES]
        stored = str(read_attributes(summary.results).get("report_window_kind", ""))
        if kind == stored and all(
                p.is_file() and p.stat().st_mtime >= summary.results.stat().st_mtime
                for p in drawn):
            return drawn
    return run_figures(summary.results, window=window)


def _print_summary(summary, figures: list[Path]) -> None:
    """What ``gsb run`` prints of a finished (or resumed) run: its figures, the report, the
    checks' notes (a deliberate time step and what it costs) and the files it wrote."""
    print(summary.describe())
    for text in summary.notes:
        print(f"note: {text}")
    print(summary.report_text())
    print(f"results: {summary.results}")
    for path in figures:
        print(f"figure: {path}")
