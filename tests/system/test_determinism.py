"""Same inputs, same bits on one machine: whatever numba's cache holds, whatever the transport.

What would break it: a kernel compiled with fastmath (LLVM then chooses the rounding by
context: what it inlines, the vector width, the CPU's FMA), a kernel loaded from numba's cache
with a stale callee compiled in (:mod:`bearing_fmu.numba_cache`), or two transports evaluating
the bearings along different sequences (the hybrid solver starts from its last solution).
Here the paper's spur case runs in fresh interpreters with numba's cache empty (every kernel
compiled in the process) and full (every kernel loaded), each in-process and through the FMUs,
and half full (the master's step compiled against the structure's and the bearings' kernels
loaded) in-process: every channel of every run, and the static solution, must be the same
bits. The film's driver and the structure's step compiled against their cached callees, in
the FMU processes, is a ``slow`` test: four bearing FMUs and the gear-shaft FMU compiling at
once take a minute of the default run's five.

From a fresh clone, and until a warm-up of this code version has merged one, the cold
in-process run is the xdist warm-up's (tests/conftest.py: it compiles the kernels the workers
then load, in an empty cache of its own, the master's step through the FMUs too:
:func:`tests.probes.warm_up.other_transports`). Elsewhere (a later run of the suite, or no
xdist) the test compiles its cold runs itself.
"""

import hashlib
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import COLD_RUN, DETERMINISM_PERIODS
from tests.helpers import PROBES, ROOT, run_isolated

PERIODS = DETERMINISM_PERIODS


def _runs(fmu_dir, numba_cache=None, env_vars=None,
          transports: tuple[str, ...] = ("in-process", "fmu")) -> dict:
    """The ``transports`` in a fresh interpreter (:func:`tests.probes.determinism.runs`)."""
    return run_isolated(module="tests.probes.determinism", numba_cache=numba_cache,
                        args=["runs", {"fmu_dir": fmu_dir, "periods": PERIODS,
                                       "transports": list(transports)}],
                        env_vars=env_vars)


def _cold_runs(fmu_dir, cache: Path) -> dict:
    """The runs with every kernel compiled in their process, ``cache`` then holding the
    kernels they compiled: the warm-up's in-process run and its cache, if it compiled cold
    (:data:`tests.conftest.COLD_RUN`), else both transports here from an empty ``cache``."""
    folder = Path(os.environ.get(COLD_RUN, "/nonexistent"))
    if (folder / "cold.json").is_file():
        print("\ncold run: the warm-up's")
        shutil.copytree(folder / "numba", cache)
        return json.loads((folder / "cold.json").read_text())
    print("\ncold run: compiled here")
    return _runs(fmu_dir, cache)


#: kernels that call kernels of other files: the hybrid film's driver, the structure step and
#: the master's compiled step (orchestrator.coupling.step)
CALLERS = ("hybrid/_kernels.*", "step/kernel.*", "coupling/step.*")
#: the callers an in-process run compiles against cached callees in the default run: the
#: master's coupled steps (their in-process structure solve inlined), which call the
#: structure's step (gear_fmu.step.kernel) and the bearings' kernels, all loaded from the
#: cache. The film's
#: driver and the structure's step compiled against their cached callees are the FMUs'
#: (:func:`test_the_fmus_compiling_against_cached_callees_give_the_same_bits`, ``slow``):
#: compiled in-process too, they took 66 s of the default run; with the in-process solve
#: compiled again as well, 24 s; the coupled steps alone 18 s (idle machine, alone).
IN_PROCESS_CALLERS = ("coupling/step.coupled_steps-*",)


def _half_warm(full: Path, half: Path, callers: tuple[str, ...] = CALLERS) -> list[Path]:
    """A copy ``half`` of the numba cache ``full`` without the entries of ``callers`` (the
    ones removed, as they were in ``full``)."""
    shutil.copytree(full, half)
    dropped = [f for pattern in callers for f in half.rglob(pattern)]
    assert len(dropped) >= len(callers), dropped
    for f in dropped:
        f.unlink()
    return dropped


def _compiled_again(half: Path, dropped: list[Path],
                    callers: tuple[str, ...] = CALLERS) -> bool:
    """Whether the run in ``half`` compiled kernels of each of ``callers`` again (those of its
    transport: a run in-process does not compile the FMU transport's)."""
    again = [{f.name for f in half.rglob(pattern)} for pattern in callers]
    return all(a and a <= {f.name for f in dropped} for a in again)


def test_same_bits_with_a_cold_a_warm_and_a_half_warm_numba_cache(fmu_dir, tmp_path):
    """Half warm: the full cache without the :data:`IN_PROCESS_CALLERS`' entries, which are
    then compiled against callees loaded from the cache (in-process; every one of the
    :data:`CALLERS` through the FMUs:
    :func:`test_the_fmus_compiling_against_cached_callees_give_the_same_bits`)."""
    cold = _cold_runs(fmu_dir, tmp_path / "a")
    warm = _runs(fmu_dir, tmp_path / "a")
    dropped = _half_warm(tmp_path / "a", tmp_path / "b", IN_PROCESS_CALLERS)
    half = _runs(fmu_dir, tmp_path / "b", transports=("in-process",))
    assert _compiled_again(tmp_path / "b", dropped, IN_PROCESS_CALLERS)
    assert cold["in-process rows"] == warm["fmu rows"] == 32 * PERIODS
    assert warm["in-process"] == warm["fmu"], "FMUs and in-process differ"
    assert {k: warm[k] for k in cold} == cold, "a warm numba cache changes the results"
    assert half == {k: warm[k] for k in half}, "callees loaded from numba's cache change the " \
        "results"


@pytest.mark.slow
def test_the_fmus_compiling_against_cached_callees_give_the_same_bits(fmu_dir, tmp_path):
    """Through the FMUs, with every kernel compiled (an empty cache), then with the
    :data:`CALLERS`' entries compiled in the FMUs' processes against callees loaded from the
    cache."""
    cold = _runs(fmu_dir, tmp_path / "a", transports=("fmu",))
    dropped = _half_warm(tmp_path / "a", tmp_path / "b")
    half = _runs(fmu_dir, tmp_path / "b", transports=("fmu",))
    assert _compiled_again(tmp_path / "b", dropped)
    assert cold["fmu rows"] == 32 * PERIODS
    assert half == cold, "callees loaded from numba's cache change the FMUs' results"


def test_a_bearing_fmu_in_a_host_without_the_package_gives_the_same_bits(fmu_dir, tmp_path):
    """``python -S`` with only the dependencies on its path: the FMU runs the code it carries
    (staged apart from the package, with the kernels numba's cache holds for this code version,
    whichever copy compiled them); along a sequence of states (the hybrid solver warm-starts
    from its last solution) its force, Kb and Cb equal the in-process model's bit for bit."""
    import site

    from bearing_fmu import BearingData
    from bearing_fmu.frames import LocalFrame
    from bearing_fmu.hybrid.model import HybridBearing
    from orchestrator.coupling.inprocess import ModelBearings

    params = {"D": 0.09, "L": 0.065, "C": 110e-6, "mu": 0.0288, "frame_angle": 0.3}
    states = [[4e-5 + 1e-6 * k, -6e-5 + 2e-6 * k, 1e-4 * k, -2e-4] for k in range(8)]
    ref = ModelBearings([HybridBearing(BearingData(0.09, 0.065, 110e-6, 0.0288), n=96)],
                        [LocalFrame(0.3, -1)], [54.0])
    expected = hashlib.sha256()
    for st in states:
        f, k, c = ref.evaluate(np.array([st]))
        expected.update(np.concatenate([f.ravel(), k.ravel(), c.ravel()]).tobytes())
    paths = [p for p in site.getsitepackages() if "site-packages" in p]
    out = run_isolated(script=PROBES / "standalone" / "bearing_host.py", python_args=["-S"],
                       args=[{"paths": paths, "fmu": fmu_dir / "BearingHybrid.fmu",
                              "params": params, "states": states}])
    assert not Path(out["module"]).is_relative_to(ROOT), out["module"]  # the FMU's own code
    assert out["hash"] == expected.hexdigest()


def test_a_change_in_a_callee_file_recompiles_its_callers(tmp_path):
    """numba checks only a kernel's own file for changes; the short-bearing kernel inlines the
    source coefficients of Eq. (3) from :mod:`bearing_fmu.reynolds`. In a copy of the code
    with a warm cache, a change of ``reynolds.py`` alone must change the force (it did not: the
    stale kernel was loaded), and the cache must not change a result of the same code."""
    import shutil

    from bearing_fmu.numba_cache import PACKAGES

    root = tmp_path / "code"
    for pkg in PACKAGES:
        shutil.copytree(ROOT / pkg, root / pkg,
                        ignore=shutil.ignore_patterns("__pycache__", "native"))
    probe = {"module": "tests.probes.determinism",
             "args": ["short_bearing_force", {"code": root}]}
    cache = tmp_path / "numba"
    first = run_isolated(**probe, numba_cache=cache)
    assert run_isolated(**probe, numba_cache=cache) == first
    reynolds = root / "bearing_fmu" / "reynolds.py"
    text = reynolds.read_text()
    old = "return y + 2.0 * x_dot, 2.0 * y_dot - x"
    assert old in text
    reynolds.write_text(text.replace(old, "return y + 2.0 * x_dot, 2.0 * y_dot - 1.001 * x"))
    changed = run_isolated(**probe, numba_cache=cache)
    assert changed["force"] != first["force"]


@pytest.mark.skipif((os.cpu_count() or 1) < 2,
                    reason="one core: OpenBLAS runs one thread whatever it is told")
def test_same_bits_whatever_the_blas_thread_count(fmu_dir):
    """OpenBLAS splits a product or factorisation of the structure's matrices (108 rows for
    the paper's case) among its threads, and the split changed the last bits: before the
    computations ran on one BLAS thread (:mod:`bearing_fmu.blas_threads`), the helical case's
    first 16 steps differed between ``OPENBLAS_NUM_THREADS=1`` and 2, and an FMU run in a
    process started after a Dask sweep (whose nanny leaves ``OPENBLAS_NUM_THREADS=1`` in its
    parent's environment) differed from ``gsb run`` by up to 3e-9. Fresh interpreters with 1
    and 2 threads: the same bits for the spur case in-process and through the FMUs, the helical
    case and the damped modes of ``gsb modal``."""
    one, two = ({"OPENBLAS_NUM_THREADS": n, "OMP_NUM_THREADS": n} for n in ("1", "2"))
    a = run_isolated(module="tests.probes.determinism", args=["linear_algebra"], env_vars=one)
    b = run_isolated(module="tests.probes.determinism", args=["linear_algebra"], env_vars=two)
    assert (a.pop("blas threads"), b.pop("blas threads")) == (1, 2)  # the contrast is real
    assert a == b
    assert _runs(fmu_dir, env_vars=one) == _runs(fmu_dir, env_vars=two)
