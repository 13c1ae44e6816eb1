"""The FMU binary: pythonfmu's native layer with this project's patches, built once per machine.

The FMUs are built by pythonfmu (:mod:`fmu_src.build`), whose shared library carries the FMI C
interface and hosts the Python slave. pythonfmu 0.7.0's library turns every Python exception of
a setter or getter into fmi2Fatal and finalises the interpreter while a C++ host's process is
being torn down. ``fmu_src/native/pythonfmu_export`` is that library's source (MIT, vendored
from pythonfmu 0.7.0) with three patches, each marked ``gear-shaft-bearing patch``:

* status protocol: a setter may return an int FMI status and a getter a tuple
  ``(values, status)``; a non-zero status is what the FMI call returns (fmi2Error at the
  fmi2SetReal that receives a bad value, fmi2Discard or fmi2Error at the read of an output that
  cannot be computed), the reason being in the FMU log. The library sets
  ``_fmi_status_protocol = True`` on the slave so that the slave knows it may do so;
* the interpreter is never finalised by the library (the exit-time abort of C++ hosts);
* a borrowed reference is no longer released (the reason for ``pin_namespace``);
* the interpreter, when the library starts it (a C/C++ host), leaves the host's signal
  handlers alone (``Py_InitializeEx(0)``).

Beside it, on Linux, ``src/loader/gsb_loader.c`` (this project's, not pythonfmu's) builds the
loader that becomes the FMU's binary: it has no Python dependency, so a C/C++ host can load
it; it loads libpython when the host has none (the paths of :func:`python_host_config`) and
forwards every FMI call to the library above (:func:`export_library` returns both).

:func:`export_library` compiles it with CMake (a dependency of fmpy) into the per-user cache
(:func:`fmu_src.fmu_bootstrap.cache_dir`) the first time and returns the cached file
afterwards; the cache key is a hash of the sources, the Python version and the platform.
Without a C++ compiler it returns None and the FMUs keep pythonfmu's library (bad values are
then reported when they are used: NaN outputs, a discarded step).
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

from fmu_src.fmu_bootstrap import cache_dir

__all__ = ["NATIVE_SOURCE", "NativeLibraries", "cache_dir", "export_library",
           "python_host_config"]

#: the patched pythonfmu-export sources
NATIVE_SOURCE = Path(__file__).resolve().parent / "native" / "pythonfmu_export"


def _key() -> str:
    h = hashlib.sha256()
    for path in sorted(NATIVE_SOURCE.rglob("*")):
        if path.is_file() and "build" not in path.relative_to(NATIVE_SOURCE).parts:
            h.update(str(path.relative_to(NATIVE_SOURCE)).encode())
            h.update(path.read_bytes())
    h.update(f"{sys.version_info[:2]} {platform.machine()} {sys.platform}".encode())
    return h.hexdigest()[:16]


def _library_name() -> str:
    return {"win32": "pythonfmu-export.dll", "darwin": "libpythonfmu-export.dylib"}.get(
        sys.platform, "libpythonfmu-export.so")


#: the loader's file name (Linux only)
LOADER_NAME = "libgsb-loader.so"


@dataclass(frozen=True)
class NativeLibraries:
    """The built native files: the patched pythonfmu library and, on Linux, the loader."""

    library: Path
    loader: Path | None


def python_host_config() -> str:
    """``resources/gsb_python.txt`` of an FMU built here: the libpython and the Python
    executable the loader uses in a host without Python (``GSB_LIBPYTHON``, ``GSB_PYTHON``
    override them): this Python's shared library and executable (a virtual environment's
    executable, so that its site-packages are seen)."""
    soname = sysconfig.get_config_var("INSTSONAME") or sysconfig.get_config_var("LDLIBRARY")
    libpython = soname or ""
    if soname:
        folders = [sysconfig.get_config_var("LIBDIR") or "", sysconfig.get_config_var("LIBPL")
                   or ""]
        multiarch = sysconfig.get_config_var("MULTIARCH")
        if multiarch and folders[0]:
            folders.insert(1, str(Path(folders[0]) / multiarch))
        found = [Path(f) / soname for f in folders if f and (Path(f) / soname).is_file()]
        libpython = str(found[0]) if found else soname  # else: the dynamic loader's search
    return (f"# read by the FMU's loader in a host without Python (GSB_LIBPYTHON and "
            f"GSB_PYTHON override)\nlibpython={libpython}\nexecutable={sys.executable}\n")


def export_library(quiet: bool = True) -> NativeLibraries | None:
    """The patched FMU library and the loader for this machine (built on first use), or None
    if they cannot be built here (a warning says why)."""
    folder = cache_dir() / "native" / _key()
    target = folder / _library_name()
    loader = folder / LOADER_NAME if sys.platform.startswith("linux") else None
    if target.is_file() and (loader is None or loader.is_file()):
        return NativeLibraries(target, loader)
    cmake = shutil.which("cmake") or str(Path(sysconfig.get_path("scripts")) / "cmake")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="build-", dir=target.parent) as tmp:
        out = Path(tmp) / "out"
        commands = [
            [cmake, "-S", str(NATIVE_SOURCE), "-B", str(Path(tmp) / "build"),
             "-DCMAKE_BUILD_TYPE=Release", f"-DPython3_EXECUTABLE={sys.executable}",
             f"-DGSB_OUTPUT_DIR={out}"],
            [cmake, "--build", str(Path(tmp) / "build"), "--config", "Release"],
        ]
        try:
            for cmd in commands:
                subprocess.run(cmd, check=True, capture_output=quiet, text=True, timeout=900)
            built = next(out.glob(_library_name()))
            built_loader = None if loader is None else next(out.glob(LOADER_NAME))
        except (OSError, subprocess.SubprocessError, StopIteration) as exc:
            detail = getattr(exc, "stderr", "") or str(exc)
            warnings.warn(f"cannot build the patched FMU library ({detail.strip()[-500:]}); the "
                          "FMUs use pythonfmu's own library: bad values are reported when "
                          "used (NaN outputs, discarded steps), not refused when set",
                          RuntimeWarning, stacklevel=2)
            return None
        if loader is not None:  # atomic: concurrent builders leave complete files
            os.replace(built_loader, loader)
        os.replace(built, target)  # last: its presence means both are there
    return NativeLibraries(target, loader)
