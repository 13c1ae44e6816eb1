"""Fixtures shared by the test modules: one build of every FMU per test session."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """A folder with every FMU of :data:`fmu_src.build.FMUS`, built once per session."""
    from fmu_src.build import build_fmus

    dest = tmp_path_factory.mktemp("fmus")
    build_fmus(dest)
    return dest
