"""Parametric sweeps on Dask: independent runs of one case with overridden fields.

Each point is a full in-process run (:func:`orchestrator.run.run_case`) on a Dask worker, reduced
there to its figures (:func:`orchestrator.analysis.run_metrics`), its steady-state orbits and
the order spectrum of its bearing forces, so only small arrays travel back. The workers get the
case's *content* (a :class:`~fmu_src.case.Case`, or its TOML text), never a path: a worker need
not share the client's folders. Every point's case is checked in the client first; a point the
case loader rejects is recorded as failed without being submitted.

A LocalCluster of single-threaded worker processes is started by default;
``scheduler="tcp://host:8786"`` uses any running Dask scheduler instead, and
``scheduler="none"`` runs the points one after the other in this process (the reference for the
parallel efficiency). A point that fails is recorded with its error and the sweep goes on. When
no worker is connected to the scheduler for ``worker_timeout`` seconds the sweep stops: the
finished points are kept, the others recorded as failed with that reason. Ctrl-C
(KeyboardInterrupt) does the same and raises :class:`SweepInterrupted`.

The sweep's results are one HDF5 file (:data:`DATASETS` lists every dataset; each carries
``unit`` and ``description`` attributes):

* root attributes: ``kind = "sweep"``, ``case`` (name), ``case_file`` (where the client read
  it), ``case_toml`` (the case's text, SI; the points override it), ``vary_keys`` (strings,
  the case fields varied), ``vary_units`` (their SI units), ``bearings`` (the bearing models,
  strings), ``periods``, ``steady_periods`` (mesh periods of the run and of its steady window),
  ``n_points``, ``n_failed``, ``status`` ("complete", "failed points", "worker timeout",
  "scheduler lost", "interrupted"), ``complete`` (true only when every point succeeded) and
  ``wall_time`` [s];
* a group per point, ``points/<index>``: attributes ``values`` (the varied values in SI units,
  in ``vary_keys`` order; the first entry of a list field), ``bearing``, ``label``,
  ``overrides`` (JSON text, as given), ``error`` and ``traceback`` if it failed, ``warnings``
  (the run's warnings, if any), and the datasets of :data:`DATASETS` if it succeeded.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import io
import json
import math
import sys
import tempfile
import threading
import time
import tomllib
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fmu_src.case import FIELDS, Case, CaseError, load_case, parse_case
from fmu_src.units import DIMENSIONS, symbol
from orchestrator.run import RunError, RunInterrupted

__all__ = ["DATASETS", "SweepInterrupted", "SweepPoint", "SweepResult", "as_case",
           "check_point", "field_unit", "point_spectrum", "read_sweep", "read_sweep_attrs",
           "run_point", "run_sweep"]

_BY_KEY = {f.key: f for f in FIELDS}

#: Datasets of a successful point: name -> (unit, description).
#:
#: :meta hide-value:
DATASETS = {
    "R": (symbol("dimensionless"), "dynamic tooth load factor: max mesh force over the static "
                                   "mesh load, steady window"),
    "force_ptp": (symbol("force"), "peak-to-peak of ||F_b|| at bearings 1-4, steady window"),
    "force_mean": (symbol("force"), "mean of ||F_b|| at bearings 1-4, steady window"),
    "orbit_centre": (symbol("length"), "centre of the ellipse fitted to the orbit [s, t] at "
                                       "bearings 1-4, steady window"),
    "orbit_mean": (symbol("length"), "mean journal position [s, t] at bearings 1-4, steady "
                                     "window"),
    "time": (symbol("time"), "time of the decimated steady-window samples"),
    "orbit": (symbol("length"), "journal position [s, t] at bearings 1-4, steady window, "
                                "decimated"),
    "bearing_force": (symbol("force"), "film force [F_s, F_t] at bearings 1-4, steady window, "
                                       "decimated"),
    "mesh_force": (symbol("force"), "total normal mesh force, steady window, decimated"),
    "static_journal": (symbol("length"), "static journal positions X0 [s, t] at bearings 1-4"),
    "wall_time": (symbol("time"), "wall time of the point on its worker"),
    "iterations_per_step": (symbol("dimensionless"), "coupled iterations per time step"),
    "spectrum_orders": (symbol("dimensionless"), "orders of the spectrum bins (cycles per "
                                                 "pinion revolution), 0 to 3.5 z1"),
    "spectrum": (symbol("force"), "single-sided peak amplitude of ||F_b|| at bearings 1-4 per "
                                  "order (full-resolution steady window, a whole number of "
                                  "pinion revolutions when it holds one)"),
    "spectrum_window": (symbol("time"), "start and end of the spectrum's window"),
}

#: the highest order kept in a point's spectrum, in mesh orders (z1)
MAX_MESH_ORDER = 3.5


class SweepInterrupted(RunInterrupted):
    """A sweep stopped by Ctrl-C; the finished points are in the file (``path``)."""

    def __init__(self, message: str, path: Path):
        import signal

        super().__init__(signal.SIGINT, message)
        self.path = path


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
    status: str = "complete"  # "complete", "failed points", "worker timeout", "scheduler lost"
    message: str = ""  # why the sweep stopped early ("" otherwise)
    warnings: dict = field(default_factory=dict)  # index: the run's warnings (stderr text)

    @property
    def complete(self) -> bool:
        return not self.failed


def field_unit(key: str) -> str:
    """SI unit of a case field (``"1"`` for counts, ``""`` for text, choices and flags)."""
    kind = _BY_KEY[key].kind
    if kind in DIMENSIONS:
        return symbol(kind)
    return "1" if kind == "count" else ""


def as_case(case) -> Case:
    """A :class:`~fmu_src.case.Case`: itself, parsed from TOML text (a string with a line break), or read
    from a file path or shipped name (in the client only: workers get the content)."""
    if isinstance(case, Case):
        return case
    if isinstance(case, str) and "\n" in case:
        try:
            return parse_case(tomllib.loads(case), "<sweep case>")
        except tomllib.TOMLDecodeError as exc:
            raise CaseError(f"sweep case: not valid TOML: {exc}") from None
    return load_case(case)


class _ThreadStderr:
    """``sys.stderr`` that sends the writes of a thread to its own buffer while it captures
    (:func:`_captured_stderr`): safe with several tasks per worker process."""

    def __init__(self, base):
        self.base = base
        self.local = threading.local()

    def _target(self):
        return getattr(self.local, "buffer", None) or self.base

    def write(self, text):
        return self._target().write(text)

    def flush(self):
        return self._target().flush()

    def __getattr__(self, name):
        return getattr(self.base, name)


_STDERR_LOCK = threading.Lock()
_STDERR_USERS = [0]


@contextlib.contextmanager
def _captured_stderr():
    """What this thread writes to ``sys.stderr`` (a run's warnings), kept in a buffer."""
    with _STDERR_LOCK:
        if not isinstance(sys.stderr, _ThreadStderr):
            sys.stderr = _ThreadStderr(sys.stderr)
        proxy = sys.stderr
        _STDERR_USERS[0] += 1
    buffer = io.StringIO()
    proxy.local.buffer = buffer
    try:
        yield buffer
    finally:
        proxy.local.buffer = None
        with _STDERR_LOCK:
            _STDERR_USERS[0] -= 1
            if _STDERR_USERS[0] == 0 and sys.stderr is proxy:
                sys.stderr = proxy.base


def point_spectrum(case: Case, results: dict, steady_periods: int) -> dict:
    """Order spectrum of ||F_b|| (bearings 1-4) of a run, from its full-resolution samples.

    The window is the last whole number of pinion revolutions of the steady window (the last
    ``steady_periods`` mesh periods), or the whole steady window if it is shorter than one
    revolution; so the pinion orders 1, z1, 2 z1, ... fall on bins when it holds a revolution.
    Orders 0 to 3.5 z1 (:func:`orchestrator.analysis.order_spectrum`)."""
    from orchestrator.analysis import order_spectrum

    z1 = int(case["gear_pair.teeth"][0])
    per_mesh = int(case["simulation.steps_per_mesh_period"])
    steady = max(1, int(steady_periods))
    revolutions = steady // z1
    n = (revolutions * z1 if revolutions >= 1 else steady) * per_mesh
    time_s = np.asarray(results["time"], dtype=float)
    n = min(n, time_s.size)
    force = np.asarray(results["bearing_force"][-n:], dtype=float)
    norm = np.hypot(force[..., 0], force[..., 1])
    orders, amp = order_spectrum(norm, z1 * per_mesh, MAX_MESH_ORDER * z1)
    dt = time_s[1] - time_s[0] if time_s.size > 1 else 0.0
    return {"spectrum_orders": orders, "spectrum": amp.T,
            "spectrum_window": np.array([time_s[-n] - dt, time_s[-1]])}


def run_point(case, point: SweepPoint, periods: int, steady_periods: int,
              keep_steps: int = 4096) -> dict:
    """Run one point and reduce it (executed on a worker). ``case``: the sweep's case as a
    :class:`~fmu_src.case.Case` or its TOML text (never a path); the point's overrides are applied here.
    Never raises (errors are returned) except :class:`~orchestrator.run.RunInterrupted`, a
    Ctrl-C of a serial sweep."""
    folder = ""
    try:
        from orchestrator.analysis import run_metrics, steady_window
        from orchestrator.results import read_results
        from orchestrator.run import run_case

        if not isinstance(case, Case):  # TOML text; a path would name the client's folders
            if not (isinstance(case, str) and "\n" in case):
                raise TypeError(f"run_point needs a Case or its TOML text, not {case!r}")
            case = as_case(case)
        case = case.with_overrides(point.overrides)
        z1 = case["gear_pair.teeth"][0]
        mesh_period = 2 * math.pi / (case["operation.speed"] * z1)
        steady_n = min(steady_periods, periods)
        steady = steady_n * mesh_period
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp, _captured_stderr() as err:
            folder = tmp
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
        out.update(point_spectrum(case, r, steady_n))
        out["wall_time"] = np.asarray(time.perf_counter() - t0)
        out["iterations_per_step"] = np.asarray(s.iterations_per_step)
        return {"ok": True, "data": out, "warnings": err.getvalue().strip()}
    except RunInterrupted:
        raise
    except Exception as exc:  # reported, the sweep goes on
        text = f"{type(exc).__name__}: {exc}"
        if folder:  # the run's file is gone with its temporary folder
            text = text.replace(folder, "<the point's temporary folder, removed>")
        return {"ok": False, "error": text, "traceback": traceback.format_exc()}


def _point_values(base: Case, overrides: dict, keys) -> list[float]:
    """The varied values of a point in SI units, bounds not checked (the first entry of a list
    field; NaN where a value is not a number or not readable)."""
    from fmu_src.units import UnitError, parse_quantity

    out = []
    for key in keys:
        value = overrides[key] if key in overrides else base.values.get(key)
        if isinstance(value, (list, tuple)):
            value = value[0] if value else math.nan
        kind = _BY_KEY[key].kind if key in _BY_KEY else None
        if kind in DIMENSIONS and isinstance(value, (int, float, str)) \
                and not isinstance(value, bool):
            try:
                value = parse_quantity(value, kind, key)
            except UnitError:
                value = math.nan
        out.append(float(value) if isinstance(value, (int, float)) else math.nan)
    return out


def check_point(case: Case, point: SweepPoint) -> Case:
    """The case of a point (its overrides and bearing model applied), checked; raises
    :class:`~fmu_src.case.CaseError`."""
    overrides = dict(point.overrides)
    if point.bearing is not None:
        overrides["bearings.model"] = point.bearing
    return case.with_overrides(overrides)


@contextlib.contextmanager
def _children_ignore_sigint():
    """SIGINT ignored while the LocalCluster starts its processes, so that they inherit it: a
    Ctrl-C in the terminal reaches the whole process group, and only this process (the
    client) should act on it (it cancels the points and closes the cluster)."""
    import signal

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _client(scheduler, n_workers, timeout):
    import logging

    from dask.distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout=timeout), None
    with _children_ignore_sigint():
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0", scheduler_kwargs={"dashboard": False},
                               silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _connect(scheduler, n_workers, timeout):
    try:
        return _client(scheduler, n_workers, timeout)
    except KeyboardInterrupt:
        raise
    except Exception as exc:
        where = f"the Dask scheduler {scheduler}" if scheduler else "a Dask LocalCluster"
        raise RunError(f"cannot connect to {where}: {type(exc).__name__}: {exc}") from None


def _workers(client) -> int:
    """Workers connected to the scheduler (0 when the client lost it)."""
    if client.status != "running":
        return 0
    info = client.scheduler_info(n_workers=1)
    return int(info.get("n_workers", len(info.get("workers", {}))))


def _open(path: Path, mode: str, wait: float = 30.0):
    """``h5py.File(path, mode)``, retried for ``wait`` s while a reader holds the file's
    lock (``gsb plot`` of a running sweep)."""
    import h5py

    t0 = time.monotonic()
    while True:
        try:
            return h5py.File(path, mode)
        except BlockingIOError:
            if time.monotonic() - t0 > wait:
                raise
            time.sleep(0.2)


def _strings(values):
    import h5py

    return np.array([str(v) for v in values], dtype=h5py.string_dtype())


def run_sweep(case, points, path: str | Path, periods: int, steady_periods: int = 26,
              scheduler: str | None = None, n_workers: int = 2, progress: bool = True,
              name: str = "", vary_keys=None, worker_timeout: float = 60.0) -> SweepResult:
    """Run the points, gather them into one HDF5 file as they complete (module docstring).

    ``case``: a :class:`~fmu_src.case.Case`, its TOML text, or a case file / shipped name read here (the
    workers get its content). ``vary_keys``: the fields varied (default: every key the points
    override, in order of appearance). ``worker_timeout`` [s]: stop when no worker is connected
    to the scheduler for that long. Raises :class:`~orchestrator.run.RunError` if the cluster
    cannot be reached (nothing written) and :class:`SweepInterrupted` on Ctrl-C (the finished
    points kept in the file)."""
    import h5py

    from orchestrator.run import Progress

    base = as_case(case)
    points = list(points)
    if vary_keys is None:
        vary_keys = list(dict.fromkeys(k for p in points for k in p.overrides))
    vary_keys = list(vary_keys)
    bearings = list(dict.fromkeys(p.bearing or base["bearings.model"] for p in points))
    path = Path(path)
    t0 = time.perf_counter()
    failed = []
    warned = {}
    status, message = "complete", ""
    rejected = {}
    for i, p in enumerate(points):
        try:
            check_point(base, p)
        except CaseError as exc:
            rejected[i] = f"CaseError: {exc}"
    client = cluster = None
    quiet = contextlib.ExitStack()
    if scheduler != "none":
        client, cluster = _connect(scheduler, n_workers, max(worker_timeout, 1.0))
        quiet.enter_context(_quiet_dask_logs())
    bar = Progress(len(points), f"sweep {name or path.stem}", enabled=progress)
    done = 0
    interrupted = False
    stored: set[int] = set()

    def store(i, res):
        """One point into the file, opened for it only: between points the file is closed,
        complete and readable (gsb plot), and a killed client loses no finished point."""
        p = points[i]
        with _open(path, "a") as f:
            g = f["points"].create_group(f"{i:04d}")
            g.attrs["overrides"] = json.dumps(p.overrides)
            g.attrs["values"] = np.asarray(_point_values(base, p.overrides, vary_keys),
                                           dtype=float)
            g.attrs["bearing"] = p.bearing or base["bearings.model"]
            g.attrs["label"] = p.label
            if res["ok"]:
                for key, val in res["data"].items():
                    d = g.create_dataset(key, data=val)
                    unit, doc = DATASETS.get(key, ("", ""))
                    d.attrs["unit"] = unit
                    d.attrs["description"] = doc
                if res.get("warnings"):
                    g.attrs["warnings"] = res["warnings"]
                    warned[i] = res["warnings"]
            else:
                g.attrs["error"] = res["error"]
                g.attrs["traceback"] = res.get("traceback", "")
                failed.append((i, res["error"]))
            f.attrs["n_failed"] = len(failed)
        stored.add(i)

    def give_up(why):
        for i in range(len(points)):
            if i not in stored:
                store(i, {"ok": False, "error": why, "traceback": ""})

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with h5py.File(path, "w") as f:
            f.attrs["kind"] = "sweep"
            f.attrs["case"] = base.name
            f.attrs["case_file"] = str(base.source)
            f.attrs["case_toml"] = base.to_toml()
            f.attrs["vary_keys"] = _strings(vary_keys)
            f.attrs["vary_units"] = _strings(field_unit(k) if k in _BY_KEY else ""
                                             for k in vary_keys)
            f.attrs["bearings"] = _strings(bearings)
            f.attrs["periods"] = int(periods)
            f.attrs["steady_periods"] = int(steady_periods)
            f.attrs["n_points"] = len(points)
            f.attrs["n_failed"] = 0
            f.attrs["status"] = "running"
            f.attrs["complete"] = False
            f.attrs["wall_time"] = 0.0
            f.create_group("points")
        try:
            for i, why in rejected.items():
                store(i, {"ok": False, "error": why, "traceback": ""})
                done += 1
            todo = [i for i in range(len(points)) if i not in rejected]
            if client is None:
                for i in todo:
                    store(i, run_point(base, points[i], periods, steady_periods))
                    done += 1
                    bar.update(done, f"{len(failed)} failed")
            else:
                status, message, done = _gather(client, base, points, todo, periods,
                                                steady_periods, store, bar, done, failed,
                                                scheduler, worker_timeout, progress)
                if message:
                    give_up(message)
        except (KeyboardInterrupt, RunInterrupted):
            interrupted = True
            status = "interrupted"
            give_up("interrupted (Ctrl-C) before the point finished")
        wall = time.perf_counter() - t0
        if status == "complete" and failed:
            status = "failed points"
        with _open(path, "a") as f:
            f.attrs["wall_time"] = wall
            f.attrs["status"] = status
            f.attrs["complete"] = not failed
    finally:
        if client is not None:
            _close(client, cluster)
        quiet.close()
    if interrupted:
        finished = len(points) - len(failed)
        raise SweepInterrupted(f"interrupted: {finished} of {len(points)} points finished, kept "
                               f"in {path} (complete = false)", path)
    return SweepResult(path, wall, len(points), failed, status, message, warned)


def _gather(client, base, points, todo, periods, steady_periods, store, bar, done, failed,
            scheduler, worker_timeout, progress):
    """Submit the points, store them as they complete; stop when no worker is connected for
    ``worker_timeout`` s. Returns (status, message, done)."""
    from dask.distributed import wait

    futures = {client.submit(run_point, base, points[i], periods, steady_periods,
                             pure=False): i for i in todo}
    pending = set(futures)
    poll = min(1.0, max(0.05, worker_timeout / 10))
    alone_since = None
    where = f"the scheduler {scheduler}" if scheduler else "the LocalCluster's scheduler"
    try:
        while pending:
            try:
                finished, pending = wait(pending, timeout=poll, return_when="FIRST_COMPLETED")
            except TimeoutError:
                finished = set()
            except Exception as exc:  # FuturesCancelledError: the client lost the scheduler
                if client.status == "running" and not any(f.cancelled() for f in pending):
                    raise
                return ("scheduler lost", f"lost the connection to {where} "
                        f"({type(exc).__name__})", done)
            for fut in finished:
                i = futures[fut]
                try:
                    res = fut.result()
                except (Exception, asyncio.CancelledError, concurrent.futures.CancelledError) \
                        as exc:  # the worker died, or the client lost the scheduler
                    res = {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                           "traceback": traceback.format_exc()}
                fut.release()
                store(i, res)
                done += 1
            if not pending:
                break
            now = time.perf_counter()
            n = _workers(client)
            if n > 0:
                alone_since = None
            elif alone_since is None:
                alone_since = now
                if progress:
                    print(f"{chr(10) * bar.tty}no Dask worker connected to {where}: waiting up to "
                          f"{worker_timeout:g} s", file=sys.stderr, flush=True)
            elif now - alone_since >= worker_timeout:
                return ("worker timeout",
                        f"worker timeout: no Dask worker connected to {where} for "
                        f"{worker_timeout:g} s", done)
            bar.update(done, f"{len(failed)} failed, {n} worker{'s' * (n != 1)}")
        bar.update(done, f"{len(failed)} failed")
        return "complete", "", done
    finally:
        if pending:
            with contextlib.suppress(Exception):
                client.cancel(list(pending))


@contextlib.contextmanager
def _quiet_dask_logs():
    """Dask's own log records (connection errors with their tracebacks) held back below
    CRITICAL: the sweep reports what they mean (the points' errors, a lost scheduler, no
    worker)."""
    import logging

    names = ["distributed"] + [n for n, x in logging.root.manager.loggerDict.items()
                               if n.startswith("distributed.") and isinstance(x, logging.Logger)]
    levels = {n: logging.getLogger(n).level for n in names}
    for n in names:
        logging.getLogger(n).setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for n, level in levels.items():
            logging.getLogger(n).setLevel(level)


def _close(client, cluster):
    with contextlib.suppress(Exception):
        client.close(timeout=10)
    if cluster is not None:
        with contextlib.suppress(Exception):
            cluster.close(timeout=10)


def read_sweep(path) -> list[dict]:
    """The points of a sweep file: dicts with ``overrides``, ``values``, ``bearing``, ``label``,
    ``error`` and the datasets (absent for failed points), in point order."""
    import h5py

    out = []
    with h5py.File(path, "r") as f:
        for key in sorted(f["points"]):
            g = f["points"][key]
            d = {"overrides": json.loads(g.attrs["overrides"]), "bearing": g.attrs["bearing"],
                 "label": g.attrs["label"], "error": g.attrs.get("error"),
                 "values": np.asarray(g.attrs.get("values", []), dtype=float),
                 "warnings": g.attrs.get("warnings", "")}
            for name in g:
                d[name] = g[name][()]
            out.append(d)
    return out


def read_sweep_attrs(path) -> dict:
    """The root attributes of a sweep file (strings arrays as lists of str)."""
    import h5py

    with h5py.File(path, "r") as f:
        out = {}
        for key, value in f.attrs.items():
            if isinstance(value, np.ndarray) and value.dtype.kind == "O":
                value = [v.decode() if isinstance(v, bytes) else str(v) for v in value]
            elif isinstance(value, bytes):
                value = value.decode()
            elif isinstance(value, np.generic):
                value = value.item()
            out[key] = value
    return out
