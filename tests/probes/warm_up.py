"""What the xdist controller runs before the workers start (tests/conftest.py), two probes in
two processes at once: the kernels are then loaded from numba's cache by the workers and the
processes the tests start, not compiled by each of them at the same time. With numba's cache
empty for this code version (a fresh clone), :func:`cold_paper_case` compiles the structure's
and the master's kernels instead of :func:`native_and_structure`, in a cache of its own, and
that compilation is also the cold run of tests/system/test_determinism.py."""

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
    import numpy as np

    from fmu_src import description
    from fmu_src.case import load_case
    from orchestrator.run.runner import run_case

    case = load_case("two_stage_reducer")
    with tempfile.TemporaryDirectory() as tmp:
        run_case(case, steps=2, in_process=True, out_dir=tmp, progress=False)
    st = description.structure(case)
    kb = np.broadcast_to(2e8 * np.eye(2), (st.nb, 2, 2)).copy()
    cb = np.broadcast_to(2e4 * np.eye(2), (st.nb, 2, 2)).copy()
    f0 = np.zeros((st.nb, 2))
    st.static(f0, kb, cb)
    st.step(description.time_step(case), f0, kb, cb)


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
    the same time."""
    import numpy as np

    from orchestrator.coupling.fmi.structure import block_arguments
    from orchestrator.coupling.step import compile_step

    compile_step(block_arguments([], [], [], [], [], [], [], [], 0.0))
    compile_step((np.zeros(1, dtype=np.int64),))  # PythonStructure.arguments


def cold_paper_case(folder: str, periods: int, default_cache: str) -> None:
    """From an empty numba cache, in this process's own ``NUMBA_CACHE_DIR`` (``folder``/numba,
    cold by construction): the native layer, then the in-process run of
    :func:`tests.probes.determinism.runs` (every kernel compiled here), its result in
    ``folder``/cold.json for tests/system/test_determinism.py, and :func:`other_transports`;
    then this code version's kernels copied into the ``default_cache`` folder where missing
    (each file written apart and renamed into place), so that the workers load them."""
    import json
    import os
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
    for path in sorted(p for p in own.rglob("*") if p.is_file()):
        target = Path(default_cache) / path.relative_to(own)
        if target.exists():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        part = target.with_name(f"{target.name}.{os.getpid()}.part")
        part.write_bytes(path.read_bytes())
        os.replace(part, target)


PROBES = probes_of(bearing_and_train_kernels, native_and_structure, cold_paper_case)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
