"""The master of the co-simulation, its runs, analyses and command line; the Python API.

>>> import orchestrator as gsb
>>> result = gsb.simulate("baguet2010_spur", periods=64)          # doctest: +SKIP
>>> result["journal_position"].shape                               # doctest: +SKIP
(2048, 4, 2)

The API (:mod:`orchestrator.api`), importable from ``orchestrator``:

* ``load_case``, ``shipped_cases``: a case file or a shipped case, checked
  (:func:`fmu_src.case.load_case`, :func:`fmu_src.case.shipped_cases`);
* ``simulate``: a run kept in memory (:func:`orchestrator.api.simulate`), its ``Result``
  (:class:`orchestrator.run.result.Result`: channels with named dimensions, ``to_xarray()``),
  and ``read_result`` for a results file (:func:`orchestrator.api.read_result`);
* ``sweep``: a parametric sweep on Dask (:func:`orchestrator.api.sweep`), ``read_sweep``
  its file as an xarray Dataset (:func:`orchestrator.api.read_sweep`); ``modes``: the
  linearised system at X0 (:func:`orchestrator.api.modes`); ``campbell``: the damped modes
  over speed with their whirl, the critical speeds and the stability threshold, labelled
  (:func:`orchestrator.api.campbell`);
* ``Case``, ``CaseError`` (:mod:`fmu_src.case`), ``RunError``
  (:class:`orchestrator.run.spec.RunError`), ``RunInterrupted``
  (:class:`orchestrator.run.progress.RunInterrupted`); the warnings a run gives once, as
  Python warnings: ``RunWarning`` and its kinds ``TimeStepWarning``, ``OverloadWarning``
  (:mod:`orchestrator.run.checks`).

Subpackages, one concern each: :mod:`~orchestrator.coupling` (the master, in-process and FMI
transports), :mod:`~orchestrator.run` (a run's life cycle, results files),
:mod:`~orchestrator.analysis`, :mod:`~orchestrator.figures`, :mod:`~orchestrator.sweeps`,
:mod:`~orchestrator.cli` (the ``gsb`` command), :mod:`~orchestrator.studies`.
"""

from __future__ import annotations

import importlib

#: public name -> the module that defines it (imported when the name is first used, so that
#: ``import orchestrator`` and ``gsb --help`` stay light)
_API = {
    "Case": "fmu_src.case", "CaseError": "fmu_src.case", "load_case": "fmu_src.case",
    "shipped_cases": "fmu_src.case", "simulate": "orchestrator.api",
    "read_result": "orchestrator.api", "read_sweep": "orchestrator.api",
    "sweep": "orchestrator.api",
    "modes": "orchestrator.api", "campbell": "orchestrator.api",
    "Result": "orchestrator.run.result",
    "RunError": "orchestrator.run.spec", "RunInterrupted": "orchestrator.run.progress",
    "RunWarning": "orchestrator.run.checks", "TimeStepWarning": "orchestrator.run.checks",
    "OverloadWarning": "orchestrator.run.checks",
}

__all__ = sorted(_API)


def __getattr__(name: str):
    if name in _API:
        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'orchestrator' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_API])
