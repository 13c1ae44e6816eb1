"""Probes of tests/system/test_fmu_system.py: the FMUs as a system engineer uses them (in the
test's process, or in fresh interpreters where the process is the point)."""

from __future__ import annotations

import sys
import time
import zipfile

import numpy as np

from tests.probes import dispatch, probes_of


def force_only_bearings(out_dir: str, gear_fmu: str, bearing_fmu: str) -> dict:
    """The spur case with lumped bearings (with damping) over 64 steps, in-process and with
    the force-only ``bearing_fmu`` for the four bearings: relative differences, the bearing
    model's label and the iterations per step of each."""
    from fmu_src.case import load_case
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import run_case

    case = load_case("baguet2010_spur", {"bearings.*.model": "lumped",
                                         "bearings.*.lumped_damping": 2000.0})
    ref = run_case(case, steps=64, in_process=True, out_dir=out_dir, progress=False)
    mine = run_case(case, steps=64, out_dir=out_dir, progress=False,
                    fmus=dict(gear=gear_fmu, bearings=[bearing_fmu] * 4))
    a, b = read_results(ref.results), read_results(mine.results)

    def rel(k):
        return float(np.abs(b[k] - a[k]).max() / np.abs(a[k]).max())

    from fmu_src.description import time_step

    return dict(position=rel("journal_position"), velocity=rel("journal_velocity"),
                position_scale=float(np.abs(a["journal_position"]).max()),
                velocity_scale=float(np.abs(a["journal_velocity"]).max()), dt=time_step(case),
                label=b["attrs"]["bearing_model"],
                its=[ref.iterations_per_step, mine.iterations_per_step])


def not_a_bearing(fmu: str) -> str | None:
    """The error of a bearing set made of ``fmu`` (None if it is accepted)."""
    from orchestrator.coupling.fmi import FmuBearings, FmuError

    try:
        FmuBearings([fmu], [dict()], [325.0])
    except FmuError as exc:
        return str(exc)
    return None


def closed_bearings(fmu_dir: str) -> list | str:
    """A bearing set evaluated after its master closed it: the error and whether the force
    read before was finite, or "evaluated"."""
    from fmu_src.case import load_case
    from orchestrator.coupling.fmi import FmuError
    from orchestrator.coupling.system import build_master

    master = build_master(load_case("baguet2010_spur"), fmu_dir=fmu_dir)
    master.solve_static()
    states = master.laws.states
    force = master.bearings.evaluate(states)[0]
    master.close()
    try:
        master.bearings.evaluate(states)
        return "evaluated"
    except FmuError as exc:
        return [str(exc), bool(np.isfinite(force).all())]


def build_at(start: float, dest: str) -> dict:
    """Wait until the time ``start`` [s since the epoch] (processes start together), then ask
    for two FMUs in ``dest``: per FMU, its modification time and fmpy's validation."""
    from fmpy.validation import validate_fmu

    from orchestrator.coupling.fmi import ensure_fmus

    while time.time() < start:
        time.sleep(0.001)
    paths = ensure_fmus(["GearShaft", "BearingShort"], dest)
    return {n: [p.stat().st_mtime_ns, validate_fmu(str(p))] for n, p in paths.items()}


def build_after_a_load(fmu: str, dest_a: str, dest_b: str) -> dict:
    """An FMU built after ``fmu`` was loaded through this package's instances: whether it has
    its binaries; then, after ``fmu`` loaded by fmpy alone in a process whose pythonfmu came
    from an FMU, the build's error."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from orchestrator.coupling.fmi import FmuBearings

    FmuBearings([fmu], [dict()], [325.0]).close()
    from fmu_src.build.fmus import build_fmus

    (built,) = build_fmus(dest_a, ["BearingShort"])
    whole = any(n.startswith("binaries/linux64/") for n in zipfile.ZipFile(built).namelist())
    for name in [m for m in sys.modules if m == "pythonfmu" or m.startswith("pythonfmu.")]:
        del sys.modules[name]  # as in a process whose first pythonfmu came from an FMU
    md = read_model_description(fmu)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu), instanceName="x",
                      modelIdentifier=md.coSimulation.modelIdentifier)
    slave.instantiate()
    try:
        build_fmus(dest_b, ["BearingShort"])
        refused = ""
    except RuntimeError as exc:
        refused = str(exc)
    slave.freeInstance()
    return {"whole": whole, "refused": refused}


PROBES = probes_of(force_only_bearings, not_a_bearing, closed_bearings, build_at,
                   build_after_a_load)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
