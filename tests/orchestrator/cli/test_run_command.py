"""``gsb run`` as a user meets it: the same run twice, a file it must not touch, a failed
step, and how a run is named.

The runs are one mesh period in-process: the command line in this process (``main``, whose
return value is the exit code), and a ``gsb`` process where a fresh process is the point (the
second run answers without computing anything).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from orchestrator.run.results import add_attributes, read_attributes, read_results

GSB = [sys.executable, "-m", "orchestrator.cli"]
ONE_PERIOD = ["baguet2010_spur", "--periods", "1", "--in-process"]
#: the progress line of a computed run ("<name> [####...] 32/32 100.0 % ..."): on stderr, one
#: at the start even when stderr is not a terminal
PROGRESS = re.compile(r"baguet2010_spur_\w+ \[[# ]*\] \d+/32")


def gsb(*args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([*GSB, *map(str, args)], capture_output=True, text=True,
                          timeout=600, cwd=cwd)


def test_the_same_run_again_answers_from_its_file_and_overwrite_computes_it(tmp_path, capsys):
    """The first run and the --overwrite one are the command line in this process (start-up
    saved); the second, whose answer is the point, a ``gsb`` process."""
    from orchestrator.cli import main

    out = tmp_path / "results"
    capsys.readouterr()
    assert main(["run", *ONE_PERIOD, "--out", str(out)]) == 0
    first = capsys.readouterr()
    assert PROGRESS.search(first.err), first.err[-2000:]
    [path] = out.glob("*.h5")
    figures = sorted(path.with_suffix("").glob("*.png"))
    assert len(figures) == 4
    stamps = [p.stat().st_mtime_ns for p in (path, *figures)]
    data = path.read_bytes()

    again = gsb("run", *ONE_PERIOD, "--out", out, cwd=tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    # nothing computed: no progress, no warning of the checks before a transient, the file
    # and its figures untouched; the same report as the run that computed it
    assert not PROGRESS.search(again.stderr) and "warning" not in again.stderr, again.stderr
    assert "32 steps read from the stored results of the same inputs" in again.stdout
    assert "--overwrite computes them again" in again.stdout
    assert path.read_bytes() == data
    assert [p.stat().st_mtime_ns for p in (path, *figures)] == stamps
    report = [line for line in first.out.splitlines() if not line.startswith(
        ("32 steps", "figure:"))]
    assert [line for line in again.stdout.splitlines() if not line.startswith(
        ("32 steps", "figure:"))] == report
    assert [line for line in again.stdout.splitlines() if line.startswith("figure:")] == \
        [line for line in first.out.splitlines() if line.startswith("figure:")]

    # --overwrite computes it again, into the same file
    capsys.readouterr()
    assert main(["run", *ONE_PERIOD, "--out", str(out), "--no-figures", "--overwrite"]) == 0
    captured = capsys.readouterr()
    assert PROGRESS.search(captured.err) and "32 steps in " in captured.out, captured
    assert path.stat().st_mtime_ns != stamps[0]
    assert len(read_results(path)["time"]) == 32


def test_a_file_of_other_inputs_is_never_reused_nor_replaced(tmp_path, capsys):
    """A complete file under the run's name whose stored case differs (a changed torque
    stands for a hash collision or a file of another version) is refused, --overwrite or
    not; an incomplete file of the run's own inputs says how to continue it."""
    from orchestrator.cli import main

    out = tmp_path / "results"
    args = ["run", *ONE_PERIOD, "--out", str(out), "--no-figures", "--quiet"]
    assert main(args) == 0
    [path] = out.glob("*.h5")
    toml = read_attributes(path)["case_toml"]
    assert "torque = 220.0" in toml  # the shipped case's value, changed below
    add_attributes(path, case_toml=toml.replace("torque = 220.0", "torque = 221.0"))
    data = path.read_bytes()
    for extra in ([], ["--overwrite"]):
        capsys.readouterr()
        assert main(args + extra) == 2
        err = capsys.readouterr().err
        assert "holds a run of other inputs" in err and "neither reused nor replaced" in err
        assert path.read_bytes() == data

    add_attributes(path, case_toml=toml, complete=False)
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "exists (incomplete, 32 steps)" in err and f"--resume {path}" in err, err

    # how it stopped, in words: an interruption as recorded, a failure after "stopped by"
    from orchestrator.run.files import describe_file

    add_attributes(path, stopped_by="interrupted by SIGINT after step 32 of 64")
    assert describe_file(path) == "incomplete, 32 steps, interrupted by SIGINT after step 32 of 64"
    add_attributes(path, stopped_by="RunError: step 33 failed")
    assert describe_file(path) == "incomplete, 32 steps, stopped by RunError: step 33 failed"


def test_the_version_and_a_static_solution_of_one_iteration_read_as_english(capsys):
    """``gsb --version`` prints the installed version; a count of one is singular."""
    from importlib.metadata import version

    from orchestrator.cli import main
    from orchestrator.run.runner import RunSummary

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"gsb {version('gear-shaft-bearing')}"
    one = RunSummary(None, 32, 1.0, 0.1, 64, 64, 1, np.zeros((4, 2)))
    assert "static solution in 1 iteration (0.10 s)" in one.describe()


def test_a_failed_step_names_the_bearing_in_units(tmp_path, capsys):
    """An unbalance of 10 m drives bearing 1's journal into the wall at step 3: the message
    names the bearing, the time in s, the position in um against the 150 um clearance and the
    eccentricity ratio (the bearing model's own check finds 1.10171: Eq. of the clearance
    circle), says what to change and prints no raw state vector. (The command line in this
    process: a ``gsb`` process adds only its start-up.)"""
    from orchestrator.cli import main

    capsys.readouterr()
    assert main(["run", *ONE_PERIOD, "--unbalance", "10 m", "--no-figures", "--quiet",
                 "--out", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    line = err.strip().splitlines()[-1]
    assert line.startswith("gsb run: error: step 3 of 32 (t = 6.97099e-05 s) failed: "), line
    assert "bearing 1's journal reached the bearing wall: eccentricity ratio 1.102 " in line
    m = re.search(r"s = ([\d.]+) um, t = ([\d.]+) um \(radial clearance 150.0 um\)", line)
    assert m, line
    assert float(m[1]) ** 2 + float(m[2]) ** 2 == pytest.approx((1.10171 * 150.0) ** 2,
                                                                 rel=2e-3)
    assert "the unbalance force of shaft pinion_shaft exceeds" in line
    assert "lower gears.pinion.unbalance (--unbalance sets every gear's)" in line
    assert "the 2 steps computed are in" in line
    assert not re.search(r"\[[-\d.e]+, ", line), line  # no raw state vector


@pytest.mark.parametrize(("stems", "model", "label"), [
    (["BearingHybrid"] * 4, "hybrid", "hybrid"),  # an SSP of gsb export-ssp
    (["BearingShort"] * 4, "short", "short"),
    (["BearingLinear"] * 4, "hybrid", "fmu-BearingLinear"),  # not the case's model
    (["My bearing v2"] * 4, "hybrid", "fmu-My-bearing-v2"),  # the user's own
])
def test_a_run_of_bearing_fmus_is_named_by_their_model(tmp_path, stems, model, label):
    from fmu_src.case import load_case
    from orchestrator.run.spec import RunSpec

    case = load_case("baguet2010_spur").with_overrides({"bearings.*.model": model})
    spec = RunSpec.of(case, fmus={"gear": Path("GearShaft.fmu"),
                                  "bearings": [tmp_path / f"{s}.fmu" for s in stems]})
    assert spec.label == label


def test_a_run_resumed_longer_is_replaced_only_with_overwrite(tmp_path, capsys):
    """A one-period run resumed to two periods keeps its file name; the one-period run asked
    again finds a run of the same inputs but of another length: it says so in numbers (no
    numpy reprs) and names --overwrite, which then replaces it."""
    from orchestrator.cli import main

    out = tmp_path / "results"
    args = ["run", *ONE_PERIOD, "--out", str(out), "--no-figures", "--quiet"]
    assert main(args) == 0
    [path] = out.glob("*.h5")
    assert main(["run", "--resume", str(path), "--periods", "2", "--no-figures", "--quiet"]) == 0
    assert len(read_results(path)["time"]) == 64
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "a run of the same inputs but of another length (steps_total 64, this run's 32" in err
    assert "--overwrite replaces it" in err and "np." not in err, err
    assert main([*args, "--overwrite"]) == 0
    assert len(read_results(path)["time"]) == 32


def test_another_window_answers_from_the_stored_run(tmp_path, capsys):
    """``--window`` chooses what the report is taken over, not what is computed: the same
    run with another window is read from its file (untouched, its name the same), reported
    and drawn over the new window."""
    from orchestrator.cli import main

    out = tmp_path / "results"
    assert main(["run", *ONE_PERIOD, "--out", str(out)]) == 0
    [path] = out.glob("*.h5")
    data = path.read_bytes()
    capsys.readouterr()
    assert main(["run", *ONE_PERIOD, "--out", str(out), "--window", "0.5 periods"]) == 0
    printed = capsys.readouterr().out
    assert "32 steps read from the stored results of the same inputs" in printed
    assert "report over the last 0.5 mesh periods" in printed
    assert list(out.glob("*.h5")) == [path] and path.read_bytes() == data
    assert read_attributes(path)["report_window_kind"] == "last half of the run"
