"""``gsb run``: static solution X0 and the nonlinear (or linear) transient of a case.

1. Build the structure slave and the bearing set, through FMUs (default; fmpy) or in-process
   (:func:`build_master`; the runner sees only the master's interfaces).
2. Static solution X0 (paper Sec. 2.2.3): the master iterates structure static solves and
   bearing linearisations with velocities zero
   (:meth:`orchestrator.coupling.master.Master.solve_static`).
3. End of initialisation: the linear model (Sec. 3.3, Table 4 case 0) freezes the bearings' 8
   coefficients at X0; the modal damping is built on the modes with the bearings' static
   stiffness (Structure docs).
4. Transient (Sec. 3.2): ``steps_per_mesh_period x mesh_periods`` coupled Newmark steps, each
   converged to the case tolerance; every step's channels go to the results file as the run
   goes (:mod:`orchestrator.run.results`: HDF5 SWMR, flushed every second with a checkpoint of the
   coupled state; an interrupted or failed run keeps what it computed, :func:`resume_run`
   continues it). The file's name and what happens to an existing one:
   :mod:`orchestrator.run.files`.

Channels (:data:`CHANNELS`, units from :mod:`fmu_src.units`): ``journal_position`` (4, 2) [s, t]
and ``journal_velocity`` (4, 2) of the journal centres, ``bearing_force`` (4, 2),
``mesh_force``, ``transmission_error``, ``gear_nodes`` (2, 2) (u, v of the pinion and gear
nodes), ``iterations`` (coupled iterations of the step).

Report (:func:`orchestrator.analysis.metrics.run_report`, over the last gear revolution or the last
half
of a shorter run; :meth:`RunSummary.report_text`), stored as numeric root attributes of the
results file once the transient stops (complete, failed or interrupted; at least 2 steps):
``dynamic_factor`` [1] (R, max mesh force over the static load), ``bearing_force_ptp`` (4,) [N]
(peak-to-peak of ||F_b||), ``line_amplitudes`` (4, n) [N] (peak amplitudes of the lines of
||F_b||, NaN where the window does not resolve a line), ``line_orders`` (n,) [1] (pinion orders),
``line_labels`` (n,) (strings: "1x", "gear_1x", "26x", ...) and ``report_window`` (2,) [s]
(start and end of the window); each numeric attribute with a unit has it in ``<name>_unit``
(:data:`ATTRIBUTE_UNITS`).
"""

from __future__ import annotations

import contextlib
import math
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fmu_src import description
from fmu_src.case import Case
from fmu_src.state_codec import StateFormatError
from fmu_src.units import symbol
from orchestrator.coupling.inprocess import InProcessStructure, ModelBearings
from orchestrator.coupling.master import Master, decode_checkpoint
from orchestrator.run import files as run_files
from orchestrator.run.checks import overload_message, time_step_warnings, unbalance_warnings
from orchestrator.run.files import results_name
from orchestrator.run.results import (
    ResultsWriter,
    add_attributes,
    clear_write_flags,
    live_writer,
    read_attributes,
    read_checkpoint,
    read_results,
)

__all__ = ["ATTRIBUTE_UNITS", "CHANNELS", "Progress", "RunError", "RunInterrupted",
           "RunSummary", "build_master", "check_periods", "resume_run", "run_case"]

#: results channels: name -> (shape per step, unit, description)
CHANNELS = {
    "journal_position": ((4, 2), symbol("length"),
                         "journal-centre displacement [s, t] at bearings 1-4, global frame"),
    "journal_velocity": ((4, 2), symbol("velocity"),
                         "journal-centre velocity [s_dot, t_dot] at bearings 1-4, global frame"),
    "bearing_force": ((4, 2), symbol("force"),
                      "film force on the journal [F_s, F_t] at bearings 1-4"),
    "mesh_force": ((), symbol("force"), "total normal mesh force (sum of slice loads)"),
    "transmission_error": ((), symbol("length"),
                           "r_b1 theta1 + r_b2 theta2 (elastic torsion at the gears)"),
    "gear_nodes": ((2, 2), symbol("length"), "[u, v] of the pinion and gear nodes"),
    "iterations": ((), symbol("dimensionless"), "coupled master iterations of the step"),
}


class RunError(RuntimeError):
    """A run that stopped; the message says where and which file keeps the computed steps."""


class RunInterrupted(RuntimeError):
    """A run stopped by SIGINT (Ctrl-C) or SIGTERM between two steps; ``exit_code`` is the
    shell's convention, 128 + the signal number (130, 143)."""

    def __init__(self, signum: int, message: str):
        super().__init__(message)
        self.signum = signum
        self.exit_code = 128 + int(signum)


@contextlib.contextmanager
def deferred_signals(signals=(signal.SIGINT, signal.SIGTERM),
                     stopping: str = "stopping after the current step"):
    """Hold SIGINT and SIGTERM in a list instead of raising where they land.

    A KeyboardInterrupt raised inside an FMU's Python code (pythonfmu runs it in this
    interpreter) is fatal for that FMU and often for the process, and Dask's waits can swallow
    one; the run (and a sweep's gather loop) checks the list between steps instead and stops
    cleanly there. ``stopping`` is what the first signal's message says happens next. Only the
    main thread can install handlers: elsewhere (a Dask worker thread) the list stays empty and
    signals keep their handlers."""
    received: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield received
        return

    def hold(signum, frame):
        if not received:
            print(f"\n{signal.Signals(signum).name} received: {stopping} (again to stop at "
                  "once)", file=sys.stderr, flush=True)
        elif signum == signal.SIGINT:  # a second Ctrl-C: the user insists
            raise KeyboardInterrupt
        received.append(signum)

    previous = {s: signal.signal(s, hold) for s in signals}
    try:
        yield received
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


@dataclass
class RunSummary:
    """What a run did (figures for the README and the benchmark)."""

    results: Path
    steps: int
    wall_time: float  # s, transient only
    static_time: float  # s
    iterations: int  # coupled iterations of the transient
    bearing_evaluations: int  # calls of the bearing set (4 bearings each)
    static_iterations: int
    static_positions: np.ndarray  # (4, 2) m
    figures: list = field(default_factory=list)
    report: dict | None = None  # orchestrator.analysis.metrics.run_report, None below 2 steps
    warnings: list = field(default_factory=list)  # sentences of the checks before the transient
    relaxed_steps: int = 0  # steps whose coupled iteration was relaxed (coupling.master)

    @property
    def iterations_per_step(self) -> float:
        return self.iterations / max(self.steps, 1)

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.wall_time if self.wall_time > 0 else math.inf

    def describe(self) -> str:
        return (f"{self.steps} steps in {self.wall_time:.1f} s ({self.steps_per_second:.0f} "
                f"steps/s), {self.iterations_per_step:.2f} coupled iterations per step, "
                f"{4 * self.bearing_evaluations} bearing evaluations; static solution in "
                f"{self.static_iterations} iterations ({self.static_time:.2f} s)"
                + (f"; {self.relaxed_steps} step(s) relaxed at a kink of a bearing law"
                   if self.relaxed_steps else ""))

    def report_text(self) -> str:
        """The report (``report``) in a few lines: R, bearing-force peak-to-peak [N] and a
        table of the line amplitudes of ||F_b|| [N] per bearing."""
        r = self.report
        if r is None:
            return f"no report: {self.steps} step(s), at least 2 needed"
        t0, t1 = r["window_s"]
        ptp = ", ".join(f"{b + 1}: {v:.0f}" for b, v in enumerate(r["bearing_force_ptp"]))
        lines = [f"dynamic factor R = {r['dynamic_factor']:.3f} ({r['window_kind']}, "
                 f"t = {t0:.6g} - {t1:.6g} s)",
                 f"bearing force peak-to-peak [N]: {ptp}",
                 "line amplitudes of ||F_b|| [N]:",
                 "bearing" + "".join(f"{label:>9}" for label in r["line_labels"])]
        amplitudes = np.asarray(r["line_amplitudes"])
        for b, row in enumerate(amplitudes):
            lines.append(f"{b + 1:>7}" + "".join("        -" if np.isnan(v) else f"{v:9.1f}"
                                                for v in row))
        if np.isnan(amplitudes).any():
            lines.append("(-: a line the window does not resolve)")
        return "\n".join(lines)


class Progress:
    """A one-line progress display on stderr, refreshed at most every ``every`` seconds; on a
    stream that is not a terminal (a log file), one line every 10 s instead."""

    def __init__(self, total: int, label: str = "", every: float = 0.5, stream=None,
                 enabled: bool = True):
        self.total = total
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every = every if self.tty else max(every, 10.0)
        self.enabled = enabled
        self.start = time.perf_counter()
        self._last = -math.inf

    def update(self, done: int, extra: str = "") -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < self.every and done < self.total:
            return
        self._last = now
        elapsed = now - self.start
        frac = done / self.total if self.total else 1.0
        eta = elapsed / frac - elapsed if frac > 0 else math.inf
        bar = "#" * int(30 * frac)
        line = (f"{self.label} [{bar:<30}] {done}/{self.total} {100 * frac:5.1f} % "
                f"{elapsed:6.1f} s, {eta:6.1f} s left {extra}")
        if self.tty:
            self.stream.write(f"\r{line}   " + ("\n" if done >= self.total else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


def _clearances(case: Case) -> list[float]:
    return [float(c) for c in case["bearings.clearance"]]


def build_master(case: Case, bearing: str | None = None, in_process: bool = False,
                 fmu_dir: Path | str | None = None, fmus: dict | None = None) -> Master:
    """The master of a case with its two slaves (``master.structure``, ``master.bearings``).

    ``bearing`` overrides ``bearings.model``. In-process the physics objects of
    :mod:`fmu_src.description` are driven directly; through FMUs the bearing FMU of that model
    and the gear-shaft FMU are taken from ``fmu_dir`` (default: the per-user cache; built
    there if missing), or ``fmus`` names the files: ``{"gear": path, "bearings": [4 paths],
    "bearing_parameters": [4 dicts] (optional)}`` (an SSP's, or a bearing FMU of the user's
    own). Release the slaves with :meth:`orchestrator.coupling.master.Master.close`.
    """
    if bearing is not None:
        case = case.with_overrides({"bearings.model": bearing})
    tol = case["simulation.tolerance"]
    max_it = case["simulation.max_iterations"]
    if in_process:
        structure = InProcessStructure(description.structure(case))
        bearings = ModelBearings(description.bearing_models(case), description.BEARING_FRAMES,
                                 description.bearing_speeds(case))
    elif fmus is not None:
        from orchestrator.coupling import fmi

        structure, bearings = fmi.system_from_files(case, fmus["gear"], fmus["bearings"],
                                                    fmus.get("bearing_parameters"))
    else:
        from orchestrator.coupling import fmi

        structure, bearings = fmi.system_from_case(case, fmu_dir=fmu_dir)
    return Master(structure, bearings, tol, max_it)


#: units of the numeric root attributes, stored beside each as ``<name>_unit``
ATTRIBUTE_UNITS = {
    "dt": symbol("time"), "speed": symbol("angular_speed"),
    "speeds": symbol("angular_speed"), "torque": symbol("torque"),
    "unbalance": symbol("length"), "clearance": symbol("length"),
    "static_journal": symbol("length"), "static_bearing_force": symbol("force"),
    "static_mesh_force": symbol("force"), "static_transmission_error": symbol("length"),
    "wall_time": symbol("time"), "dynamic_factor": symbol("dimensionless"),
    "bearing_force_ptp": symbol("force"), "line_amplitudes": symbol("force"),
    "line_orders": symbol("dimensionless"), "report_window": symbol("time"),
}


def _with_units(attrs: dict) -> dict:
    return attrs | {f"{k}_unit": ATTRIBUTE_UNITS[k] for k in attrs if k in ATTRIBUTE_UNITS}


def _start(master: Master, case: Case, dt: float, stop_if_asked, echo: bool) -> tuple:
    """Static solution X0 and the end of initialisation; returns (static report, x0,
    (static mesh force [N], static transmission error [m]), warnings, seconds)."""
    t0 = time.perf_counter()
    try:
        static = master.solve_static()
    except Exception as exc:
        try:
            why = overload_message(case)
        except Exception:  # the explanation must not hide the failure
            why = None
        if why is not None:
            raise RunError(f"{case.source}: no static solution: {why}") from None
        raise RunError(f"{case.source}: static solution failed: {exc}") from exc
    x0 = static.states[:, :2].copy()
    stop_if_asked("after the static solution")
    # leave initialisation: linear bearings freeze, the structure builds its modal
    # damping on the modes with the bearings' static stiffness
    structure = master.structure
    master.exit_initialization()
    # read after leaving initialisation: a gear-shaft FMU in initialisation mode would solve
    # its static problem again for outputs read after the final laws were set
    static_mesh = (structure.mesh_force(), structure.transmission_error())
    try:
        warnings = time_step_warnings(
            case, master.laws, dt,
            structure.structure if isinstance(structure, InProcessStructure) else None)
    except (ValueError, np.linalg.LinAlgError) as exc:  # a check, not the run
        warnings = [f"the time-step check could not run: {exc}"]
    warnings = unbalance_warnings(case) + warnings
    for text in warnings if echo else ():
        print(f"warning: {text}", file=sys.stderr, flush=True)
    return static, x0, static_mesh, warnings, time.perf_counter() - t0


def run_case(case: Case, bearing: str | None = None, periods: int | None = None,
             in_process: bool = False, out_dir: Path | str = "results",
             fmu_dir: Path | str | None = None, progress: bool = True, figures: bool = True,
             fmus: dict | None = None, steps: int | None = None, overwrite: bool = False,
             flush_seconds: float = 1.0, echo_warnings: bool = True) -> RunSummary:
    """Run a case (module docstring); returns a :class:`RunSummary`.

    ``steps``: stop after this many time steps (a quick look; default: all the periods').
    ``echo_warnings``: print the checks' warnings on stderr (they are also in the summary and
    the results file).
    The results file is named after the effective parameters
    (:func:`orchestrator.run.files.results_name`); an existing one stops the run before it
    starts unless ``overwrite`` (:func:`orchestrator.run.files.target`: a complete file is
    replaced only by a complete run).

    ``fmus``: run these FMU files instead of the built ones (:func:`build_master`); the
    results are then named after the bearing FMU file. Raises :class:`RunError` (with the
    results file that keeps the steps computed) if the static solution or a step fails, and
    :class:`RunInterrupted` after SIGINT or SIGTERM, which stop the run between two steps with
    the results file closed and marked interrupted.
    """
    model = case["bearings.model"] if bearing is None else bearing
    label = model if fmus is None else Path(fmus["bearings"][0]).stem
    periods = check_periods(case["simulation.mesh_periods"] if periods is None else periods)
    if steps is not None and int(steps) < 1:
        raise RunError(f"steps = {steps!r}: need at least one step")
    case = case.with_overrides({"bearings.model": model, "simulation.mesh_periods": periods})
    steps_per_period = case["simulation.steps_per_mesh_period"]
    n_steps = periods * steps_per_period if steps is None else int(steps)
    name = results_name(case, label, in_process, steps,
                        None if fmus is None else fmus["bearings"][0])
    try:
        where = run_files.target(out_dir, name, overwrite)
    except run_files.TargetError as exc:
        raise RunError(str(exc)) from None
    attrs = {
        "kind": "run", "case": case["case.name"], "case_file": str(case.source),
        "case_toml": case.to_toml(), "bearing_model": label,
        "mode": "in-process" if in_process else "fmu",
        "bearing_fmu": "" if fmus is None else str(Path(fmus["bearings"][0]).resolve()),
        "dt": description.time_step(case), "steps_per_mesh_period": steps_per_period,
        "mesh_periods": periods, "steps_total": n_steps, "speed": case["operation.speed"],
        "speeds": description.bearing_speeds(case), "teeth": list(case["gear_pair.teeth"]),
        "torque": case["operation.torque"], "unbalance": list(case["operation.unbalance"]),
        "clearance": _clearances(case), "tolerance": case["simulation.tolerance"],
        "interrupted": "", "stopped_by": "",
    }
    return _run(case, attrs, where, 0, None, in_process, fmu_dir, fmus, progress, figures,
                flush_seconds, echo=echo_warnings)


def check_periods(periods) -> int:
    """``periods`` (``--periods``, a case's ``simulation.mesh_periods``) as a whole number of
    mesh periods >= 1; RunError naming the value otherwise."""
    if isinstance(periods, bool) or not isinstance(periods, (int, np.integer)) or periods < 1:
        raise RunError(f"--periods {periods!r}: need a whole number of mesh periods >= 1")
    return int(periods)


def resume_run(path: Path | str, periods: int | None = None, fmu_dir: Path | str | None = None,
               progress: bool = True, figures: bool = True,
               flush_seconds: float = 1.0) -> RunSummary:
    """Continue the run of a results file from its last checkpoint (``gsb run --resume``).

    The case comes from the file (``case_toml``), the static solution is solved again and must
    equal the stored one, then the structure, the bearings' warm starts and the laws are
    restored from the checkpoint (:meth:`orchestrator.coupling.master.Master.checkpoint`; through
    FMUs, their serialised FMU states) and the steps go on in the same file: the trajectory is
    that of an uninterrupted run. ``periods`` extends the run (default: the file's own length).

    The checkpoint is numeric arrays (:mod:`fmu_src.state_codec`), checked before anything is
    computed: a pickle (the format of older versions, which can run code when loaded), another
    format, version or kind is refused with a :class:`RunError` naming the file and the reason;
    entries that do not fit the case are refused when restored.
    """
    from fmu_src.case import CaseError
    from orchestrator.analysis.metrics import stored_case

    path = Path(path)
    if not path.is_file():
        raise RunError(f"--resume {path}: no such file")
    pid = live_writer(path)
    if pid is not None:
        raise RunError(f"--resume {path}: process {pid} is still writing it (stop it first: "
                       f"kill -INT {pid})")
    state = run_files.describe_file(path)
    if state.startswith(("open for writing", "not a readable")):
        raise RunError(f"--resume {path}: {state}")
    a = read_attributes(path)
    if a.get("kind") != "run" or "case_toml" not in a:
        raise RunError(f"--resume {path}: not the results file of a gsb run of this version "
                       "(no stored case)")
    if a.get("bearing_fmu"):
        raise RunError(f"--resume {path}: a run of a bearing FMU of your own (or of an SSP) "
                       "cannot be resumed; run it again")
    try:
        case = stored_case(a, str(path))
    except CaseError as exc:
        raise RunError(f"--resume {path}: the stored case does not load: {exc}") from None
    try:
        ckpt = read_checkpoint(path)
        if ckpt is not None:
            decode_checkpoint(ckpt[1])  # the format, version and kind, before any work
    except StateFormatError as exc:
        raise RunError(f"--resume {path}: {exc}") from None
    if ckpt is None:
        raise RunError(f"--resume {path}: the file holds no checkpoint (the run stopped before "
                       "its first flush); run it again")
    rows, blob = ckpt
    with contextlib.suppress(OSError):
        if clear_write_flags(path):  # what h5clear -s does
            print(f"note: {path} was not closed by its run (killed?): its rows after the last "
                  f"checkpoint (step {rows}) are computed again", file=sys.stderr, flush=True)
    steps_per_period = int(a["steps_per_mesh_period"])
    if periods is not None:
        periods = check_periods(periods)
        n_steps = periods * steps_per_period
    else:
        n_steps = int(a["steps_total"])
    if n_steps <= rows:
        raise RunError(f"--resume {path}: the file already holds {rows} steps "
                       f"({rows / steps_per_period:g} mesh periods); give --periods above "
                       f"{rows // steps_per_period} to extend it")
    attrs = {"mesh_periods": a["mesh_periods"] if periods is None else periods,
             "steps_total": n_steps, "interrupted": "", "stopped_by": "",
             "resumed_at_step": rows}
    where = run_files.Target(path, path, path.with_suffix(""))
    in_process = a["mode"] == "in-process"
    return _run(case, attrs, where, rows, blob, in_process, fmu_dir, None, progress, figures,
                flush_seconds, stored_x0=np.asarray(a["static_journal"]))


def _run(case, attrs, where, first, blob, in_process, fmu_dir, fmus, progress, figures,
         flush_seconds, stored_x0=None, echo: bool = True) -> RunSummary:
    """Static solution, then steps ``first`` .. ``steps_total`` into ``where`` (from a
    checkpoint ``blob`` when resuming)."""
    dt = float(attrs.get("dt", description.time_step(case)))
    n_steps = int(attrs["steps_total"])
    path = where.write
    name = where.final.stem
    writer = None  # this run's results file, once the transient starts
    kept = {}  # where the steps of a run that did not complete are

    def give_up(**how) -> Path:
        writer.close(complete=False, **how)
        kept["path"] = where.finish(False)
        return kept["path"]

    with deferred_signals() as received:

        def stop_if_asked(where_: str, writer: ResultsWriter | None = None) -> None:
            if not received:
                return
            sig = signal.Signals(received[0]).name
            kept = "nothing was written" if writer is None else f"{writer.rows} steps kept in"
            if writer is not None:
                kept += " " + str(give_up(stopped_by=f"interrupted by {sig} {where_}",
                                          interrupted=sig))
            raise RunInterrupted(received[0], f"interrupted by {sig} {where_}; {kept}")

        master = build_master(case, None, in_process, fmu_dir, fmus)
        structure = master.structure
        try:
            stop_if_asked("before the static solution")
            static, x0, static_mesh, warnings, static_time = _start(master, case, dt,
                                                                     stop_if_asked, echo)
            if stored_x0 is not None:
                diff = float(np.abs(x0 - stored_x0).max())
                if diff > 0.0:
                    print(f"warning: the static solution differs from the stored one by "
                          f"{diff:.3e} m (another code version or machine): the resumed "
                          f"steps may differ from an uninterrupted run at that level",
                          file=sys.stderr, flush=True)
            if blob is not None:
                try:
                    master.restore(blob)
                except StateFormatError as exc:  # "the checkpoint ...": what does not fit
                    raise RunError(f"--resume {path}: {exc}") from None
                except Exception as exc:
                    raise RunError(f"--resume {path}: the checkpoint does not restore: "
                                   f"{exc}") from exc
            else:
                attrs |= {"static_journal": x0, "static_bearing_force": static.bearing_force,
                          "static_iterations": static.iterations,
                          "static_mesh_force": static_mesh[0],
                          "static_transmission_error": static_mesh[1],
                          "warnings": "\n".join(warnings)}
            stop_if_asked("after the static solution")

            bar = Progress(n_steps, name, enabled=progress)
            start_iterations = master.total_iterations
            start_evals = master.total_bearing_evaluations
            start_relaxed = master.relaxed_steps
            t_start = time.perf_counter()
            try:
                if blob is None:
                    writer = ResultsWriter(path, CHANNELS, _with_units(attrs),
                                           flush_seconds=flush_seconds,
                                           checkpoint=master.checkpoint)
                else:
                    writer = ResultsWriter.resume(path, CHANNELS, first, attrs,
                                                  flush_seconds=flush_seconds,
                                                  checkpoint=master.checkpoint)
            except OSError as exc:
                raise RunError(f"cannot write {path}: {exc}") from None
            bar.update(first)
            for i in range(first, n_steps):
                t = i * dt
                try:
                    report = master.step(t, dt)
                except Exception as exc:
                    into = give_up(checkpoint=False, stopped_by=f"{type(exc).__name__}: {exc}")
                    raise RunError(
                        f"step {i + 1} of {n_steps} (t = {t + dt:.6e} s) failed: {exc}; "
                        f"the {i} steps computed are in {into}") from exc
                mesh_force, te, gear_nodes = structure.step_outputs()
                writer.append(time=(i + 1) * dt, journal_position=report.states[:, :2],
                              journal_velocity=report.states[:, 2:],
                              bearing_force=report.bearing_force, mesh_force=mesh_force,
                              transmission_error=te, gear_nodes=gear_nodes,
                              iterations=report.iterations)
                if progress and (i & 63) == 0:
                    its = (master.total_iterations - start_iterations) / (i + 1 - first)
                    bar.update(i + 1, f"{its:.2f} it/step")
                stop_if_asked(f"after step {i + 1} of {n_steps}", writer)
            wall = time.perf_counter() - t_start
            its = (master.total_iterations - start_iterations) / max(n_steps - first, 1)
            bar.update(n_steps, f"{its:.2f} it/step")
            writer.close(complete=True, wall_time=wall)
            path = where.finish(True)
        except (RunError, RunInterrupted):
            if "path" in kept:  # report what the file kept; the run's error comes first
                with contextlib.suppress(Exception):
                    _store_report(kept["path"])
            raise
        except BaseException as exc:  # a bug or a second Ctrl-C: keep the steps all the same
            if writer is not None and "path" not in kept:
                with contextlib.suppress(Exception):
                    give_up(checkpoint=False, stopped_by=f"{type(exc).__name__}: {exc}")
            raise
        finally:
            master.close()
    summary = RunSummary(path, n_steps - first, wall, static_time,
                         master.total_iterations - start_iterations,
                         master.total_bearing_evaluations - start_evals, static.iterations, x0,
                         warnings=warnings, relaxed_steps=master.relaxed_steps - start_relaxed)
    summary.report = _store_report(path)
    if figures:
        from orchestrator.figures.run import run_figures

        summary.figures = run_figures(path, where.figures)
    return summary


def _store_report(path: Path) -> dict | None:
    """:func:`orchestrator.analysis.metrics.run_report` of a closed results file, stored as its root
    attributes (module docstring); None (nothing stored) below 2 steps."""
    from orchestrator.analysis.metrics import run_report

    results = read_results(path)
    if results["time"].size < 2:
        return None
    report = run_report(results)
    add_attributes(path, **_with_units({
        "dynamic_factor": report["dynamic_factor"],
        "bearing_force_ptp": report["bearing_force_ptp"],
        "line_amplitudes": report["line_amplitudes"], "line_orders": report["line_orders"],
        "line_labels": report["line_labels"], "report_window": report["window_s"]}))
    return report


def static_report(case: Case, positions: np.ndarray) -> str:
    """Eccentricity ratio and position of each journal at X0 (clearance units)."""
    lines = []
    for b, (pos, c) in enumerate(zip(positions, _clearances(case), strict=True)):
        lines.append(f"bearing {b + 1}: s/C = {pos[0] / c:+.4f}, t/C = {pos[1] / c:+.4f}, "
                     f"eccentricity {math.hypot(*pos) / c:.4f}")
    return "\n".join(lines)
