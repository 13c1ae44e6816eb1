"""Parametric sweeps on Dask: independent runs of one case with overridden fields.

Each point is a full in-process run (:func:`orchestrator.run.run_case`) on a Dask worker, reduced
there to its figures (:func:`orchestrator.analysis.run_metrics`) and its steady-state orbits, so
only small arrays travel back. A LocalCluster of single-threaded worker processes is started
by default; ``scheduler="tcp://host:8786"`` uses any running Dask scheduler instead, and
``scheduler="none"`` runs the points one after the other in this process (the reference for the
parallel efficiency). A point that fails is recorded with its error and the sweep goes on.

The sweep's results are one HDF5 file: a group per point (``points/<index>``) with the overrides
and the model as attributes (or the error), and datasets ``R``, ``force_ptp`` (4,), ``force_mean``
(4,), ``orbit_centre`` (4, 2), ``orbit`` (n, 4, 2) (journal positions over the steady window,
decimated), ``bearing_force`` (n, 4, 2) and ``mesh_force`` (n,) over the steady window.
"""

from __future__ import annotations

import json
import math
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["SweepPoint", "SweepResult", "read_sweep", "run_point", "run_sweep"]


@dataclass(frozen=True)
class SweepPoint:
    """One run of a sweep: case-field overrides (values as in a case file) and a bearing model."""

    overrides: dict
    bearing: str | None = None
    label: str = ""


@dataclass
class SweepResult:
    path: Path
    wall_time: float
    n_points: int
    failed: list = field(default_factory=list)  # (index, message)


def run_point(case_path: str, point: SweepPoint, periods: int, steady_periods: int,
              keep_steps: int = 4096) -> dict:
    """Run one point and reduce it (executed on a worker). Never raises: errors are returned."""
    try:
        from fmu_src.case import load_case
        from orchestrator.analysis import run_metrics, steady_window
        from orchestrator.results import read_results
        from orchestrator.run import run_case

        case = load_case(case_path, point.overrides)
        z1 = case["gear_pair.teeth"][0]
        mesh_period = 2 * math.pi / (case["operation.speed"] * z1)
        steady = min(steady_periods, periods) * mesh_period
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            s = run_case(case, bearing=point.bearing, periods=periods, in_process=True,
                         out_dir=tmp, progress=False, figures=False)
            r = read_results(s.results)
        metrics = run_metrics(r, steady)
        win = steady_window(r["time"], steady)
        stride = max(1, int(np.count_nonzero(win)) // keep_steps)
        out = {k: np.asarray(v) for k, v in metrics.items()}
        out["time"] = r["time"][win][::stride]
        out["orbit"] = r["journal_position"][win][::stride]
        out["bearing_force"] = r["bearing_force"][win][::stride]
        out["mesh_force"] = r["mesh_force"][win][::stride]
        out["static_journal"] = np.asarray(s.static_positions)
        out["wall_time"] = np.asarray(time.perf_counter() - t0)
        out["iterations_per_step"] = np.asarray(s.iterations_per_step)
        return {"ok": True, "data": out}
    except Exception as exc:  # reported, the sweep goes on
        return {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc()}


def _client(scheduler, n_workers):
    from dask.distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster), cluster


def run_sweep(case_path: str | Path, points, path: str | Path, periods: int,
              steady_periods: int = 26, scheduler: str | None = None, n_workers: int = 2,
              progress: bool = True, name: str = "") -> SweepResult:
    """Run the points, gather them into one HDF5 file as they complete (module docstring)."""
    import h5py

    from orchestrator.run import Progress

    points = list(points)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    case_path = str(case_path)
    t0 = time.perf_counter()
    failed = []
    bar = Progress(len(points), f"sweep {name or path.stem}", enabled=progress)
    with h5py.File(path, "w") as f:
        f.attrs["case_file"] = case_path
        f.attrs["periods"] = periods
        f.attrs["steady_periods"] = steady_periods
        f.attrs["complete"] = False
        grp = f.create_group("points")

        def store(i, res):
            g = grp.create_group(f"{i:04d}")
            p = points[i]
            g.attrs["overrides"] = json.dumps(p.overrides)
            g.attrs["bearing"] = p.bearing or ""
            g.attrs["label"] = p.label
            if res["ok"]:
                for key, val in res["data"].items():
                    g.create_dataset(key, data=val)
            else:
                g.attrs["error"] = res["error"]
                g.attrs["traceback"] = res["traceback"]
                failed.append((i, res["error"]))
            f.flush()

        done = 0
        if scheduler == "none":
            for i, p in enumerate(points):
                store(i, run_point(case_path, p, periods, steady_periods))
                done += 1
                bar.update(done, f"{len(failed)} failed")
        else:
            from dask.distributed import as_completed

            client, cluster = _client(scheduler, n_workers)
            try:
                futures = {client.submit(run_point, case_path, p, periods, steady_periods,
                                         pure=False): i for i, p in enumerate(points)}
                for fut in as_completed(futures):
                    i = futures[fut]
                    try:
                        res = fut.result()
                    except Exception as exc:  # the worker died
                        res = {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                               "traceback": traceback.format_exc()}
                    store(i, res)
                    done += 1
                    bar.update(done, f"{len(failed)} failed")
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
        wall = time.perf_counter() - t0
        f.attrs["wall_time"] = wall
        f.attrs["complete"] = True
    return SweepResult(path, wall, len(points), failed)


def read_sweep(path) -> list[dict]:
    """The points of a sweep file: dicts with ``overrides``, ``bearing``, ``label``, ``error``
    and the datasets (absent for failed points), in point order."""
    import h5py

    out = []
    with h5py.File(path, "r") as f:
        for key in sorted(f["points"]):
            g = f["points"][key]
            d = {"overrides": json.loads(g.attrs["overrides"]), "bearing": g.attrs["bearing"],
                 "label": g.attrs["label"], "error": g.attrs.get("error")}
            for name in g:
                d[name] = g[name][()]
            out.append(d)
    return out
