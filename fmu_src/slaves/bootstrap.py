"""First code an FMU of this package runs: the per-user cache and the FMU's own code.

Copied to the root of every FMU's resources and imported by its slave script before anything
else, so it uses the standard library only. :func:`stage_code` copies the FMU's code
(``resources/gsb_code``, written by :mod:`fmu_src.build.fmus` with a content hash) once into the
per-user cache and puts it first on ``sys.path``: the FMU then runs in any Python with numpy,
scipy and numba, without this package installed. Its numba kernels are cached per version of
the code, whatever copy of the code compiled them (:mod:`bearing_fmu.numba_cache`), so they
compile once per machine and code version, not at every instantiation from a freshly
extracted FMU. A host that has already imported the package's modules keeps them (one copy of
a module per process).

:func:`require` first checks that the Python the FMU runs in has the packages that code needs
(:data:`REQUIREMENTS`): without them the instantiation fails with what to install and into
which Python, a message pythonfmu's library gives the host's logger (the user of a C/C++ host
sees no Python traceback).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import tempfile
from pathlib import Path

__all__ = ["REQUIREMENTS", "REQUIREMENTS_TEXT", "cache_dir", "locked", "require", "stage_code"]

#: folder of the FMU's resources holding its code, and the file with the code's hash
CODE_DIR = "gsb_code"
HASH_FILE = "HASH"
#: the packages the FMU's code imports besides the standard library and pythonfmu (which the
#: FMU carries)
REQUIREMENTS = ("numpy", "scipy", "numba", "threadpoolctl")
#: the same as words, for messages: "numpy, scipy, numba and threadpoolctl"
REQUIREMENTS_TEXT = f"{', '.join(REQUIREMENTS[:-1])} and {REQUIREMENTS[-1]}"


def require(fmu: str) -> None:
    """Import every package of :data:`REQUIREMENTS`; ImportError naming the FMU, the packages
    missing (or failing to import), this Python's executable and the command that installs
    them, if any does not import. Before numpy first loads in the process, its BLAS is set to
    one thread unless the host chose a count (``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS``):
    hosts call FMUs from several threads at once, and a threaded
    OpenBLAS called from two threads corrupts its work (``bearing_fmu.blas_threads``)."""
    import importlib

    if "numpy" not in sys.modules:
        for name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(name, "1")

    missing: dict[str, str] = {}  # package -> why it does not import
    for name in REQUIREMENTS:
        try:
            importlib.import_module(name)
        except ImportError as exc:  # numba without numpy fails on numpy: name that one
            culprit = (exc.name or "").split(".")[0]
            missing.setdefault(culprit if culprit in REQUIREMENTS else name, str(exc))
    if missing:
        exe = sys.executable or "python"
        names = " ".join(missing)
        why = "; ".join(f"{name}: {reason}" for name, reason in missing.items())
        raise ImportError(f"{fmu}.fmu runs Python code that needs {REQUIREMENTS_TEXT}, and "
                          f"the Python running it ({exe}, Python "
                          f"{sys.version.split()[0]}) lacks {names.replace(' ', ', ')} ({why}). "
                          f"Install into that Python: {exe} -m pip install {names}")


def cache_dir() -> Path:
    """The per-user cache folder: ``GSB_CACHE_DIR``, else the platform's user cache folder
    (``$XDG_CACHE_HOME`` or ``~/.cache`` on Linux, ``~/Library/Caches`` on macOS,
    ``%LOCALAPPDATA%`` on Windows) + ``gear-shaft-bearing``."""
    env = os.environ.get("GSB_CACHE_DIR")
    if env:
        return Path(env)
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA", Path.home() / "AppData" / "Local"))
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "gear-shaft-bearing"


@contextlib.contextmanager
def locked(folder: Path):
    """An exclusive lock on ``folder/.build.lock`` while the block runs, for the builds into a
    cache folder (POSIX ``flock``; elsewhere none: the builds' atomic moves still leave
    complete files)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    with open(folder / ".build.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def stage_code(resources: str | Path) -> Path | None:
    """Copy ``resources/gsb_code`` to ``<cache>/code/<hash>`` (once; atomic) and put it first on
    ``sys.path``. Returns the staged folder, or None for an FMU without packaged code."""
    src = Path(resources) / CODE_DIR
    if not (src / HASH_FILE).is_file():
        return None
    target = cache_dir() / "code" / (src / HASH_FILE).read_text().strip()
    if not (target / HASH_FILE).is_file():
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=".staging-", dir=target.parent))
        try:
            shutil.copytree(src, tmp / "code")
            try:
                os.replace(tmp / "code", target)  # atomic; a concurrent stager may have won
            except OSError:
                if not (target / HASH_FILE).is_file():
                    raise
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    if str(target) not in sys.path:
        sys.path.insert(0, str(target))
    return target
