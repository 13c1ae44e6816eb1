"""What the xdist controller runs before the workers start (tests/conftest.py), two probes in
two processes at once: the kernels are then loaded from numba's cache by the workers and the
processes the tests start, not compiled by each of them at the same time."""

from __future__ import annotations

import tempfile

from tests.probes import dispatch, probes_of


def bearing_kernels() -> None:
    """Every bearing model's kernels, in-process and through the bearing set, and the static
    equilibrium."""
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


def native_and_structure() -> None:
    """The native layer, then the structure's and the master's kernels (short in-process runs
    of both shipped cases)."""
    from fmu_src.build.native import export_library
    from fmu_src.case import load_case
    from orchestrator.run.runner import run_case

    export_library()
    with tempfile.TemporaryDirectory() as tmp:
        for case, model in (("baguet2010_spur", "lumped"), ("baguet2010_helical", "lumped")):
            run_case(load_case(case, {"bearings.*.model": model}), steps=2, in_process=True,
                     out_dir=tmp + "/" + case, progress=False)


PROBES = probes_of(bearing_kernels, native_and_structure)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
