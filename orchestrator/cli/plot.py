"""``gsb plot FILE``: the figures of a results file, a run's
(:func:`orchestrator.figures.run.run_figures`) or a sweep's
(:func:`orchestrator.figures.sweep.sweep_figures`), also of an incomplete file or one still
being written."""

from __future__ import annotations

from pathlib import Path

from fmu_src.case import CaseError

__all__ = ["add_parser", "file_kind", "plot"]

#: channels that make a file without a ``kind`` attribute a run's results
_RUN_CHANNELS = {"time", "journal_position", "bearing_force"}


def add_parser(sub) -> None:
    p = sub.add_parser("plot", help="draw the figures of a run or sweep results file",
                       description="Draw the PNG figures of a results file of `gsb run` "
                                   "(orbits, bearing forces, spectra, mesh) or `gsb sweep`, "
                                   "also of an incomplete one or one still being written; "
                                   "prints the path of each figure.")
    p.add_argument("file", type=Path, help="results file (.h5)")
    p.add_argument("--out", type=Path, default=None,
                   help="folder of the figures (default: the folder beside the file named "
                        "after it)")
    p.add_argument("--window", default=None,
                   help="a run's file: the window of the figures instead of the stored case's "
                        "simulation.window ('26 periods', '0.05 s', '2 revolutions of "
                        "<shaft>')")
    p.set_defaults(func=plot)


def file_kind(path) -> str:
    """"run" or "sweep" for a results file; CaseError (one line naming the file) if it is
    missing, not HDF5 or neither."""
    import h5py

    from orchestrator.run.results import open_results

    path = Path(path)
    if not path.exists():
        raise CaseError(f"{path}: no such file")
    if path.is_dir():
        raise CaseError(f"{path}: is a folder, not a results file")
    try:
        if not h5py.is_hdf5(path):
            raise CaseError(f"{path}: not an HDF5 results file")
        with open_results(path) as f:
            kind = f.attrs.get("kind", "")
            kind = kind.decode() if isinstance(kind, bytes) else str(kind)
            names = set(f.keys())
    except OSError as exc:
        raise CaseError(f"{path}: cannot read it: {exc}".replace("\n", " ")) from None
    if kind in ("run", "sweep"):
        return kind
    if not kind and _RUN_CHANNELS <= names:
        return "run"
    raise CaseError(f"{path}: neither a run nor a sweep results file "
                    f"(kind = {kind!r}, datasets: {', '.join(sorted(names)) or 'none'})")


def plot(args) -> int:
    path = Path(args.file)
    kind = file_kind(path)
    try:
        if kind == "run":
            from orchestrator.figures.run import run_figures

            written = run_figures(path, args.out, window=args.window)
        else:
            if args.window is not None:
                raise CaseError(f"{path}: --window applies to a run's results file; a "
                                f"sweep's points are reduced over their window as they run: "
                                f"gsb sweep --window")
            from orchestrator.figures.sweep import sweep_figures

            written = sweep_figures(path, args.out)
    except (KeyError, ValueError, OSError) as exc:
        if isinstance(exc, CaseError):
            raise
        what = f"missing {exc}" if isinstance(exc, KeyError) else str(exc)
        raise CaseError(f"{path}: cannot draw the {kind} figures: {what}"
                        .replace("\n", " ")) from None
    for figure in written:
        print(figure)
    return 0
