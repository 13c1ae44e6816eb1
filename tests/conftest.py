"""Fixtures shared by the test modules: one build of every FMU for the whole test run.

With pytest-xdist the workers share it: the FMUs are built once, under a lock, into a folder
of the run's base temporary directory that every worker sees. Before the workers start, the
controller builds the native layer and fills numba's cache (:data:`WARM_UP`, two processes side
by side): the workers, and the processes the tests start, then load the kernels instead of
each compiling them at the same time at the start of a run from a fresh clone.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from fmu_src.slaves.bootstrap import locked
from tests.helpers import probe_command, probe_env

ROOT = Path(__file__).resolve().parents[1]

#: what the xdist controller runs before the workers start, in two processes at once
#: (:mod:`tests.probes.warm_up`): every bearing model's kernels, then a two-stage train's; the
#: native layer, the structure's and the master's kernels (short in-process runs)
WARM_UP = ("bearing_and_train_kernels", "native_and_structure")
#: the environment variable that names, in the workers, the folder of the warm-up's cold run
#: (:func:`tests.probes.warm_up.cold_paper_case`): its numba cache and result
COLD_RUN = "GSB_TEST_COLD_RUN"
#: the paper case's length in mesh periods in tests/system/test_determinism.py
DETERMINISM_PERIODS = 2


#: the file a warm-up's merged cold run leaves in numba's cache folder of this code version
WARMED = "gsb-test-warm-up-merged"


def _version_cache() -> Path:
    """numba's cache folder of this code version (:mod:`bearing_fmu.numba_cache`)."""
    from bearing_fmu.numba_cache import version_folder

    return version_folder(str(ROOT))


def _cold_run_in_warm_up() -> bool:
    """Whether no warm-up of this code version merged its cold run into numba's cache yet (a
    fresh clone, or one where only ``gsb run`` filled it: the README's order). Then the cold
    run replaces the warm-up's second probe, whose kernels it compiles too; otherwise the
    determinism test compiles it in a worker, beside the other tests."""
    return not (_version_cache() / WARMED).is_file()


def pytest_configure(config):
    """Every module of :data:`LONGEST_FIRST` exists (a moved one would silently lose its place);
    in the xdist controller (not in a worker, not in a run without xdist): :data:`WARM_UP`.
    Until a warm-up of this code version has done so (:func:`_cold_run_in_warm_up`), the
    second probe is the cold run of tests/system/test_determinism.py instead, in a cache of
    its own that is then merged into numba's (:func:`tests.probes.warm_up.cold_paper_case`,
    :func:`tests.probes.warm_up.merge_cache`): the kernels a fresh clone compiles once for the
    workers are the cold ones that test compares, not compiled a second time by it. After the
    README's ``gsb run`` (numba's cache holds the paper case's in-process kernels), the
    second probe would compile the FMU transport's kernels and the test its cold run of both
    transports: 326 s for the suite against 266 s from an empty cache.
    A failure there is not reported: the tests that need the same things report it (the
    determinism test then compiles its cold run itself)."""
    import tempfile

    missing = [path for path in LONGEST_FIRST if not (ROOT / path).is_file()]
    if missing:
        raise pytest.UsageError(f"tests/conftest.py LONGEST_FIRST names missing modules: "
                                f"{', '.join(missing)}")
    if not hasattr(config, "workerinput"):
        _temporary_folder_of_the_run(config)
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    commands = [(probe_command("tests.probes.warm_up", probe), probe_env())
                for probe in WARM_UP]
    merge = None  # the cold run's cache, merged into numba's once both probes are done
    if _cold_run_in_warm_up():
        from bearing_fmu.numba_cache import cache_base

        folder = Path(tempfile.mkdtemp(prefix="gsb_cold_run_"))
        (folder / "numba").mkdir()
        config.add_cleanup(lambda: shutil.rmtree(folder, ignore_errors=True))
        os.environ[COLD_RUN] = str(folder)  # the workers start with this environment
        commands[1] = (probe_command("tests.probes.warm_up", "cold_paper_case", {
            "folder": str(folder), "periods": DETERMINISM_PERIODS}),
            probe_env() | {"NUMBA_CACHE_DIR": str(folder / "numba")})
        merge = probe_command("tests.probes.warm_up", "merge_cache", {
            "source": str(folder / "numba"), "target": str(cache_base())})
    procs = [subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL) for command, env in commands]
    codes = [proc.wait(timeout=900) for proc in procs]
    if merge is not None:
        merged = subprocess.run(merge, env=probe_env(), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, timeout=300)
        if codes[1] == 0 and merged.returncode == 0:
            _version_cache().mkdir(parents=True, exist_ok=True)
            (_version_cache() / WARMED).touch()


def _temporary_folder_of_the_run(config) -> None:
    """``TMPDIR`` of this run (its workers and every process they start) is a folder of its
    own, removed when the run ends: the FMU hosts (ecos unpacks each SSP into a temporary
    folder it keeps, fmpy extracts FMUs), Dask and the probes leave their temporary files
    there, not in the user's (about 85 MB in 19 folders per run otherwise). pytest's own
    folders (``tmp_path``) stay where they were (``PYTEST_DEBUG_TEMPROOT``), kept after the
    run as usual."""
    import tempfile

    root = tempfile.gettempdir()
    os.environ.setdefault("PYTEST_DEBUG_TEMPROOT", root)
    folder = tempfile.mkdtemp(prefix="gsb-tests-", dir=root)
    os.environ["TMPDIR"] = folder
    tempfile.tempdir = None  # (this process too: gettempdir() reads TMPDIR again)
    config.add_cleanup(lambda: shutil.rmtree(folder, ignore_errors=True))


#: the modules that take longest (CPU seconds of a run on a 2-core machine), run first
#: so that no worker is left alone with one of them at the end (xdist keeps this order with
#: --no-loadscope-reorder; it would otherwise send the modules with most tests first)
LONGEST_FIRST = (
    # 35: the kernels compiled from an empty cache, then in part
    "tests/system/test_determinism.py",
    "tests/system/test_results_safety.py",  # 41
    "tests/system/test_ecos.py",  # 14
    "tests/system/test_fmu_system.py",  # 12
    "tests/system/test_fmu_run.py",  # 11
    "tests/system/test_paper_results.py",  # 10
    "tests/orchestrator/sweeps/test_sweep_cli.py",  # 10
    "tests/docs/test_api_docs.py",  # 9
    "tests/fmu_src/test_native_build.py",  # 9
)


def pytest_collection_modifyitems(config, items):
    """:data:`LONGEST_FIRST`, then the rest in collection order."""
    rank = {path: k for k, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


def _shared(tmp_path_factory, name: str):
    """A folder of this test run shared by all xdist workers (the run's own otherwise)."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent
    folder = root / name
    folder.mkdir(parents=True, exist_ok=True)
    return folder


#: an environment variable naming a folder for :func:`fmu_dir` kept between test runs (the
#: FMUs are then built again only when stale: other code, other variables)
FMU_DIR = "GSB_TEST_FMU_DIR"
#: the shipped case of another gear train than the paper's whose gear-shaft FMU the tests use
TRAIN_CASE = "two_stage_reducer"


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """A folder with every FMU of :data:`fmu_src.build.fmus.FMUS`, built once per test run
    (or kept in the folder :data:`FMU_DIR` names), and the gear-shaft FMU of
    :data:`TRAIN_CASE`'s gear train (:func:`orchestrator.coupling.fmi.cache.gear_fmu_name`)."""
    from fmu_src.build.fmus import FMUS
    from fmu_src.build.native import export_library, native_status
    from fmu_src.case import shipped_case
    from orchestrator.coupling.fmi.cache import ensure_fmus

    if export_library() is None:  # the FMUs would behave as pythonfmu's own, not as specified
        pytest.fail(f"the FMUs' native layer cannot be built here: {native_status()[1]}",
                    pytrace=False)
    kept = os.environ.get(FMU_DIR)
    dest = Path(kept) if kept else _shared(tmp_path_factory, "fmus")
    ensure_fmus(list(FMUS), dest)  # under its own lock: one build for every worker
    ensure_fmus(["GearShaft"], dest, case=shipped_case(TRAIN_CASE))
    return dest


@pytest.fixture(scope="session")
def ssp_file(tmp_path_factory):
    """``gsb export-ssp baguet2010_spur``: the paper's system as an SSP archive."""
    folder = _shared(tmp_path_factory, "ssp")
    path = folder / "baguet2010_spur.ssp"
    with locked(folder):
        if not path.is_file():
            proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "export-ssp",
                                   "baguet2010_spur", "--dest", str(folder)],
                                  capture_output=True, text=True, timeout=600, cwd=folder)
            assert proc.returncode == 0, proc.stderr[-2000:]
    return path


def _transmission_fmu(tmp_path_factory, case: str):
    folder = _shared(tmp_path_factory, "transmission")
    path = folder / f"{case}.fmu"
    with locked(folder):
        if not path.is_file():
            proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "export-fmu",
                                   case, "--dest", str(folder)],
                                  capture_output=True, text=True, timeout=600, cwd=folder)
            assert proc.returncode == 0, proc.stderr[-2000:]
    return path


@pytest.fixture(scope="session")
def transmission_fmu(tmp_path_factory):
    """``gsb export-fmu baguet2010_spur``: the paper's transmission as one FMU."""
    return _transmission_fmu(tmp_path_factory, "baguet2010_spur")


@pytest.fixture(scope="session")
def helical_transmission_fmu(tmp_path_factory):
    """``gsb export-fmu baguet2010_helical``."""
    return _transmission_fmu(tmp_path_factory, "baguet2010_helical")
