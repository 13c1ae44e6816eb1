"""Numba's cache for this project's kernels, kept per version of the whole code.

numba caches a compiled kernel beside its source and, to decide whether the entry is stale,
looks at that one file only. A kernel that calls or inlines functions of other files (the
hybrid kernels call the Ritz, LCP and Jacobian kernels and inline :mod:`bearing_fmu.reynolds`;
the structure step calls the mesh and Newmark kernels) kept its old compiled body after one of
those files changed: a run then computed with code that was no longer there, and its last
digits depended on what the cache held.

:func:`install` (called first by each package's ``__init__``) puts a locator in front of
numba's own: a kernel of ``bearing_fmu``, ``gear_fmu`` or ``fmu_src`` is cached where numba
would cache it (``NUMBA_CACHE_DIR``, else beside the source, else the user-wide folder), in a
subfolder ``gsb-<code hash>`` named by the content of every module of those packages
(:func:`code_hash`). Any change of the code starts an empty folder; the eight most recent
ones are kept. Everything else numba caches is left alone.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

#: the packages whose kernels share one code version
PACKAGES = ("bearing_fmu", "gear_fmu", "fmu_src")
#: code versions kept side by side in one cache folder
KEEP = 8
PREFIX = "gsb-"


@functools.cache
def code_hash(root: str) -> str:
    """sha256 (16 hex digits) of every ``.py`` file of :data:`PACKAGES` under ``root``."""
    digest = hashlib.sha256()
    for pkg in PACKAGES:
        for path in sorted((Path(root) / pkg).rglob("*.py")):
            if "__pycache__" not in path.parts:
                digest.update(path.relative_to(root).as_posix().encode() + b"\0"
                              + path.read_bytes())
    return digest.hexdigest()[:16]


def _root_of(py_file: str) -> str | None:
    """The folder holding the package of ``py_file`` if it is one of :data:`PACKAGES`."""
    path = Path(py_file).resolve()
    for parent in path.parents:
        if parent.name in PACKAGES and (parent / "__init__.py").is_file():
            return str(parent.parent)
    return None


def _prune(folder: Path) -> None:
    """Drop all but the :data:`KEEP` most recently used code versions in ``folder``."""
    versions = sorted((p for p in folder.glob(PREFIX + "*") if p.is_dir()),
                      key=lambda p: p.stat().st_mtime, reverse=True)
    for old in versions[KEEP:]:
        shutil.rmtree(old, ignore_errors=True)


def _impl_class():
    """numba's class holding the list of locators (``_CacheImpl`` in some releases)."""
    from numba.core import caching

    return getattr(caching, "CacheImpl", None) or caching._CacheImpl


def _locator_class():
    from numba.core import caching

    class CodeVersionLocator(caching._CacheLocator):
        """numba's own choice of folder for a kernel of this project, plus ``gsb-<hash>``."""

        def __init__(self, inner, root: str):
            self._inner = inner
            self._parent = Path(inner.get_cache_path())
            self._path = str(self._parent / (PREFIX + code_hash(root)))

        def ensure_cache_path(self):
            fresh = not os.path.isdir(self._path)
            os.makedirs(self._path, exist_ok=True)
            tempfile.TemporaryFile(dir=self._path).close()  # writable, as numba checks
            if fresh:
                _prune(self._parent)

        def get_cache_path(self):
            return self._path

        def get_source_stamp(self):
            return self._inner.get_source_stamp()

        def get_disambiguator(self):
            return self._inner.get_disambiguator()

        @classmethod
        def from_function(cls, py_func, py_file):
            root = _root_of(py_file) if os.path.exists(py_file) else None
            if root is None:
                return None
            for other in _impl_class()._locator_classes:
                if other is cls:
                    continue
                inner = other.from_function(py_func, py_file)
                if inner is not None:
                    break
            else:
                return None
            self = cls(inner, root)
            try:
                self.ensure_cache_path()
            except OSError:
                return None
            return self

    return CodeVersionLocator


def install() -> None:
    """Put the code-version locator first in numba's list (once per process)."""
    classes = _impl_class()._locator_classes
    if not any(getattr(c, "__name__", "") == "CodeVersionLocator" for c in classes):
        classes.insert(0, _locator_class())
