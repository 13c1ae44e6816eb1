"""``gsb doctor``: what this machine gives the package, and what is missing with its fix.

Prints the Python and the packages the FMUs need, whether numba can give an in-process run's
bearings threads, the cache folders (FMUs, numba's compiled kernels, the FMUs' staged code),
whether the FMUs' native layer is built (and why not), and which Python an FMU host will
start. ``--rebuild`` tries the native layer again, showing CMake's output. Exit code 0 when
nothing is missing, 1 otherwise.
"""

from __future__ import annotations

import importlib.metadata
import os
import platform
import shutil
import subprocess
import sys
from pathlib import Path

from fmu_src.slaves.bootstrap import REQUIREMENTS, REQUIREMENTS_TEXT

__all__ = ["add_parser", "report"]

#: what the FMUs and the runs import, in the order printed
PACKAGES = ("numpy", "scipy", "numba", "llvmlite", "threadpoolctl", "fmpy", "pythonfmu", "h5py",
            "matplotlib", "dask", "pyamg")


def add_parser(sub) -> None:
    p = sub.add_parser("doctor", help="what this machine gives the package (versions, caches, "
                                      "the FMUs' native layer) and the fix for what is missing",
                       description=__doc__)
    p.add_argument("--rebuild", action="store_true",
                   help="try to build the FMUs' native layer again, showing CMake's output")
    p.set_defaults(func=run)


def _version(name: str) -> str | None:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def _tool_version(cmd: list[str]) -> str:
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return "does not run"
    return out.strip().splitlines()[0] if out.strip() else "?"


def _kernel_cache() -> str:
    """Where numba keeps this code version's kernels (a compiled kernel's cache folder)."""
    from bearing_fmu.reynolds import nodal_force

    cache = getattr(nodal_force, "_cache", None)
    path = getattr(cache, "_cache_path", None)
    return str(path) if path else "unknown (numba's internals changed)"


def _python(lines: list, problems: list) -> None:
    """The interpreter, its headers and the packages."""
    from fmu_src.build.native import VENDORED_PYTHONFMU, python_build_config

    venv = sys.prefix != sys.base_prefix
    lines.append(f"Python       {platform.python_version()} ({platform.python_implementation()}"
                 f", {platform.machine()}) {sys.executable}"
                 + (f" (virtual environment of {sys.base_prefix})" if venv else ""))
    include = python_build_config()["include"]
    has_headers = (Path(include) / "Python.h").is_file()
    lines.append(f"  headers    {include}" + ("" if has_headers else "  (Python.h MISSING)"))
    versions = {name: _version(name) for name in PACKAGES}
    lines.append("packages     " + ", ".join(f"{n} {v or 'MISSING'}" for n, v in versions.items()))
    for name, v in versions.items():
        if v is None:
            problems.append(f"{name} is not installed: pip install -e . (or pip install {name})")
    if versions["pythonfmu"] not in (None, VENDORED_PYTHONFMU):
        problems.append(f"pythonfmu {versions['pythonfmu']} is installed; the FMUs' native "
                        f"layer is pythonfmu {VENDORED_PYTHONFMU}'s: pip install "
                        f"pythonfmu=={VENDORED_PYTHONFMU}")


def _threads(lines: list, problems: list) -> None:
    """Whether ``gsb run --in-process --threads N`` can share the bearings among threads (an
    option: nothing is a problem without it)."""
    import numba

    from bearing_fmu.hybrid.model import threading_layer

    layer = threading_layer()
    limit = numba.config.NUMBA_NUM_THREADS
    if layer is None:
        lines.append("threads      none: numba has no OpenMP or TBB layer here, so --threads "
                     "stays at 1 (apt install libgomp1, or pip install tbb)")
    else:
        lines.append(f"threads      numba's {layer} layer, up to {limit}: gsb run --in-process "
                     f"--threads {min(limit, 4)} shares the hybrid bearings")


def _caches(lines: list, problems: list) -> None:
    """The per-user cache, the FMUs of this code version, numba's kernels, the staged code."""
    from fmu_src.build.fmus import code_hash
    from fmu_src.slaves.bootstrap import cache_dir
    from orchestrator.coupling.fmi.cache import default_fmu_dir

    lines.append(f"caches       per-user {cache_dir()}"
                 + ("  (GSB_CACHE_DIR)" if os.environ.get("GSB_CACHE_DIR") else ""))
    fmu_dir = default_fmu_dir()
    built = sorted(p.stem for p in fmu_dir.glob("*.fmu")) if fmu_dir.is_dir() else []
    lines.append(f"  FMUs       {fmu_dir} (code {code_hash()}): "
                 + (", ".join(built) if built else "none built yet (the first run through "
                                                   "FMUs builds them)"))
    lines.append(f"  kernels    {_kernel_cache()}"
                 + ("  (NUMBA_CACHE_DIR)" if os.environ.get("NUMBA_CACHE_DIR") else ""))
    lines.append(f"  FMU code   {cache_dir() / 'code'} (what a host without this package runs)")


def _native(lines: list, problems: list) -> None:
    """The native layer, and the tools that build it."""
    from fmu_src.build.native import find_cmake, native_status

    native, reason = native_status()
    if native is not None:
        lines.append(f"native layer built: {native.library}"
                     + (f"\n  loader     {native.loader}" if native.loader else ""))
    else:
        lines.append(f"native layer NOT BUILT: {reason}")
        if not reason.startswith("not built yet"):
            problems.append(f"the FMUs' native layer: {reason}; then gsb doctor --rebuild")
    cmake = find_cmake()
    cxx = shutil.which(os.environ.get("CXX", "c++")) or shutil.which("g++") or \
        shutil.which("clang++")
    lines.append(f"  cmake      {cmake or 'MISSING (pip install cmake)'}"
                 + (f" ({_tool_version([cmake, '--version'])})" if cmake else ""))
    lines.append(f"  compiler   {cxx or 'MISSING (Debian/Ubuntu: apt install g++)'}"
                 + (f" ({_tool_version([cxx, '--version'])})" if cxx else ""))


def _hosts(lines: list, problems: list) -> None:
    """What an FMU host starts: its own Python (fmpy), or the loader's (a C/C++ host)."""
    from fmu_src.build.native import python_host_config

    host = dict(line.split("=", 1) for line in python_host_config().splitlines()
                if "=" in line and not line.startswith("#"))
    lines.append("FMU hosts    a Python host (fmpy) runs the FMUs in its own interpreter, which "
                 f"needs {REQUIREMENTS_TEXT}")
    libpython = host.get("libpython", "")
    lines.append(f"  C/C++ host the loader starts {host.get('executable')} with libpython "
                 f"{libpython or 'NONE'} (GSB_PYTHON, GSB_LIBPYTHON override)")
    if not libpython or not Path(libpython).is_file():
        problems.append("no shared libpython for this Python (a static build): a C/C++ host "
                        "cannot start it; use a Python built with --enable-shared (pyenv: "
                        "PYTHON_CONFIGURE_OPTS=--enable-shared) or set GSB_LIBPYTHON")
    check = subprocess.run([host.get("executable", sys.executable), "-c",
                            f"import {', '.join(REQUIREMENTS)}"], capture_output=True, text=True,
                           timeout=120)
    if check.returncode == 0:
        lines.append(f"  it imports {REQUIREMENTS_TEXT}: ok")
    else:
        last = (check.stderr.strip().splitlines() or ["?"])[-1]
        problems.append(f"the FMU hosts' Python {host.get('executable')} cannot import the "
                        f"FMUs' dependencies ({last}): install {REQUIREMENTS_TEXT} there")


def report() -> tuple[list[str], list[str]]:
    """(lines to print, problems with their fix)."""
    lines, problems = [], []
    for part in (_python, _threads, _caches, _native, _hosts):
        part(lines, problems)
    return lines, problems


def run(args) -> int:
    from fmu_src.build.native import export_library

    if args.rebuild:
        print("building the FMUs' native layer (CMake's output follows)", flush=True)
        export_library(quiet=False, retry=True)
    lines, problems = report()
    print("\n".join(lines))
    if problems:
        print("\nto fix:" + "".join(f"\n- {p}" for p in problems))
        return 1
    print("\nnothing missing")
    return 0
