"""Probes of tests/fmu_src/test_instance_memory.py: instantiate/free cycles of one FMU through
fmpy in a process of their own, and what stays behind."""

from __future__ import annotations

import gc
import os

from tests.probes import dispatch, probes_of


def _rss() -> int:
    """The process's resident memory [bytes] (Linux)."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


#: measured cycles between two full collections
COLLECT_EVERY = 10


def cycles(fmu: str, warm_up: int, cycles: int, held: int) -> dict:
    """Instantiate/free cycles of ``fmu``, as a host that restarts its slaves runs them:
    fmi2Instantiate, fmi2SetupExperiment, initialisation, a read of three outputs,
    fmi2Terminate, fmi2FreeInstance.

    After ``warm_up`` cycles: ``alive``, the slave objects still in the process after
    ``held`` more cycles run with Python's garbage collector off (a slave freed by
    fmi2FreeInstance is gone at once; one in reference cycles waits for the collector); then
    ``growth_per_cycle``, the growth of resident memory over ``cycles`` more cycles, divided
    by ``cycles`` [bytes]: what stays behind, not what waits to be collected. A full
    collection runs before each end and every :data:`COLLECT_EVERY` cycles, so that the
    host's own garbage (fmpy leaves some 40 KiB in reference cycles per instance) does not
    raise the heap's high-water mark in between."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu)
    folder = extract(fmu)
    ident = md.coSimulation.modelIdentifier
    outputs = [v.valueReference for v in md.modelVariables
               if v.causality == "output" and v.type == "Real"][:3]

    def cycle():
        s = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=ident,
                      instanceName="memory")
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        s.getReal(outputs)
        s.terminate()
        s.freeInstance()

    for _ in range(warm_up):
        cycle()
    gc.collect()
    gc.disable()
    try:
        for _ in range(held):
            cycle()
        # the generated slave class is named after the model identifier (fmu_src.build.fmus)
        alive = sum(1 for o in gc.get_objects()
                    if type(o).__name__ == ident and not isinstance(o, type))
    finally:
        gc.enable()
    gc.collect()
    before = _rss()
    for k in range(cycles):
        cycle()
        if k % COLLECT_EVERY == COLLECT_EVERY - 1:
            gc.collect()
    gc.collect()
    return dict(alive=alive, growth_per_cycle=(_rss() - before) / cycles)


PROBES = probes_of(cycles)


def main(argv=None):
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
