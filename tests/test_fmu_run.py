"""The paper's case run through real FMUs (gear-shaft FMU + four bearing FMUs, fmpy) against the
in-process master, which tests/test_run.py checks against a monolithic Newton-Raphson.

Each configuration runs in a fresh interpreter that exits normally (the way a user's host runs
the FMUs; see test_bearing_fmus.py for why).
"""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from fmu_src.build import build_fmus

ROOT = Path(__file__).parents[1]


@pytest.fixture(scope="module")
def fmu_dir(tmp_path_factory):
    dest = tmp_path_factory.mktemp("fmus")
    build_fmus(dest, ["GearShaft", "BearingHybrid", "BearingLinear", "BearingLumped"])
    return dest


def run_isolated(code: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=600, cwd=ROOT)
    assert proc.returncode == 0, f"exit code {proc.returncode}: {proc.stderr[-3000:]}"
    return json.loads(proc.stdout.strip().splitlines()[-1])


def compare(fmu_dir, model, periods, tmp):
    return run_isolated(f"""
        import json
        import numpy as np
        from orchestrator.case import load_case
        from orchestrator.results import read_results
        from orchestrator.run import run_case
        case = load_case("models/baguet2010_spur.toml")
        out = {{}}
        for in_process in (True, False):
            s = run_case(case, bearing={model!r}, periods={periods}, in_process=in_process,
                         out_dir={str(tmp)!r}, fmu_dir={str(fmu_dir)!r}, progress=False,
                         figures=False)
            r = read_results(s.results)
            out[in_process] = (r["journal"], r["bearing_force"], s.iterations_per_step,
                               r["attrs"]["mode"])
        j_in, f_in, it_in, _ = out[True]
        j_fmu, f_fmu, it_fmu, mode = out[False]
        print(json.dumps({{
            "journal": float(np.abs(j_fmu - j_in).max() / np.abs(j_in).max()),
            "force": float(np.abs(f_fmu - f_in).max() / np.abs(f_in).max()),
            "it_in": it_in, "it_fmu": it_fmu, "mode": mode, "steps": len(j_in)}}))
    """)


def test_fmu_cosimulation_equals_the_in_process_master(fmu_dir, tmp_path):
    """256 steps of the paper's case with hybrid bearings: the FMUs and the in-process slaves
    run the same code on the same numbers; agreement far inside the coupling tolerance 1e-5."""
    r = compare(fmu_dir, "hybrid", 8, tmp_path)
    print(f"\nFMUs vs in-process, 256 steps: journal {r['journal']:.1e}, force {r['force']:.1e}"
          f" (relative); {r['it_fmu']:.2f} vs {r['it_in']:.2f} iterations per step")
    assert r["mode"] == "fmu" and r["steps"] == 256
    assert r["journal"] < 1e-8 and r["force"] < 1e-8
    assert 1.5 < r["it_fmu"] < 4.0


@pytest.mark.parametrize("model", ["linear", "lumped"])
def test_affine_bearing_fmus_converge_in_one_pass(fmu_dir, tmp_path, model):
    r = compare(fmu_dir, model, 2, tmp_path)
    assert r["it_fmu"] == 1.0 and r["it_in"] == 1.0
    assert r["journal"] < 1e-8


def test_swapping_the_bearing_fmu_is_a_file_name(fmu_dir):
    """The bearing set of a case differs between models only by the FMU file it loads."""
    r = run_isolated(f"""
        import json
        from orchestrator.case import load_case
        from orchestrator.fmi import system_from_case
        case = load_case("models/baguet2010_spur.toml")
        out = {{}}
        for model in ("hybrid", "lumped"):
            st, b = system_from_case(case, model, {str(fmu_dir)!r})
            out[model] = sorted({{s.path.name for s in b.slaves}})
            b.close(); st.close()
        print(json.dumps(out))
    """)
    assert r == {"hybrid": ["BearingHybrid.fmu"], "lumped": ["BearingLumped.fmu"]}
