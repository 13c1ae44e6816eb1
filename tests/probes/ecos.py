"""Probe of tests/system/test_ecos.py: ecospy (ecos's library, a C++ co-simulation master)
runs an SSP archive in a fresh interpreter (it needs libtbb on the library path)."""

from __future__ import annotations

from tests.probes import dispatch, probes_of


def simulate(ssp: str, step_size: float, steps: int, case: str = "baguet2010_spur") -> dict:
    """The journal outputs of the gear-shaft FMU (``x``, 4 per bearing) and each bearing's
    eccentricity (``e``) after the initialisation and after each of ``steps`` steps, at full
    precision; ``case``: the shipped case whose train the archive holds (its names)."""
    from ecospy import EcosSimulation

    from fmu_src.case import shipped_case
    from fmu_src.contract import bearing_component, bearing_names, journal_output_names

    train = shipped_case(case)
    gear = _gear_component(ssp)
    names = [f"{gear}::{n}" for n in journal_output_names(train)]
    ecc = [f"{bearing_component(b)}::eccentricity" for b in bearing_names(train)]
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


def _gear_component(ssp: str) -> str:
    """The name of the archive's component whose FMU is ``GearShaft.fmu``
    (:func:`fmu_src.build.ssp.gear_component` chose it for its case)."""
    import zipfile
    from xml.etree import ElementTree as ET

    from fmu_src.build.ssp import NS

    with zipfile.ZipFile(ssp) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    return next(c.get("name") for c in root.iterfind(".//ssd:Component", NS)
                if c.get("source", "").endswith("GearShaft.fmu"))


PROBES = probes_of(simulate)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
