"""The scripts of benchmarks/ still run against the code (their figures are quoted in
docs/benchmarks.md): each at its smallest size, in a fresh interpreter, exits 0 and prints
figures. Nothing here is timed: speed is read from the scripts' own output, never asserted."""

import re
import subprocess
import sys

import pytest

from tests.helpers import ROOT, probe_env

#: script -> the smallest run of it (arguments)
SMALLEST = {
    "paper_case.py": ["--periods", "1", "--skip-fmu"],
    "results_writer.py": ["--periods", "1", "--skip-fmu"],
    "structure_step.py": ["--steps", "20"],
    "fmu_overhead.py": ["--steps", "5"],
    "startup.py": ["--repeat", "1"],
    "sweep_efficiency.py": ["--periods", "1", "--speeds", "2"],
    "bearing_models.py": [],
    "transmission_fmu.py": ["--periods", "1", "--repeat", "1"],
    "campbell.py": ["--repeat", "1", "--speeds", "3"],
    "kernel_parts.py": ["--steps", "2", "--calls", "10"],
    "bearing_set.py": ["--steps", "2", "--repeat", "1"],
    "base_runs.py": ["--periods", "2", "--cases", "spur", "--models", "lumped"],
    "run_up.py": ["--periods", "2", "--repeat", "1"],
    "held_arrays.py": ["--arrays", "3", "--calls", "10"],
    "scaling.py": ["--periods", "1", "--slices", "10"],
}


def test_every_benchmark_is_run_here():
    assert {p.name for p in (ROOT / "benchmarks").glob("*.py")} == set(SMALLEST)


@pytest.mark.parametrize("script", sorted(SMALLEST))
def test_the_benchmark_runs_at_its_smallest_size(script, fmu_dir, tmp_path, request):
    args = SMALLEST[script]
    if script == "fmu_overhead.py":
        args = [*args, "--fmu", str(fmu_dir / "GearShaft.fmu")]
    if script == "transmission_fmu.py":
        args = [*args, "--fmu", str(request.getfixturevalue("transmission_fmu"))]
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), *args],
                          capture_output=True, text=True, timeout=600, cwd=tmp_path,
                          env=probe_env())
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert re.search(r"\d\.\d", proc.stdout), proc.stdout[-2000:]  # figures printed
