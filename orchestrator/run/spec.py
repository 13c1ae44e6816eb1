"""What a run is: the case (which carries every physical and numerical setting, the bearing
model and the number of mesh periods included), the transport and how many steps.

:class:`RunSpec` is built once from the case (:meth:`RunSpec.of`); the time step, the number
of steps and the results file's settings attributes all derive from it, so no setting has a
second carrier. :func:`orchestrator.coupling.system.build_master` builds its master.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fmu_src import description
from fmu_src.case import Case
from fmu_src.contract import bearing_fmu_name
from fmu_src.units import symbol

__all__ = ["ATTRIBUTE_UNITS", "RunError", "RunSpec", "check_periods", "check_threads",
           "with_units"]


class RunError(RuntimeError):
    """A run that stopped; the message says where and which file keeps the computed steps."""


def check_periods(periods) -> int:
    """``periods`` (``--periods``, a case's ``simulation.mesh_periods``) as a whole number of
    mesh periods >= 1; RunError naming the value otherwise."""
    if isinstance(periods, bool) or not isinstance(periods, (int, np.integer)) or periods < 1:
        raise RunError(f"--periods {periods!r}: need a whole number of mesh periods >= 1")
    return int(periods)


def check_threads(threads, in_process: bool) -> int:
    """``threads`` (``--threads``) as a whole number from 1 to numba's ``NUMBA_NUM_THREADS``,
    above 1 for an in-process run only; RunError naming the value and the limit otherwise
    (:func:`bearing_fmu.hybrid.model.thread_count`)."""
    from bearing_fmu.hybrid.model import thread_count

    try:
        threads = thread_count(threads, "--threads ")
    except ValueError as exc:
        raise RunError(str(exc)) from None
    if threads > 1 and not in_process:
        raise RunError(f"--threads {threads}: threads share the bearings of an in-process run "
                       "(--in-process); through the FMUs the master calls each bearing FMU in "
                       "turn")
    return threads


@dataclass(frozen=True)
class RunSpec:
    """One run: ``case`` (checked, with every override applied), the transport (``in_process``;
    through FMUs ``fmus`` names FMU files of the user's own, else ``fmu_dir`` the folder of
    the built ones), ``steps`` (None: all of ``simulation.mesh_periods``) and ``threads``,
    how many threads share the hybrid bearings of an in-process run
    (:meth:`bearing_fmu.hybrid.model.HybridSet.use_threads`: the same bits whatever the
    count, so it is no setting of the results and not stored with them)."""

    case: Case
    in_process: bool = False
    fmus: dict | None = None
    fmu_dir: Path | str | None = None
    steps: int | None = None
    threads: int = 1

    @classmethod
    def of(cls, case: Case, in_process: bool = False, fmus: dict | None = None,
           fmu_dir=None, steps: int | None = None, threads: int = 1) -> RunSpec:
        """The spec of a case, its number of periods checked (:func:`check_periods`), and its
        steps and threads (:func:`check_threads`)."""
        check_periods(case["simulation.mesh_periods"])
        if steps is not None and (isinstance(steps, bool) or int(steps) < 1):
            raise RunError(f"steps = {steps!r}: need at least one step")
        threads = check_threads(threads, in_process)
        spec = cls(case, in_process, fmus, fmu_dir, None if steps is None else int(steps),
                   threads)
        spec.check_window()
        spec.check_speed_profile()
        return spec

    def check_speed_profile(self) -> None:
        """RunError before the run for a run-up whose ramp is shorter than one period of the
        fastest mesh at the highest speed (``simulation.steps_per_mesh_period`` steps): a
        step would hold the change of speed the meshes see (docs/equations.md "Run-ups")."""
        from fmu_src.description import mesh_period, speed_profile

        p = speed_profile(self.case)
        period = mesh_period(self.case)
        if p.varies and p.shortest_change < period:
            raise RunError(f"drive.speed_profile = {self.case['drive.speed_profile']!r}: a "
                           f"ramp of {p.shortest_change:.3g} s is shorter than one mesh period "
                           f"at {p.max_speed:g} rad/s ({period:.3g} s, "
                           f"{self.case['simulation.steps_per_mesh_period']} steps), which the "
                           f"step cannot resolve: ramp over {period:.3g} s or more")

    def check_window(self) -> None:
        """RunError before the run for a ``simulation.window`` longer than the run (the
        default window, the last revolution of the slowest shaft, becomes the last half of a
        shorter run: :func:`orchestrator.analysis.metrics.report_window`)."""
        from orchestrator.analysis.metrics import window_duration

        text = self.case["simulation.window"]
        length = self.n_steps * self.dt
        if text:
            duration, _ = window_duration(self.case)
            if duration > length * (1.0 + 1e-9):
                raise RunError(f"simulation.window = {text!r} ({duration:.4g} s) is longer "
                               f"than the run ({self.n_steps} steps, {length:.4g} s): shorten "
                               f"it, or lengthen the run (simulation.mesh_periods)")

    @property
    def dt(self) -> float:
        """The time step [s]: a mesh period / ``simulation.steps_per_mesh_period``."""
        return description.time_step(self.case)

    @property
    def n_steps(self) -> int:
        return (self.case["simulation.mesh_periods"] * self.case["simulation.steps_per_mesh_period"]
                if self.steps is None else self.steps)

    @property
    def label(self) -> str:
        """The bearings' model's name (``hybrid``; ``mixed`` for bearings of several models),
        also when the bearing FMUs are this package's own of that model (an SSP archive of
        ``gsb export-ssp``: ``BearingHybrid`` is named ``hybrid`` as in a direct run); for a
        bearing FMU of the user's own, ``fmu-`` and its file's stem, so that the results file
        says whose bearing law it holds."""
        model = description.shared_bearing_model(self.case) or "mixed"
        if self.fmus is None:
            return model
        stems = {Path(p).stem for p in self.fmus["bearings"]}
        if model != "mixed" and stems == {bearing_fmu_name(model)}:
            return model
        stem = Path(self.fmus["bearings"][0]).stem
        return "fmu-" + "".join(c if c.isalnum() or c in "-." else "-" for c in stem)

    def attributes(self) -> dict:
        """The settings stored as root attributes of the results file (numbers in SI units;
        :func:`with_units` adds the units): ``speed`` the input speed, ``speeds``,
        ``bearing_shafts`` and ``clearance`` per bearing (the case's bearing order),
        ``unbalance`` per gear, ``mesh_teeth`` (n_meshes, 2) the teeth of each mesh's gears,
        driver first. The names of the bearings, meshes and gears label the file's
        dimensions (:mod:`orchestrator.run.channels`)."""
        case = self.case
        lay = description.layout(case)
        return {
            "kind": "run", "case": case["case.name"], "case_file": str(case.source),
            "case_toml": case.to_toml(), "bearing_model": self.label,
            "mode": "in-process" if self.in_process else "fmu",
            "bearing_fmu": ("" if self.fmus is None
                            else str(Path(self.fmus["bearings"][0]).resolve())),
            "bearing_fmu_sha256": ("" if self.fmus is None else hashlib.sha256(
                Path(self.fmus["bearings"][0]).read_bytes()).hexdigest()),
            "dt": self.dt, "steps_per_mesh_period": case["simulation.steps_per_mesh_period"],
            "mesh_periods": case["simulation.mesh_periods"], "steps_total": self.n_steps,
            "speed": case["drive.speed"], "speeds": description.bearing_speeds(case),
            "bearing_shafts": [b.shaft for b in lay.bearings],
            "mesh_teeth": np.array(description.mesh_teeth(case), dtype=np.int64).reshape(-1, 2),
            "torque": case["drive.torque"],
            "unbalance": [case[f"gears.{g}.unbalance"] for g in case.names("gears")],
            "clearance": [float(case[f"bearings.{b}.clearance"])
                          for b in case.names("bearings")],
            "tolerance": case["simulation.tolerance"], "interrupted": "", "stopped_by": "",
        }


#: units of the numeric root attributes, stored beside each as ``<name>_unit``
ATTRIBUTE_UNITS = {
    "dt": symbol("time"), "speed": symbol("angular_speed"),
    "speeds": symbol("angular_speed"), "torque": symbol("torque"),
    "unbalance": symbol("length"), "clearance": symbol("length"),
    "static_journal": symbol("length"), "static_bearing_force": symbol("force"),
    "static_mesh_force": symbol("force"), "static_transmission_error": symbol("length"),
    "static_shaft_speed": symbol("angular_speed"),
    "wall_time": symbol("time"), "dynamic_factor": symbol("dimensionless"),
    "bearing_force_ptp": symbol("force"), "transmission_error_ptp": symbol("length"),
    "line_amplitudes": symbol("force"), "line_orders": symbol("dimensionless"),
    "line_frequencies": symbol("frequency"), "report_window": symbol("time"),
}


def with_units(attrs: dict) -> dict:
    """``attrs`` and the unit of each that has one, as ``<name>_unit``."""
    return attrs | {f"{k}_unit": ATTRIBUTE_UNITS[k] for k in attrs if k in ATTRIBUTE_UNITS}
