"""Fixtures shared by the test modules: one build of every FMU per test session."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """A folder with every FMU of :data:`fmu_src.build.FMUS`, built once per session."""
    from fmu_src.build import build_fmus
    from fmu_src.native_build import export_library, native_status

    if export_library() is None:  # the FMUs would behave as pythonfmu's own, not as specified
        pytest.fail(f"the FMUs' native layer cannot be built here: {native_status()[1]}",
                    pytrace=False)
    dest = tmp_path_factory.mktemp("fmus")
    build_fmus(dest)
    return dest


@pytest.fixture(scope="session")
def ssp_file(tmp_path_factory):
    """``gsb export-ssp baguet2010_spur``: the paper's system as an SSP archive."""
    import subprocess
    import sys

    folder = tmp_path_factory.mktemp("ssp")
    proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "export-ssp",
                           "baguet2010_spur", "--dest", str(folder)],
                          capture_output=True, text=True, timeout=600, cwd=folder)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return folder / "baguet2010_spur.ssp"
