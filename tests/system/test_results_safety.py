"""Results a user can trust: nothing clobbered, nothing lost, runs that resume, no traceback.

The runs that are interrupted, killed or resumed from a file are ``gsb`` processes, as a user
starts them. The reference for a resumed run is an uninterrupted run of the same case (in the
test's process): every channel must be equal to 1e-12 (relative; they are in fact identical).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from orchestrator.run.results import read_checkpoint, read_results
from tests.helpers import paced_gsb, probe_command, probe_env, run_here

GSB = [sys.executable, "-m", "orchestrator.cli"]
ROOT = Path(__file__).resolve().parents[2]
QUICK = ["--bearing", "linear", "--in-process", "--no-figures", "--quiet"]
PROBES = "tests.probes.results_safety"


def gsb(*args, cwd, timeout=600, env=None):
    return subprocess.run([*GSB, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd, env=env)


def only(folder: Path, pattern: str = "*.h5") -> Path:
    files = sorted(folder.glob(pattern))
    assert len(files) == 1, files
    return files[0]


def test_runs_with_other_overrides_keep_their_own_files(tmp_path, capsys):
    out = tmp_path / "results"
    a = gsb("run", "baguet2010_spur", "--periods", "1", *QUICK, "--out", out, cwd=tmp_path)
    b = gsb("run", "baguet2010_spur", "--periods", "1", "--speed", "400 rad/s", *QUICK,
            "--out", out, cwd=tmp_path)
    assert a.returncode == 0 and b.returncode == 0, (a.stderr[-1500:], b.stderr[-1500:])
    files = sorted(out.glob("*.h5"))
    assert len(files) == 2 and all(f.name.startswith("baguet2010_spur_linear_inprocess_")
                                   for f in files)
    speeds = sorted(float(read_results(f)["attrs"]["speed"]) for f in files)
    assert speeds == [325.0, 400.0]
    # the same run again (the command line in this process): answered from its file,
    # nothing computed, both files untouched
    from orchestrator.cli import main

    before = files[0].stat().st_mtime_ns, files[1].stat().st_mtime_ns
    capsys.readouterr()
    assert main(["run", "baguet2010_spur", "--periods", "1", *QUICK, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "32 steps read from the stored results" in printed and "--overwrite" in printed
    assert (files[0].stat().st_mtime_ns, files[1].stat().st_mtime_ns) == before


def test_a_failing_run_leaves_a_complete_file_untouched(tmp_path, capsys):
    """--overwrite over a complete file, and the new run fails at step 40: the complete file
    stays as it was, the failed run's 39 steps are in <name>.partial.h5, which the next runs
    name (kept when answered from the complete file, replaced by an --overwrite)."""
    from orchestrator.cli import main

    out = tmp_path / "results"
    assert main(["run", "baguet2010_spur", "--periods", "2", *QUICK, "--out", str(out)]) == 0
    complete = only(out)
    data = complete.read_bytes()
    args = ["run", "baguet2010_spur", "--periods", "2", *QUICK, "--out", str(out), "--overwrite"]
    proc = subprocess.run(probe_command(PROBES, "failing_run", {"args": args, "at": 40}),
                          capture_output=True, text=True, timeout=600, cwd=tmp_path,
                          env=probe_env())
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert "step 40 of 64" in proc.stderr and ".partial.h5" in proc.stderr
    assert complete.read_bytes() == data
    partial = only(out, "*.partial.h5")
    r = read_results(partial)
    assert len(r["time"]) == 39 and not r["attrs"]["complete"]
    assert "forced failure" in r["attrs"]["stopped_by"]
    capsys.readouterr()
    assert main(args[:-1]) == 0  # answered from the complete file
    err = capsys.readouterr().err
    assert f"gsb run: warning: {partial} (incomplete, 39 steps, stopped by " in err, err
    assert "holds the steps of an --overwrite" in err and "kept; the next --overwrite" in err
    assert main(args) == 0
    assert "this --overwrite replaces it" in capsys.readouterr().err
    assert not partial.exists() and complete.is_file()


def _interrupt(cmd, out: Path, sig, cwd) -> tuple[subprocess.CompletedProcess, dict]:
    """Start ``cmd`` (paced: :func:`paced_gsb`), wait until its results file has rows and a
    checkpoint (read while it is written: SWMR), send ``sig``; returns the finished process
    and what the reader saw."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=cwd)
    seen = {}
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None:
        files = list(out.glob("*.h5"))
        if files:
            try:
                r = read_results(files[0])
            except OSError:  # created, not yet in SWMR mode
                r = None
            # rows and, written just after them, the checkpoint they resume from (a kill
            # between the two at the first flush leaves rows a resume cannot continue)
            if r is not None and len(r["time"]) >= 40 and read_checkpoint(files[0]):
                seen = {"rows": len(r["time"]), "complete": bool(r["attrs"]["complete"])}
                break
        time.sleep(0.05)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr), seen


@pytest.mark.parametrize("transport", ["in-process", "fmu"])
def test_signals_and_a_kill_keep_the_steps_and_the_run_resumes_exactly(transport, fmu_dir,
                                                                       tmp_path):
    """SIGINT and SIGTERM in the middle of a run (hybrid bearings: warm-started solvers):
    exit 130 / 143, no traceback, the steps kept with the reason; the file is readable while
    the run writes it; ``gsb run --resume`` then finishes it, equal to an uninterrupted run."""
    # the interrupted runs are paced (at least PACE s a step: 3 s for the run) so that the
    # signal lands in the transient whatever the machine's speed: the first rows appear with
    # the first flush, after 1 s of steps
    periods = "24"
    opts = ["--no-figures", "--quiet", "--fmu-dir", str(fmu_dir)]
    from fmu_src.case import load_case
    from orchestrator.run.runner import run_case

    if transport == "in-process":
        opts.append("--in-process")
    # the uninterrupted reference, in this process
    run_case(load_case("baguet2010_spur").with_overrides({"simulation.mesh_periods": int(periods)}),
             in_process=transport == "in-process", fmu_dir=fmu_dir, out_dir=tmp_path / "ref",
             progress=False)
    reference = read_results(only(tmp_path / "ref"))
    n = len(reference["time"])
    # SIGKILL (a crash, a power cut): no clean-up at all; the rows up to the last flush and
    # its checkpoint are kept, the resume computes the rest (in-process: one transport suffices
    # for what the file format guarantees)
    kill = (signal.SIGKILL,) if transport == "in-process" else ()
    for sig in (signal.SIGINT, signal.SIGTERM, *kill):
        out = tmp_path / sig.name
        proc, seen = _interrupt(paced_gsb("run", "baguet2010_spur", "--periods", periods,
                                          *opts, "--out", out), out, sig, tmp_path)
        assert seen and not seen["complete"], "the file could not be read during the run"
        path = only(out)
        r = read_results(path)
        kept = len(r["time"])
        assert 0 < kept < n, (kept, n)
        assert not r["attrs"]["complete"]
        if sig == signal.SIGKILL:
            assert proc.returncode == -int(sig)
        else:
            assert proc.returncode == 128 + int(sig), proc.stderr[-2000:]
            assert "Traceback" not in proc.stderr and f"interrupted by {sig.name}" in proc.stderr
            # the count it announces is the rows the file holds
            assert f"; {kept} steps kept in {path}; `gsb run --resume {path}` continues it" \
                in proc.stderr, (kept, proc.stderr[-500:])
            assert r["attrs"]["interrupted"] == sig.name and sig.name in r["attrs"]["stopped_by"]
        np.testing.assert_array_equal(r["journal_position"], reference["journal_position"][:kept])
        if transport == "fmu" and sig == signal.SIGINT:
            continue  # through FMUs one resume (of the SIGTERM run) shows the FMU states
        resume = ["run", "--resume", str(path), "--fmu-dir", str(fmu_dir), "--no-figures",
                  "--quiet"]
        if transport == "in-process":  # the command line in this process (start-up saved)
            from orchestrator.cli import main

            assert main(resume) == 0
        else:  # a new process restores the FMUs' serialised states from the file
            res = gsb(*resume, cwd=tmp_path)
            assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr[-2000:]
        r = read_results(path)
        assert r["attrs"]["complete"] and r["attrs"]["resumed_at_step"] <= kept
        assert len(r["time"]) == n
        for key in ("journal_position", "journal_velocity", "bearing_force", "mesh_force",
                    "transmission_error"):
            scale = np.abs(reference[key]).max()
            err = np.abs(r[key] - reference[key]).max() / scale
            assert err <= 1e-12, (sig.name, key, err)
        print(f"\n{transport} {sig.name}: exit {proc.returncode}, {kept} of {n} steps kept, "
              f"read while written at {seen['rows']} rows; resumed from step "
              f"{r['attrs']['resumed_at_step']}: equal to the uninterrupted run")


def test_resume_extends_a_run(tmp_path, capsys):
    """--periods on a resume extends a complete run; the result equals one longer run (the
    command line called in this process: the subprocess tests above cover the process)."""
    from orchestrator.cli import main

    assert main(["run", "baguet2010_spur", "--periods", "3", *QUICK, "--out",
                 str(tmp_path / "short")]) == 0
    assert main(["run", "baguet2010_spur", "--periods", "5", *QUICK, "--out",
                 str(tmp_path / "long")]) == 0
    short, long = only(tmp_path / "short"), only(tmp_path / "long")
    capsys.readouterr()
    assert main(["run", "--resume", str(short)]) == 2
    assert "give --periods above 3" in capsys.readouterr().err
    assert main(["run", "--resume", str(short), "--periods", "5", "--no-figures",
                 "--quiet"]) == 0
    r, ref = read_results(short), read_results(long)
    assert r["attrs"]["complete"] and r["attrs"]["mesh_periods"] == 5
    np.testing.assert_array_equal(r["journal_position"], ref["journal_position"])
    # gsb export: X0 at t = 0, then one row per step, columns named with their units, values
    # to the last digit
    capsys.readouterr()
    assert main(["export", str(short), "--csv", str(tmp_path / "short.csv")]) == 0
    lines = (tmp_path / "short.csv").read_text().splitlines()
    head = lines[0].split(",")
    assert len(lines) == 1 + 1 + 160 and head[0] == "time [s]"
    assert ("journal_position[bearing=1][axis=t] [m]" in head
            and "bearing_force[bearing=4][axis=s] [N]" in head)
    col = head.index("mesh_force[mesh=mesh] [N]")
    assert float(lines[1].split(",")[col]) == r["attrs"]["static_mesh_force"][0]
    assert [float(line.split(",")[col]) for line in lines[2:]] == r["mesh_force"][:, 0].tolist()


class _WritesAFile:
    """Unpickling this creates ``path``: a pickle that runs code when it is loaded."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _put_checkpoint(path: Path, data: bytes, format_version: bool = True) -> None:
    """Replace the last checkpoint of a results file by ``data`` (a crafted file); without
    ``format_version``, as the files of older versions were."""
    import h5py

    with h5py.File(path, "a") as f:
        grp = f["resume"]
        slot, _, rows = (int(v) for v in grp["index"][()])
        blob = np.frombuffer(data, dtype=np.uint8)
        grp[f"slot{slot}"].resize(blob.size, axis=0)
        grp[f"slot{slot}"][:] = blob
        grp["index"][:] = np.array([slot, blob.size, rows], dtype=np.int64)
        if not format_version:
            del grp.attrs["format_version"]


def test_a_checkpoint_that_is_not_plain_numbers_is_refused_and_never_loaded(tmp_path):
    """A results file handed over by someone else: ``gsb run --resume`` refuses a checkpoint
    that is a pickle (one that would create a file when loaded: it is not loaded), another
    kind of state, or one lacking an entry, exit code 2 with the file and the reason, and the
    file is left as it was."""
    import hashlib
    import io
    import pickle
    import shutil

    from fmu_src.state_codec import decode, encode
    from orchestrator.coupling.master import CHECKPOINT_KIND

    run = gsb("run", "baguet2010_spur", "--periods", "1", *QUICK, "--out", tmp_path / "run",
              cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    original = only(tmp_path / "run")
    rows, blob = read_checkpoint(original)
    assert rows == 32
    decode(blob, CHECKPOINT_KIND)  # what the run wrote is a checkpoint
    with np.load(io.BytesIO(blob), allow_pickle=False) as z:
        without_laws = {n: z[n] for n in z.files if not n.startswith("__") and n != "laws/f0"}
    marker = tmp_path / "marker"
    evil = pickle.dumps(_WritesAFile(marker))
    cases = [
        ("pickle", evil, True, ["the checkpoint is a Python pickle", "refused"]),
        ("older", evil, False, ["no format_version", "pickles: refused"]),
        ("kind", encode("gsb.gear_shaft_fmu_state", {"x": 1.0}), True,
         ["is a 'gsb.gear_shaft_fmu_state' state, not a 'gsb.master_checkpoint' state"]),
        ("entry", encode(CHECKPOINT_KIND, without_laws), True,
         ["the checkpoint lacks the entry 'laws/f0'"]),
    ]
    for name, data, versioned, words in cases:
        path = tmp_path / f"{name}.h5"
        shutil.copy(original, path)
        _put_checkpoint(path, data, versioned)
        before = hashlib.sha256(path.read_bytes()).hexdigest()
        proc = gsb("run", "--resume", path, "--periods", "2", "--no-figures", "--quiet",
                   cwd=tmp_path)
        lines = [ln for ln in proc.stderr.splitlines() if ln.strip()
                 and "warning: " not in ln]
        assert proc.returncode == 2, (name, proc.stderr[-2000:])
        assert "Traceback" not in proc.stderr and len(lines) == 1, (name, proc.stderr)
        assert lines[0].startswith("gsb ") and f"--resume {path}: " in lines[0], lines[0]
        for w in words:
            assert w in lines[0], (name, w, lines[0])
        assert not marker.exists(), name  # the pickle was never loaded
        assert hashlib.sha256(path.read_bytes()).hexdigest() == before, name
    # the marker would have been written, had the pickle been loaded
    pickle.loads(evil).close()
    assert marker.exists()


#: (arguments, words the one-line message must contain); run in one subprocess (no traceback)
BAD_INPUTS = [
    (["run", "baguet2010_spur", "--periods", "0"], ["--periods 0", ">= 1"]),
    (["run", "baguet2010_spur", "--set", "tolerance=1e-6"], ["tolerance", "section.key"]),
    (["run", "baguet2010_spur", "--set", "a.b.c=1"], ["a.b.c", "section.key"]),
    (["run", "baguet2010_spur", "--set", "simulation.nope=1"], ["simulation.nope"]),
    (["run", "baguet2010_spur", "--torque", "0 N m"], ["drive.torque", "> 0"]),
    (["run", "baguet2010_spur", "--speed", "-5 rad/s"], ["drive.speed", "> 0"]),
    (["run", "baguet2010_spur", "--unbalance", "3 N"], ["gears.*.unbalance", "N"]),
    (["run", "baguet2010_spur", "--in-process", "--torque", "50000 N m"],
     ["bearing 1 carries", "N, its film at most", "bearings.*.length", "drive.torque"]),
    (["run", "baguet2010_spur", "--set", "meshes.mesh.centre_distance=380 mm"],
     ["meshes.mesh", "centre_distance = 380.000 mm", "366.000 mm"]),
    (["run", "baguet2010_spur", "--set", "gears.*.profile_shift=0.9"],
     ["meshes.mesh", "profile_shift = [0.9, 0.9]", "root circle"]),
    (["run", "nope_case"], ["nope_case", "shipped cases"]),
    (["run", "--resume", "missing.h5"], ["--resume", "missing.h5"]),
    (["run", "--resume", "not_hdf5.h5"], ["--resume", "not_hdf5.h5"]),
    (["run", "baguet2010_spur", "--out", "a_file"], ["--out a_file", "not a folder"]),
    (["run", "baguet2010_spur", "--out", "/proc/no/such"], ["--out /proc/no/such"]),
    (["modal", "baguet2010_spur", "--bearing-stiffness", "-1"], ["--bearing-stiffness", "> 0"]),
    (["build-fmus", "Nope"], ["Nope", "shipped cases"]),
    (["export", "missing.h5"], ["missing.h5", "no such file"]),
    (["export", "not_hdf5.h5"], ["not_hdf5.h5", "HDF5"]),
    (["plot", "not_hdf5.h5"], ["not_hdf5.h5"]),
    (["cases", "--show", "nope"], ["--show nope", "baguet2010_spur"]),
]


def test_bad_input_gives_one_line_and_exit_2(tmp_path):
    (tmp_path / "not_hdf5.h5").write_text("not HDF5")
    (tmp_path / "a_file").write_text("")
    commands = [a for a, _ in BAD_INPUTS]
    proc = subprocess.run(probe_command(PROBES, "bad_inputs", {"commands": commands}),
                          capture_output=True, text=True, timeout=600, cwd=tmp_path,
                          env=probe_env())
    assert proc.returncode == 0, proc.stderr[-3000:]
    results = json.loads(proc.stdout.strip().splitlines()[-1])
    for (args, words), (exit_code, stderr) in zip(BAD_INPUTS, results, strict=True):
        lines = [ln for ln in stderr.splitlines() if ln.strip()
                 and "warning: " not in ln]
        assert exit_code == 2, (args, exit_code, stderr)
        assert "Traceback" not in stderr, (args, stderr)
        assert len(lines) == 1 and lines[0].startswith("gsb "), (args, stderr)
        for w in words:
            assert w in lines[0], (args, w, lines[0])


@pytest.mark.slow
def test_a_regular_install_runs_a_shipped_case_from_any_folder(fmu_dir, tmp_path):
    """``pip install .`` (not editable) into a fresh folder, then ``gsb run baguet2010_spur
    --periods 4`` from another folder, through FMUs: the cases and the FMU sources ship.
    Slow (about 75 s): the fresh copy compiles every numba kernel again."""
    site = tmp_path / "site"
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                          "--target", str(site), str(ROOT)],
                         capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert pip.returncode == 0, pip.stderr[-3000:]
    assert (site / "gsb_models" / "baguet2010_spur.toml").is_file()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = dict(os.environ, PYTHONPATH=str(site))  # ahead of the editable checkout
    code = "import orchestrator, sys; print(orchestrator.__file__)"
    where = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           env=env, cwd=elsewhere)
    assert where.stdout.startswith(str(site)), where.stdout
    proc = gsb("run", "baguet2010_spur", "--periods", "4", "--fmu-dir", fmu_dir, "--quiet",
               cwd=elsewhere, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    r = read_results(only(elsewhere / "results"))
    assert r["attrs"]["complete"] and len(r["time"]) == 128 and r["attrs"]["mode"] == "fmu"
    listing = gsb("cases", cwd=elsewhere, env=env)
    assert listing.returncode == 0 and "baguet2010_helical" in listing.stdout


@pytest.mark.parametrize("transport", ["in-process", "fmu"])
def test_every_bearing_model_resumes_exactly(transport, fmu_dir):
    """The warm starts of every registered model (hybrid, FD, ...) are in the checkpoint:
    4 steps, resumed to 8, equal 8 steps in one go, in-process and through FMUs."""
    from bearing_fmu import MODELS

    out = run_here(module=PROBES, args=["resume_every_model", {
        "in_process": transport == "in-process", "fmu_dir": fmu_dir}])
    assert sorted(out) == sorted(MODELS)
    for model, (steps, diff) in out.items():
        assert steps == 8 and diff == 0.0, (transport, model, steps, diff)
    print(f"\n{transport}: resumed = uninterrupted for {', '.join(out)}")
