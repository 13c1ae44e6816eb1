"""Probes of tests/system/test_results_safety.py: ``gsb`` failing midway, bad command lines,
every bearing model resumed."""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile

import numpy as np

from tests.probes import dispatch, probes_of


def failing_run(args: list[str], at: int) -> None:
    """``gsb args`` whose master's ``at``-th coupled step raises; exits with its code."""
    import pytest

    from orchestrator import cli
    from tests.helpers import fail_master_step

    fail_master_step(pytest.MonkeyPatch(), at=at)
    sys.exit(cli.main(args))


def bad_inputs(commands: list[list[str]]) -> list:
    """Per command line, ``gsb``'s exit code and what it wrote to stderr."""
    from orchestrator import cli

    out = []
    for args in commands:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            try:
                code = cli.main(args)
            except SystemExit as exc:  # argparse
                code = exc.code
        out.append([code, err.getvalue()])
    return out


def resume_every_model(in_process: bool, fmu_dir: str) -> dict:
    """Per registered bearing model: the rows of a run of 4 steps resumed to one mesh period,
    and its largest journal-position difference to the run of one period in one go (8 steps
    per mesh period; coarse film grids: the FD model's solves dominate otherwise)."""
    from bearing_fmu import MODELS
    from fmu_src.case import load_case
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import resume_run, run_case

    out = {}
    case = load_case("baguet2010_spur", {"simulation.steps_per_mesh_period": 8,
                                         "bearings.*.nodes": 48, "bearings.*.axial_intervals": 8})
    kw = dict(in_process=in_process, fmu_dir=fmu_dir, progress=False)
    with tempfile.TemporaryDirectory() as tmp:
        for model in MODELS:
            one = case.with_overrides({"bearings.*.model": model, "simulation.mesh_periods": 1})
            ref = run_case(one, out_dir=tmp + "/ref_" + model, **kw)
            part = run_case(one, steps=4, out_dir=tmp + "/" + model, **kw)
            resume_run(part.results, periods=1, fmu_dir=fmu_dir, progress=False)
            a, b = read_results(ref.results), read_results(part.results)
            out[model] = [len(b["time"]), float(np.abs(a["journal_position"]
                                                        - b["journal_position"]).max())]
    return out


PROBES = probes_of(failing_run, bad_inputs, resume_every_model)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
