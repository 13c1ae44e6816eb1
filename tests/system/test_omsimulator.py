"""OMSimulator 3.0 (OpenModelica's FMI/SSP tool) runs the SSP archive of ``gsb export-ssp``.

OMSimulator 3.0.0's Python API (``OMSimulator.SSP(path).instantiate()``) puts co-simulation
FMUs in a weakly coupled system whose step it takes from its API only
(``setFixedStepSize``): the SSD's default experiment gives it the start and stop times, and an
``oms:SimulationInformation`` solver annotation would move the FMUs into a model-exchange system,
which co-simulation FMUs refuse ("doesn't support model exchange mode"). The probe passes the
case's step as a user must (docs/fmu-variables.md). OMSimulator orders the FMUs by their
declared dependencies: the bearings are evaluated at the journal states the gear-shaft FMU gave
after the step (Gauss-Seidel),
:func:`orchestrator.studies.coupling_accuracy.non_iterative` with lag 0.

The tool: a Linux build of OMSimulator 3.0 as a tarball, named by ``GSB_OMSIMULATOR`` (the
tarball or a folder holding ``oms-install``) or found at ``../shared/tools/omsimulator/`` beside
the checkout; unpacked once into the per-user cache. Skipped, saying why, without it.
"""

from __future__ import annotations

import json
import os
import subprocess
import tarfile
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import ROOT, film_bounds, probe_command, probe_env

CASE = "baguet2010_spur"
STEPS = 64
#: where OMSimulator's Python package sits in its install tree
PACKAGE = Path("oms-install") / "lib" / "x86_64-linux-gnu"


def _tool() -> Path:
    """The folder holding ``oms-install``: ``GSB_OMSIMULATOR`` or the shared tarball, unpacked
    into the per-user cache (under a lock: one unpacking for every xdist worker)."""
    from fmu_src.slaves.bootstrap import cache_dir, locked

    given = os.environ.get("GSB_OMSIMULATOR")
    found = sorted((ROOT.parent / "shared" / "tools" / "omsimulator").glob("*.tar.xz"))
    source = Path(given) if given else (found[-1] if found else None)
    if source is None or not source.exists():
        pytest.skip("OMSimulator 3.0 not found: set GSB_OMSIMULATOR to its Linux tarball or "
                    "folder, or put the tarball in ../shared/tools/omsimulator/")
    if source.is_dir():
        return source
    folder = cache_dir() / "omsimulator" / source.name.removesuffix(".tar.xz")
    folder.mkdir(parents=True, exist_ok=True)
    with locked(folder):
        if not (folder / PACKAGE / "OMSimulator").is_dir():
            with tarfile.open(source) as tar:
                tar.extractall(folder, filter="data")
    return folder


@pytest.fixture(scope="module")
def omsimulator_run(ssp_file):
    """The probe's journal states after the initialisation and each of :data:`STEPS` steps."""
    from fmu_src import description
    from fmu_src.case import load_case

    tool = _tool()
    env = probe_env()
    env["PYTHONPATH"] = os.pathsep.join([env["PYTHONPATH"], str(tool / PACKAGE)])
    dt = description.time_step(load_case(CASE))
    cmd = probe_command("tests.probes.omsimulator", "simulate",
                        {"ssp": ssp_file, "step_size": dt, "steps": STEPS})
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                          env=dict(env, PYTHONFAULTHANDLER="1"), cwd=ssp_file.parent)
    if proc.returncode != 0 and "No module named" in proc.stderr:
        pytest.skip(f"OMSimulator's Python package cannot be imported here: "
                    f"{proc.stderr.strip().splitlines()[-1]}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    return np.array(json.loads(proc.stdout.strip().splitlines()[-1])["x"]).reshape(-1, 4, 4)


def test_omsimulator_runs_the_ssp_as_a_gauss_seidel_master_would(omsimulator_run):
    """OMSimulator's trajectories equal the emulated Gauss-Seidel scheme's to the film
    solver's accuracy over 64 steps (the argument and the bounds of
    tests/system/test_ecos.py, :func:`tests.helpers.film_bounds`: the hybrid film solver's
    force within tol = 1e-8 of the exact one whatever its warm start, and the host's own
    order of the bearing calls; measured here 3.3e-12 of the largest position), and differ
    from ``gsb run``'s iterative master by the non-iterative coupling error (9 % of the
    orbit's peak-to-peak at the paper's step, docs/fmu-variables.md)."""
    from fmu_src.case import load_case
    from orchestrator.studies.coupling_accuracy import iterative, non_iterative, orbit_error

    x = omsimulator_run
    case = load_case(CASE)
    ref = non_iterative(case, STEPS, lag=0)
    scale = np.abs(ref[:, :, :2]).max()
    position = float(np.abs(x[:, :, :2] - ref[:, :, :2]).max() / scale)
    velocity = float(np.abs(x[:, :, 2:] - ref[:, :, 2:]).max() / np.abs(ref[:, :, 2:]).max())
    coupling = 100.0 * orbit_error(x, iterative(case, STEPS))
    print(f"\nOMSimulator vs the emulated Gauss-Seidel master, {STEPS} steps: positions "
          f"{position:.1e}, velocities {velocity:.1e}; against gsb run {coupling:.1f} %")
    from fmu_src.description import time_step

    bound, v_bound = film_bounds(scale, np.abs(ref[:, :, 2:]).max(), time_step(case))
    assert position < bound and velocity < v_bound
    assert 1.0 < coupling < 30.0  # it does not iterate: not gsb run's numbers


def test_the_gear_shaft_component_name_is_no_segment_of_its_variables():
    """OMSimulator 3.0 drops every segment of a variable's name equal to its component's name
    (or ``model``, ``root``): the paper's shaft ``gear_shaft`` must not share the component's."""
    from fmu_src.build.ssp import GEAR, gear_component

    assert gear_component(["shafts.pinion_shaft.length[1]"]) == GEAR
    assert gear_component(["shafts.gear_shaft.length[1]"]) == f"{GEAR}_fmu"
    assert gear_component(["a.gear_shaft", "b.gear_shaft_fmu"]) == f"{GEAR}_fmu_fmu"
