"""``gsb reproduce``: the paper's section 4 regenerated (runs, sweeps, figures, report)."""

from __future__ import annotations

__all__ = ["add_parser"]


def add_parser(sub) -> None:
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
