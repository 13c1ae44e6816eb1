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
* a borrowed reference is no longer released (the reason for ``pin_namespace``).

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
from pathlib import Path

from fmu_src.fmu_bootstrap import cache_dir

__all__ = ["NATIVE_SOURCE", "cache_dir", "export_library"]

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


def export_library(quiet: bool = True) -> Path | None:
    """The patched FMU library for this machine (built on first use), or None if it cannot be
    built here (a warning says why)."""
    target = cache_dir() / "native" / _key() / _library_name()
    if target.is_file():
        return target
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
        except (OSError, subprocess.SubprocessError, StopIteration) as exc:
            detail = getattr(exc, "stderr", "") or str(exc)
            warnings.warn(f"cannot build the patched FMU library ({detail.strip()[-500:]}); the "
                          "FMUs use pythonfmu's own library: bad values are reported when "
                          "used (NaN outputs, discarded steps), not refused when set",
                          RuntimeWarning, stacklevel=2)
            return None
        os.replace(built, target)  # atomic: concurrent builders leave one complete file
    return target
