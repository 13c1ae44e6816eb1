"""``gsb run``: static solution X0 and the nonlinear (or linear) transient of a case.

A run is a :class:`~orchestrator.run.spec.RunSpec` (the case, which carries every setting,
and the transport) taken through the steps of a :class:`Runner`; the rows go to a recorder
that observes the steps: a results file (:class:`~orchestrator.run.results.ResultsWriter`,
:func:`run_case`, :func:`resume_run`) or memory (:class:`~orchestrator.run.result.MemoryRecorder`,
:func:`simulate_case`, behind :func:`orchestrator.api.simulate`).

1. Start: the structure slave and the bearing set, through FMUs (default; fmpy) or in-process
   (:func:`~orchestrator.coupling.system.build_master`; the runner sees only the master's
   interfaces).
2. Static solution X0 (paper Sec. 2.2.3): the master iterates structure static solves and
   bearing linearisations with velocities zero
   (:meth:`orchestrator.coupling.master.Master.solve_static`).
3. End of initialisation: the linear model (Sec. 3.3, Table 4 case 0) freezes the bearings' 8
   coefficients at X0; the modal damping is built on the modes with the bearings' static
   stiffness (Structure docs).
4. Transient (Sec. 3.2): ``steps_per_mesh_period x mesh_periods`` coupled Newmark steps, each
   converged to the case tolerance; every step's channels go to the results file as the run
   goes (:mod:`orchestrator.run.results`: HDF5 SWMR, flushed every second with a checkpoint of
   the coupled state; an interrupted or failed run keeps what it computed, :func:`resume_run`
   continues it). The file's name and what happens to an existing one:
   :mod:`orchestrator.run.files`.

Channels (:func:`orchestrator.run.channels.channels`, with named dimensions, labelled by the
case's names of its nb bearings, its meshes and its gears): ``journal_position`` (nb, 2)
[s, t] and ``journal_velocity`` (nb, 2) of the journal centres, ``bearing_force`` (nb, 2),
``mesh_force`` (n_meshes,), ``transmission_error`` (n_meshes,), ``gear_node`` (n_gears, 2)
(s, t of each gear's node), ``iterations`` (coupled iterations of the step).

Report (:func:`orchestrator.analysis.metrics.run_report`, over the last revolution of the
slowest shaft or the last half of a shorter run; :meth:`RunSummary.report_text`), stored as
numeric root attributes of the results file once the transient stops (complete, failed or
interrupted; at least 2 steps): ``dynamic_factor`` (n_meshes,) [1] (R of each mesh, its max
force over its static load), ``transmission_error_ptp`` (n_meshes,) [m],
``bearing_force_ptp`` (nb,) [N] (peak-to-peak of ||F_b||), ``line_amplitudes`` (nb, n) [N]
(peak amplitudes of the lines of ||F_b||, NaN where the window does not resolve a line),
``line_frequencies`` (n,) [Hz], ``line_orders`` (nb, n) [1] (cycles per revolution of each
bearing's shaft), ``line_labels`` (n,) (strings: "pinion_shaft_1x", "mesh_GMF", ...),
``report_window`` (2,) [s] (start and end of the window) and ``report_window_kind`` (its
name); each numeric attribute with a unit has it in ``<name>_unit``
(:data:`~orchestrator.run.spec.ATTRIBUTE_UNITS`).
"""

from __future__ import annotations

import contextlib
import math
import shlex
import signal
import sys
import time
import warnings as python_warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bearing_fmu.blas_threads import one_blas_thread
from fmu_src import description
from fmu_src.case import Case
from fmu_src.state_codec import StateFormatError
from orchestrator.coupling.master import StepReport, decode_checkpoint
from orchestrator.coupling.system import build_master
from orchestrator.run import files as run_files
from orchestrator.run.channels import channels, coordinates, dims
from orchestrator.run.checks import (
    FIRST_GUESS_EPS,
    OverloadWarning,
    TimeStepWarning,
    overload_message,
    shaft_unbalance,
    time_step_findings,
    unbalance_warnings,
)
from orchestrator.run.progress import Progress, RunInterrupted, deferred_signals
from orchestrator.run.result import MemoryRecorder, Result
from orchestrator.run.results import (
    ResultsWriter,
    add_attributes,
    clear_write_flags,
    live_writer,
    read_attributes,
    read_checkpoint,
    read_results,
)
from orchestrator.run.spec import RunError, RunSpec, check_periods, with_units

__all__ = ["RunSummary", "Runner", "resume_run", "run_case", "simulate_case",
           "stored_summary"]

#: steps per block at most (a compiled call in-process, the master's Python loop otherwise)
#: (:meth:`orchestrator.coupling.master.Master.steps`): signals, the progress bar and the
#: results file's flushes are seen between calls (128 steps of the paper's case: about 20 ms
#: in-process, 60 ms through the FMUs)
BLOCK_STEPS = 128


@dataclass
class RunSummary:
    """What a run did (figures for the README and the benchmark)."""

    results: Path | None  # the results file; None for a run kept in memory
    steps: int
    wall_time: float  # s, transient only
    static_time: float  # s
    iterations: int  # coupled iterations of the transient
    bearing_evaluations: int  # calls of the bearing set (every bearing each)
    static_iterations: int
    static_positions: np.ndarray  # (nb, 2) m
    report: dict | None = None  # orchestrator.analysis.metrics.run_report, None below 2 steps
    warnings: list = field(default_factory=list)  # sentences of the checks before the transient
    notes: list = field(default_factory=list)  # what the checks state once (a deliberate step)
    relaxed_steps: int = 0  # steps whose coupled iteration was relaxed (coupling.master)
    #: (t [s], sub-steps) of each step taken again in sub-steps (coupling.master.SUBSTEPS)
    substeps: list = field(default_factory=list)
    stored: bool = False  # read from the complete results file of the same inputs, not computed

    @property
    def iterations_per_step(self) -> float:
        return self.iterations / max(self.steps, 1)

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.wall_time if self.wall_time > 0 else math.inf

    def describe(self) -> str:
        if self.stored:
            return (f"{self.steps} steps read from the stored results of the same inputs "
                    f"(computed in {self.wall_time:.1f} s, {self.iterations_per_step:.2f} "
                    f"coupled iterations per step); nothing computed: --overwrite computes "
                    f"them again")
        return (f"{self.steps} steps in {self.wall_time:.1f} s ({self.steps_per_second:.0f} "
                f"steps/s), {self.iterations_per_step:.2f} coupled iterations per step, "
                f"{len(self.static_positions) * self.bearing_evaluations} bearing "
                f"evaluations; static solution in "
                f"{self.static_iterations} iteration{'s' * (self.static_iterations != 1)} "
                f"({self.static_time:.2f} s)"
                + (f"; {self.relaxed_steps} step(s) relaxed at a kink of a bearing law"
                   if self.relaxed_steps else "")
                + (f"; {substeps_text(self.substeps)}" if self.substeps else ""))

    def report_text(self) -> str:
        """The report (``report``) in a few lines: R and the transmission-error peak-to-peak
        of each mesh, the bearing-force peak-to-peak [N] and a table of the line amplitudes
        of ||F_b|| [N] per bearing, each named as in the case."""
        r = self.report
        if r is None:
            return f"no report: {self.steps} step(s), at least 2 needed"
        return report_text(r)


def report_text(r: dict) -> str:
    """:meth:`RunSummary.report_text` of a report
    (:func:`orchestrator.analysis.metrics.run_report`)."""
    t0, t1 = r["window_s"]
    meshes, bearings = list(r["mesh_names"]), list(r["bearing_names"])
    R, te = np.atleast_1d(r["dynamic_factor"]), np.atleast_1d(r["transmission_error_ptp"])
    lines = [f"report over the {r['window_kind']} (t = {t0:.6g} - {t1:.6g} s):"]
    if len(meshes) == 1:
        which = "" if meshes[0] == "mesh" else f" (mesh {meshes[0]})"  # a pair's usual name
        lines.append(f"dynamic factor R = {R[0]:.3f}, transmission error peak-to-peak "
                     f"{te[0] * 1e6:.3g} um{which}")
    else:
        lines.append("dynamic factor R, transmission error peak-to-peak per mesh: "
                     + "; ".join(f"{m}: R = {v:.3f}, TE {e * 1e6:.3g} um"
                                 for m, v, e in zip(meshes, R, te, strict=True)))
    lines.append("bearing force peak-to-peak [N]: " + ", ".join(
        f"{b}: {v:.0f}" for b, v in zip(bearings, r["bearing_force_ptp"], strict=True)))
    amplitudes = np.asarray(r["line_amplitudes"])
    width = max(8, *(len(b) + 1 for b in bearings))
    label_width = max(len(s) for s in r["line_labels"]) + 1
    lines.append("line amplitudes of ||F_b|| [N] per bearing:")
    lines.append(f"{'line':<{label_width}}{'f [Hz]':>9}"
                 + "".join(f"{b:>{width}}" for b in bearings))
    for k, label in enumerate(r["line_labels"]):
        lines.append(f"{label:<{label_width}}{r['line_frequencies'][k]:9.4g}" + "".join(
            f"{'-':>{width}}" if np.isnan(v) else f"{v:{width}.1f}" for v in amplitudes[:, k]))
    orders = np.asarray(r["line_orders"])
    lines.append("orders of the lines, cycles per revolution of each bearing's shaft:")
    seen: dict[tuple, list] = {}
    for b, name in enumerate(bearings):
        key = tuple(np.round(orders[b], 9))
        seen.setdefault(key, []).append(name)
    for key, names in seen.items():
        lines.append(f"  bearing{'s' * (len(names) > 1)} {', '.join(names)}: " + ", ".join(
            f"{label} {q:.4g}" for label, q in zip(r["line_labels"], key, strict=True)))
    speeds = r.get("window_speeds")
    if speeds is not None and speeds[0] != speeds[1]:
        lines.append(f"(-: the input speed varies over the window, {speeds[0]:.4g} -> "
                     f"{speeds[1]:.4g} rad/s: a run-up has no lines at fixed frequencies)")
    elif np.isnan(amplitudes).any():
        lines.append("(-: a line the window does not resolve)")
    return "\n".join(lines)


@dataclass
class Static:
    """What the static step leaves: the master's report, X0 (nb, 2) [m], the static force [N]
    and transmission error [m] of each mesh, the gear nodes' u, v (n_gears, 2) [m], the
    checks' warnings and notes and the wall time [s]."""

    report: StepReport
    x0: np.ndarray
    mesh_force: np.ndarray
    transmission_error: np.ndarray
    gear_node: np.ndarray
    warnings: list
    seconds: float
    notes: list = field(default_factory=list)
    shaft_speed: np.ndarray = None  # (n_shafts,) [rad/s] at t = 0


class Stop(Exception):
    """A signal received, seen between two steps (``where``: "after step 12 of 64", ...)."""

    def __init__(self, signum: int, where: str):
        super().__init__(where)
        self.signum = signum
        self.where = where

    @property
    def signame(self) -> str:
        return signal.Signals(self.signum).name

    @property
    def stopped_by(self) -> str:
        """How the run ended, as its results record it."""
        return f"interrupted by {self.signame} {self.where}"

    def message(self, kept: str) -> RunInterrupted:
        """The exception the run raises; ``kept``: where its steps are."""
        return RunInterrupted(self.signum, f"{self.stopped_by}; {kept}")


class StepFailed(Exception):
    """Step ``index`` (0-based), from ``t`` [s], raised ``cause``."""

    def __init__(self, index: int, t: float, cause: BaseException):
        super().__init__(str(cause))
        self.index, self.t, self.cause = index, t, cause

    @property
    def stopped_by(self) -> str:
        """How the run ended, as its results record it."""
        return f"{type(self.cause).__name__}: {self}"

    def error(self, spec: RunSpec, kept: str, rows: int | str | None = None) -> RunError:
        """The exception the run raises: the step, its time [s], what failed in units and
        what to do (:func:`failure_text`); ``kept``: where its ``rows`` steps are."""
        rows = self.index if rows is None else rows
        return RunError(f"step {self.index + 1} of {spec.n_steps} (t = "
                        f"{self.t + spec.dt:.6g} s) failed: {failure_text(spec.case, self.cause)}"
                        f"; the {rows} steps computed are in {kept}")


def failure_text(case: Case, cause: BaseException) -> str:
    """What failed in a step, for the user: for a bearing that carries where it failed
    (``bearing``, its name, or ``bearing_index``, its 0-based place in the case's order, and
    ``state``, the global s, t [m] and their rates [m/s], as the in-process bearing set and
    the FMU transport attach them), the bearing by name, its journal's position in um and
    eccentricity ratio against the clearance, and what to change; else the cause's own
    message."""
    name, state = _failed_bearing(case, cause), getattr(cause, "state", None)
    if name is None or state is None or len(state) != 4:
        return str(cause)
    s, t, sd, td = (float(v) for v in state)
    clearance = float(case[f"bearings.{name}.clearance"])
    eps = math.hypot(s, t) / clearance
    where = (f"s = {s * 1e6:.1f} um, t = {t * 1e6:.1f} um (radial clearance "
             f"{clearance * 1e6:.1f} um)")
    if eps >= 1.0:
        lay = description.layout(case)
        shaft = lay.bearings[case.names("bearings").index(name)].shaft
        if any(f"shaft {shaft}," in w for w in unbalance_warnings(case)):
            keys = " or ".join(shaft_unbalance(lay, shaft)[1])
            todo = (f"the unbalance force of shaft {shaft} exceeds its bearings' load capacity "
                    f"(the warning above): lower {keys} (--unbalance sets every gear's) or "
                    "drive.speed (--speed)")
        else:
            todo = ("lower the load (--torque, --unbalance) or the speed (--speed), or give "
                    f"the film more capacity (bearings.{name}.viscosity, "
                    f"bearings.{name}.length, a smaller bearings.{name}.clearance)")
        return (f"bearing {name}'s journal reached the bearing wall: eccentricity ratio "
                f"{eps:.4g} (must stay below 1) at {where}; {todo}")
    reason = str(getattr(cause, "reason", "")) or str(cause)
    return (f"bearing {name} failed at {where}, eccentricity ratio {eps:.4g}, velocity "
            f"s_dot = {sd:.4g} m/s, t_dot = {td:.4g} m/s: {reason}")


def _failed_bearing(case: Case, cause: BaseException) -> str | None:
    """The name of the bearing a step's error carries (module :func:`failure_text`), None if
    it carries none the case knows."""
    names = case.names("bearings")
    bearing = getattr(cause, "bearing", None)
    if isinstance(bearing, str) and bearing in names:
        return bearing
    index = getattr(cause, "bearing_index", None)
    if isinstance(index, (int, np.integer)) and 0 <= index < len(names):
        return names[int(index)]
    if isinstance(bearing, (int, np.integer)) and 1 <= bearing <= len(names):
        return names[int(bearing) - 1]  # a 1-based number (transports of earlier versions)
    return None


class Runner:
    """The steps of a run: :meth:`start` (the master and its slaves), :meth:`static` (X0 and
    the end of initialisation), :meth:`transient` (the coupled steps, each row handed to a
    recorder) and :meth:`finish` (the slaves released).

    ``received``: the signals received so far
    (:func:`~orchestrator.run.progress.deferred_signals`), checked between two steps
    (:class:`Stop`); ``echo``: print the checks' warnings on stderr."""

    def __init__(self, spec: RunSpec, received=(), echo: bool = True):
        self.spec = spec
        self.received = received
        self.echo = echo
        self.master = None
        self._speeds = None  # (speed profile, layout) of shaft_speeds

    def stop_if_asked(self, where: str) -> None:
        if self.received:
            raise Stop(self.received[0], where)

    def start(self) -> None:
        """The master and its two slaves (:func:`~orchestrator.coupling.system.build_master`)."""
        s = self.spec
        self.master = build_master(s.case, s.in_process, s.fmu_dir, s.fmus, threads=s.threads)
        self.stop_if_asked("before the static solution")

    def static(self) -> Static:
        """Static solution X0 and the end of initialisation; RunError if there is none."""
        case, master = self.spec.case, self.master
        t0 = time.perf_counter()
        try:
            static = master.solve_static()
        except Exception as exc:
            try:
                why = overload_message(case) or overload_message(case, FIRST_GUESS_EPS)
            except Exception:  # the explanation must not hide the failure
                why = None
            if why is not None:
                raise RunError(f"{case.source}: no static solution: {why}") from None
            name = _failed_bearing(case, exc)
            at = "" if name is None else f" at bearing {name}"
            raise RunError(f"{case.source}: static solution failed{at}: {exc}") from exc
        x0 = static.states[:, :2].copy()
        self.stop_if_asked("after the static solution")
        # leave initialisation: linear bearings freeze, the structure builds its modal
        # damping on the modes with the bearings' static stiffness
        structure = master.structure
        master.exit_initialization()
        # read after leaving initialisation: a gear-shaft FMU in initialisation mode would
        # solve its static problem again for outputs read after the final laws were set
        mesh_force, te, gear_node = structure.step_outputs()
        try:
            steps, notes = time_step_findings(case, master.laws, self.spec.dt,
                                              structure.physics)
        except (ValueError, np.linalg.LinAlgError) as exc:  # a check, not the run
            steps, notes = [f"the time-step check could not run: {exc}"], []
        notes = run_up_notes(case, self.spec.dt) + notes
        overloads = unbalance_warnings(case)
        warnings = overloads + steps
        if self.echo:  # Python warnings: the command line prints each as one line
            for texts, category in ((overloads, OverloadWarning), (steps, TimeStepWarning)):
                for text in texts:
                    python_warnings.warn(text, category, stacklevel=2)
        return Static(static, x0, mesh_force, te, np.array(gear_node, dtype=float), warnings,
                      time.perf_counter() - t0, notes, self.shaft_speeds([0.0])[0])

    def shaft_speeds(self, times) -> np.ndarray:
        """(len(times), n_shafts) each shaft's signed speed about +z [rad/s] at ``times`` [s]
        (:func:`gear_fmu.loads.shaft_speeds` at the input speed of
        :func:`fmu_src.description.speed_profile`)."""
        from fmu_src.description import layout, speed_profile
        from gear_fmu.loads import shaft_speeds

        if self._speeds is None:
            self._speeds = (speed_profile(self.spec.case), layout(self.spec.case))
        profile, lay = self._speeds
        return shaft_speeds(lay, np.array([profile.speed(float(t)) for t in times])[:, None])

    @one_blas_thread
    def transient(self, recorder, first: int = 0, bar: Progress | None = None) -> dict:
        """Steps ``first`` .. ``n_steps`` - 1, each row appended to ``recorder``; returns the
        counts of the transient (``wall_time`` [s], ``iterations``, ``bearing_evaluations``,
        ``relaxed_steps``). Raises :class:`StepFailed` and :class:`Stop`."""
        master, dt, n_steps = self.master, self.spec.dt, self.spec.n_steps
        structure = master.structure
        start = (master.total_iterations, master.total_bearing_evaluations,
                 master.relaxed_steps, len(master.substepped))
        t_start = time.perf_counter()
        if bar is not None:
            bar.update(first)
        i = first
        while i < n_steps:
            t = i * dt
            try:
                block = master.steps(i, dt, min(BLOCK_STEPS, n_steps - i))
                if block is None:
                    report = master.step(t, dt)
            except Exception as exc:
                raise StepFailed(i, t, exc) from exc
            if block is None:
                mesh_force, te, gear_nodes = structure.step_outputs()
                recorder.append(time=(i + 1) * dt, journal_position=report.states[:, :2],
                                journal_velocity=report.states[:, 2:],
                                bearing_force=report.bearing_force, mesh_force=mesh_force,
                                transmission_error=te, gear_node=gear_nodes,
                                shaft_speed=self.shaft_speeds([(i + 1) * dt])[0],
                                iterations=report.iterations)
                last, i = i, i + 1
            else:
                last, i = i, i + block.count
                self._record(recorder, block, last, dt)
                if block.error is not None:
                    raise StepFailed(i, i * dt, block.error) from block.error
            if bar is not None and (last >> 6) != (i >> 6):  # every 64 steps
                its = (master.total_iterations - start[0]) / (i - first)
                bar.update(i, f"{its:.2f} it/step")
            self.stop_if_asked(f"after step {i} of {n_steps}")
        done = {"wall_time": time.perf_counter() - t_start,
                "iterations": master.total_iterations - start[0],
                "bearing_evaluations": master.total_bearing_evaluations - start[1],
                "relaxed_steps": master.relaxed_steps - start[2],
                "substeps": master.substepped[start[3]:]}
        if bar is not None:
            bar.update(n_steps, f"{done['iterations'] / max(n_steps - first, 1):.2f} it/step")
        return done

    def _record(self, recorder, block, first: int, dt: float) -> None:
        """The rows of a block of steps from step ``first``
        (:meth:`~orchestrator.coupling.master.Master.steps`); a block that ended on a failed
        step does not flush (the state after it is not one to resume from)."""
        if block.count:
            states = block.states
            times = np.arange(first + 1, first + 1 + block.count) * dt
            recorder.append_rows(
                block.count, flush=block.error is None, time=times,
                shaft_speed=self.shaft_speeds(times),
                journal_position=states[:, :, :2], journal_velocity=states[:, :, 2:],
                bearing_force=block.bearing_force, mesh_force=block.mesh_force,
                transmission_error=block.transmission_error, gear_node=block.gear_nodes,
                iterations=block.iterations)

    def finish(self) -> None:
        """Release the slaves (the FMU instances through FMUs)."""
        if self.master is not None:
            self.master.close()

    def summary(self, static: Static, done: dict, path: Path | None, steps: int) -> RunSummary:
        return RunSummary(path, steps, done["wall_time"], static.seconds, done["iterations"],
                          done["bearing_evaluations"], static.report.iterations, static.x0,
                          warnings=static.warnings, notes=static.notes,
                          relaxed_steps=done["relaxed_steps"], substeps=done["substeps"])


def substeps_text(substeps) -> str:
    """``"N step(s) ... "``: the steps taken in sub-steps, ``(t [s], count)`` each
    (:data:`orchestrator.coupling.master.SUBSTEPS`), the first five times."""
    at = ", ".join(f"{t:.6g} s ({m})" for t, m in substeps[:5])
    more = f" and {len(substeps) - 5} more" if len(substeps) > 5 else ""
    return (f"{len(substeps)} step(s) whose coupled iteration did not converge taken again "
            f"in sub-steps, at t = {at}{more}")


def run_up_notes(case, dt: float) -> list[str]:
    """What a run-up (``drive.speed_profile``) changes, said once on the run: the speeds,
    the inertia of the ramp, the time step fixed from the highest mesh frequency reached;
    nothing at constant speed."""
    from fmu_src.description import mesh_period, speed_profile

    p = speed_profile(case)
    if not p.varies:
        return []
    return [f"run-up: the input speed follows drive.speed_profile ({p.describe()}; up to "
            f"{p.max_acceleration:.4g} rad/s^2: the train's inertia loads the torsion while it "
            f"changes); dt = {dt:.4g} s is fixed from the fastest mesh at {p.max_speed:g} "
            f"rad/s ({1.0 / mesh_period(case):.4g} Hz); the meshes, unbalances and bearings "
            f"follow the speed"]


def _substep_attributes(substeps) -> dict:
    """The results file's record of the steps taken in sub-steps: the sentence, and every
    one's start time [s] and sub-step count; nothing when there are none."""
    if not substeps:
        return {}
    return {"substeps": substeps_text(substeps),
            "substep_times": np.array([t for t, _ in substeps]),
            "substep_counts": np.array([m for _, m in substeps], dtype=np.int64)}


def _static_attributes(static: Static) -> dict:
    return {"static_journal": static.x0, "static_bearing_force": static.report.bearing_force,
            "static_iterations": static.report.iterations,
            "static_mesh_force": static.mesh_force,
            "static_transmission_error": static.transmission_error,
            "static_gear_node": static.gear_node,
            "static_shaft_speed": static.shaft_speed,
            "warnings": "\n".join(static.warnings), "notes": "\n".join(static.notes)}


def simulate_case(spec: RunSpec, progress: bool = False, echo_warnings: bool = True) -> Result:
    """The run of ``spec`` kept in memory (:func:`orchestrator.api.simulate`); raises
    :class:`~orchestrator.run.spec.RunError` or :class:`~orchestrator.run.progress.RunInterrupted`
    with the steps
    computed so far in the exception's ``result``."""
    from orchestrator.analysis.metrics import run_report

    attrs = with_units(spec.attributes())
    coords = coordinates(spec.case)
    recorder = MemoryRecorder(channels(coords), attrs, coords)
    with deferred_signals() as received:
        runner = Runner(spec, received, echo_warnings)
        try:
            runner.start()
            static = runner.static()
            recorder.attrs |= with_units(_static_attributes(static))
            bar = Progress(spec.n_steps, spec.case["case.name"], enabled=progress)
            done = runner.transient(recorder, 0, bar)
        except Stop as stop:
            recorder.close(False, interrupted=stop.signame, stopped_by=stop.stopped_by)
            exc = stop.message(f"{recorder.rows} steps kept in the result")
            exc.result = recorder.result()
            raise exc from None
        except StepFailed as failed:
            recorder.close(False, stopped_by=failed.stopped_by)
            exc = failed.error(spec, "the exception's result")
            exc.result = recorder.result()
            raise exc from failed.cause
        finally:
            runner.finish()
    recorder.close(True, wall_time=done["wall_time"])
    summary = runner.summary(static, done, None, spec.n_steps)
    result = recorder.result(summary)
    if spec.n_steps >= 2:
        summary.report = run_report(result.as_dict())
        result.attrs |= with_units(_report_attributes(summary.report))
    return result


def run_case(case: Case, in_process: bool = False, out_dir: Path | str = "results",
             fmu_dir: Path | str | None = None, progress: bool = True, fmus: dict | None = None,
             steps: int | None = None, overwrite: bool = False, flush_seconds: float = 1.0,
             echo_warnings: bool = True, threads: int = 1) -> RunSummary:
    """Run a case into a results file (module docstring); returns a :class:`RunSummary`.

    The case carries every setting (the bearing models in ``bearings.*.model``, the length in
    ``simulation.mesh_periods``: :meth:`fmu_src.case.Case.with_overrides`). ``steps``: stop
    after this many time steps (a quick look; default: all the periods'). ``echo_warnings``:
    print the checks' warnings on stderr (they are also in the summary and the results file).
    ``threads``: how many threads share the hybrid bearings of an in-process run
    (:class:`~orchestrator.run.spec.RunSpec`).
    The results file is named after the effective parameters
    (:func:`orchestrator.run.files.results_name`). An existing complete one of the same inputs
    answers instead of a run (:func:`stored_summary`, ``summary.stored``; ``overwrite``
    computes it again and replaces it once complete), an incomplete one stops the run before
    it starts unless ``overwrite``, one of other inputs always does
    (:func:`orchestrator.run.files.target`).

    ``fmus``: run these FMU files instead of the built ones
    (:func:`~orchestrator.coupling.system.build_master`); the results are then named after the
    bearing FMU file. Raises :class:`~orchestrator.run.spec.RunError` (with the results file that
    keeps the steps
    computed) if the static solution or a step fails, and
    :class:`~orchestrator.run.progress.RunInterrupted` after SIGINT or SIGTERM, which stop the
    run between two steps with the results file closed and marked interrupted.
    """
    spec = RunSpec.of(case, in_process, fmus, fmu_dir, steps, threads)
    name = run_files.results_name(spec.case, spec.label, in_process, steps,
                                  None if fmus is None else fmus["bearings"][0])
    attributes = spec.attributes()
    try:
        where = run_files.target(out_dir, name, overwrite, attributes)
    except run_files.TargetError as exc:
        raise RunError(str(exc)) from None
    if where.stored:
        return stored_summary(where.final, spec.case["simulation.window"])
    return _run_to_file(spec, attributes, where, progress=progress,
                        flush_seconds=flush_seconds, echo=echo_warnings)


def stored_summary(path: Path, window: str | None = None) -> RunSummary:
    """The summary of a complete results file, read from it (nothing computed): its steps,
    wall time, coupled iterations, static solution and report
    (:func:`orchestrator.analysis.metrics.run_report` of its channels, over ``window``, the
    ``simulation.window`` of this request, when given, instead of the stored case's)."""
    from orchestrator.analysis.metrics import run_report

    results = read_results(path)
    a = results["attrs"]
    steps = len(results["time"])
    warnings, notes = ([w for w in str(a.get(key, "")).split("\n") if w]
                       for key in ("warnings", "notes"))
    return RunSummary(Path(path), steps, float(a.get("wall_time", 0.0)), 0.0,
                      int(np.sum(results["iterations"])), 0,
                      int(a.get("static_iterations", 0)), np.asarray(a["static_journal"]),
                      report=run_report(results, window) if steps >= 2 else None,
                      warnings=warnings, notes=notes, stored=True)


def resume_run(path: Path | str, periods: int | None = None, fmu_dir: Path | str | None = None,
               progress: bool = True, flush_seconds: float = 1.0,
               threads: int = 1) -> RunSummary:
    """Continue the run of a results file from its last checkpoint (``gsb run --resume``).

    The case comes from the file (``case_toml``), the static solution is solved again and must
    equal the stored one, then the structure, the bearings' warm starts and the laws are
    restored from the checkpoint (:meth:`orchestrator.coupling.master.Master.checkpoint`;
    through FMUs, their serialised FMU states) and the steps go on in the same file: the
    trajectory is that of an uninterrupted run. ``periods`` extends the run (default: the
    file's own length); ``threads`` as :func:`run_case`'s (the same bits).

    The checkpoint is numeric arrays (:mod:`fmu_src.state_codec`), checked before anything is
    computed: a pickle (the format of older versions, which can run code when loaded), another
    format, version or kind is refused with a :class:`~orchestrator.run.spec.RunError` naming
    the file and the reason; entries that do not fit the case are refused when restored.
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
    steps_per_period = case["simulation.steps_per_mesh_period"]
    if periods is not None:
        case = case.with_overrides({"simulation.mesh_periods": check_periods(periods)})
    steps = None if periods is not None else int(a["steps_total"])
    spec = RunSpec.of(case, a["mode"] == "in-process", None, fmu_dir, steps, threads)
    if spec.n_steps <= rows:
        raise RunError(f"--resume {path}: the file already holds {rows} steps "
                       f"({rows / steps_per_period:g} mesh periods); give --periods above "
                       f"{rows // steps_per_period} to extend it")
    attrs = {"mesh_periods": a["mesh_periods"] if periods is None else periods,
             "steps_total": spec.n_steps, "interrupted": "", "stopped_by": "",
             "resumed_at_step": rows}
    where = run_files.Target(path, path)
    return _run_to_file(spec, attrs, where, rows, blob, progress, flush_seconds,
                        stored_x0=np.asarray(a["static_journal"]))


def _run_to_file(spec: RunSpec, attrs: dict, where, first: int = 0, blob=None,
                 progress: bool = True, flush_seconds: float = 1.0, stored_x0=None,
                 echo: bool = True) -> RunSummary:
    """The runner's steps with a results file as recorder: a new one (``blob`` None), or
    ``where.write`` continued after its first ``first`` rows from the checkpoint ``blob``."""
    path, name = where.write, where.final.stem
    writer = None  # this run's results file, once the transient starts
    kept = {}  # where the steps of a run that did not complete are

    def give_up(**how) -> Path:
        writer.close(complete=False, **how)
        kept["path"] = where.finish(False)
        return kept["path"]

    with deferred_signals() as received:
        runner = Runner(spec, received, echo)
        try:
            runner.start()
            static = runner.static()
            if stored_x0 is not None:
                diff = float(np.abs(static.x0 - stored_x0).max())
                if diff > 0.0:
                    print(f"warning: the static solution differs from the stored one by "
                          f"{diff:.3e} m (another code version or machine): the resumed "
                          f"steps may differ from an uninterrupted run at that level",
                          file=sys.stderr, flush=True)
            if blob is not None:
                try:
                    runner.master.restore(blob)
                except StateFormatError as exc:  # "the checkpoint ...": what does not fit
                    raise RunError(f"--resume {path}: {exc}") from None
                except Exception as exc:
                    raise RunError(f"--resume {path}: the checkpoint does not restore: "
                                   f"{exc}") from exc
            else:
                attrs |= _static_attributes(static)
            runner.stop_if_asked("after the static solution")
            try:
                coords = coordinates(spec.case)
                if blob is None:
                    writer = ResultsWriter(path, channels(coords), with_units(attrs),
                                           flush_seconds=flush_seconds,
                                           checkpoint=runner.master.checkpoint, dims=dims,
                                           coords=coords)
                else:
                    writer = ResultsWriter.resume(path, channels(coords), first, attrs,
                                                  flush_seconds=flush_seconds,
                                                  checkpoint=runner.master.checkpoint)
            except OSError as exc:
                raise RunError(f"cannot write {path}: {exc}") from None
            bar = Progress(spec.n_steps, name, enabled=progress)
            done = runner.transient(writer, first, bar)
            writer.close(complete=True, wall_time=done["wall_time"],
                         **_substep_attributes(done["substeps"]))
            path = where.finish(True)
        except Stop as stop:
            if writer is None:
                raise stop.message("nothing was written") from None
            into = give_up(stopped_by=stop.stopped_by, interrupted=stop.signame)
            with contextlib.suppress(Exception):
                _store_report(into)
            raise stop.message(f"{_rows_in(into)} steps kept in {into}; `gsb run --resume "
                               f"{shlex.quote(str(into))}` continues it") from None
        except StepFailed as failed:
            into = give_up(checkpoint=False, stopped_by=failed.stopped_by)
            with contextlib.suppress(Exception):
                _store_report(into)
            raise failed.error(spec, into, _rows_in(into)) from failed.cause
        except RunError:
            raise
        except BaseException as exc:  # a bug or a second Ctrl-C: keep the steps all the same
            if writer is not None and "path" not in kept:
                with contextlib.suppress(Exception):
                    give_up(checkpoint=False, stopped_by=f"{type(exc).__name__}: {exc}")
            raise
        finally:
            runner.finish()
    summary = runner.summary(static, done, path, spec.n_steps - first)
    summary.report = _store_report(path)
    return summary


def _rows_in(path: Path) -> int | str:
    """The rows a closed results file holds, read from the file (the count a user's reader
    sees, whatever was buffered or flushed when the run stopped); "?" if it cannot be read."""
    from orchestrator.run.results import open_results

    try:
        with open_results(path) as f:
            return int(f["time"].shape[0])
    except (OSError, KeyError):
        return "?"


def _report_attributes(report: dict) -> dict:
    return {"dynamic_factor": report["dynamic_factor"],
            "transmission_error_ptp": report["transmission_error_ptp"],
            "bearing_force_ptp": report["bearing_force_ptp"],
            "line_amplitudes": report["line_amplitudes"], "line_orders": report["line_orders"],
            "line_frequencies": report["line_frequencies"],
            "line_labels": report["line_labels"], "report_window": report["window_s"],
            "report_window_kind": report["window_kind"]}


def _store_report(path: Path) -> dict | None:
    """:func:`orchestrator.analysis.metrics.run_report` of a closed results file, stored as
    its root attributes (module docstring); None (nothing stored) below 2 steps."""
    from orchestrator.analysis.metrics import run_report

    results = read_results(path)
    if results["time"].size < 2:
        return None
    report = run_report(results)
    add_attributes(path, **with_units(_report_attributes(report)))
    return report


def static_report(case: Case, positions: np.ndarray) -> str:
    """Eccentricity ratio and position of each journal at X0 (clearance units)."""
    lines = []
    names = case.names("bearings")
    clearances = [float(case[f"bearings.{b}.clearance"]) for b in names]
    for b, pos, c in zip(names, positions, clearances, strict=True):
        lines.append(f"bearing {b}: s/C = {pos[0] / c:+.4f}, t/C = {pos[1] / c:+.4f}, "
                     f"eccentricity {math.hypot(*pos) / c:.4f}")
    return "\n".join(lines)
