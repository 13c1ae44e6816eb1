"""Wall time of the transmission FMU (``gsb export-fmu``) against the in-process run.

Usage: ``python benchmarks/transmission_fmu.py [--periods N] [--repeat R] [--fmu PATH]
[--case NAME] [--nanoseconds] [--every K]``

Builds the case's transmission FMU (or takes ``--fmu``), then times, alternating ``R``
times in this one process: the in-process run (``orchestrator.simulate(..., in_process=True)``,
results in memory) and the FMU driven by fmpy as a host records it (``doStep`` at the case's
step, then the 26 outputs read: journal states, film forces, mesh force, transmission error).
Both after a one-period warm-up (numba's kernels loaded, the FMU's code staged). Prints each
time [s], the medians and their ratio FMU / in-process. ``--case``: another shipped case (default
the paper's spur case). ``--nanoseconds``: the host steps by the case's step rounded to whole
nanoseconds, as libcosim keeps time (a step that does not recur with the mesh period:
:data:`gear_fmu.step.events.DRIFT_FRACTION`); the in-process run keeps the case's step.
``--every K``: the host's communication step is K of the case's steps (the FMU cuts it into K
internal steps, :func:`orchestrator.coupling.transmission.internal_steps`) and it reads the
outputs after each: a system model that exchanges less often than the gears need.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time

CASE = "baguet2010_spur"


def in_process(case, periods: int) -> float:
    import orchestrator as gsb

    t0 = time.perf_counter()
    gsb.simulate(case.with_overrides({"simulation.mesh_periods": periods}), in_process=True,
                 progress=False)
    return time.perf_counter() - t0


def through_fmu(fmu: str, dt: float, steps: int) -> float:
    import shutil

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    t0 = time.perf_counter()
    md = read_model_description(fmu)
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"
               and v.type == "Real"]
    folder = extract(fmu)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    for k in range(steps):
        slave.doStep(k * dt, dt)
        slave.getReal(outputs)
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(folder, ignore_errors=True)
    return time.perf_counter() - t0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--periods", type=int, default=256, help="mesh periods (default 256)")
    p.add_argument("--repeat", type=int, default=3, help="alternating pairs (default 3)")
    p.add_argument("--fmu", help="a transmission FMU of the case (default: built now)")
    p.add_argument("--case", default=CASE, help=f"a shipped case (default {CASE})")
    p.add_argument("--nanoseconds", action="store_true",
                   help="the FMU's host step rounded to whole nanoseconds (libcosim's clock)")
    p.add_argument("--every", type=int, default=1,
                   help="the host's step in case steps (default 1)")
    args = p.parse_args()

    from fmu_src.build.fmus import build_transmission_fmu
    from fmu_src.case import load_case
    from fmu_src.description import time_step

    case = load_case(args.case)
    dt = time_step(case)
    if args.every < 1:
        p.error(f"--every {args.every}: the host's step is at least one case step")
    host_dt = args.every * dt
    host_dt = round(host_dt * 1e9) * 1e-9 if args.nanoseconds else host_dt
    steps = args.periods * case["simulation.steps_per_mesh_period"]
    with tempfile.TemporaryDirectory() as tmp:
        fmu = args.fmu or str(build_transmission_fmu(case, tmp))
        in_process(case, 1)
        through_fmu(fmu, dt, case["simulation.steps_per_mesh_period"])
        a, b = [], []
        for k in range(args.repeat):
            a.append(in_process(case, args.periods))
            b.append(through_fmu(fmu, host_dt, steps // args.every))
            print(f"pair {k + 1}: in-process {a[-1]:.2f} s, transmission FMU {b[-1]:.2f} s "
                  f"({args.periods} mesh periods, {steps // args.every} host steps of "
                  f"{host_dt!r} s)", flush=True)
    ma, mb = statistics.median(a), statistics.median(b)
    print(f"median: in-process {ma:.2f} s, transmission FMU {mb:.2f} s, "
          f"FMU / in-process {mb / ma:.3f}")


if __name__ == "__main__":
    main()
