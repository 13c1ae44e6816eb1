"""Fixtures shared by the test modules: one build of every FMU for the whole test run.

With pytest-xdist the workers share it: the FMUs are built once, under a lock, into a folder
of the run's base temporary directory that every worker sees. Before the workers start, the
controller fills numba's cache (:data:`WARM_UP`, two processes side by side), so that the
workers load the kernels instead of each compiling all of them.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from fmu_src.fmu_bootstrap import locked


def _shared(tmp_path_factory, name: str):
    """A folder of this test run shared by all xdist workers (the run's own otherwise)."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent
    folder = root / name
    folder.mkdir(parents=True, exist_ok=True)
    return folder


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """A folder with every FMU of :data:`fmu_src.build.FMUS`, built once per test run."""
    from fmu_src.build import FMUS
    from fmu_src.native_build import export_library, native_status
    from orchestrator.fmi.cache import ensure_fmus

    if export_library() is None:  # the FMUs would behave as pythonfmu's own, not as specified
        pytest.fail(f"the FMUs' native layer cannot be built here: {native_status()[1]}",
                    pytrace=False)
    dest = _shared(tmp_path_factory, "fmus")
    ensure_fmus(list(FMUS), dest)  # under its own lock: one build for every worker
    return dest


@pytest.fixture(scope="session")
def ssp_file(tmp_path_factory):
    """``gsb export-ssp baguet2010_spur``: the paper's system as an SSP archive."""
    folder = _shared(tmp_path_factory, "ssp")
    path = folder / "baguet2010_spur.ssp"
    with locked(folder):
        if not path.is_file():
            proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "export-ssp",
                                   "baguet2010_spur", "--dest", str(folder)],
                                  capture_output=True, text=True, timeout=600, cwd=folder)
            assert proc.returncode == 0, proc.stderr[-2000:]
    return path
