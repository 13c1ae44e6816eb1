"""The coupled system of a case: the master with its structure slave and its bearing set.

:func:`build_master` is the one place a case becomes a
:class:`~orchestrator.coupling.master.Master`, in-process
(:mod:`orchestrator.coupling.inprocess`, on the physics objects of :mod:`fmu_src.description`)
or through FMUs (:mod:`orchestrator.coupling.fmi`): runs, ``gsb modal``, the SSP export and
the studies all couple a case through it.
"""

from __future__ import annotations

import logging
import warnings
from pathlib import Path

from bearing_fmu import numba_cache
from bearing_fmu.hybrid.model import thread_count
from fmu_src import description
from fmu_src.case import Case
from gear_fmu.structure import Structure
from orchestrator.coupling.inprocess import InProcessStructure, ModelBearings
from orchestrator.coupling.master import Master
from orchestrator.coupling.step import CoupledSteps

__all__ = ["announce_compilation", "build_master"]


def build_master(case: Case, in_process: bool = False, fmu_dir: Path | str | None = None,
                 fmus: dict | None = None, structure: Structure | None = None,
                 threads: int = 1) -> Master:
    """The master of a case with its two slaves (``master.structure``, ``master.bearings``).

    In-process the physics objects of :mod:`fmu_src.description` are driven directly; through
    FMUs the bearing FMU of each bearing's model and the gear-shaft FMU are taken from
    ``fmu_dir`` (default: the per-user cache; built there if missing), or ``fmus`` names the
    files: ``{"gear": path, "bearings": [4 paths], "bearing_parameters": [4 dicts]
    (optional)}`` (an SSP's, or a bearing FMU of the user's own). In-process, ``fmus`` with
    ``"bearings"`` only couples the in-process structure with those bearing FMUs (the
    transmission FMU with a bearing FMU of the user's own). Release the slaves with
    :meth:`orchestrator.coupling.master.Master.close`.

    ``structure`` (in-process only): the :class:`gear_fmu.structure.Structure` to drive instead
    of one built from the case, e.g. one structure linearised with the bearings of several
    speeds (:class:`orchestrator.analysis.campbell.Linearisation`): the caller vouches that it
    is the case's.

    ``threads``: how many threads share the bearings when they are in-process hybrid ones of
    one n (:meth:`bearing_fmu.hybrid.model.HybridSet.use_threads`); any other bearings run on
    one, which a warning says.
    """
    tol = case["simulation.tolerance"]
    max_it = case["simulation.max_iterations"]
    cold = numba_cache.cold()  # before the structure's construction compiles a kernel
    if structure is not None and not in_process:
        raise ValueError("build_master: a structure object can only be driven in-process "
                         "(in_process=True)")
    if in_process:
        structure = InProcessStructure(description.structure(case) if structure is None
                                       else structure)
        if fmus is not None:
            from orchestrator.coupling import fmi

            bearings = fmi.FmuBearings(fmus["bearings"], fmus.get("bearing_parameters")
                                       or description.bearing_parameters(case),
                                       description.bearing_speeds(case))
        else:
            bearings = ModelBearings(description.bearing_models(case),
                                     description.bearing_frames(case),
                                     description.bearing_speeds(case),
                                     description.layout(case).bearing_names)
    elif fmus is not None:
        from orchestrator.coupling import fmi

        structure, bearings = fmi.system_from_files(case, fmus["gear"], fmus["bearings"],
                                                    fmus.get("bearing_parameters"))
    else:
        from orchestrator.coupling import fmi

        structure, bearings = fmi.system_from_case(case, fmu_dir=fmu_dir)
    if threads != 1:
        _share_bearings(bearings, threads, "the bearing FMUs" if fmus is not None or not
                        in_process else "bearings other than hybrid")
    announce_compilation(cold)  # after the FMUs' build: the kernels compile on first calls
    return Master(structure, bearings, tol, max_it,
                  stepper=CoupledSteps(structure, bearings))


def _share_bearings(bearings, threads: int, what: str) -> None:
    """Give the in-process hybrid bearings of a run ``threads`` threads
    (:meth:`bearing_fmu.hybrid.model.HybridSet.use_threads`); say once that any other bearings
    (``what``: other models, bearing FMUs) run on one thread, after the same check of the
    count."""
    hybrid = getattr(bearings, "hybrid_sets", None)
    if hybrid:
        for one in hybrid:
            one.use_threads(threads)
        return
    thread_count(threads, "threads = ")
    warnings.warn(f"threads = {threads}: {what} run on one thread (threads share hybrid "
                  "bearings only)", RuntimeWarning, stacklevel=3)


def announce_compilation(cold: bool) -> None:
    """Say on the ``gsb.startup`` log (printed by the command line) that numba compiles this
    code version's kernels, if ``cold`` (:func:`bearing_fmu.numba_cache.cold`, asked before
    the first kernel call): the first command on a machine is otherwise silent for 15-25 s."""
    if cold:
        logging.getLogger("gsb.startup").info(
            "compiling the numba kernels into %s (once per code version on this machine) ...",
            numba_cache.cache_base())
