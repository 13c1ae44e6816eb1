"""Parametric sweeps on Dask: independent runs of one case with overridden fields.

Each point is a full in-process run (:func:`orchestrator.run.runner.run_case`) on a Dask worker,
reduced there to its figures (:func:`orchestrator.analysis.metrics.run_metrics`), its
steady-state orbits and the order spectrum of its bearing forces, so only small arrays travel back.
The workers get the
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

The sweep's results are one HDF5 file, written one point at a time: :mod:`orchestrator.sweeps.file`.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import math
import os
import signal
import sys
import threading
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fmu_src import description
from fmu_src.case import Case, CaseError, load_case, parse_case, parse_toml
from orchestrator.run.progress import RunInterrupted, deferred_signals
from orchestrator.run.spec import RunError
from orchestrator.sweeps import file as sweep_file
from orchestrator.sweeps.file import DATASETS, field_unit, read_sweep, read_sweep_attrs

__all__ = ["DATASETS", "SweepInterrupted", "SweepPoint", "SweepResult", "as_case",
           "check_point", "field_unit", "point_spectrum", "read_sweep", "read_sweep_attrs",
           "run_point", "run_sweep", "sweep_window"]

#: the highest order kept in a point's spectrum, in orders of the fastest mesh
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

    def to_xarray(self):
        """The sweep file as an :class:`xarray.Dataset` over the varied fields and the bearing
        models (:func:`orchestrator.sweeps.file.sweep_dataset`)."""
        return sweep_file.sweep_dataset(self.path)


def as_case(case) -> Case:
    """A :class:`~fmu_src.case.Case`: itself, parsed from TOML text (a string with a line
    break), or read from a file path or shipped name (in the client only: workers get the
    content)."""
    if isinstance(case, Case):
        return case
    if isinstance(case, str) and "\n" in case:
        return parse_case(parse_toml(case, "sweep case"), "<sweep case>")
    return load_case(case)


def point_spectrum(case: Case, results: dict, window_s: float) -> dict:
    """Order spectrum of ||F_b|| (every bearing) of a run, from its full-resolution samples,
    in peak amplitude (:func:`orchestrator.analysis.spectrum.order_spectrum`, the scale of
    every figure), in orders of the input shaft (cycles per input revolution; divide by a
    shaft's speed ratio for that shaft's orders), 0 to 3.5 times the fastest mesh's order.

    The window is the last whole number of input revolutions of the steady window (its last
    ``window_s`` seconds: :func:`orchestrator.analysis.metrics.report_window`), or the whole
    steady window if it is shorter than one revolution; so the input shaft's orders (the
    paper's pinion orders 1, z1, 2 z1, ...) fall on bins when it holds a revolution and read
    their amplitudes exactly. In a run-up (``drive.speed_profile``) the orders are those of
    the input's speed at the end of the run (the spectrum of a window over which the speed
    changes smears its lines)."""
    from fmu_src.description import layout, speed_profile, time_step
    from orchestrator.analysis.campbell import order_lines
    from orchestrator.analysis.spectrum import order_spectrum

    fastest = max(order_lines(case)["mesh_orders"] or [1.0])  # mesh periods per input rev
    per_revolution = fastest * int(case["simulation.steps_per_mesh_period"])  # steps
    dt = time_step(case)
    profile = speed_profile(case)
    speed = abs(layout(case).drive.speed)
    if profile.varies:  # the time step is the highest speed's: steps per revolution at the end
        speed = profile.speed(float(np.asarray(results["time"])[-1]))
        per_revolution = 2.0 * math.pi / (speed * dt)
    steps = max(1, round(window_s / dt))
    revolutions = int(steps / per_revolution + 1e-9)
    n = round(revolutions * per_revolution) if revolutions >= 1 else steps
    time_s = np.asarray(results["time"], dtype=float)
    n = min(n, time_s.size)
    force = np.asarray(results["bearing_force"][-n:], dtype=float)
    norm = np.hypot(force[..., 0], force[..., 1])
    input_hz = speed / (2.0 * math.pi)
    orders, amp = order_spectrum(norm, dt, input_hz, max_order=MAX_MESH_ORDER * fastest)
    step = time_s[1] - time_s[0] if time_s.size > 1 else 0.0
    return {"spectrum_orders": orders, "spectrum": amp.T,
            "spectrum_window": np.array([time_s[-n] - step, time_s[-1]])}


def run_point(case, point: SweepPoint, periods: int, keep_steps: int = 4096) -> dict:
    """Run one point and reduce it (executed on a worker) over its window (the case's
    ``simulation.window``: :func:`orchestrator.analysis.metrics.report_window`). ``case``: the
    sweep's case as a :class:`~fmu_src.case.Case` or its TOML text (never a path); the point's
    overrides are applied here. Never raises (errors are returned) except
    :class:`~orchestrator.run.progress.RunInterrupted`, a Ctrl-C of a serial sweep."""
    try:
        from orchestrator.analysis.metrics import report_window, run_metrics, steady_window
        from orchestrator.run.runner import simulate_case
        from orchestrator.run.spec import RunSpec

        if not isinstance(case, Case):  # TOML text; a path would name the client's folders
            if not (isinstance(case, str) and "\n" in case):
                raise TypeError(f"run_point needs a Case or its TOML text, not {case!r}")
            case = as_case(case)
        run = {"simulation.mesh_periods": periods}
        if point.bearing is not None:
            run["bearings.*.model"] = point.bearing
        case = case.with_overrides(point.overrides | run)
        t0 = time.perf_counter()
        result = simulate_case(RunSpec.of(case, in_process=True), echo_warnings=False)
        s, r = result.summary, result.as_dict()
        steady, _ = report_window(case, r["time"])
        metrics = run_metrics(r, steady)
        win = steady_window(r["time"], steady)
        stride = max(1, int(np.count_nonzero(win)) // keep_steps)
        out = {k: np.asarray(v) for k, v in metrics.items()}
        out["time"] = r["time"][win][::stride]
        out["orbit"] = r["journal_position"][win][::stride]
        out["bearing_force"] = r["bearing_force"][win][::stride]
        out["mesh_force"] = r["mesh_force"][win][::stride]
        out["transmission_error"] = r["transmission_error"][win][::stride]
        out["static_journal"] = np.asarray(s.static_positions)
        out["window_s"] = np.asarray(steady)
        out.update(point_spectrum(case, r, steady))
        out["wall_time"] = np.asarray(time.perf_counter() - t0)
        out["iterations_per_step"] = np.asarray(s.iterations_per_step)
        return {"ok": True, "data": out, "warnings": "\n".join(s.warnings)}
    except RunInterrupted:
        raise
    except Exception as exc:  # reported, the sweep goes on
        text = f"{type(exc).__name__}: {exc}"
        if _touched(exc):
            text = f"{PHYSICS_STOP}: {text}"
        return {"ok": False, "error": text, "traceback": traceback.format_exc()}


#: how the error of a point whose run stopped on physics starts: a journal touched its
#: bearing (:class:`bearing_fmu.base.EccentricityError` among the causes), which no solver
#: can take it past, unlike a solver giving up
PHYSICS_STOP = "stopped on physics (a journal touched its bearing)"


def _touched(exc: BaseException) -> bool:
    """Whether an :class:`~bearing_fmu.base.EccentricityError` is ``exc`` or among its causes."""
    from bearing_fmu.base import EccentricityError

    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, EccentricityError):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def stopped_on_physics(error: str) -> bool:
    """Whether a failed point's ``error`` (a :class:`SweepResult`'s) is a physics stop
    (:data:`PHYSICS_STOP`), to be counted apart from the solver's failures."""
    return error.startswith(PHYSICS_STOP)


def check_point(case: Case, point: SweepPoint) -> Case:
    """The case of a point (its overrides and bearing model applied), checked; raises
    :class:`~fmu_src.fields.CaseError`."""
    overrides = dict(point.overrides)
    if point.bearing is not None:
        overrides["bearings.*.model"] = point.bearing
    return case.with_overrides(overrides)


def sweep_window(case: Case, points, periods: int) -> str:
    """The name of the window every point's figures are taken over (the case's
    ``simulation.window``, :func:`orchestrator.analysis.metrics.report_window`, for a run of
    ``periods`` mesh periods): "last 26 mesh periods", or each distinct name joined by "; " when
    the points differ (a window in seconds over several speeds is the same name). Raises
    :class:`~fmu_src.fields.CaseError` naming the first point whose run is shorter than the
    window (a point the case loader rejects is skipped: it is recorded as failed)."""
    from fmu_src.description import mesh_period
    from orchestrator.analysis.metrics import report_window

    names = []
    for i, point in enumerate(points):
        try:
            own = check_point(case, point).with_overrides({"simulation.mesh_periods": periods})
        except CaseError:
            continue
        try:
            _, name = report_window(own, [periods * mesh_period(own)])
        except ValueError as exc:
            raise CaseError(f"point {i} ({point.label or point.overrides}): {exc}") from None
        names.append(name)
    return "; ".join(dict.fromkeys(names))


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


@contextlib.contextmanager
def _environment_kept():
    """This process's environment as it was: Dask's nanny sets ``OMP_NUM_THREADS``,
    ``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS`` and ``MALLOC_TRIM_THRESHOLD_`` in the
    environment of the process that starts a worker (``distributed.nanny.pre-spawn-environ``)
    and leaves them there, so that every program this process starts afterwards would run its
    BLAS on one thread."""
    saved = dict(os.environ)
    try:
        yield
    finally:
        for name in set(os.environ) - set(saved):
            del os.environ[name]
        os.environ.update({k: v for k, v in saved.items() if os.environ.get(k) != v})


def dask_client(scheduler, n_workers: int, timeout: float):
    """``(client, cluster)``: a client of the scheduler at ``scheduler`` (cluster None), or of
    a new LocalCluster of ``n_workers`` processes; ``timeout`` [s] to connect."""
    import logging

    from dask.distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout=timeout), None
    with _children_ignore_sigint(), _environment_kept():
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0", scheduler_kwargs={"dashboard": False},
                               silence_logs=logging.ERROR)
    return Client(cluster), cluster


def unguarded_main_call() -> str | None:
    """``"<script>:<line>"`` when the sweep was called from a script's top-level code outside
    an ``if __name__ == "__main__":`` block, else None. A LocalCluster starts its workers as
    new Python processes, which import the script again: unguarded, each would start a sweep
    of its own before it is running (multiprocessing's "bootstrapping phase" error, 255
    lines, then "Nanny failed to start"). Found from the outermost frame of ``__main__`` and
    the script's syntax tree; None when there is no script file (an interactive session, a
    notebook: their workers do not import it)."""
    import ast
    import inspect

    main = sys.modules.get("__main__")
    script = getattr(main, "__file__", None)
    frame, line = inspect.currentframe(), None
    while frame is not None:
        if frame.f_globals is getattr(main, "__dict__", None) and frame.f_code.co_name == \
                "<module>":
            line = frame.f_lineno
        frame = frame.f_back
    if script is None or line is None:
        return None
    try:
        tree = ast.parse(Path(script).read_text(), script)
    except (OSError, SyntaxError, ValueError):
        return None

    def guard(node: ast.If) -> bool:
        t = node.test
        return (isinstance(t, ast.Compare)
                and isinstance(t.left, ast.Name) and t.left.id == "__name__"
                and any(isinstance(c, ast.Constant) and c.value == "__main__"
                        for c in t.comparators))

    guarded = any(guard(n) and n.lineno <= line <= (n.end_lineno or n.lineno)
                  for n in ast.walk(tree) if isinstance(n, ast.If))
    return None if guarded else f"{script}:{line}"


def _connect(scheduler, n_workers, timeout):
    if scheduler is None:
        where = unguarded_main_call()
        if where is not None:
            raise RunError(f"{where}: a sweep on a local Dask cluster starts worker processes "
                           "that import this script again: call it under "
                           "`if __name__ == \"__main__\":`, or run the points in this process "
                           "(scheduler=\"none\"; gsb sweep --scheduler none)")
    try:
        return dask_client(scheduler, n_workers, timeout)
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


def run_sweep(case, points, path: str | Path, periods: int, scheduler: str | None = None,
              n_workers: int = 2, progress: bool = True, name: str = "", vary_keys=None,
              worker_timeout: float = 60.0) -> SweepResult:
    """Run the points, gather them into one HDF5 file as they complete (module docstring).

    ``case``: a :class:`~fmu_src.case.Case`, its TOML text, or a case file / shipped name read
    here (the workers get its content); its ``simulation.window`` is every point's window
    (:func:`sweep_window`). ``vary_keys``: the fields varied (default: every key the
    points override, in order of appearance). ``worker_timeout`` [s]: stop when no worker is
    connected to the scheduler for that long. Raises :class:`~fmu_src.fields.CaseError` for a
    window longer than a point's run and :class:`~orchestrator.run.spec.RunError` if the
    cluster cannot be reached (nothing written in either case), :class:`SweepInterrupted` on
    Ctrl-C (the finished points kept in the file)."""
    from orchestrator.run.progress import Progress

    base = as_case(case)
    points = list(points)
    window = sweep_window(base, points, periods)
    if vary_keys is None:
        vary_keys = list(dict.fromkeys(k for p in points for k in p.overrides))
    vary_keys = list(vary_keys)
    own = description.shared_bearing_model(base) or "mixed"
    bearings = list(dict.fromkeys(p.bearing or own for p in points))
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
        """One point into the file (:func:`orchestrator.sweeps.file.store_point`)."""
        if res["ok"] and res.get("warnings"):
            warned[i] = res["warnings"]
        elif not res["ok"]:
            failed.append((i, res["error"]))
        sweep_file.store_point(path, i, points[i], base, vary_keys, res, len(failed))
        stored.add(i)

    def give_up(why):
        for i in range(len(points)):
            if i not in stored:
                store(i, {"ok": False, "error": why, "traceback": ""})

    try:
        sweep_file.write_header(path, base, vary_keys, bearings, periods, window,
                                len(points))
        try:
            for i, why in rejected.items():
                store(i, {"ok": False, "error": why, "traceback": ""})
                done += 1
            todo = [i for i in range(len(points)) if i not in rejected]
            if client is None:
                for i in todo:
                    store(i, run_point(base, points[i], periods))
                    done += 1
                    bar.update(done, f"{len(failed)} failed")
            else:  # Ctrl-C taken between polls: Dask's waits may swallow a KeyboardInterrupt
                with deferred_signals((signal.SIGINT,), "stopping the sweep") as asked:
                    status, message, done = _gather(client, base, points, todo, periods,
                                                    store, bar, done, failed,
                                                    scheduler, worker_timeout, progress, asked)
                if message:
                    give_up(message)
        except (KeyboardInterrupt, RunInterrupted):
            interrupted = True
            status = "interrupted"
            give_up("interrupted (Ctrl-C) before the point finished")
        wall = time.perf_counter() - t0
        if status == "complete" and failed:
            status = "failed points"
        sweep_file.finish(path, status, not failed, wall)
    finally:
        if client is not None:
            _close(client, cluster)
        quiet.close()
    if interrupted:
        finished = len(points) - len(failed)
        raise SweepInterrupted(f"interrupted: {finished} of {len(points)} points finished, kept "
                               f"in {path} (complete = false)", path)
    return SweepResult(path, wall, len(points), failed, status, message, warned)


def _gather(client, base, points, todo, periods, store, bar, done, failed, scheduler,
            worker_timeout, progress, asked):
    """Submit the points, store them as they complete; stop when no worker is connected for
    ``worker_timeout`` s, and with KeyboardInterrupt once ``asked`` (the signals received,
    :func:`orchestrator.run.progress.deferred_signals`) is not empty. Returns (status, message,
    done)."""
    from dask.distributed import wait

    futures = {client.submit(run_point, base, points[i], periods, pure=False): i
               for i in todo}
    pending = set(futures)
    poll = min(1.0, max(0.05, worker_timeout / 10))
    alone_since = None
    where = f"the scheduler {scheduler}" if scheduler else "the LocalCluster's scheduler"
    try:
        while pending:
            if asked:
                raise KeyboardInterrupt
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
