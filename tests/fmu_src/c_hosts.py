"""Building the C test hosts of ``tests/fmu_src/hosts`` (FMI 2.0 hosts without Python)."""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from fmu_src.build.native import NATIVE_DIR

HOSTS = Path(__file__).resolve().parent / "hosts"


def compile_host(source: str, output: Path, *flags: str) -> Path:
    """``output`` compiled from ``hosts/<source>`` with ``flags`` (e.g. ``-shared -fPIC``),
    against the FMI headers of the native layer's upstream; the test is skipped without a C
    compiler (gcc or cc on PATH)."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc or cc on PATH) to build the test hosts")
    include = NATIVE_DIR / "upstream" / "src"  # fmi/fmi2Functions.h
    cmd = [cc, "-O1", "-Wall", *flags, f"-I{include}", str(HOSTS / source), "-o", str(output),
           "-ldl"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, f"{' '.join(cmd)}:\n{proc.stderr[-2000:]}"
    return output


def unzip_fmu(fmu: Path, folder: Path):
    """``fmu`` unzipped into ``folder`` for a C host (its Linux binary made executable): its
    model description and its variables' value references by name."""
    from fmpy import read_model_description

    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    (folder / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so").chmod(0o755)
    return md, {v.name: v.valueReference for v in md.modelVariables}
