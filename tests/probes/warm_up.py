"""What the xdist controller runs before the workers start (tests/conftest.py), two probes in
two processes at once: the kernels are then loaded from numba's cache by the workers and the
processes the tests start, not compiled by each of them at the same time. Until a warm-up
of this code version has merged one (a fresh clone, with or without the README's ``gsb run``),
:func:`cold_paper_case` compiles the structure's and the master's kernels instead of
:func:`native_and_structure`, in a cache of its own, and that compilation is also the cold run
of tests/system/test_determinism.py."""

from __future__ import annotations

import tempfile

from tests.probes import dispatch, probes_of


def bearing_and_train_kernels() -> None:
    """Every bearing model's kernels, in-process and through the bearing set, and the static
    equilibrium; then the kernels of a train of two meshes and mixed bearing models
    (:func:`train_kernels`)."""
    import numpy as np

    from bearing_fmu import MODELS, BearingData, model_class
    from bearing_fmu.static import static_equilibrium
    from orchestrator.coupling.inprocess import ModelBearings

    b = BearingData(0.07, 0.05, 150e-6, 0.0288)
    for name in MODELS:
        model = model_class(name).from_parameters(b)
        model.evaluate(6e-5, -6e-5, 1e-3, -1e-3, 325.0)
        ModelBearings([model], [(0.3, -1)], [325.0]).evaluate(np.array([[6e-5, -6e-5, 0.0, 0.0]]))
    static_equilibrium(model_class("hybrid").from_parameters(b), (0.0, -2251.0), 325.0)
    train_kernels()


def train_kernels() -> None:
    """The compiled step of the shipped two-stage reducer (two meshes, hybrid and short
    bearings), in-process and as its gear-shaft FMU takes it (a structure's step alone).

    numba compiles the step again for each number of meshes and each set of bearing models
    (both are in the types of its arguments): about 70 s from an empty cache, which every
    worker that meets the train first would otherwise spend at once."""
    from fmu_src.case import load_case
    from orchestrator.run.runner import run_case

    case = load_case("two_stage_reducer")
    with tempfile.TemporaryDirectory() as tmp:
        run_case(case, steps=2, in_process=True, out_dir=tmp, progress=False)
    structure_step(case)


def structure_step(case):
    """One step of ``case``'s structure alone on stiff linear supports (as a gear-shaft FMU
    takes it); returns the structure."""
    import numpy as np

    from fmu_src import description

    st = description.structure(case)
    kb = np.broadcast_to(2e8 * np.eye(2), (st.nb, 2, 2)).copy()
    cb = np.broadcast_to(2e4 * np.eye(2), (st.nb, 2, 2)).copy()
    f0 = np.zeros((st.nb, 2))
    st.static(f0, kb, cb)
    st.step(description.time_step(case), f0, kb, cb)
    return st


def native_and_structure() -> None:
    """The native layer, then the structure's and the master's kernels (short in-process runs
    of both shipped cases) and :func:`other_transports`."""
    from fmu_src.build.native import export_library
    from fmu_src.case import load_case
    from orchestrator.run.runner import run_case

    export_library()
    with tempfile.TemporaryDirectory() as tmp:
        for case, model in (("baguet2010_spur", "lumped"), ("baguet2010_helical", "lumped")):
            run_case(load_case(case, {"bearings.*.model": model}), steps=2, in_process=True,
                     out_dir=tmp + "/" + case, progress=False)
    other_transports()


def other_transports() -> None:
    """The master's step through the gear-shaft FMU and with a structure called back in
    Python, compiled without an FMU (:func:`orchestrator.coupling.step.compile_step`): about
    30 s from an empty cache, which the first tests of both workers would otherwise spend at
    the same time. Then what the FMUs compile on their side for the paper's case
    (:func:`fmu_kernels`)."""
    import numpy as np

    from orchestrator.coupling.fmi.structure import block_arguments
    from orchestrator.coupling.step import compile_step

    compile_step(block_arguments([], [], [], [], [], [], [], [], 0.0))
    compile_step((np.zeros(1, dtype=np.int64),))  # PythonStructure.arguments
    fmu_kernels()


def fmu_kernels() -> None:
    """The kernels the FMUs of the paper's case compile in their own processes: the
    gear-shaft FMU's structure step alone (one mesh) and its unpacking of the laws, the hybrid
    bearing FMU's C law. About 8 s from an empty cache, which the determinism test's warm run
    and a worker's first FMU test each spent (a numba compile listener over a cold suite)."""
    import numpy as np

    import bearing_fmu.hybrid._native  # noqa: F401  (compiles the C law on import)
    from fmu_src.case import load_case
    from fmu_src.contract import unpack_law_arrays

    st = structure_step(load_case("baguet2010_spur"))
    unpack_law_arrays(np.zeros(14 * st.nb))


def cold_paper_case(folder: str, periods: int) -> None:
    """From an empty numba cache, in this process's own ``NUMBA_CACHE_DIR`` (``folder``/numba,
    cold by construction): the native layer, then the in-process run of
    :func:`tests.probes.determinism.runs` (every kernel compiled here), its result in
    ``folder``/cold.json for tests/system/test_determinism.py, and :func:`other_transports`
    (with :func:`fmu_kernels`).
    The controller then merges this cache into numba's (:func:`merge_cache`)."""
    import json
    from pathlib import Path

    from bearing_fmu.numba_cache import cache_base
    from fmu_src.build.native import export_library
    from tests.probes.determinism import runs

    export_library()
    own = cache_base()
    if any(p.is_file() for p in own.rglob("*")):  # (importing the packages makes folders)
        raise RuntimeError(f"{own}: not an empty numba cache")
    result = runs(None, periods, ("in-process",))
    (Path(folder) / "cold.json").write_text(json.dumps(result))
    other_transports()


def merge_cache(source: str, target: str) -> None:
    """The kernels of the numba cache folder ``source`` added to ``target``'s, once nothing
    writes to either: a file ``target`` lacks is copied; an index (``.nbi``, one per function:
    its compiled signatures and their data files) that both hold gets the signatures only
    ``source`` has, their data files copied under the next free numbers. Copying only what is
    missing would keep ``target``'s index of a function that both compiled for other
    signatures (the two-stage train's step in one, the paper case's in the other) and lose the
    other's, which the tests would then compile again, several at once. Reads and writes
    numba's index format (``numba.core.caching.IndexDataCacheFile``: the numba version
    pickled, then the pickled (source stamp, {signature key: data file})); an index of
    another numba version or stamp is left as it is."""
    import os
    import pickle
    from pathlib import Path

    from numba.core.serialize import dumps

    def put(path: Path, data: bytes) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        part = path.with_name(f"{path.name}.{os.getpid()}.part")
        part.write_bytes(data)
        os.replace(part, path)

    def read(path: Path):
        with open(path, "rb") as f:
            version = pickle.load(f)
            return version, f.read()

    src, dst = Path(source), Path(target)
    files = sorted(p for p in src.rglob("*") if p.is_file())
    for path in files:  # the data files first: an index never names a missing one
        if path.suffix != ".nbi" and not (dst / path.relative_to(src)).exists():
            put(dst / path.relative_to(src), path.read_bytes())
    for path in (p for p in files if p.suffix == ".nbi"):
        out = dst / path.relative_to(src)
        if not out.exists():
            put(out, path.read_bytes())
            continue
        (v_in, raw_in), (v_out, raw_out) = read(path), read(out)
        if v_in != v_out:
            continue
        stamp_in, theirs = pickle.loads(raw_in)
        stamp_out, ours = pickle.loads(raw_out)
        if stamp_in != stamp_out:
            continue
        base = path.name[:-len(".nbi")]
        used = set(ours.values())
        for key, name in theirs.items():
            if key in ours:
                continue
            number = 1
            while f"{base}.{number}.nbc" in used:
                number += 1
            new = f"{base}.{number}.nbc"
            put(out.with_name(new), (path.parent / name).read_bytes())
            used.add(new)
            ours[key] = new
        put(out, pickle.dumps(v_out, protocol=-1) + dumps((stamp_out, ours)))


PROBES = probes_of(bearing_and_train_kernels, native_and_structure, cold_paper_case,
                   merge_cache)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
