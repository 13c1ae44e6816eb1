"""Probe of tests/system/test_libcosim.py: libcosim (OSP's C++ co-simulation library, through
its Python binding libcosimpy) runs the transmission FMU in a fresh interpreter."""

from __future__ import annotations

import ctypes

from tests.probes import dispatch, probes_of
from tests.probes.transmission import OUTPUTS


def _quiet() -> None:
    """libcosim logs at debug level to stdout by default; warnings and errors only (the FMU's
    failure messages are errors)."""
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.WARNING)


def _series(observer, slave: int, reference: int, count: int) -> tuple[list, list, list]:
    """A time-series observer's first ``count`` samples of one real variable from step 0:
    (values, step numbers, time points [ns]). libcosimpy's ``time_series_real_samples`` takes
    step number 0 for an unfilled slot and so drops the initial sample; this reads the same C
    function (``cosim_observer_slave_get_real_samples``) without that trimming."""
    from libcosimpy._internal import libcosimc, wrap_function
    from libcosimpy.CosimObserver import CosimObserver

    values, steps, times = (ctypes.c_double * count)(), (ctypes.c_int64 * count)(), \
        (ctypes.c_int64 * count)()
    get = wrap_function(lib=libcosimc(), funcname="cosim_observer_slave_get_real_samples",
                        argtypes=[ctypes.POINTER(CosimObserver), ctypes.c_int, ctypes.c_uint32,
                                  ctypes.c_int64, ctypes.c_size_t, ctypes.c_double * count,
                                  ctypes.c_int64 * count, ctypes.c_int64 * count],
                        restype=ctypes.c_int64)
    read = get(observer.ptr(), slave, reference, 0, count, values, steps, times)
    if read != count:
        raise RuntimeError(f"libcosim returned {read} samples of variable {reference}, "
                           f"expected {count}")
    return values[:], steps[:], times[:]


def simulate(fmu: str, step_ns: int, steps: int) -> dict:
    """The transmission FMU alone in a libcosim execution of fixed step ``step_ns`` [ns]
    (libcosim's clock counts whole nanoseconds), ``steps`` steps one at a time.

    Returns the 26 outputs of :data:`tests.probes.transmission.OUTPUTS` read by a last-value
    observer after each step (``rows``), the same outputs from a time-series observer from the
    initialisation on (``series``: ``steps + 1`` rows, X0 first, with libcosim's step numbers
    and time points), libcosim's time after each step [ns] and the FMU's internal step count.
    """
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    _quiet()
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=fmu, instance_name="transmission")
    index = execution.add_local_slave(local_slave=slave)
    if index < 0:
        raise RuntimeError(f"libcosim did not load {fmu}")
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    out_refs = [refs[n] for n in OUTPUTS]
    last = CosimObserver.create_last_value()
    series = CosimObserver.create_time_series()
    execution.add_observer(observer=last)
    execution.add_observer(observer=series)
    for ref in out_refs:
        series.start_time_series(index, value_reference=ref,
                                 variable_type=CosimVariableType.REAL)
    rows, times = [], []
    for _ in range(steps):
        if not execution.step():
            raise RuntimeError(f"libcosim step failed: {execution.status()}")
        times.append(execution.status().current_time)
        rows.append(last.last_real_values(index, out_refs))
    columns = [_series(series, index, ref, steps + 1) for ref in out_refs]
    internal = last.last_integer_values(index, [refs["steps"]])[0]
    del series, last, execution, slave  # the FMU freed while Python is whole
    return {"rows": rows, "times": times, "internal_steps": internal,
            "series": [list(r) for r in zip(*(c[0] for c in columns), strict=True)],
            "series_steps": columns[0][1], "series_times": columns[0][2]}


def driven(fmu: str, step_ns: int, speeds: list, max_speed: float) -> dict:
    """The transmission FMU in a libcosim execution of fixed step ``step_ns`` [ns], its
    parameter ``max_speed`` [rad/s] an initial value, its input ``speed`` set by libcosim's
    override manipulator to ``speeds[k]`` before step k: the outputs of
    :data:`tests.probes.transmission.OUTPUTS` after each step and the internal step count."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    _quiet()
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=fmu, instance_name="transmission")
    index = execution.add_local_slave(local_slave=slave)
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    execution.real_initial_value(index, refs["max_speed"], max_speed)
    last = CosimObserver.create_last_value()
    execution.add_observer(observer=last)
    override = CosimManipulator.create_override()
    execution.add_manipulator(manipulator=override)
    out_refs = [refs[n] for n in OUTPUTS]
    rows = []
    for w in speeds:
        override.slave_real_values(index, [refs["speed"]], [w])
        if not execution.step():
            raise RuntimeError(f"libcosim step failed: {execution.status()}")
        rows.append(last.last_real_values(index, out_refs))
    internal = last.last_integer_values(index, [refs["steps"]])[0]
    del override, last, execution, slave  # the FMU freed while Python is whole
    return {"rows": rows, "internal_steps": internal}


def impossible_step(fmu: str, step_ns: int, torque: float, observe: bool) -> dict:
    """After one step, an override manipulator sets a ``torque`` [N m] no bearing can carry:
    the steps libcosim took until one failed, its execution state then and its last error
    message, and whether a further step is refused; with a last-value observer (``observe``,
    which reads the outputs after every step) or without."""
    from libcosimpy._internal import get_last_error_message
    from libcosimpy.CosimEnums import CosimExecutionState
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    _quiet()
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=fmu, instance_name="transmission")
    index = execution.add_local_slave(local_slave=slave)
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    last = CosimObserver.create_last_value()
    if observe:
        execution.add_observer(observer=last)
    override = CosimManipulator.create_override()
    execution.add_manipulator(manipulator=override)
    out = {"ok_steps": int(execution.step())}
    override.slave_real_values(index, [refs["torque"]], [torque])
    while out["ok_steps"] < 50 and execution.step():
        out["ok_steps"] += 1
    out["state"] = CosimExecutionState(execution.status().state).name
    out["error"] = get_last_error_message()
    out["step again"] = execution.step()
    del override, last, execution, slave
    return out


PROBES = probes_of(simulate, driven, impossible_step)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
