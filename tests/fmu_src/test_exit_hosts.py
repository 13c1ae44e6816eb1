"""A host that leaves fmi2Terminate and fmi2FreeInstance to its exit handlers exits with 0.

OMSimulator's Python API ends the instances a script left running from C++ static destructors,
which run after Python has finalised its interpreter: pythonfmu 0.7.0's library then calls
PyGILState_Ensure on the finalised interpreter and the process dies of SIGSEGV (exit 139)
after its work is done (patch 0009 of fmu_src/native/patches). Two small hosts built here
from ``hosts/exit_host.c`` run a bearing FMU, take a few steps and register the end of the
instance for the process's exit:

* a C program without Python (the FMU's loader loads libpython; the interpreter is never
  finalised, patch 0002): an atexit() handler;
* a Python process driving the same code as a shared library through ctypes
  (:mod:`tests.probes.exit_host`): an atexit() handler, or the library's destructor, both of
  which run after Py_FinalizeEx, as OMSimulator's destructors do.

Each run must exit with 0, its exit handler having called both functions (it says so on
stdout, fmi2Terminate returning fmi2OK), nothing on stderr about a crash. Skipped without a C
compiler.
"""

from __future__ import annotations

import signal
import subprocess

import pytest

from tests.fmu_src.c_hosts import compile_host, unzip_fmu
from tests.helpers import probe_command, probe_env

FMU = "BearingHybrid"
STEPS = 3
#: what a crash or a heap corruption leaves on stderr
CRASH_WORDS = ("Segmentation", "corrupted", "Aborted", "double free", "Fatal Python error")
RUNS = [pytest.param(4, id="4-runs"), pytest.param(50, id="50-runs", marks=pytest.mark.slow)]


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    """(the C program, the shared library) compiled from ``hosts/exit_host.c``."""
    out = tmp_path_factory.mktemp("exit_hosts")
    return (compile_host("exit_host.c", out / "exit_host", "-DEXIT_HOST_MAIN"),
            compile_host("exit_host.c", out / "libexit_host.so", "-shared", "-fPIC"))


@pytest.fixture(scope="module")
def unzipped(fmu_dir, tmp_path_factory):
    """(the folder of the unzipped bearing FMU, its GUID)."""
    folder = tmp_path_factory.mktemp("exit_host_fmu")
    md, _ = unzip_fmu(fmu_dir / f"{FMU}.fmu", folder)
    return folder, md.guid


def _check(runs, command, env, cwd):
    """Run ``command`` ``runs`` times; the failed runs (index, exit code, what was wrong)."""
    failures = []
    for k in range(runs):
        proc = subprocess.run(command, capture_output=True, text=True, timeout=300, env=env,
                              cwd=cwd)
        lines = proc.stdout.splitlines()
        wrong = [w for w in CRASH_WORDS if w in proc.stderr]
        if "exit: fmi2Terminate 0" not in lines or "exit: fmi2FreeInstance done" not in lines:
            wrong.append("the exit handler did not end the instance")
        if proc.returncode != 0 or wrong:
            code = (f"killed by {signal.Signals(-proc.returncode).name}" if proc.returncode < 0
                    else f"exit code {proc.returncode}")
            failures.append((k, code, wrong, proc.stdout[-300:], proc.stderr[-800:]))
    return failures


@pytest.mark.parametrize("runs", RUNS)
def test_a_c_host_that_ends_the_instance_at_exit_exits_cleanly(hosts, unzipped, tmp_path,
                                                               runs):
    program, _ = hosts
    folder, guid = unzipped
    failures = _check(runs, [str(program), str(folder), FMU, guid, str(STEPS)], probe_env(),
                      tmp_path)
    print(f"\nC host, instance ended by atexit(): {runs - len(failures)} of {runs} runs "
          "exited with 0")
    assert not failures, failures


@pytest.mark.parametrize("how", [0, 1], ids=["atexit", "destructor"])
@pytest.mark.parametrize("runs", RUNS)
def test_a_python_host_that_ends_the_instance_after_finalisation_exits_cleanly(
        hosts, unzipped, tmp_path, runs, how):
    """The case of OMSimulator's Python API; pythonfmu 0.7.0's library exits with 139 there."""
    _, library = hosts
    folder, guid = unzipped
    command = probe_command("tests.probes.exit_host", str(library), str(folder), FMU, guid,
                            str(STEPS), str(how))
    failures = _check(runs, command, probe_env(), tmp_path)
    print(f"\nPython host, instance ended by {('atexit()', 'a destructor')[how]} after "
          f"Py_FinalizeEx: {runs - len(failures)} of {runs} runs exited with 0")
    assert not failures, failures
