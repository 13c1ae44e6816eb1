"""The FMUs' native layer builds from the running interpreter, whatever else is on PATH, and
from pythonfmu's pristine sources with this project's patch series applied exactly.

Under pyenv, CMake's FindPython finds a shim's ``python3.X-config`` before the interpreter it
is given and the build fails; the FMUs would then fall back, silently, to pythonfmu's own
library.
A patch that no longer fits its upstream must stop the build, not apply approximately.
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

GSB = [sys.executable, "-m", "orchestrator.cli"]
MARK = "gear-shaft-bearing patch"
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
    assert "imports numpy, scipy, numba and threadpoolctl: ok" in out
    from bearing_fmu.hybrid.model import threading_layer  # the same answer in this process

    layer = threading_layer()
    assert (f"threads      numba's {layer} layer, up to " if layer else
            "threads      none: numba has no OpenMP or TBB layer here") in out
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

    root = Path(__file__).resolve().parents[2]
    deps = tomllib.loads((root / "pyproject.toml").read_text())["project"]["dependencies"]
    assert f"pythonfmu=={VENDORED_PYTHONFMU}" in deps
    assert importlib.metadata.version("pythonfmu") == VENDORED_PYTHONFMU


def test_the_patch_series_applies_to_the_pristine_copy_and_leaves_its_marks(tmp_path):
    """upstream/ carries no change of this project; every patch, numbered in order and
    described, applies exactly, and every line it adds with the mark is in the patched tree,
    beside the loader and the CMake project that joins the two."""
    from fmu_src.build.native import NATIVE_DIR, PATCHES_APPLIED, patch_series, prepare_sources
    from fmu_src.build.native_patch import read_patch

    upstream = [p for p in (NATIVE_DIR / "upstream").rglob("*") if p.is_file()]
    assert upstream and not [p for p in upstream if MARK.encode() in p.read_bytes()]
    tree = prepare_sources(tmp_path / "src")
    patches = [read_patch(p) for p in patch_series()]
    assert [p.name[:5] for p in patches] == [f"{i:04d}-" for i in range(1, len(patches) + 1)]
    assert (tree / PATCHES_APPLIED).read_text().split() == [p.name for p in patches]
    for patch in patches:
        assert patch.description.startswith(f"{MARK} {patch.name[:4]}: "), patch.name
        assert "What:" in patch.description and "Why:" in patch.description, patch.name
        marked = [(path, line) for path, line in patch.added_lines() if MARK in line]
        assert marked, f"{patch.name} adds no line with {MARK!r}"
        for path, line in marked:
            patched = (tree / "upstream" / path).read_text().splitlines(keepends=True)
            assert line in patched, (patch.name, path, line)
    assert (tree / "loader" / "gsb_loader.c").is_file()
    assert (tree / "CMakeLists.txt").read_bytes() == (NATIVE_DIR / "CMakeLists.txt").read_bytes()


def test_a_patch_whose_context_does_not_match_is_refused_by_patch_and_hunk(tmp_path,
                                                                            monkeypatch):
    """One context line of a patch's second hunk altered: the patch is refused with its name,
    file and hunk, its first hunk is not written either, and the build says so."""
    from fmu_src.build import native as native_build
    from fmu_src.build.native_patch import PatchError, apply_series

    source = next(p for p in native_build.patch_series() if "borrowed" in p.name)
    text = source.read_text()
    context = "     Py_DECREF(pLocals);\n     Py_DECREF(pyModule);\n-    Py_DECREF(pGlobals);"
    assert text.count(context) == 1
    corrupt = tmp_path / source.name
    corrupt.write_text(text.replace(context, context.replace("pLocals", "pLocal")))
    tree = shutil.copytree(native_build.NATIVE_DIR / "upstream", tmp_path / "upstream")
    target = tree / "src" / "pythonfmu" / "PySlaveInstance.cpp"
    before = target.read_bytes()
    with pytest.raises(PatchError) as caught:
        apply_series([corrupt], tree)
    message = str(caught.value)
    assert message.startswith(f"{source.name}: src/pythonfmu/PySlaveInstance.cpp: hunk 2 (@@ ")
    assert "does not match at line" in message and "pLocal)" in message
    assert target.read_bytes() == before

    monkeypatch.setattr(native_build, "patch_series", lambda: [corrupt])
    with pytest.raises(native_build.NativeBuildError, match=f"does not apply: {source.name}"):
        native_build.build_library(tmp_path / "native")
