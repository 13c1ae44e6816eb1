"""Probes of tests/system/test_transmission_fmu.py: the transmission FMU in fmpy, driven call
by call as an FMI host does, in a fresh interpreter (the FMU runs the code it carries)."""

from __future__ import annotations

from tests.probes import dispatch, probes_of


def outputs_of(case: str = "baguet2010_spur") -> list[str]:
    """The Real outputs of the transmission FMU of the shipped case ``case`` (per bearing its
    journal state and film force, per mesh its force and transmission error)."""
    from fmu_src.case import shipped_case
    from fmu_src.contract import transmission_output_names

    return transmission_output_names(shipped_case(case))


#: the outputs of the paper's transmission FMU, read after the initialisation and after every
#: communication step: per bearing (s, t, s_dot, t_dot), the film forces, the mesh force and
#: the transmission error
OUTPUTS = outputs_of()


class Host:
    """One instance of the FMU (fmpy's FMU2Slave) with its variables by name; ``outputs``:
    the names :meth:`outputs` reads (default :data:`OUTPUTS`)."""

    def __init__(self, fmu: str, name: str = "transmission", outputs=None):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.md = read_model_description(fmu)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.folder = extract(fmu)
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.folder,
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=name)
        self.messages: list[str] = []  # what the FMU logged
        self.slave.instantiate(loggingOn=True, callbacks=self._callbacks())
        self.out_vrs = [self.vars[n].valueReference for n in (outputs or OUTPUTS)]

    def _callbacks(self):
        from fmpy.fmi2 import (
            calloc,
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
            free,
        )

        def logger(env, name, status, category, message):
            self.messages.append(message.decode(errors="replace"))

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(logger)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._keep = cb  # the ctypes callbacks live as long as the instance
        return cb

    def set(self, values: dict) -> None:
        for name, value in values.items():
            v = self.vars[name]
            setter = {"Real": self.slave.setReal, "Integer": self.slave.setInteger,
                      "Boolean": self.slave.setBoolean, "String": self.slave.setString}[v.type]
            setter([v.valueReference], [value])

    def outputs(self) -> list[float]:
        return list(self.slave.getReal(self.out_vrs))

    def integer(self, name: str) -> int:
        return self.slave.getInteger([self.vars[name].valueReference])[0]

    def start(self, start_values: dict | None = None) -> list[float]:
        self.slave.setupExperiment(startTime=0.0)
        self.set(start_values or {})
        self.slave.enterInitializationMode()
        x0 = self.outputs()
        self.slave.exitInitializationMode()
        return x0

    def steps(self, h: float, n: int, first: int = 0) -> list[list[float]]:
        rows = []
        for k in range(first, first + n):
            self.slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            rows.append(self.outputs())
        return rows

    def close(self) -> None:
        import shutil

        self.slave.terminate()
        self.slave.freeInstance()
        shutil.rmtree(self.folder, ignore_errors=True)


def run(fmu: str, runs: list, case: str = "baguet2010_spur") -> list:
    """Each run ``{"start_values": {...}, "h": step [s], "n": steps}`` in a new instance: the
    outputs after the initialisation, then after each step; the internal step count. ``case``:
    the shipped case whose train the FMU holds (its outputs' names)."""
    out = []
    for spec in runs:
        host = Host(fmu, outputs=outputs_of(case))
        rows = [host.start(spec.get("start_values"))]
        rows += host.steps(spec["h"], spec["n"])
        out.append({"rows": rows, "steps": host.integer("steps")})
        host.close()
    return out


def state_round_trip(fmu: str, h: float, n: int, k: int) -> dict:
    """n steps straight on; back to the state after k steps (fmi2SetFMUstate) and on again;
    the state serialised, deserialised into a new instance and on again from there."""
    host = Host(fmu)
    host.start()
    host.steps(h, k)
    state = host.slave.getFMUstate()
    blob = host.slave.serializeFMUstate(state)
    straight = host.steps(h, n - k, first=k)
    host.slave.setFMUstate(state)
    again = host.steps(h, n - k, first=k)
    host.slave.freeFMUstate(state)
    other = Host(fmu, "other")
    other.slave.setupExperiment(startTime=0.0)
    other.slave.enterInitializationMode()
    other.slave.exitInitializationMode()
    other.slave.setFMUstate(other.slave.deSerializeFMUstate(blob))
    restored = other.steps(h, n - k, first=k)
    host.close()
    other.close()
    return {"straight": straight, "again": again, "restored": restored, "bytes": len(blob)}


def impossible_step(fmu: str, h: float, torque: float) -> dict:
    """A torque no bearing can carry set after the initialisation: the steps taken until a
    doStep is refused, the FMI status of that doStep, of the next read and of a further
    doStep (fmpy's messages), and the outputs that read returned, if any."""
    from fmpy.fmi1 import FMICallException

    host = Host(fmu)
    host.start()
    host.set({"torque": torque})
    out = {"ok_steps": 0}
    for k in range(50):
        try:
            host.slave.doStep(k * h, h)
        except FMICallException as exc:
            out["doStep"] = str(exc)
            break
        out["ok_steps"] = k + 1
    for what, call in (("getReal", host.outputs),
                       ("doStep again", lambda: host.slave.doStep(k * h, h))):
        try:
            out[what + " values"] = call()
            out[what] = "fmi2OK"
        except FMICallException as exc:
            out[what] = str(exc)
    host.close()
    return out


def _drive(host: Host, h: float, speeds: list, first: int, last: int) -> list:
    """Steps ``first`` to ``last - 1`` of ``h`` [s], the input ``speed`` set to ``speeds[k]``
    before step k: the outputs after each."""
    rows = []
    for k in range(first, last):
        host.set({"speed": speeds[k]})
        rows += host.steps(h, 1, first=k)
    return rows


def driven(fmu: str, h: float, speeds: list, start_values: dict | None = None,
           state_at: int | None = None) -> dict:
    """The input ``speed`` set to ``speeds[k]`` before the k-th doStep of ``h`` [s] (the
    speed to reach at its end): the outputs after each step and the internal step count.
    With ``state_at``: the state saved after that many steps, the rest run again from it in
    the same instance and, serialised, in a new one (``again``, ``restored``)."""
    n = len(speeds)
    at = n if state_at is None else state_at
    host = Host(fmu)
    host.start(start_values)
    rows = _drive(host, h, speeds, 0, at)
    if state_at is not None:
        state = host.slave.getFMUstate()
        blob = host.slave.serializeFMUstate(state)
        rows += _drive(host, h, speeds, at, n)
    out = {"rows": rows, "steps": host.integer("steps")}
    if state_at is not None:
        host.slave.setFMUstate(state)
        out["again"] = _drive(host, h, speeds, at, n)
        host.slave.freeFMUstate(state)
        other = Host(fmu, "other")
        other.start(start_values)
        other.slave.setFMUstate(other.slave.deSerializeFMUstate(blob))
        out["restored"] = _drive(other, h, speeds, at, n)
        other.close()
    host.close()
    return out


def speed_refusals(fmu: str, h: float, cases: list) -> list:
    """Each ``{"start_values": {...}, "speed": value}`` in a new instance: the FMI status of
    setting ``speed`` to ``value`` after the initialisation (fmpy's message, or "fmi2OK"),
    what the FMU logged then, and whether a step then runs."""
    from fmpy.fmi1 import FMICallException

    out = []
    for spec in cases:
        host = Host(fmu)
        host.start(spec.get("start_values"))
        since = len(host.messages)
        try:
            host.set({"speed": spec["speed"]})
            status = "fmi2OK"
        except FMICallException as exc:
            status = str(exc)
        log = "; ".join(host.messages[since:])
        try:
            host.steps(h, 1)
            stepped = True
        except FMICallException:
            stepped = False
        out.append({"status": status, "log": log, "stepped": stepped})
        host.close()
    return out


def simulate(fmu: str, dt: float, steps: int) -> list:
    """fmpy's one call, ``simulate_fmu``, recording the outputs every ``dt`` [s]: its rows
    after the start."""
    from fmpy import simulate_fmu

    res = simulate_fmu(fmu, step_size=dt, stop_time=steps * dt, output=OUTPUTS,
                       output_interval=dt)
    return [[float(res[n][k]) for n in OUTPUTS] for k in range(1, len(res))]


PROBES = probes_of(driven, speed_refusals, run, state_round_trip, impossible_step, simulate)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
