"""The Python API: a case in, results in memory out (re-exported by :mod:`orchestrator`).

>>> import orchestrator as gsb
>>> case = gsb.load_case("baguet2010_spur")
>>> case["drive.speed"]  # SI units: rad/s
325.0

``gsb.simulate(case, periods=64)`` runs it and returns a
:class:`~orchestrator.run.result.Result`; ``result["journal_position"]`` is an array (time,
bearing, axis) [m] and
``result.to_xarray()`` the same labelled. :func:`sweep` runs a parametric sweep on Dask,
:func:`modes` linearises a case about its static solution and :func:`campbell` does it over
speeds.
"""

from __future__ import annotations

import itertools
from pathlib import Path

from fmu_src.case import Case, load_case
from orchestrator.run.result import Result
from orchestrator.run.spec import RunSpec

__all__ = ["campbell", "modes", "read_result", "simulate", "sweep"]


def _case(case) -> Case:
    return case if isinstance(case, Case) else load_case(case)


def _with(case: Case, periods: int | None, bearing: str | None) -> Case:
    """``periods`` and ``bearing`` as the case fields they are (``simulation.mesh_periods``,
    ``bearings.*.model``: every bearing), through the case's one override path and its
    checks."""
    fields = {}
    if periods is not None:
        fields["simulation.mesh_periods"] = periods
    if bearing is not None:
        fields["bearings.*.model"] = bearing
    return case.with_overrides(fields) if fields else case


def simulate(case, periods: int | None = None, bearing: str | None = None, *,
             in_process: bool = False, steps: int | None = None,
             results_dir: str | Path | None = None, fmu_dir: str | Path | None = None,
             progress: bool = True, threads: int = 1) -> Result:
    """Static solution X0, then the transient of ``case``; the result in memory.

    Parameters
    ----------
    case : Case or str or path
        A case (:func:`fmu_src.case.load_case`), the name of a shipped case or a case file.
    periods : int, optional
        Mesh periods to simulate (the case's ``simulation.mesh_periods``).
    bearing : str, optional
        Bearing model of every bearing (the case's ``bearings.*.model``: ``hybrid``,
        ``short``, ``fd``, ``linear``, ``lumped``).
    in_process : bool
        Drive the physics objects directly instead of the FMUs (same numbers, bit for bit).
    steps : int, optional
        Stop after this many time steps.
    results_dir : path, optional
        Also write the results file there, as ``gsb run --out`` does (named after the
        parameters, never overwritten; HDF5 that xarray opens with ``engine="h5netcdf"``);
        the same call again reads that file instead of computing it.
    fmu_dir : path, optional
        Folder of the built FMUs (default: the per-user cache, built there if missing).
    progress : bool
        A progress line on stderr.
    threads : int
        In-process: how many threads share the hybrid bearings (the same numbers, bit for
        bit; faster with a core to spare, which each thread keeps busy while the run lasts).

    Returns
    -------
    Result
        ``result[name]`` for the channels (:mod:`orchestrator.run.channels`),
        ``result.report`` (R, bearing-force peak-to-peak, order lines), ``result.attrs`` (the
        settings), ``result.to_xarray()``.

    Raises
    ------
    fmu_src.fields.CaseError
        A case or an override that cannot run (the message names the field and the limit).
    orchestrator.run.spec.RunError
        No static solution, or a step that failed (``exc.result``: the steps computed).
    orchestrator.run.progress.RunInterrupted
        Ctrl-C or SIGTERM, between two steps (``exc.result``: the steps computed).
    """
    from orchestrator.run.runner import run_case, simulate_case

    case = _with(_case(case), periods, bearing)
    if results_dir is None:
        return simulate_case(RunSpec.of(case, in_process, None, fmu_dir, steps, threads),
                             progress=progress)
    summary = run_case(case, in_process=in_process, out_dir=results_dir, fmu_dir=fmu_dir,
                       progress=progress, steps=steps, threads=threads)
    result = Result.from_file(summary.results)
    result.summary = summary
    return result


def read_result(path: str | Path) -> Result:
    """The channels and settings of a results file (``gsb run``'s, or :func:`simulate`'s with
    ``results_dir``), also while a run writes it. FileNotFoundError or ValueError naming the
    file when it is missing or not a run's results file (a sweep file: ``gsb plot``)."""
    from orchestrator.run.results import read_attributes

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such results file")
    try:
        kind = read_attributes(path).get("kind")
    except OSError as exc:
        raise ValueError(f"{path}: not a readable results file ({exc})") from None
    if kind != "run":
        raise ValueError(f"{path}: not the results file of a run (kind {kind!r}); a sweep's "
                         "file is read with orchestrator.sweeps.file.read_sweep")
    return Result.from_file(path)


def sweep(case, vary: dict, path: str | Path, periods: int, bearings=None,
          steady_periods: int = 26, scheduler: str | None = None, n_workers: int = 2,
          progress: bool = True):
    """Every combination of the values in ``vary`` (``{"drive.speed": [300, 325, 350],
    ...}``, values as in a case file) and of ``bearings`` (default: the case's model), each an
    in-process run of ``periods`` mesh periods on Dask (``scheduler``: a cluster's address;
    default: ``n_workers`` local processes), written to the sweep file ``path`` as the points
    complete. Returns :class:`orchestrator.sweeps.runner.SweepResult`; ``gsb plot path`` draws
    its figures."""
    from orchestrator.sweeps.runner import SweepPoint, run_sweep

    keys = list(vary)
    models = [None] if bearings is None else list(bearings)
    points = [SweepPoint(dict(zip(keys, values, strict=True)), model)
              for model in models for values in itertools.product(*vary.values())]
    return run_sweep(_case(case), points, path, periods, steady_periods, scheduler,
                     n_workers, progress, vary_keys=keys)


def modes(case, undamped: bool = True):
    """The case linearised about its static solution X0: bearing Kb, Cb, the mean mesh
    stiffness, the damped (and undamped) modes
    (:class:`orchestrator.analysis.campbell.Linearised`)."""
    from orchestrator.analysis.campbell import linearise

    return linearise(_case(case), undamped=undamped)


def campbell(case, speeds, bearing_stiffness: float | None = None,
             max_frequency: float = 6000.0):
    """The Campbell diagram of a case as an :class:`xarray.Dataset` (speed x mode).

    At every input speed its own static solution X0, the bearings linearised there and the
    gyroscopic matrix at that speed (when the case has it, ``simulation.gyroscopic``), then
    the damped modes (:func:`orchestrator.analysis.campbell.campbell_data`), labelled by
    :func:`orchestrator.analysis.campbell.campbell_dataset`: ``frequency`` [Hz],
    ``damping_ratio``, ``log_decrement``, ``whirl_direction`` per speed and mode (1-based),
    the critical speeds along ``crossing`` and the attribute ``stability_threshold_rad_s``.

    Parameters
    ----------
    case : Case or str or path
    speeds : array_like
        Input speeds [rad/s], increasing, > 0.
    bearing_stiffness : float, optional
        Isotropic bearings [N/m] without damping instead of the film at each X0.
    max_frequency : float
        Modes above 1.5 times this [Hz] are left out.
    """
    import numpy as np

    from fmu_src.case import CaseError
    from orchestrator.analysis.campbell import campbell_data, campbell_dataset

    w = np.asarray(speeds, dtype=float).ravel()
    if w.size < 2 or not np.all(np.isfinite(w)) or w[0] <= 0.0 or np.any(np.diff(w) <= 0.0):
        raise CaseError(f"speeds {w.tolist()!r} rad/s: at least two, finite, > 0 and "
                        "increasing")
    case = _case(case)
    return campbell_dataset(campbell_data(case, w, bearing_stiffness,
                                          max_frequency=max_frequency))
