"""What ``gsb run`` says before and around its run: the time step's cost (a warning when it
is material, a note once when the shipped case keeps its step on purpose) and the
one-off start-up work of a first run (FMU build, native layer, numba compilation)."""

import os
import subprocess
import sys

import pytest

from tests.helpers import ROOT

GSB = [sys.executable, "-m", "orchestrator.cli"]


def gsb(*args, env=None, cwd):
    env = dict(os.environ if env is None else env)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    return subprocess.run([*GSB, *map(str, args)], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=600)


def test_shipped_case_states_its_step_once_and_does_not_warn(tmp_path):
    """The paper's step (T/32) gives the 4366 Hz mesh mode 9.9 steps per period, 3.3 % period
    error (tan(omega_h dt / 2) = omega dt / 2): stated once in the summary, no warning."""
    proc = gsb("run", "baguet2010_spur", "--periods", 1, "--in-process", "--no-figures",
               "--quiet", "--out", tmp_path, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "warning" not in proc.stderr
    notes = [line for line in proc.stdout.splitlines() if line.startswith("note: time step")]
    assert len(notes) == 1, proc.stdout
    assert "32 steps per period of the fastest mesh, which the shipped case" in notes[0]
    assert "4366 Hz" in notes[0] and "9.9 time steps per period" in notes[0]
    assert "lengthens its period by 3.3 %" in notes[0]
    assert "simulation.steps_per_mesh_period >= 59" in notes[0]


def test_a_coarser_step_warns_with_the_period_error(tmp_path):
    """T/16: the 4366 Hz mode gets 4.9 steps per period, 12.3 % period error; the 2159 Hz one
    10.0 steps, 3.2 %: both warn (stderr), with the step that brings them under 1 %."""
    proc = gsb("run", "baguet2010_spur", "--periods", 1, "--in-process", "--no-figures",
               "--quiet", "--out", tmp_path, "--set", "simulation.steps_per_mesh_period=16",
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    warnings = [line for line in proc.stderr.splitlines()
                if line.startswith("gsb run: warning: ")]
    assert len(warnings) == 2, proc.stderr
    assert "4366 Hz" in warnings[1] and "lengthens its period by 12.3 %" in warnings[1]
    assert "steps_per_mesh_period >= 59 (now 16)" in warnings[1]
    assert "2159 Hz" in warnings[0] and "lengthens its period by 3.2 %" in warnings[0]
    assert "note: time step" not in proc.stdout


@pytest.mark.parametrize("show", [True, False])
def test_the_cli_shows_an_fmu_build_unless_quiet(show, tmp_path, monkeypatch, capsys):
    """The library logs the build on ``gsb.startup``; the CLI prints it on stderr, ``--quiet``
    (show False) not (the build itself stubbed: what is printed is the point)."""
    import fmu_src.build.fmus
    from orchestrator.coupling.fmi.cache import ensure_fmus
    from orchestrator.run.progress import startup_log

    built = []
    monkeypatch.setattr(fmu_src.build.fmus, "build_fmus",
                        lambda dest, names, **kw: built.append(names))
    with startup_log(show, always=True):  # as gsb's main runs a command
        ensure_fmus(["GearShaft"], tmp_path)
    err = capsys.readouterr().err
    assert built == [["GearShaft"]]
    if show:
        assert err == (f"gsb: building the FMUs GearShaft in {tmp_path} (once per code "
                       "version) ...\n")
    else:
        assert err == ""


@pytest.mark.slow
def test_a_first_run_says_what_it_builds_and_compiles(tmp_path):
    """An empty cache (FMUs, native layer, numba kernels): a run through FMUs prints one line
    per one-off step, in order, on stderr; the run itself succeeds."""
    env = dict(os.environ, GSB_CACHE_DIR=str(tmp_path / "cache"),
               NUMBA_CACHE_DIR=str(tmp_path / "cache" / "numba"))
    proc = gsb("run", "baguet2010_spur", "--periods", 1, "--no-figures", "--out", tmp_path,
               env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("gsb: ")]
    assert [line.split(" (once per")[1] for line in lines] == [
        " code version) ...", " machine and Python version) ...",
        " code version on this machine) ..."], proc.stderr
    assert lines[0].startswith("gsb: building the FMUs GearShaft, BearingHybrid in ")
    assert lines[1].startswith("gsb: building the FMUs' native layer with CMake in ")
    assert lines[2].startswith("gsb: compiling the numba kernels into ")



@pytest.mark.slow
def test_modal_says_once_that_it_compiles_on_an_empty_cache(tmp_path):
    """An empty numba cache: ``gsb modal`` says on stderr, once, that it compiles the kernels
    (the structure's construction compiles the first of them, before any master is built;
    the command was otherwise silent for about 15 s), and gives its modes."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    proc = gsb("modal", "baguet2010_spur", "--out", tmp_path, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.count("gsb: compiling the numba kernels into ") == 1, proc.stderr
    assert "bending" in proc.stdout


def test_each_python_environment_has_its_own_fmu_folder(monkeypatch, tmp_path):
    """An FMU's loader names the Python that built it: the per-user FMU folder is one per
    code version and interpreter, so another virtual environment builds its own FMUs instead
    of running the first one's Python in a C host."""
    from fmu_src.build.fmus import code_hash
    from orchestrator.coupling.fmi.cache import default_fmu_dir

    monkeypatch.setenv("GSB_CACHE_DIR", str(tmp_path))
    mine = default_fmu_dir()
    monkeypatch.setattr(sys, "executable", str(tmp_path / "other-venv" / "bin" / "python"))
    other = default_fmu_dir()
    assert mine != other and mine.parent == other.parent == tmp_path / "fmus"
    assert mine.name.startswith(f"{code_hash()}-") and other.name.startswith(f"{code_hash()}-")
