"""Bad input to ``gsb``: one line ``gsb <command>: error: ...`` naming what was typed and
why, exit 2, never a traceback or an internal error.

Each group runs its first command as a user would (a ``gsb`` process: the exit code the shell
sees) and its variants through :func:`orchestrator.cli.main` in this process (the same code
path, without a second interpreter start)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from orchestrator.cli import main
from tests.helpers import probe_env

GSB = [sys.executable, "-m", "orchestrator.cli"]
#: the dimensional form of ``gsb bearing`` but for --speed and --load
FILM = ["--diameter", "0.07", "--length", "0.05", "--clearance", "150e-6",
        "--viscosity", "0.0288"]


def gsb(*args, cwd) -> tuple[int, str]:
    """Exit code and stderr of a ``gsb`` process."""
    proc = subprocess.run([*GSB, *map(str, args)], capture_output=True, text=True, timeout=120,
                          cwd=cwd, env=probe_env())
    return proc.returncode, proc.stderr


def in_process(capsys, *args) -> tuple[int, str]:
    """Exit code and stderr of ``gsb args`` run by :func:`orchestrator.cli.main` here."""
    capsys.readouterr()
    code = main([str(a) for a in args])
    return code, capsys.readouterr().err


def one_error_line(code: int, stderr: str, command: str) -> str:
    """The single error line of a refused command line (checked: exit 2, no traceback)."""
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert code == 2, (code, stderr)
    assert "Traceback" not in stderr and "internal error" not in stderr, stderr
    assert len(lines) == 1 and lines[0].startswith(f"gsb {command}: error: "), stderr
    return lines[0]


def test_a_file_that_is_not_a_case_is_named_with_what_it_is(tmp_path, capsys):
    """An HDF5 results file given as the case points to --resume; other binary files and
    folders are named as what they are, not decoded as text."""
    import h5py

    h5 = tmp_path / "run.h5"
    with h5py.File(h5, "w") as f:
        f["time"] = [0.0, 1.0]
    line = one_error_line(*gsb("run", h5.name, cwd=tmp_path), "run")
    assert f"{h5.name}: not a case file: an HDF5 file" in line
    assert f"gsb run --resume {h5.name}" in line
    with h5py.File(h5, "w", userblock_size=512) as f:  # the signature after a user block
        f["time"] = [0.0, 1.0]
    assert f"{h5}: not a case file: an HDF5 file" in one_error_line(
        *in_process(capsys, "run", h5), "run")

    png = tmp_path / "mesh.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    assert f"{png}: not a case file: a PNG image" in one_error_line(
        *in_process(capsys, "run", png), "run")
    blob = tmp_path / "case.toml"
    blob.write_bytes(b"[case]\nname = \"\xff\xfe\"\n")  # not UTF-8 from byte 15 on
    assert f"{blob}: not a case file: not UTF-8 text (byte 0xff at offset 15)" in \
        one_error_line(*in_process(capsys, "modal", blob), "modal")
    assert f"{tmp_path}: a folder, not a case file" in one_error_line(
        *in_process(capsys, "run", tmp_path), "run")


def test_a_toml_syntax_error_names_the_file_and_line(tmp_path):
    case = tmp_path / "broken.toml"
    case.write_text('[case]\nname = "x"\n\n[gear_pair\nteeth = [26, 157]\n')
    line = one_error_line(*gsb("run", case.name, cwd=tmp_path), "run")
    assert f"{case.name}, line 4, column 11: not valid TOML: Expected ']'" in line


def test_override_errors_name_the_option_and_the_closest_field(tmp_path, capsys):
    """A typo in --set is the option's, not the shipped case file's; the closest field is
    offered. --speed, --torque and --unbalance go the same way."""
    line = one_error_line(*gsb("run", "baguet2010_spur", "--set", "bearings.*.viscosty=0.03",
                               cwd=tmp_path), "run")
    assert "--set bearings.*.viscosty=0.03: unknown field bearings.*.viscosty; did you mean " \
           "bearings.*.viscosity?" in line
    assert ".toml" not in line  # the file holds no such field: it is not blamed

    for args, words in [
        (["--set", "bearing.*.viscosity=0.03"],
         ["--set bearing.*.viscosity=0.03: unknown section [bearing]", "bearings.*.viscosity?"]),
        (["--set", "bearings.7.viscosity=0.03"],
         ["override bearings.7.viscosity: the case has no bearing '7'",
          "(bearings: 1, 2, 3, 4)"]),
        (["--set", "tolerance=1e-6"], ["--set tolerance=1e-6: 'tolerance' is not section.key",
                                       "did you mean simulation.tolerance?"]),
        (["--set", "simulation.steps_per_mesh_period=2.5"],
         ["--set simulation.steps_per_mesh_period=2.5: simulation.steps_per_mesh_period: "
          "expected an integer, got 2.5"]),
        (["--speed", "3000 rpmx"], ["--speed '3000 rpmx': drive.speed: unknown unit 'rpmx'",
                                    "an angular speed takes one of the units rad/s, rpm"]),
        (["--torque", "3 mm"], ["--torque '3 mm': drive.torque: '3 mm' is a length, "
                                "expected a torque"]),
        (["--unbalance", "-1 mm"], ["--unbalance '-1 mm': gears.*.unbalance = '-1 mm': "
                                    "must be >= 0.0 m"]),
    ]:
        line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", *args), "run")
        assert ".toml" not in line, line
        for w in words:
            assert w in line, (w, line)
    # the same options of another command
    line = one_error_line(*in_process(capsys, "sweep", "baguet2010_spur", "--vary",
                                      "speed=100:200:2", "--set", "drive.sped=3"), "sweep")
    assert "--set drive.sped=3: unknown field drive.sped; did you mean " \
           "drive.speed?" in line
    # an override that is right on its own but not with the file's other fields names both
    line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", "--set",
                                      "shafts.*.inner_diameter=100 mm"), "run")
    assert "baguet2010_spur.toml with shafts.*.inner_diameter overridden: " \
           "shafts.pinion_shaft.inner_diameter[1] = 0.1 m must be smaller than" in line


def test_thread_counts_are_refused_before_anything_runs(tmp_path, capsys):
    """--threads: a whole number from 1 to numba's NUMBA_NUM_THREADS; above 1 for an
    in-process run only (the master calls the bearing FMUs in turn)."""
    import numba

    limit = numba.config.NUMBA_NUM_THREADS
    for value in (0, limit + 1):
        line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", "--in-process",
                                          "--threads", value, "--out", tmp_path), "run")
        assert f"--threads {value}: need a whole number from 1 to {limit} (numba's " \
               "NUMBA_NUM_THREADS on this machine)" in line, line
    if limit >= 2:
        line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", "--threads", 2,
                                          "--out", tmp_path), "run")
        assert "--threads 2: threads share the bearings of an in-process run (--in-process)" \
            in line, line
    assert not any(tmp_path.iterdir())  # refused before a results file was opened


def test_threads_for_other_bearings_are_said_once_on_one_line(tmp_path, capsys):
    """--threads with bearings that are not hybrid ones: the run goes on, one thread, and
    says so on one line of the command's own (no Python warning format, no source path)."""
    import numba

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba allows one thread here")
    code, err = in_process(capsys, "run", "baguet2010_spur", "--in-process", "--threads", 2,
                           "--bearing", "linear", "--periods", 1, "--no-figures", "--quiet",
                           "--out", tmp_path)
    assert code == 0, err
    lines = [ln for ln in err.splitlines() if "thread" in ln]
    assert lines == ["gsb run: warning: threads = 2: bearings other than hybrid run on one thread "
                     "(threads share hybrid bearings only)"], err


def test_bearing_calculator_errors_follow_the_convention(tmp_path, capsys):
    """Every bad input of ``gsb bearing`` names the option and its value, exit 2."""
    line = one_error_line(*gsb("bearing", "--l-over-d", "0.5", "--eccentricity", "1.2",
                               cwd=tmp_path), "bearing")
    assert "--eccentricity 1.2: must be in [0, 1)" in line

    for args, words in [
        (["--l-over-d", "0.5"], ["give --l-over-d and --eccentricity"]),
        (["--l-over-d", "0", "--eccentricity", "0.5"], ["--l-over-d 0: must be finite and > 0"]),
        (["--l-over-d", "1", "--eccentricity", "nan"], ["--eccentricity nan: must be in [0, 1)"]),
        (["--diameter", "0.07"], ["the dimensional form needs --length, --clearance, "
                                  "--viscosity, --speed, --load"]),
        ([*FILM, "--speed", "0", "--load", "10"], ["--speed 0: must be finite and > 0"]),
        ([*FILM, "--speed", "325", "--load", "inf"], ["--load inf: must be finite"]),
        ([*FILM, "--speed", "325", "--load", "10", "--eccentricity", "0.3"],
         ["--eccentricity belongs to the dimensionless form"]),
        (["--l-over-d", "1", "--eccentricity", "0.5", "--nodes", "0"],
         ["--nodes 0: the hybrid model needs >= 16"]),
        (["--model", "fd", "--l-over-d", "1", "--eccentricity", "0.5", "--nodes", "3"],
         ["--nodes 3: the fd model needs >= 8"]),
        (["--model", "short", "--l-over-d", "1", "--eccentricity", "0.5", "--nodes", "40"],
         ["short bearing model: no option 'nodes'"]),
        (["--l-over-d", "1", "--eccentricity", "0.5", "--pressure-png",
          str(tmp_path / "no" / "p.png")], [f"--pressure-png {tmp_path / 'no' / 'p.png'}: "
                                            f"no folder {tmp_path / 'no'}"]),
    ]:
        line = one_error_line(*in_process(capsys, "bearing", *args), "bearing")
        for w in words:
            assert w in line, (w, line)


@pytest.mark.parametrize("dimension,phrase", [("angular_speed", "an angular speed"),
                                              ("inertia", "an inertia"),
                                              ("length", "a length"),
                                              ("dimensionless", "a dimensionless number")])
def test_unit_messages_read_as_english(dimension, phrase):
    from fmu_src.units import UnitError, parse_quantity

    with pytest.raises(UnitError) as err:
        parse_quantity("1 furlong", dimension, "x")
    assert f"unknown unit 'furlong' in '1 furlong'; {phrase} takes one of the units " in \
        str(err.value)


def test_window_errors_name_the_field_and_the_run_length(tmp_path, capsys):
    """``--window`` text that is no window, a shaft that is not the train's, a window longer
    than the run: one line each, exit 2, before anything runs."""
    out = ["--out", str(tmp_path), "--in-process", "--periods", "64"]
    line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", "--window", "3 kg",
                                      *out), "run")
    assert "simulation.window: cannot read '3 kg' as a window: write '26 periods'" in line
    line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", "--window",
                                      "1 rev of gearshaft", *out), "run")
    assert "no shaft 'gearshaft'; the shafts are pinion_shaft, gear_shaft; did you mean " \
           "gear_shaft?" in line
    line = one_error_line(*in_process(capsys, "run", "baguet2010_spur", "--window",
                                      "1 rev of gear_shaft", *out), "run")
    assert "is longer than the run (2048 steps, 0.04759 s)" in line
    assert not list(tmp_path.iterdir())
