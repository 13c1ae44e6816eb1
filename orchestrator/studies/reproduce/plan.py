"""What ``gsb reproduce`` runs: the plan (full or quick) and the runs and sweeps it makes.

Every run is an in-process run of a shipped case (by name: any working directory); the sweeps
go to Dask (:mod:`orchestrator.sweeps.runner`). Results are kept under the output folder (``runs/``,
``sweeps/``) before anything is drawn (:mod:`orchestrator.studies.reproduce.figures`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from fmu_src.case import load_case
from fmu_src.description import time_step
from fmu_src.examples import HELICAL, SPUR, helix_overrides
from orchestrator.coupling.system import build_master
from orchestrator.run.runner import run_case
from orchestrator.sweeps.runner import SweepPoint, run_sweep

__all__ = ["FULL", "QUICK", "Plan", "run_base_cases", "run_parameter_sweeps", "run_table4",
           "window_text"]


@dataclass(frozen=True)
class Plan:
    """What a reproduction runs."""

    periods: int  # mesh periods of every run (paper: 2048)
    speeds: tuple  # rad/s, Figs. 8, 10, 11, 16
    torques: tuple  # N m, Fig. 9
    unbalances: tuple  # m, Fig. 10 (0.6 mm is the base case)
    helix_angles: tuple  # deg, Figs. 11, 14
    table4_periods: int  # transient length timed for Table 4 (FD projected from fd_periods)
    fd_periods: int
    #: the window of every figure (``simulation.window``; "": the default rule, the last
    #: revolution of the slowest shaft: the paper's last gear revolution, 157 mesh periods)
    window: str = ""
    label: str = "full"


#: The full reproduction (the paper's run length and parameter grids).
#:
#: :meta hide-value:
FULL = Plan(periods=2048, speeds=tuple(float(w) for w in range(100, 1201, 100)),
            torques=(50.0, 100.0, 220.0, 400.0, 600.0), unbalances=(0.6e-3, 1.2e-3, 2.4e-3),
            helix_angles=(0.0, 5.0, 10.0, 12.5), table4_periods=2048, fd_periods=16)
#: ``--quick``: fewer periods, speeds and parameter values; not steady state.
#:
#: :meta hide-value:
QUICK = Plan(periods=192, speeds=(100.0, 325.0, 600.0, 900.0, 1200.0),
             torques=(100.0, 220.0, 400.0), unbalances=(0.6e-3, 2.4e-3),
             helix_angles=(0.0, 12.5), table4_periods=64, fd_periods=2,
             label="quick")


def window_text(plan: Plan) -> str:
    """The plan's window as the spur case names it, with its length in mesh periods (the
    report's and the figures')."""
    from fmu_src.description import mesh_period
    from orchestrator.analysis.metrics import window_duration

    case = load_case(SPUR, {"simulation.window": plan.window} if plan.window else None)
    duration, name = window_duration(case)
    return f"{name}, {duration / mesh_period(case):.4g} mesh periods"


def run_base_cases(plan: Plan, out: Path, progress: bool) -> dict:
    """The base runs; returns their results file names (in ``out/runs``) by key."""
    runs = {}
    for key, path, model in (("spur_hybrid", SPUR, "hybrid"), ("spur_linear", SPUR, "linear"),
                             ("helical_hybrid", HELICAL, "hybrid"),
                             ("helical_linear", HELICAL, "linear"),
                             ("helical_lumped", HELICAL, "lumped")):
        case = load_case(path, {"bearings.*.model": model,
                                "simulation.mesh_periods": plan.periods})
        s = run_case(case, in_process=True,
                     out_dir=out / "runs", progress=progress,
                     overwrite=True)  # a reproduction regenerates its runs
        runs[key] = s.results.name
    return runs


def run_table4(plan: Plan, out: Path, progress: bool) -> list[dict]:
    """Static eccentricity in bearing 1 per method against FD/multigrid 192 x 32; timing."""
    methods = [("0", "L. - H.M.", "linear", 192), ("1", "N.L. - S.B.T.", "short", 192),
               ("2", "N.L. - H.M.", "hybrid", 192), ("3", "N.L. - H.M.", "hybrid", 384),
               ("4", "N.L. - M.M.", "fd", 192)]
    rows = []
    for case_no, label, model, nodes in methods:
        periods = plan.fd_periods if model == "fd" else plan.table4_periods
        case = load_case(SPUR, {"bearings.*.nodes": nodes, "bearings.*.model": model,
                                "simulation.mesh_periods": periods})
        first = case.names("bearings")[0]
        master = build_master(case, in_process=True)
        master.solve_static()
        ecc = (math.hypot(*master.structure.journal_states()[0, :2])
               / case[f"bearings.{first}.clearance"])
        # one coupled step before the timed run: on a machine (or a numba cache) that has not
        # run this model yet, the timed run would otherwise include the compilation of its
        # coupled step (10 s for the short bearings: a time ratio of 1.9 instead of 0.6)
        master.exit_initialization()
        master.steps(0, time_step(case), 1)
        s = run_case(case, in_process=True,
                     out_dir=out / "runs" / "table4", progress=progress,
                     overwrite=True)
        per_step = s.wall_time / s.steps
        evals_per_step = len(case.names("bearings")) * s.bearing_evaluations / s.steps
        full_steps = 2048 * 32
        rows.append({"case": case_no, "method": label, "model": model,
                     "mesh": "x" if model in ("short",) else (f"{nodes} x 32" if model == "fd"
                                                             else str(nodes)),
                     "eccentricity": ecc, "periods_timed": periods,
                     "time_full_run": per_step * full_steps,
                     "evaluations_full_run": evals_per_step * full_steps,
                     "iterations_per_step": s.iterations_per_step,
                     "projected": periods < 2048})
    ref = rows[-1]["eccentricity"]
    for r in rows:
        r["error"] = (r["eccentricity"] - ref) / ref
    return rows


def run_parameter_sweeps(plan: Plan, out: Path, scheduler, workers, progress) -> dict:
    """All sweep files (``out/sweeps/<name>.h5``), run one after the other on the cluster;
    returns the failed points of each."""
    w = plan.speeds
    window = {"simulation.window": plan.window} if plan.window else {}
    spur, helical = load_case(SPUR, window), load_case(HELICAL, window)  # content to workers
    sweeps = {
        "fig08_speed": (spur, [SweepPoint({"drive.speed": s}, m, f"{m} {s:g}")
                               for m in ("hybrid", "linear") for s in w]),
        "fig09_torque": (spur, [SweepPoint({"drive.torque": T}, "hybrid", f"T {T:g}")
                                for T in plan.torques]),
        "fig10_unbalance": (spur, [
            SweepPoint({"drive.speed": s, "gears.*.unbalance": e}, m,
                       f"{m} e {e * 1e3:g} mm {s:g}")
            for e in plan.unbalances if e != 0.6e-3 for m in ("hybrid", "linear") for s in w]),
        "fig11_helix": (spur, [
            SweepPoint({"drive.speed": s, **helix_overrides(b)}, "hybrid",
                       f"beta {b:g} {s:g}")
            for b in plan.helix_angles if b != 0.0 for s in (*w, 325.0)]),
        "fig16_models": (helical, [SweepPoint({"drive.speed": s}, m, f"{m} {s:g}")
                                   for m in ("lumped", "linear") for s in w]),
    }
    failed = {}
    for name, (case, points) in sweeps.items():
        res = run_sweep(case, points, out / "sweeps" / f"{name}.h5", plan.periods,
                        scheduler=scheduler, n_workers=workers,
                        progress=progress, name=name)
        failed[name] = res.failed
    return failed
