"""Probe of tests/system/test_determinism.py: a bearing FMU in a host without this package.

``python -S tests/probes/standalone/bearing_host.py <JSON keyword arguments of host()>``, run
by its path (not ``-m``: the repository must not be on the path): only the standard library is
imported before the folders given (the dependencies' site-packages) are put first on the path,
then fmpy runs the FMU. Prints one JSON line.
"""

from __future__ import annotations

import hashlib
import json
import sys

#: the FMU's outputs hashed, in this order
OUTPUTS = ["F_s", "F_t", "K_ss", "K_st", "K_ts", "K_tt", "C_ss", "C_st", "C_ts", "C_tt"]


def host(paths: list[str], fmu: str, params: dict, states: list[list[float]]) -> dict:
    """A hash of the outputs of the bearing FMU ``fmu`` (parameters ``params``, rotation sign
    -1, 96 nodes, 54 rad/s) along ``states``, and the file of the ``bearing_fmu`` it ran."""
    sys.path[:0] = paths
    import numpy as np
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu), instanceName="b",
                      modelIdentifier=md.coSimulation.modelIdentifier)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr[n] for n in params], list(params.values()))
    slave.setInteger([vr["rotation_sign"], vr["nodes"]], [-1, 96])
    slave.setReal([vr["omega"]], [54.0])
    h = hashlib.sha256()
    for st in states:
        slave.setReal([vr[n] for n in ("s", "t", "s_dot", "t_dot")], st)
        h.update(np.array(slave.getReal([vr[n] for n in OUTPUTS])).tobytes())
    module = sys.modules["bearing_fmu"].__file__
    slave.terminate()
    slave.freeInstance()
    return {"hash": h.hexdigest(), "module": module}


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    print(json.dumps(host(**json.loads(argv[0]))))


if __name__ == "__main__":
    main()
