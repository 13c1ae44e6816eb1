"""``gsb reproduce``: the results of the paper's section 4 regenerated from fresh runs.

Runs (all in-process slaves; the FMU path is checked equal to it by the test suite):

* base runs of the spur and helical cases with the hybrid, linear and lumped bearings
  (Figs. 5-7, 12-15, 17);
* Table 4: static eccentricity in bearing 1 against the finite-difference/multigrid reference
  (192 x 32) for each method, and the wall time of the transient per method;
* sweeps on Dask (:mod:`orchestrator.sweeps.runner`): speed x {hybrid, linear} (Fig. 8), torque
  (Fig. 9), unbalance x speed x {hybrid, linear} (Fig. 10), helix angle x speed (Figs. 11, 14),
  helical speed x {lumped, linear, hybrid} (Fig. 16).

Then every figure is drawn and ``report.md`` puts each next to what the paper states, with our
numbers and checks of the paper's claims (pass/fail, never tuned). ``--quick`` uses fewer periods,
speeds and parameter values so that it ends in minutes; its results are not steady state and
say so.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, fields
from pathlib import Path

from orchestrator.run.results import read_results
from orchestrator.studies.reproduce.figures import draw_all
from orchestrator.studies.reproduce.plan import (
    FULL,
    QUICK,
    Plan,
    run_base_cases,
    run_parameter_sweeps,
    run_table4,
)
from orchestrator.studies.reproduce.report import json_default, write_report
from orchestrator.sweeps.file import read_sweep

__all__ = ["FULL", "QUICK", "Plan", "draw", "reproduce"]


def reproduce(out: str | Path = "results/reproduce", quick: bool = False,
              scheduler: str | None = None, workers: int = 2, progress: bool = True,
              plan: Plan | None = None) -> Path:
    """Run everything (module docstring), then :func:`draw`; returns the report's path.

    ``plan`` replaces :data:`~orchestrator.studies.reproduce.plan.QUICK` /
    :data:`~orchestrator.studies.reproduce.plan.FULL` (e.g. a smaller one for tests). The runs are
    kept in ``out`` (``runs/``, ``sweeps/``, ``reproduce.json``) before anything is drawn.
    """
    if plan is None:
        plan = QUICK if quick else FULL
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    timings = {}
    t = time.perf_counter()
    runs = run_base_cases(plan, out, progress)
    timings["base runs"] = time.perf_counter() - t
    t = time.perf_counter()
    table = run_table4(plan, out, progress)
    timings["Table 4"] = time.perf_counter() - t
    t = time.perf_counter()
    failed = run_parameter_sweeps(plan, out, scheduler, workers, progress)
    timings["sweeps"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    (out / "reproduce.json").write_text(json.dumps(
        {"plan": asdict(plan), "runs": runs, "table4": table, "timings": timings,
         "failed": failed}, indent=1, default=json_default))
    return draw(out)


def draw(out: str | Path = "results/reproduce") -> Path:
    """Figures and ``report.md`` from the runs of :func:`reproduce` kept in ``out``."""
    out = Path(out)
    meta = json.loads((out / "reproduce.json").read_text())
    known = {f.name for f in fields(Plan)}  # an earlier version's plan held steady_periods
    plan = Plan(**{k: tuple(v) if isinstance(v, list) else v for k, v in meta["plan"].items()
                   if k in known})
    runs = {k: read_results(out / "runs" / name) for k, name in meta["runs"].items()}
    sweeps = {p.stem: read_sweep(p) for p in sorted((out / "sweeps").glob("*.h5"))}
    figs = draw_all(runs, sweeps, plan, out / "figures")
    report = write_report(out, plan, meta, figs)
    meta["figures"] = {k: v[1] for k, v in figs.items()}
    (out / "reproduce.json").write_text(json.dumps(meta, indent=1, default=json_default))
    return report
