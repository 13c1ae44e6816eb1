"""One FMI 2.0 co-simulation slave instantiated through fmpy, with its message log.

Calls go through fmpy's low-level functions with preallocated ctypes arrays (a few µs each).
A slave that fails (e.g. eccentricity >= 1, a Newmark step that does not converge) logs the
reason with status error and returns NaN outputs or a non-OK status; the transports of
:mod:`orchestrator.coupling.fmi` turn that into :class:`FmuError` with the slave's log.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

__all__ = ["FmuError", "FmuInstance", "all_finite", "status_name"]

_STATUS = ("ok", "warning", "discard", "error", "fatal", "pending")


def status_name(status: int) -> str:
    return _STATUS[status] if 0 <= status < len(_STATUS) else f"illegal status {status}"


def all_finite(values) -> bool:
    """True when every value read from an FMU (a ctypes array or a list of floats) is finite:
    their sum first, which any non-finite value makes non-finite (a few µs cheaper than numpy
    on the hot path), then ``np.isfinite`` to tell a sum overflowing from finite values."""
    return math.isfinite(sum(values)) or bool(np.isfinite(np.asarray(values, dtype=float)).all())


class FmuError(RuntimeError):
    """An FMU call failed; the message carries the slave's log."""


class FmuInstance:
    """One instantiated FMI 2.0 co-simulation slave with a message log."""

    def __init__(self, path: Path | str, instance_name: str):
        # pythonfmu's library puts the FMU's resources first on sys.path, and a pythonfmu FMU
        # carries a copy of pythonfmu's Python modules there (no binaries): imported now, the
        # installed pythonfmu is the one the FMU's slave and later imports in this process
        # (fmu_src.build.fmus) get, not the copy of the first FMU instantiated
        import pythonfmu  # noqa: F401
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        path = Path(path)
        if not path.is_file():
            raise FmuError(f"FMU file not found: {path}")
        self.path = path
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.messages: list[str] = []
        self.errors = 0  # messages logged with status error or fatal
        self._dir = extract(str(path))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=instance_name)

        from fmpy.fmi2 import calloc as _calloc
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
        )
        from fmpy.fmi2 import free as _free

        def logger(env, name, status, category, message):
            self.messages.append(f"[{status_name(status)}] {message.decode(errors='replace')}")
            if status >= 3:
                self.errors += 1

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(logger)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(_free)
        self._callbacks = cb  # keep the ctypes callbacks alive
        try:
            self.fmu.instantiate(loggingOn=True, callbacks=cb)
        except Exception as exc:  # fmpy says only "Failed to instantiate model": add why
            log = "; ".join(self.messages[-5:]) or "the FMU logged nothing"
            raise FmuError(f"{path.name} ({instance_name}): fmi2Instantiate failed: {log}") \
                from exc

    def set(self, values: dict, who: str | None = None) -> None:
        """Set parameters or inputs by name (one call per type); FmuError with the FMU's log
        if the FMU refuses a value (fmi2Error: out of its bounds, not finite)."""
        import ctypes

        by_type: dict[str, tuple[list, list]] = {}
        for name, value in values.items():
            vrs, vals = by_type.setdefault(self.types[name], ([], []))
            vrs.append(self.vr[name])
            vals.append(value)
        f = self.fmu
        setter = {"Real": f.dll.fmi2SetReal, "Integer": f.dll.fmi2SetInteger,
                  "Boolean": f.dll.fmi2SetBoolean, "String": f.dll.fmi2SetString}
        for kind, (vrs, vals) in by_type.items():
            n = len(vrs)
            if kind == "Real":
                arr = (ctypes.c_double * n)(*[float(v) for v in vals])
            elif kind in ("Integer", "Boolean"):
                arr = (ctypes.c_int * n)(*[int(v) for v in vals])
            else:
                arr = (ctypes.c_char_p * n)(*[str(v).encode() for v in vals])
            since = len(self.messages)
            status = setter[kind](f.component, (ctypes.c_uint * n)(*vrs), n, arr)
            if status > 1:
                names = [k for k in values if self.types[k] == kind]
                raise FmuError(f"{who or self.path.name}: {self.path.name} refused "
                               f"{', '.join(names)} ({status_name(status)}): "
                               f"{self.log_tail(since=since)}")

    def errors_since(self, since: int) -> bool:
        """Whether a message with status error or fatal was logged from index ``since`` on."""
        return any(m.startswith(("[error]", "[fatal]")) for m in self.messages[since:])

    def log_tail(self, n: int = 3, since: int = 0) -> str:
        """The last ``n`` log messages (from index ``since`` on), for error messages."""
        tail = self.messages[since:][-n:]
        return "; ".join(tail) if tail else "(no message in the FMU log)"

    @property
    def can_serialize(self) -> bool:
        """Whether the FMU declares canSerializeFMUstate (and get/set FMU state)."""
        cs = self.md.coSimulation
        return bool(cs.canGetAndSetFMUstate and cs.canSerializeFMUstate)

    def serialize_state(self) -> bytes:
        """The instance's current FMU state as bytes (fmi2GetFMUstate,
        fmi2SerializeFMUstate; the copy is freed before returning)."""
        f = self.fmu
        state = f.getFMUstate()
        try:
            return f.serializeFMUstate(state)
        finally:
            f.freeFMUstate(state)

    def restore_serialized(self, data: bytes) -> None:
        """Set the instance to a state of :meth:`serialize_state` (fmi2DeSerializeFMUstate,
        fmi2SetFMUstate); :class:`FmuError` with the FMU's log when the FMU refuses the
        bytes (this package's FMUs read only their own state format: no pickle, another
        model's state or a damaged one is refused with fmi2Error, the instance intact)."""
        from fmpy.fmi1 import FMICallException

        f = self.fmu
        since = len(self.messages)
        state = None
        try:
            state = f.deSerializeFMUstate(data)
            f.setFMUstate(state)
        except FMICallException as exc:
            what = "fmi2DeSerializeFMUstate" if state is None else "fmi2SetFMUstate"
            raise FmuError(f"{self.path.name}: {what} refused the serialised state "
                           f"({status_name(exc.status)}): {self.log_tail(since=since)}") from None
        finally:
            if state is not None:
                f.freeFMUstate(state)

    def close(self) -> None:
        """Terminate and free the instance, remove the extracted folder (idempotent)."""
        if self.fmu is None:
            return
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            self.fmu = None
            shutil.rmtree(self._dir, ignore_errors=True)


