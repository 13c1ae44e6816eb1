"""``gsb sweep``: a parametric sweep of a case on Dask, from the command line.

The points are the Cartesian product of the ``--vary`` values and the ``--bearing`` models; each
point's case is built and checked here before anything is submitted (a bad value stops the
command with exit 2, naming the option, the value and the limit). The workers get the case's
content, never a path (:mod:`orchestrator.sweeps.runner`). The sweep file is
``OUT/<case>_sweep_<hash>.h5``, the hash of the effective case, the varied values, the bearing
models and the periods; its figures go to ``OUT/<file stem>/``
(:func:`orchestrator.figures.sweep.sweep_figures`).

Exit codes: 0 every point succeeded, 1 some failed (or no worker for ``--worker-timeout``
seconds), 2 bad input, 130 Ctrl-C (the finished points kept, the file marked incomplete).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
import sys
from pathlib import Path

import numpy as np

from bearing_fmu import MODELS
from fmu_src.case import CaseError, field_of
from fmu_src.units import DIMENSIONS, UnitError, parse_quantity

__all__ = ["MAX_POINTS", "SHORTHANDS", "add_parser", "parse_vary", "sweep"]

#: ``--vary`` shorthands (``*``: every gear)
SHORTHANDS = {"speed": "drive.speed", "torque": "drive.torque",
              "unbalance": "gears.*.unbalance"}
#: the most points a sweep may have
MAX_POINTS = 10000
#: failed points listed at the end (the file has them all)
LISTED = 20

_SPEC = re.compile(r"^\s*(\S+)\s*(.*?)\s*$")


def add_parser(sub) -> None:
    from orchestrator.cli.options import parse_override

    p = sub.add_parser(
        "sweep", help="a parametric sweep of a case on Dask (speed, torque, any field)",
        description="Runs a case over the Cartesian product of the --vary values and the "
                    "--bearing models, in parallel on Dask (a LocalCluster, or a running "
                    "scheduler), and gathers every point into one HDF5 file "
                    "OUT/<case>_sweep_<hash>.h5 (R, bearing-force peak-to-peak, orbits, order "
                    "spectrum of the bearing forces) with figures in OUT/<file stem>/. Exit "
                    "0: every point succeeded; 1: some failed (listed, recorded in the file); "
                    "2: bad input; 130: Ctrl-C (finished points kept).")
    p.add_argument("case", help="case file (TOML) or the name of a shipped case, e.g. "
                                "baguet2010_spur")
    p.add_argument("--vary", action="append", default=[], required=True, metavar="KEY=SPEC",
                   help="a varied field (repeatable: Cartesian product). KEY: speed, torque, "
                        "unbalance (drive.speed, drive.torque, gears.*.unbalance: every gear) "
                        "or any numeric case field, section.key or section.name.key (* for "
                        "every instance). SPEC: START:STOP:COUNT (COUNT "
                        "evenly spaced values, ends included) or a comma list A,B,C; numbers "
                        "in the field's SI unit (speed rad/s, torque N m, unbalance m), or "
                        "followed by a unit the case files accept: 'speed=1000:12000:12 rpm', "
                        "'unbalance=0.6,1.2 mm'")
    p.add_argument("--set", dest="overrides", action="append", type=parse_override, default=[],
                   metavar="SECTION.[NAME.]KEY=VALUE",
                   help="override a case field for every point (repeatable)")
    p.add_argument("--bearing", default=None, metavar="MODEL[,MODEL...]",
                   help="bearing model(s) of every bearing, comma-separated: every point "
                        f"runs with each ({', '.join(MODELS)}; default: the case's own)")
    p.add_argument("--periods", type=int, default=None,
                   help="mesh periods of every run (default: the case's "
                        "simulation.mesh_periods)")
    p.add_argument("--window", default=None, metavar="TEXT",
                   help="the steady window every point's figures are taken over: '26 "
                        "periods' (mesh periods of the fastest mesh), '0.05 s' or '2 "
                        "revolutions of SHAFT' (default: the case's simulation.window, by "
                        "default the last revolution of the slowest shaft, 157 mesh periods "
                        "for the paper's gear, or the last half of the run if shorter)")
    p.add_argument("--steady-periods", type=int, default=None, metavar="N",
                   help="the same as --window 'N periods' (kept for earlier scripts)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="address of a running Dask scheduler (tcp://host:8786); 'none' runs "
                        "the points one after the other in this process (default: a "
                        "LocalCluster of --workers processes)")
    p.add_argument("--workers", type=int, default=None,
                   help="LocalCluster worker processes, one thread each (default 2)")
    p.add_argument("--worker-timeout", type=float, default=60.0, metavar="SECONDS",
                   help="stop when no worker is connected to the scheduler for this long; "
                        "the unfinished points are recorded as failed (default 60; also the "
                        "time allowed to connect to --scheduler)")
    p.add_argument("--out", default="results", help="output folder (default results/)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the sweep file if the same sweep was run before")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=sweep)


def _number(text: str, option: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise CaseError(f"{option}: {text!r} is not a number") from None
    if not math.isfinite(x):
        raise CaseError(f"{option}: {text!r} is not finite")
    return x


def parse_vary(text: str) -> tuple[str, list]:
    """``KEY=SPEC`` of ``--vary`` -> (case field, values in SI units; ints for counts).
    Raises :class:`~fmu_src.fields.CaseError` naming the option, the value and the limit."""
    option = f"--vary {text}"
    if "=" not in text:
        raise CaseError(f"{option}: expected KEY=SPEC (e.g. speed=100:1200:12)")
    key, spec = (part.strip() for part in text.split("=", 1))
    full = SHORTHANDS.get(key, key)
    try:
        field = field_of(full)
    except CaseError as exc:
        raise CaseError(f"{option}: unknown key {key!r} ({exc}); use "
                        f"{', '.join(SHORTHANDS)} or a case field (docs/case-files.md)") from None
    if field.kind not in DIMENSIONS and field.kind != "count":
        raise CaseError(f"{option}: {full} is a {field.kind} field; --vary takes numeric "
                        "fields (set this one with --set)")
    m = _SPEC.match(spec)
    if not m:
        raise CaseError(f"{option}: empty SPEC; expected START:STOP:COUNT or A,B,C")
    body, unit = m.groups()
    parts = body.split(":")
    if len(parts) == 3:
        start, stop = (_number(x, option) for x in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise CaseError(f"{option}: COUNT {parts[2]!r} is not an integer") from None
        if count < 1:
            raise CaseError(f"{option}: COUNT {count} must be >= 1")
        if count > MAX_POINTS:
            raise CaseError(f"{option}: COUNT {count} must be <= {MAX_POINTS}")
        if count == 1 and start != stop:
            raise CaseError(f"{option}: COUNT 1 needs START = STOP (got {start:g}, {stop:g})")
        values = np.linspace(start, stop, count).tolist()
    elif len(parts) == 1:
        items = [x.strip() for x in body.split(",")]
        if not all(items):
            raise CaseError(f"{option}: an empty value in the list {body!r}")
        values = [_number(x, option) for x in items]
        if len(values) > MAX_POINTS:
            raise CaseError(f"{option}: {len(values)} values, must be <= {MAX_POINTS}")
    else:
        raise CaseError(f"{option}: expected START:STOP:COUNT or A,B,C, got {body!r}")
    if field.kind == "count":
        if unit:
            raise CaseError(f"{option}: {full} is a count, it takes no unit ({unit!r})")
        if any(not float(v).is_integer() for v in values):
            raise CaseError(f"{option}: {full} is a count, the values "
                            f"{', '.join(f'{v:g}' for v in values)} must be integers")
        values = [int(v) for v in values]
    elif unit:
        try:
            values = [parse_quantity(f"{v!r} {unit}", field.kind, full) for v in values]
        except UnitError as exc:
            raise CaseError(f"{option}: {exc}") from None
    if len(set(values)) != len(values):
        raise CaseError(f"{option}: repeated values")
    return full, values


def _bearings(text: str | None, case) -> list[str | None]:
    """The models of ``--bearing``, or the case's own (None) when not given."""
    if text is None:
        return [None]
    names = [x.strip() for x in text.split(",")]
    for name in names:
        if name not in MODELS:
            raise CaseError(f"--bearing {text}: unknown bearing model {name!r}; known: "
                            f"{', '.join(MODELS)}")
    if len(set(names)) != len(names):
        raise CaseError(f"--bearing {text}: a model is repeated")
    return names


def _fmt(key: str, value) -> str:
    from orchestrator.sweeps.file import field_unit

    unit = field_unit(key)
    return f"{key.split('.')[-1]} {value:g}{' ' + unit if unit not in ('', '1') else ''}"


def sweep_hash(case, vary: list, bearings: list, periods: int) -> str:
    """8 hex digits of the effective case (its window too), the varied values, the bearing
    models and the periods (the sweep file's name)."""
    blob = json.dumps({"case": case.to_toml(header=False), "vary": [[k, list(v)] for k, v in vary],
                       "bearings": bearings, "periods": periods})
    return hashlib.sha256(blob.encode()).hexdigest()[:8]


def _plan(args):
    """The checked inputs: (case, vary [(key, values)], bearings, points, periods); the
    case carries the window (``--window``)."""
    from fmu_src import description
    from fmu_src.case import load_case
    from orchestrator.cli.options import set_overrides
    from orchestrator.run.spec import check_periods
    from orchestrator.sweeps.runner import SweepPoint, check_point, sweep_window

    window = _window(args)
    overrides = set_overrides(args.overrides)
    if window is not None:
        overrides["simulation.window"] = window
    case = load_case(args.case, overrides)
    vary = []
    for text in args.vary:
        key, values = parse_vary(text)
        if any(k == key for k, _ in vary):
            raise CaseError(f"--vary {text}: {key} is varied twice")
        for v in values:  # each value on its own: the message names the option
            try:
                case.with_overrides({key: v})
            except CaseError as exc:
                raise CaseError(f"--vary {text}: {exc}") from None
        vary.append((key, values))
    bearings = _bearings(args.bearing, case)
    n = len(bearings)
    for _, values in vary:
        n *= len(values)
    if n > MAX_POINTS:
        raise CaseError(f"--vary {' --vary '.join(args.vary)}: {n} points, must be <= "
                        f"{MAX_POINTS}")
    periods = check_periods(case["simulation.mesh_periods"] if args.periods is None
                            else args.periods)
    keys = [k for k, _ in vary]
    points = []
    for bearing in bearings:
        for combo in itertools.product(*(values for _, values in vary)):
            overrides = dict(zip(keys, combo, strict=True))
            own = description.shared_bearing_model(case) or "mixed"
            label = ", ".join([bearing or own] + [_fmt(k, v) for k, v in overrides.items()])
            p = SweepPoint(overrides, bearing, label)
            try:
                check_point(case, p)
            except CaseError as exc:
                raise CaseError(f"point {len(points)} ({label}): {exc}") from None
            points.append(p)
    try:
        sweep_window(case, points, periods)
    except CaseError as exc:
        given = f"--window {window!r}" if window is not None else "the case's window"
        raise CaseError(f"{given} for --periods {periods}: {exc}") from None
    return case, vary, bearings, points, periods


def _window(args) -> str | None:
    """``--window``, or ``--steady-periods N`` as 'N periods' (None: the case's own)."""
    if args.steady_periods is None:
        return args.window
    if args.window is not None:
        raise CaseError(f"--steady-periods {args.steady_periods}: the same as --window; give "
                        f"one of them, not both (--window {args.window!r})")
    if args.steady_periods < 1:
        raise CaseError(f"--steady-periods {args.steady_periods}: must be >= 1")
    return f"{args.steady_periods} periods"


def _checks(args) -> None:
    t = args.worker_timeout
    if not (math.isfinite(t) and t > 0):
        raise CaseError(f"--worker-timeout {t:g}: must be finite and > 0 s")
    if args.workers is not None:
        if args.scheduler is not None:
            raise CaseError(f"--workers {args.workers}: a LocalCluster option, not with "
                            f"--scheduler {args.scheduler}")
        if args.workers < 1:
            raise CaseError(f"--workers {args.workers}: must be >= 1")


def sweep(args) -> int:
    from orchestrator.sweeps.runner import run_sweep, stopped_on_physics

    _checks(args)
    case, vary, bearings, points, periods = _plan(args)
    digest = sweep_hash(case, vary, bearings, periods)
    path = Path(args.out) / f"{case.name}_sweep_{digest}.h5"
    if path.exists() and not args.overwrite:
        raise CaseError(f"{path} exists (the same sweep was run before); --overwrite replaces "
                        "it")
    res = run_sweep(case, points, path, periods, scheduler=args.scheduler,
                    n_workers=args.workers or 2, progress=not args.quiet, name=path.stem,
                    vary_keys=[k for k, _ in vary], worker_timeout=args.worker_timeout)
    ok = res.n_points - len(res.failed)
    physics = sum(stopped_on_physics(error) for _, error in res.failed)
    print(f"sweep: {res.path}")
    print(f"{res.n_points} points ({len(bearings)} bearing model{'s' * (len(bearings) > 1)} x "
          f"{' x '.join(str(len(v)) for _, v in vary)}), {ok} succeeded, "
          f"{len(res.failed) - physics} failed"
          + (f", {physics} stopped on physics (a journal touched its bearing)" if physics
             else "") + f", {res.wall_time:.1f} s")
    for i, error in res.failed[:LISTED]:
        print(f"failed: points/{i:04d} ({points[i].label}): {error.splitlines()[0]}")
    if len(res.failed) > LISTED:
        print(f"failed: {len(res.failed) - LISTED} more (attribute 'error' of their groups)")
    if res.warnings:
        first = next(iter(res.warnings.values())).splitlines()[0]
        print(f"warnings: {len(res.warnings)} point{'s' * (len(res.warnings) > 1)} warned "
              f"(attribute 'warnings' of their groups), e.g. {first}")
    if not args.no_figures and ok:
        from orchestrator.figures.sweep import sweep_figures

        try:
            figures = sweep_figures(res.path)
        except Exception as exc:  # the sweep is kept; say why there is no figure
            print(f"gsb sweep: warning: figures not drawn: {type(exc).__name__}: {exc}",
                  file=sys.stderr)
            figures = []
        for fig in figures:
            print(f"figure: {fig}")
    if res.message:
        option = (f" (--worker-timeout {args.worker_timeout:g})"
                  if res.status == "worker timeout" else "")
        print(f"gsb sweep: {res.message}{option}: stopped; {ok} of {res.n_points} points "
              f"succeeded, {len(res.failed)} recorded as failed in {res.path}", file=sys.stderr)
        return 1
    if res.failed:
        print(f"gsb sweep: {len(res.failed)} of {res.n_points} points failed; recorded in "
              f"{res.path} (attribute 'error' of their groups points/<index>)", file=sys.stderr)
        return 1
    return 0
