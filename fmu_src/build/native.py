"""The FMU binary: pythonfmu's native layer with this project's patches, built once per machine.

The FMUs are built by pythonfmu (:mod:`fmu_src.build.fmus`), whose shared library carries the FMI C
interface and hosts the Python slave. pythonfmu 0.7.0's library turns every Python exception of
a setter or getter into fmi2Fatal and finalises the interpreter while a C++ host's process is
being torn down. ``fmu_src/native`` (:data:`NATIVE_DIR`; ``UPSTREAM.md`` there says where each
part comes from and how to update it) holds:

* ``upstream/``: that library's source as pythonfmu 0.7.0 ships it (MIT), unmodified;
* ``patches/``: this project's changes to it, one concern per numbered patch, each change
  marked ``gear-shaft-bearing patch`` in the code:

  - status protocol: a setter may return an int FMI status and a getter a tuple
    ``(values, status)``; a non-zero status is what the FMI call returns (fmi2Error at the
    fmi2SetReal that receives a bad value, fmi2Discard or fmi2Error at the read of an output
    that cannot be computed), the reason being in the FMU log. The library sets
    ``_fmi_status_protocol = True`` on the slave so that the slave knows it may do so;
  - the interpreter is never finalised by the library (the exit-time abort of C++ hosts);
  - a borrowed reference is not released (upstream releases it: the reason for
    ``pin_namespace``);
  - the interpreter, when the library starts it (a C/C++ host), leaves the host's signal
    handlers alone (``Py_InitializeEx(0)``);
  - CMake takes the Python of the build from this interpreter's ``sysconfig``, and builds into
    a given folder;
  - bytes fmi2DeSerializeFMUstate's slave refuses (not a state it wrote: the slaves read only
    :mod:`fmu_src.state_codec` states) make the call return fmi2Error, the instance kept, and
    ``_set_fmu_state`` may return a status as a setter does;
  - fmi2FreeInstance frees the instance: the library keeps no Python object from one
    instantiation to the next, and calls the slave's ``_fmi_release()`` before it drops it, so
    that the slave breaks its reference cycles and is freed at once
    (``ContractSlave._fmi_release`` in :mod:`fmu_src.slaves.support`);
  - no call enters Python once the interpreter is finalised (a Python host whose C exit
    handlers or C++ static destructors end the instances, as OMSimulator's Python API does):
    fmi2Terminate returns fmi2OK and fmi2FreeInstance frees the C++ side only;

* ``loader/``: this project's loader (Linux), the FMU's binary: it has no Python dependency,
  so a C/C++ host can load it; it loads libpython when the host has none (the paths of
  :func:`python_host_config`) and forwards every FMI call to the library above
  (:func:`export_library` returns both);
* ``CMakeLists.txt``: the project that builds the two.

:func:`prepare_sources` copies them into a build folder and applies the patches there, with
:mod:`fmu_src.build.native_patch` (strict: a hunk whose context does not match stops the build), so
that a machine needs neither git nor GNU patch and the pristine copy can be replaced by a new
release and the series re-applied.

:func:`export_library` compiles it with CMake (a dependency of fmpy) into the per-user cache
(:func:`fmu_src.slaves.bootstrap.cache_dir`) the first time and returns the cached file
afterwards; the cache key is a hash of the sources (:func:`native_sources`: the pristine copy,
the patches, the loader), the Python version and the platform. The Python it builds against is
the running interpreter, described by its own ``sysconfig`` (:func:`python_build_config`),
never what CMake's FindPython finds on PATH (under pyenv, a shim's ``python3.X-config`` of
another version).

Where it cannot be built (no C++ compiler, no CMake, no Python headers), :func:`export_library`
says why and how to fix it, once, records the reason in the cache (:data:`UNAVAILABLE`; ``gsb
doctor --rebuild`` tries again) and returns None: the FMUs then keep pythonfmu's own library,
with which a refused value is only logged (the call returns fmi2OK), an output that cannot be
computed reads NaN, and a C/C++ host must preload libpython.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import logging
import subprocess
import sys
import sysconfig
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

from fmu_src.slaves.bootstrap import cache_dir, locked
from fmu_src.build.native_patch import PatchError, apply_series

__all__ = ["NATIVE_DIR", "UNAVAILABLE", "VENDORED_PYTHONFMU", "NativeBuildError",
           "NativeLayerWarning", "NativeLibraries", "cache_dir", "export_library", "find_cmake",
           "native_sources", "native_status", "patch_series", "prepare_sources",
           "python_build_config", "python_host_config"]

#: pythonfmu's pristine library (upstream/), the patches (patches/), the loader (loader/)
NATIVE_DIR = Path(__file__).resolve().parent.parent / "native"
#: what of NATIVE_DIR the build uses (UPSTREAM.md, documentation only, is not)
_BUILT_FROM = ("CMakeLists.txt", "upstream", "patches", "loader")
#: in a prepared tree: the patches applied, one a line (the CMake project requires it)
PATCHES_APPLIED = "PATCHES_APPLIED"


def native_sources() -> list[tuple[str, Path]]:
    """(path relative to :data:`NATIVE_DIR`, file) of every file the native layer is built
    from, sorted: what a build's cache key and the FMUs' code hash cover."""
    files = []
    for name in _BUILT_FROM:
        top = NATIVE_DIR / name
        for path in [top] if top.is_file() else top.rglob("*"):
            if path.is_file():
                files.append((path.relative_to(NATIVE_DIR).as_posix(), path))
    return sorted(files)


def patch_series() -> list[Path]:
    """The patch files, in the order they apply (their numbers)."""
    return sorted((NATIVE_DIR / "patches").glob("*.patch"))


def prepare_sources(dest: Path) -> Path:
    """Write into ``dest`` the tree CMake builds: the pristine copy with the patch series
    applied, the loader and the project joining them; ``dest``. Raises
    :class:`~fmu_src.build.native_patch.PatchError` when a patch does not apply exactly."""
    dest.mkdir(parents=True, exist_ok=True)
    for rel, path in native_sources():
        if not rel.startswith("patches/"):
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, dest / rel)
    applied = apply_series(patch_series(), dest / "upstream")
    (dest / PATCHES_APPLIED).write_text("".join(p.name + "\n" for p in applied))
    return dest


def _key() -> str:
    h = hashlib.sha256()
    for rel, path in native_sources():
        h.update(rel.encode() + b"\0" + path.read_bytes())
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


#: the pythonfmu release whose native library is vendored (pyproject.toml pins it)
VENDORED_PYTHONFMU = "0.7.0"
#: in a native cache folder: why the library could not be built there (and the fix)
UNAVAILABLE = "UNAVAILABLE.txt"


class NativeBuildError(RuntimeError):
    """The native layer cannot be built here: ``reason`` and ``fix`` in words."""

    def __init__(self, reason: str, fix: str):
        super().__init__(f"{reason}; fix: {fix}")
        self.reason, self.fix = reason, fix


class NativeLayerWarning(RuntimeWarning):
    """The FMUs are built with pythonfmu's own library (the reason and the fix in the text)."""


def python_build_config() -> dict:
    """What the native layer is compiled against, from this interpreter's own ``sysconfig``:
    ``include`` (the folder of ``Python.h``) and ``library`` (the import library a module
    must link on Windows; empty elsewhere, where the host process provides Python's
    symbols)."""
    include = sysconfig.get_paths()["include"]
    library = ""
    if sys.platform == "win32":
        library = str(Path(sys.base_prefix) / "libs" / "python3.lib")
    return {"include": include, "library": library}


def find_cmake() -> str | None:
    """CMake beside this interpreter (the ``cmake`` wheel fmpy installs), else on PATH."""
    scripts = Path(sysconfig.get_path("scripts"))
    for candidate in (scripts / "cmake", scripts / "cmake.exe"):
        if candidate.is_file():
            return str(candidate)
    return shutil.which("cmake")


def _diagnose(output: str) -> NativeBuildError:
    """The reason and the fix from CMake's output."""
    tail = " ".join(line.strip() for line in output.strip().splitlines()[-6:])[-400:]
    if "CMAKE_CXX_COMPILER" in output or "CMAKE_C_COMPILER" in output:
        return NativeBuildError("no C/C++ compiler found (CMake: " + tail + ")",
                                "install one (Debian/Ubuntu: apt install g++; macOS: "
                                "xcode-select --install; Windows: Visual Studio Build Tools)")
    return NativeBuildError(f"CMake failed: {tail}",
                            "run `gsb doctor --rebuild` to see the whole output")


def build_library(folder: Path, quiet: bool = True) -> NativeLibraries:
    """Compile the patched library (and, on Linux, the loader) into ``folder``; raises
    :class:`NativeBuildError`."""
    config = python_build_config()
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    if not (Path(config["include"]) / "Python.h").is_file():
        raise NativeBuildError(
            f"the C headers of this Python ({sys.executable}, {version}) are not installed "
            f"({config['include']}/Python.h is missing)",
            f"install them (Debian/Ubuntu: apt install python{version}-dev; pyenv and the "
            "python.org installers include them)")
    cmake = find_cmake()
    if cmake is None:
        raise NativeBuildError("CMake not found (beside this Python or on PATH)",
                               "pip install cmake")
    files = _files(folder)
    target, loader = files.library, files.loader
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="build-", dir=folder) as tmp:
        out = Path(tmp) / "out"
        try:
            source = prepare_sources(Path(tmp) / "src")
        except PatchError as exc:
            raise NativeBuildError(f"the patch series does not apply: {exc}",
                                   "restore fmu_src/native as released (its UPSTREAM.md says "
                                   "how the patches are kept in step with upstream/)") from None
        commands = [
            [cmake, "-S", str(source), "-B", str(Path(tmp) / "build"),
             "-DCMAKE_BUILD_TYPE=Release", f"-DGSB_PYTHON_INCLUDE_DIR={config['include']}",
             f"-DGSB_PYTHON_LIBRARY={config['library']}", f"-DGSB_OUTPUT_DIR={out}"],
            [cmake, "--build", str(Path(tmp) / "build"), "--config", "Release"],
        ]
        for cmd in commands:
            try:
                proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
            except (OSError, subprocess.SubprocessError) as exc:
                raise NativeBuildError(f"{cmd[0]} could not run: {exc}",
                                       "check the CMake installation (pip install cmake)"
                                       ) from None
            if not quiet:
                print(proc.stdout + proc.stderr, flush=True)
            if proc.returncode != 0:
                raise _diagnose((proc.stdout or "") + (proc.stderr or ""))
        built = next(out.glob(_library_name()), None)
        built_loader = None if loader is None else next(out.glob(LOADER_NAME), None)
        if built is None or (loader is not None and built_loader is None):
            raise NativeBuildError(f"CMake built no {_library_name()} / {LOADER_NAME}",
                                   "run `gsb doctor --rebuild` to see the whole output")
        if loader is not None:  # atomic: concurrent builders leave complete files
            os.replace(built_loader, loader)
        os.replace(built, target)  # last: its presence means both are there
    return files


def _files(folder: Path) -> NativeLibraries:
    """Where the library and (on Linux) the loader of ``folder`` are, built or not."""
    loader = folder / LOADER_NAME if sys.platform.startswith("linux") else None
    return NativeLibraries(folder / _library_name(), loader)


def native_folder() -> Path:
    """This machine's folder of the native layer for these sources and this Python."""
    return cache_dir() / "native" / _key()


def native_status() -> tuple[NativeLibraries | None, str | None]:
    """(the built files, None) or (None, why they are not there: the recorded reason, or
    "not built yet")."""
    folder = native_folder()
    files = _files(folder)
    if files.library.is_file() and (files.loader is None or files.loader.is_file()):
        return files, None
    marker = folder / UNAVAILABLE
    if marker.is_file():
        return None, marker.read_text().strip()
    return None, "not built yet (it is built with the first FMU)"


_WARNED: set = set()


def export_library(quiet: bool = True, retry: bool = False) -> NativeLibraries | None:
    """The patched FMU library and the loader for this machine (built on first use), or None
    if they cannot be built here: then a :class:`NativeLayerWarning` (once per process) says
    why and how to fix it, and the reason is recorded so that later calls do not try again
    (``retry`` does: ``gsb doctor --rebuild``)."""
    folder = native_folder()
    built, _ = native_status()
    if built is not None:
        return built
    marker = folder / UNAVAILABLE
    with locked(folder):  # processes that start at once: one builds, the others wait
        built, _ = native_status()
        if built is not None:
            return built
        if marker.is_file() and not retry:
            reason = marker.read_text().strip()
        else:
            try:
                logging.getLogger("gsb.startup").info(
                    "building the FMUs' native layer with CMake in %s (once per machine and "
                    "Python version) ...", folder)
                built = build_library(folder, quiet)
                marker.unlink(missing_ok=True)  # a retry that succeeded
                return built
            except NativeBuildError as exc:
                reason = str(exc)
                marker.write_text(reason + "\n")
    if reason not in _WARNED:
        _WARNED.add(reason)
        warnings.warn(
            f"the FMUs' native layer cannot be built on this machine: {reason}; then `gsb "
            "doctor --rebuild`. Until then the FMUs carry pythonfmu's own library: a value "
            "out of bounds is only logged (the call returns fmi2OK), an output that cannot be "
            "computed reads NaN, and a C/C++ host must preload libpython (README, 'pythonfmu "
            "notes')", NativeLayerWarning, stacklevel=2)
    return None
