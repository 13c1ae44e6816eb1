"""Where numba caches this project's kernels (:mod:`bearing_fmu.numba_cache`): the end-to-end
checks (a changed callee recompiles its callers; cold = warm) are in
tests/system/test_determinism.py; here the locator of a kernel outside the hashed packages."""

from __future__ import annotations

import shutil
from pathlib import Path

from bearing_fmu import numba_cache

ROOT = Path(__file__).resolve().parents[2]


def _locator(root: Path):
    """The locator numba would use for the master's compiled step in the code under root."""
    path = root / "orchestrator" / "coupling" / "step.py"
    namespace: dict = {}
    code = compile("def coupled_steps():\n    pass\n", str(path), "exec")
    exec(code, namespace)
    return numba_cache._locator_class().from_function(namespace["coupled_steps"], str(path))


def test_a_kernel_calling_the_packages_is_cached_with_their_version_and_its_own_content(
        tmp_path, monkeypatch):
    """The master's compiled step (orchestrator.coupling.step) calls the structure's and the
    bearings' kernels: cached in the folder of their code version (a change of a callee: a new
    folder), with its own file's content in the stamp (a change of the file: another stamp, so
    numba compiles it again). Under numba's own locator it was cached beside its source and checked
    against that file only, so a changed callee left it stale."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    from numba.core import config

    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "numba"))
    root = tmp_path / "code"
    for pkg in (*numba_cache.PACKAGES, "orchestrator"):
        shutil.copytree(ROOT / pkg, root / pkg,
                        ignore=shutil.ignore_patterns("__pycache__", "native", "build"))
    first = _locator(root)
    assert first is not None
    version = numba_cache.PREFIX + numba_cache.code_hash(str(root))
    folder = tmp_path / "numba" / version / "orchestrator" / "coupling"
    assert Path(first.get_cache_path()) == folder
    step = root / "orchestrator" / "coupling" / "step.py"
    step.write_text(step.read_text() + "\n# changed\n")
    second = _locator(root)
    assert second.get_cache_path() == first.get_cache_path()
    assert second.get_source_stamp() != first.get_source_stamp()
    assert second.get_source_stamp()[:2] == first.get_source_stamp()[:2]


def test_a_kernel_numba_cannot_cache_is_compiled_with_numba_s_warning(tmp_path, monkeypatch):
    """A kernel of the packages that numba cannot cache (here: it sets numba's thread count
    inside, a dynamic global) compiles and runs with numba's own "cannot cache" warning, which
    points to its file: the locator has the source file numba's warning asks for (it raised
    AttributeError instead)."""
    import numba
    import pytest
    from numba.core import config
    from numba.core.errors import NumbaWarning

    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "numba"))
    path = ROOT / "bearing_fmu" / "static.py"  # a file of the packages: this project's locator
    namespace = {"numba": numba}
    exec(compile("def threads():\n    numba.set_num_threads(1)\n"
                 "    return numba.get_num_threads()\n", str(path), "exec"), namespace)
    kernel = numba.njit(cache=True)(namespace["threads"])
    with pytest.warns(NumbaWarning, match='Cannot cache compiled function "threads"') as seen:
        assert kernel() == 1
    assert any(w.filename == str(path) for w in seen)
