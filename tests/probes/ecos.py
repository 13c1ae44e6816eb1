"""Probe of tests/system/test_ecos.py: ecospy (ecos's library, a C++ co-simulation master)
runs an SSP archive in a fresh interpreter (it needs libtbb on the library path)."""

from __future__ import annotations

from tests.probes import dispatch, probes_of


def simulate(ssp: str, step_size: float, steps: int) -> dict:
    """The 16 journal outputs of the gear-shaft FMU (``x``) and the four eccentricities
    (``e``) after the initialisation and after each of ``steps`` steps, at full precision."""
    from ecospy import EcosSimulation

    names = [f"gear_shaft::{v}_{j}" for j in range(1, 5) for v in ("s", "t", "s_dot", "t_dot")]
    ecc = [f"bearing{j}::eccentricity" for j in range(1, 5)]
    x, e = [], []
    with EcosSimulation(ssp_path=ssp, step_size=step_size) as sim:
        sim.init(parameter_set="case")
        for k in range(steps + 1):
            if k:
                sim.step(1)
            x.append([sim.get_real(n) for n in names])
            e.append([sim.get_real(n) for n in ecc])
        sim.terminate()
    return dict(x=x, e=e)


PROBES = probes_of(simulate)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
