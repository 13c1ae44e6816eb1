"""The FMUs' native layer builds from the running interpreter, whatever else is on PATH.

Under pyenv, CMake's FindPython found a shim's ``python3.13-config`` before the interpreter it
was given and the build failed; the FMUs then fell back, silently, to pythonfmu's own library.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

GSB = [sys.executable, "-m", "orchestrator.cli"]
OTHER = f"3.{sys.version_info.minor + 2}"  # a version this interpreter is not


def _decoys(folder: Path) -> Path:
    """``python3.X-config`` and ``python3-config`` of another version, as pyenv's shims put
    first on PATH: they answer for a Python this is not, with headers that do not exist."""
    folder.mkdir()
    script = ("#!/bin/sh\ncase \"$1\" in\n"
              f"  --includes|--cflags) echo -I/nonexistent/include/python{OTHER} ;;\n"
              f"  --prefix|--exec-prefix) echo /nonexistent ;;\n"
              f"  --extension-suffix) echo .cpython-3{OTHER[2:]}-x86_64-linux-gnu.so ;;\n"
              f"  --abiflags) echo ;;\n  *) echo -lpython{OTHER} ;;\nesac\n")
    for name in (f"python{OTHER}-config", "python3-config", "python-config"):
        path = folder / name
        path.write_text(script)
        path.chmod(path.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    return folder


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the loader is Linux only")
def test_build_fmus_builds_the_native_layer_with_a_decoy_python_config_first_on_path(tmp_path):
    decoys = _decoys(tmp_path / "shims")
    env = {**os.environ, "PATH": f"{decoys}{os.pathsep}{os.environ.get('PATH', '')}",
           "GSB_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("VIRTUAL_ENV", None)  # gsb called by its path, the environment not activated
    proc = subprocess.run([*GSB, "build-fmus", "--fmu", "BearingLumped", "--dest",
                           str(tmp_path / "fmus")], capture_output=True, text=True,
                          timeout=900, cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "native layer cannot be built" not in proc.stderr, proc.stderr[-3000:]
    with zipfile.ZipFile(tmp_path / "fmus" / "BearingLumped.fmu") as z:
        names = z.namelist()
        python_txt = z.read("resources/gsb_python.txt").decode()
    # the loader is the FMU's binary, the patched library beside it
    assert "binaries/linux64/libpythonfmu-export.so" in names
    assert f"executable={sys.executable}" in python_txt
    built = list((tmp_path / "cache" / "native").glob("*/libpythonfmu-export.so"))
    assert len(built) == 1


def test_a_machine_without_the_headers_is_told_why_and_how_once(tmp_path, monkeypatch):
    """No Python.h: one NativeLayerWarning with the reason and the fix, the reason recorded,
    the FMUs' build goes on with pythonfmu's library; a second call says nothing more."""
    import warnings

    from fmu_src.build import native as native_build

    monkeypatch.setenv("GSB_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(native_build, "python_build_config",
                        lambda: {"include": str(tmp_path / "no-headers"), "library": ""})
    monkeypatch.setattr(native_build, "_WARNED", set())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert native_build.export_library() is None
        assert native_build.export_library() is None
    messages = [str(w.message) for w in caught
                if issubclass(w.category, native_build.NativeLayerWarning)]
    assert len(messages) == 1, messages
    assert "Python.h is missing" in messages[0] and "-dev" in messages[0]
    assert "fmi2OK" in messages[0] and "gsb doctor --rebuild" in messages[0]
    built, reason = native_build.native_status()
    assert built is None and "Python.h is missing" in reason


def test_gsb_doctor_names_the_python_the_caches_and_the_native_layer(fmu_dir, tmp_path):
    """After a session's FMU build (``fmu_dir``, which needs the native layer): the layer is
    reported built; exit code 0 when nothing is missing, else 1 with a fix per problem."""
    proc = subprocess.run([*GSB, "doctor"], capture_output=True, text=True, timeout=300,
                          cwd=tmp_path)
    out = proc.stdout
    assert sys.executable in out and "numba " in out and "pythonfmu 0.7.0" in out
    assert "native layer built:" in out and "libgsb-loader.so" in out
    assert "imports numpy, scipy and numba: ok" in out
    if proc.returncode == 0:
        assert "nothing missing" in out
    else:
        assert proc.returncode == 1 and "to fix:\n- " in out, out + proc.stderr


def test_pythonfmu_is_pinned_to_the_release_whose_library_is_vendored():
    """The native layer is pythonfmu 0.7.0's library, patched: its Python side (the builder,
    Fmi2Slave, the setup_experiment signature the library calls) must be that release."""
    import importlib.metadata
    import tomllib

    from fmu_src.build.native import VENDORED_PYTHONFMU

    root = Path(__file__).resolve().parents[1]
    deps = tomllib.loads((root / "pyproject.toml").read_text())["project"]["dependencies"]
    assert f"pythonfmu=={VENDORED_PYTHONFMU}" in deps
    assert importlib.metadata.version("pythonfmu") == VENDORED_PYTHONFMU
