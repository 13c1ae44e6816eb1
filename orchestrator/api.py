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
import math
from pathlib import Path

from fmu_src.case import Case, load_case
from orchestrator.run.progress import startup_log
from orchestrator.run.result import Result
from orchestrator.run.spec import RunSpec

__all__ = ["campbell", "modes", "read_result", "read_sweep", "simulate", "sweep"]


def _case(case) -> Case:
    return case if isinstance(case, Case) else load_case(case)


def _with(case: Case, periods: int | None = None, bearing: str | None = None,
          fields: dict | None = None, seconds: float | None = None) -> Case:
    """The case with the call's settings as the case fields they are: ``fields`` (any field,
    as ``--set``), ``bearing`` (``bearings.*.model``: every bearing), ``periods``
    (``simulation.mesh_periods``) or ``seconds`` (the whole mesh periods of the fastest mesh
    that cover that time [s], at the case's speed after the overrides), through the case's
    one override path and its checks (CaseError naming the field and the limit)."""
    from fmu_src.case import CaseError

    fields = dict(fields or {})
    if bearing is not None:
        fields["bearings.*.model"] = bearing
    case = case.with_overrides(fields) if fields else case
    if periods is not None and seconds is not None:
        raise CaseError(f"periods = {periods!r} and seconds = {seconds!r}: give one run length")
    if seconds is not None:
        from fmu_src.description import mesh_period

        if isinstance(seconds, bool) or not isinstance(seconds, (int, float)) \
                or not math.isfinite(seconds) or seconds <= 0.0:
            raise CaseError(f"seconds = {seconds!r}: the run length must be a finite time > 0 s")
        periods = max(1, math.ceil(seconds / mesh_period(case) - 1e-9))
    if periods is not None:
        case = case.with_overrides({"simulation.mesh_periods": periods})
    return case


def simulate(case, periods: int | None = None, bearing: str | None = None, *,
             seconds: float | None = None, speed=None, torque=None, unbalance=None,
             window: str | None = None, overrides: dict | None = None,
             in_process: bool = False, steps: int | None = None,
             results_dir: str | Path | None = None, fmu_dir: str | Path | None = None,
             progress: bool = True, threads: int = 1) -> Result:
    """Static solution X0, then the transient of ``case``; the result in memory.

    Parameters
    ----------
    case : Case or str or path
        A case (:func:`fmu_src.case.load_case`), the name of a shipped case or a case file.
    periods : int, optional
        Mesh periods of the fastest mesh to simulate (the case's ``simulation.mesh_periods``).
    bearing : str, optional
        Bearing model of every bearing (the case's ``bearings.*.model``: ``hybrid``,
        ``short``, ``fd``, ``linear``, ``lumped``).
    seconds : float, optional
        Run length [s] instead of ``periods``: the whole mesh periods that cover it.
    speed, torque, unbalance : float or str, optional
        The input speed (``drive.speed``), input torque (``drive.torque``) and the unbalance
        eccentricity of every gear (``gears.*.unbalance``): SI numbers or strings with units
        (``"3000 rpm"``), as ``gsb run --speed --torque --unbalance``.
    window : str, optional
        The last part of the run that ``result.report`` is taken over (the case's
        ``simulation.window``, ``gsb run --window``): ``"26 periods"`` (of the fastest mesh),
        ``"0.05 s"`` or ``"2 revolutions of gear_shaft"``; default: the last revolution of the
        slowest shaft, or the last half of a shorter run. Stored with the report
        (``report["window_kind"]``, ``report["window_s"]``).
    overrides : dict, optional
        Any case field, ``{"bearings.3.clearance": "120 um"}`` (``gsb run --set``).
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
        A progress line on stderr, and what a first call builds or compiles (the FMUs, the
        numba kernels: a minute once per code version), as ``gsb run`` says it.
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

    named = {"drive.speed": speed, "drive.torque": torque, "gears.*.unbalance": unbalance,
             "simulation.window": window}
    fields = dict(overrides or {}) | {k: v for k, v in named.items() if v is not None}
    case = _with(_case(case), periods, bearing, fields, seconds)
    with startup_log(progress):
        if results_dir is None:
            return simulate_case(RunSpec.of(case, in_process, None, fmu_dir, steps, threads),
                                 progress=progress)
        summary = run_case(case, in_process=in_process, out_dir=results_dir, fmu_dir=fmu_dir,
                           progress=progress, steps=steps, threads=threads)
    result = Result.from_file(summary.results)
    result.summary = summary
    return result


def _file_of_kind(path, kind: str, what: str, other: str) -> Path:
    """``path`` as a Path once it is a readable file whose root attribute ``kind`` is ``kind``;
    FileNotFoundError or ValueError naming it (``what`` it should be, ``other``: how the
    other kind of file is read) otherwise."""
    from orchestrator.run.results import read_attributes

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such {what}")
    try:
        found = read_attributes(path).get("kind")
    except OSError as exc:
        raise ValueError(f"{path}: not a readable {what} ({exc})") from None
    if found != kind:
        raise ValueError(f"{path}: not a {what} (kind {found!r}); {other}")
    return path


def read_result(path: str | Path) -> Result:
    """The channels and settings of a results file (``gsb run``'s, or :func:`simulate`'s with
    ``results_dir``), also while a run writes it. FileNotFoundError or ValueError naming the
    file when it is missing or not a run's results file (a sweep file: :func:`read_sweep`)."""
    return Result.from_file(_file_of_kind(path, "run", "results file of a run",
                                          "a sweep's file is read with read_sweep"))


def read_sweep(path: str | Path):
    """A sweep file (:func:`sweep`'s or ``gsb sweep``'s, also while it runs) as an
    :class:`xarray.Dataset`: the varied fields and the bearing models as dimensions, the
    points' figures (R, peak-to-peaks, orbit centres, ...) as variables, NaN and an ``error``
    where a point failed (:func:`orchestrator.sweeps.file.sweep_dataset`). FileNotFoundError or
    ValueError naming the file when it is missing or not a sweep's."""
    from orchestrator.sweeps.file import sweep_dataset

    return sweep_dataset(_file_of_kind(path, "sweep", "sweep file",
                                       "a run's file is read with read_result"))


def sweep(case, vary: dict, path: str | Path, periods: int, bearings=None,
          window: str | None = None, scheduler: str | None = None, n_workers: int = 2,
          progress: bool = True, overwrite: bool = False, steady_periods: int | None = None):
    """Every combination of the values in ``vary`` (``{"drive.speed": [300, 325, 350],
    ...}``, values as in a case file) and of ``bearings`` (default: the case's model), each an
    in-process run of ``periods`` mesh periods on Dask (``scheduler``: a cluster's address;
    default: ``n_workers`` local processes), written to the sweep file ``path`` as the points
    complete. ``window``: the steady window every point is reduced over, as
    ``simulation.window`` (``"26 periods"``, ``"0.05 s"``, ``"2 revolutions of gear_shaft"``;
    default: the case's own, by default the last revolution of the slowest shaft or the last
    half of the run if shorter), stored in the file (attribute ``window``, variable
    ``window_s``); ``steady_periods=N``, an earlier spelling of ``window="N periods"``, warns.
    An existing ``path`` is a RunError unless ``overwrite``; a window longer than a point's run
    a CaseError (nothing run). Returns :class:`orchestrator.sweeps.runner.SweepResult`
    (``.to_xarray()``: the varied fields and the bearing models as dimensions,
    :func:`read_sweep`); ``gsb plot path`` draws its figures."""
    import warnings

    from fmu_src.case import CaseError
    from orchestrator.run.spec import RunError
    from orchestrator.sweeps.runner import SweepPoint, run_sweep

    if steady_periods is not None:
        if window is not None:
            raise CaseError(f"steady_periods={steady_periods}: the same as window; give one of "
                            f"them, not both (window={window!r})")
        warnings.warn(f"sweep(steady_periods={steady_periods}) is "
                      f"sweep(window='{steady_periods} periods')", DeprecationWarning,
                      stacklevel=2)
        window = f"{steady_periods} periods"
    if Path(path).exists() and not overwrite:
        raise RunError(f"{path} exists: a sweep never replaces a file silently; "
                       "overwrite=True replaces it, read_sweep(path) reads it")
    keys = list(vary)
    models = [None] if bearings is None else list(bearings)
    points = [SweepPoint(dict(zip(keys, values, strict=True)), model)
              for model in models for values in itertools.product(*vary.values())]
    base = _with(_case(case), fields=None if window is None else {"simulation.window": window})
    return run_sweep(base, points, path, periods, scheduler, n_workers, progress,
                     vary_keys=keys)


def modes(case, undamped: bool = True, progress: bool = True):
    """The case linearised about its static solution X0: bearing Kb, Cb, the mean mesh
    stiffness, the damped (and undamped) modes with their whirl
    (:class:`orchestrator.analysis.campbell.Linearised`; modes numbered from 1 where printed:
    ``damped.frequency_hz[0]`` is mode 1). ``progress``: say what a first call compiles."""
    from orchestrator.analysis.campbell import linearise

    with startup_log(progress):
        return linearise(_case(case), undamped=undamped)


def campbell(case, speeds, bearing_stiffness: float | None = None,
             max_frequency: float = 6000.0, progress: bool = True):
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
    progress : bool
        Say what a first call compiles (numba's kernels, once per code version).
    """
    import numpy as np

    from fmu_src.case import CaseError
    from orchestrator.analysis.campbell import campbell_data, campbell_dataset

    w = np.asarray(speeds, dtype=float).ravel()
    if w.size < 2 or not np.all(np.isfinite(w)) or w[0] <= 0.0 or np.any(np.diff(w) <= 0.0):
        raise CaseError(f"speeds {w.tolist()!r} rad/s: at least two, finite, > 0 and "
                        "increasing")
    with startup_log(progress):
        return campbell_dataset(campbell_data(_case(case), w, bearing_stiffness,
                                              max_frequency=max_frequency))
