"""Probe of tests/system/test_omsimulator.py: OMSimulator 3.0's Python API runs an SSP archive
in a fresh interpreter (its package on ``PYTHONPATH``)."""

from __future__ import annotations

from tests.probes import dispatch, probes_of


def simulate(ssp: str, step_size: float, steps: int, case: str = "baguet2010_spur") -> dict:
    """The journal states (s, t, s_dot, t_dot of every bearing FMU's inputs, ``x``) after the
    initialisation and after each of ``steps`` steps of ``step_size`` [s], at full precision:
    ``SSP(path).instantiate()``, the step through ``setFixedStepSize`` (OMSimulator 3.0 takes
    it from its API only: docs/fmu-variables.md), ``initialize``, ``stepUntil``."""
    from OMSimulator import SSP, CRef

    from fmu_src.case import shipped_case
    from fmu_src.contract import bearing_component, bearing_names

    train = shipped_case(case)
    system = train["case.name"]
    names = [(bearing_component(b), v) for b in bearing_names(train)
             for v in ("s", "t", "s_dot", "t_dot")]
    model = SSP(ssp)
    inst = model.instantiate()
    inst.setResultFile("omsimulator_res.mat")
    inst.setFixedStepSize(step_size)
    inst.setStopTime(steps * step_size)
    inst.initialize()
    x = []
    for k in range(steps + 1):
        if k:
            inst.stepUntil(k * step_size)
        x.append([inst.getValue(CRef(system, c, v)) for c, v in names])
    inst.terminate()
    inst.delete()
    return dict(x=x)


PROBES = probes_of(simulate)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
