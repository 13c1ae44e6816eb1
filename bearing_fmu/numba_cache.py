"""Numba's cache for this project's kernels: one per version of the whole code, shared by every
copy of that code.

numba caches a compiled kernel beside its source and, to decide whether the entry is stale,
looks at that one file only. A kernel that calls or inlines functions of other files (the
hybrid kernels call the Ritz, LCP and Jacobian kernels and inline :mod:`bearing_fmu.reynolds`;
the structure step calls the mesh and Newmark kernels) keeps its stale compiled body after one
of those files changes: a run then computes with code that is no longer there, and its last
digits depend on what the cache holds.

:func:`install` (called first by each package's ``__init__``) puts a locator in front of
numba's own: a kernel of ``bearing_fmu``, ``gear_fmu`` or ``fmu_src`` is cached in
``<numba's cache>/gsb-<code hash>/<package folder>/``, where numba's cache is
``NUMBA_CACHE_DIR`` or numba's user-wide folder (``~/.cache/numba`` on Linux) and the code hash
covers every module of those packages (:func:`code_hash`). Any change of the code starts an
empty folder (the eight most recent are kept), and every copy of one version shares it: the
installed package and the code an FMU carries (staged by :mod:`fmu_src.slaves.bootstrap`) load
each other's kernels, so an FMU in another tool's process starts without compiling what
``gsb run`` compiled. A kernel of ``orchestrator`` (:data:`CALLERS`: the master's compiled
step calls the structure's and the bearings' kernels) is cached in the same folder with its own
file's content in its stamp. Everything else numba caches is left alone.
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
#: packages whose kernels call those of :data:`PACKAGES` but that an FMU does not all carry
#: (the master's compiled step, :mod:`orchestrator.coupling.step`): cached in the folder of
#: the code version they call, with their own file's content in the source stamp (numba then
#: compiles them again when that file changes; the code hash covers their callees)
CALLERS = ("orchestrator",)
#: folders of those packages that an FMU does not carry (fmu_src's build tools): left out of
#: the hash, so that the installed package and an FMU's copy of the code agree on it
SKIP = frozenset(("__pycache__", "build"))
#: code versions kept side by side in one cache folder
KEEP = 8
PREFIX = "gsb-"


@functools.cache
def code_hash(root: str) -> str:
    """sha256 (16 hex digits) of every ``.py`` file of :data:`PACKAGES` under ``root``
    (outside :data:`SKIP`)."""
    digest = hashlib.sha256()
    for pkg in PACKAGES:
        for path in sorted((Path(root) / pkg).rglob("*.py")):
            if not SKIP.intersection(path.relative_to(root).parts):
                digest.update(path.relative_to(root).as_posix().encode() + b"\0"
                              + path.read_bytes())
    return digest.hexdigest()[:16]


def cache_base() -> Path:
    """``NUMBA_CACHE_DIR``, else numba's user-wide cache folder."""
    from numba.core import config
    from numba.misc.appdirs import AppDirs

    if config.CACHE_DIR:
        return Path(config.CACHE_DIR)
    return Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)


def version_folder(root: str | None = None) -> Path:
    """numba's cache folder of the code version under ``root`` (this copy of the code by
    default): ``<numba's cache>/gsb-<code hash>``."""
    if root is None:
        root = str(Path(__file__).resolve().parents[1])
    return cache_base() / (PREFIX + code_hash(root))


def _root_of(py_file: str) -> str | None:
    """The folder holding the package of ``py_file`` if it is one of :data:`PACKAGES` or
    :data:`CALLERS`."""
    path = Path(py_file).resolve()
    for parent in path.parents:
        if parent.name in PACKAGES + CALLERS and (parent / "__init__.py").is_file():
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
        """``<numba's cache>/gsb-<code hash>/<package folder>`` for a kernel of this project,
        with the code hash as its source stamp (the same for every copy of the code)."""

        def __init__(self, py_func, py_file: str, root: str):
            self._lineno = py_func.__code__.co_firstlineno
            self._py_file = py_file  # where numba's "cannot cache" warning points
            rel = Path(py_file).resolve().relative_to(root)
            self._version = PREFIX + code_hash(root)
            self._stamp = (self._version, rel.as_posix())
            if rel.parts[0] in CALLERS:
                own = hashlib.sha256(Path(py_file).read_bytes()).hexdigest()[:16]
                self._stamp = (*self._stamp, own)
            self._path = str(version_folder(root) / rel.parent)

        def ensure_cache_path(self):
            fresh = not os.path.isdir(self._path)
            os.makedirs(self._path, exist_ok=True)
            tempfile.TemporaryFile(dir=self._path).close()  # writable, as numba checks
            if fresh:
                _prune(cache_base())

        def get_cache_path(self):
            return self._path

        def get_source_stamp(self):
            return self._stamp

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            root = _root_of(py_file) if os.path.exists(py_file) else None
            if root is None:
                return None
            self = cls(py_func, py_file, root)
            try:
                self.ensure_cache_path()
            except OSError:  # not writable: numba's own locators decide
                return None
            return self

    return CodeVersionLocator


def cold() -> bool:
    """Whether no kernel of this code version is in the cache yet (the first run compiles
    them: :func:`install`)."""
    return not any(version_folder().rglob("*.nbi"))


def install() -> None:
    """Put the code-version locator first in numba's list (once per process)."""
    classes = _impl_class()._locator_classes
    if not any(getattr(c, "__name__", "") == "CodeVersionLocator" for c in classes):
        classes.insert(0, _locator_class())
