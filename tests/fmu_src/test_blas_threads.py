"""An FMU's process computes its linear algebra on one BLAS thread (bearing_fmu.blas_threads):
FMI hosts call FMUs from several threads at once, and a threaded OpenBLAS called from two
threads at once corrupted an LU factorisation of the gear-shaft FMU under ecos (singular
tangents, crashes, at random: tests/system/test_ecos.py on the two-stage reducer with its
gyroscopic terms)."""

from tests.helpers import ROOT, run_isolated

#: the repository on the probes' path (run_isolated's code probes start from a temporary folder)
ON_PATH = {"PYTHONPATH": str(ROOT)}


def test_an_fmu_instance_limits_the_process_to_one_blas_thread():
    """Created in a process whose BLAS has two threads, an instance leaves it one, in its own
    thread and in a thread the host starts afterwards."""
    out = run_isolated("""
        import json, threading
        from threadpoolctl import ThreadpoolController
        import scipy.linalg
        from bearing_fmu.blas_threads import limit_for_good

        def counts():
            return [c.get_num_threads() for c in
                    ThreadpoolController().select(user_api="blas").lib_controllers]

        before = counts()
        limit_for_good()
        seen = {}
        t = threading.Thread(target=lambda: seen.update(thread=counts()))
        t.start(); t.join()
        print(json.dumps({"before": before, "after": counts(), "thread": seen["thread"]}))
    """, env_vars={"OPENBLAS_NUM_THREADS": "2"} | ON_PATH)
    assert max(out["before"]) == 2
    assert set(out["after"]) == {1} and set(out["thread"]) == {1}


def test_one_thread_for_good_holds_after_an_enclosing_limit_ends():
    """An FMU instance made inside a run's ``with ONE_BLAS_THREAD`` (fmpy in the master's
    process): when the run's limit ends, the process keeps one thread (not the two it had), so
    the decorated calls that then skip the limit still compute with one."""
    out = run_isolated("""
        import json
        from threadpoolctl import ThreadpoolController
        import scipy.linalg
        from bearing_fmu.blas_threads import ONE_BLAS_THREAD, limit_for_good, one_blas_thread

        def counts():
            return [c.get_num_threads() for c in
                    ThreadpoolController().select(user_api="blas").lib_controllers]

        before = counts()
        with ONE_BLAS_THREAD:
            limit_for_good()
        after = counts()
        inside = one_blas_thread(counts)()
        print(json.dumps({"before": before, "after": after, "inside": inside}))
    """, env_vars={"OPENBLAS_NUM_THREADS": "2"} | ON_PATH)
    assert max(out["before"]) == 2
    assert set(out["after"]) == {1} and set(out["inside"]) == {1}


def test_an_fmus_bootstrap_sets_one_blas_thread_before_numpy_loads():
    """A host without numpy loaded (a C host): the FMU's bootstrap sets the BLAS thread
    variables to 1 unless the host set them."""
    out = run_isolated(f"""
        import importlib.util, json, os, sys
        for name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):  # a host that chose none
            os.environ.pop(name, None)
        # as an FMU's slave script loads it: the file alone, before any package of ours
        spec = importlib.util.spec_from_file_location(
            "fmu_bootstrap", {str(ROOT / "fmu_src" / "slaves" / "bootstrap.py")!r})
        bootstrap = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(bootstrap)
        assert "numpy" not in sys.modules
        bootstrap.require("Probe")
        print(json.dumps({{k: os.environ.get(k) for k in ("OPENBLAS_NUM_THREADS",
                                                          "MKL_NUM_THREADS")}}))
    """)
    assert out == {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
