"""FMU slaves driven through fmpy: the same master interface as :mod:`orchestrator.inprocess`.

Calls go through fmpy's low-level functions with preallocated ctypes arrays (a few µs each).
A slave that fails (e.g. eccentricity >= 1) logs the reason with status error and returns NaN
outputs or a discard status; it is turned into a Python exception here, with the slave's log.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from fmu_src.contract import BEARING_VARIABLES, DAMPING_NAMES, FORCE_NAMES, STIFFNESS_NAMES
from orchestrator.master import BearingSet

__all__ = ["FmuBearings", "FmuError"]


class FmuError(RuntimeError):
    """An FMU call failed; the message carries the slave's log."""


class _Fmu:
    """One instantiated FMI 2.0 co-simulation slave with a message log."""

    def __init__(self, path: Path | str, instance_name: str):
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
            self.messages.append(f"[{status}] {message.decode(errors='replace')}")

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(logger)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(_free)
        self._callbacks = cb  # keep the ctypes callbacks alive
        self.fmu.instantiate(loggingOn=True, callbacks=cb)

    def set(self, values: dict) -> None:
        reals = {k: v for k, v in values.items() if self.types[k] == "Real"}
        ints = {k: v for k, v in values.items() if self.types[k] == "Integer"}
        if reals:
            self.fmu.setReal([self.vr[k] for k in reals], [float(v) for v in reals.values()])
        if ints:
            self.fmu.setInteger([self.vr[k] for k in ints], [int(v) for v in ints.values()])


class FmuBearings(BearingSet):
    """Bearing FMUs (any of the five models: same variables), one instance per bearing.

    Parameters
    ----------
    fmus : sequence of path
        FMU file of each bearing (swap a model by naming another file).
    parameters : sequence of dict
        Parameter values of each bearing (names of :data:`fmu_src.contract.BEARING_VARIABLES`).
    omegas : sequence of float
        Shaft speed magnitude at each bearing [rad/s].
    """

    _INPUTS = ("s", "t", "s_dot", "t_dot")
    _OUTPUTS = FORCE_NAMES + STIFFNESS_NAMES + DAMPING_NAMES

    def __init__(self, fmus, parameters, omegas):
        names = {v.name for v in BEARING_VARIABLES if v.causality == "parameter"}
        self.slaves = []
        for b, (path, params) in enumerate(zip(fmus, parameters, strict=True)):
            unknown = set(params) - names
            if unknown:
                raise ValueError(f"bearing {b + 1}: unknown FMU parameters {sorted(unknown)}")
            s = _Fmu(path, f"bearing{b + 1}")
            s.fmu.setupExperiment(startTime=0.0)
            s.fmu.enterInitializationMode()
            s.set(params)
            s.set({"omega": float(omegas[b])})
            self.slaves.append(s)
        self.in_init = True
        fm = self.slaves[0].fmu
        self._in_vr = [(ctypes.c_uint * 4)(*[s.vr[n] for n in self._INPUTS]) for s in self.slaves]
        self._out_vr = [(ctypes.c_uint * 10)(*[s.vr[n] for n in self._OUTPUTS])
                        for s in self.slaves]
        self._in_val = (ctypes.c_double * 4)()
        self._out_val = (ctypes.c_double * 10)()
        self._set = fm.fmi2SetReal
        self._get = fm.fmi2GetReal

    def evaluate(self, states):
        nb = len(self.slaves)
        force = np.empty((nb, 2))
        kb = np.empty((nb, 2, 2))
        cb = np.empty((nb, 2, 2))
        for b, s in enumerate(self.slaves):
            for i in range(4):
                self._in_val[i] = states[b, i]
            s.fmu.fmi2SetReal(s.fmu.component, self._in_vr[b], 4, self._in_val)
            s.fmu.fmi2GetReal(s.fmu.component, self._out_vr[b], 10, self._out_val)
            out = np.frombuffer(self._out_val, dtype=np.float64).copy()
            if not np.all(np.isfinite(out)):
                log = "; ".join(s.messages[-3:])
                raise FmuError(f"bearing {b + 1} ({s.path.name}) failed at state "
                               f"{states[b].tolist()}: {log}")
            force[b] = out[:2]
            kb[b] = out[2:6].reshape(2, 2)
            cb[b] = out[6:].reshape(2, 2)
        return force, kb, cb

    def static_position(self, loads):
        """Per-bearing 2-D Newton on F(X) + W = 0 through the FMU, kept inside the clearance."""
        pos = np.zeros((len(self.slaves), 2))
        for b, s in enumerate(self.slaves):
            clearance = float(s.fmu.getReal([s.vr["C"]])[0])
            x = np.zeros(2)
            states = np.zeros((len(self.slaves), 4))
            for _ in range(100):
                states[b, :2] = x
                f, k, _ = self.evaluate(states)
                res = f[b] + loads[b]
                if np.linalg.norm(res) <= 1e-10 * max(np.linalg.norm(loads[b]), 1e-300):
                    break
                step = np.linalg.solve(k[b], res)
                alpha = 1.0
                while np.hypot(*(x + alpha * step)) >= 0.95 * clearance:
                    alpha *= 0.5
                x = x + alpha * step
            pos[b] = x
        return pos

    def exit_initialization(self) -> None:
        """Leave initialisation mode (the linear FMU freezes its coefficients here)."""
        for s in self.slaves:
            s.fmu.exitInitializationMode()
        self.in_init = False

    def close(self) -> None:
        """Terminate and free every instance, remove the extracted FMU folders."""
        import shutil

        for s in self.slaves:
            s.fmu.terminate()
            s.fmu.freeInstance()
            shutil.rmtree(s._dir, ignore_errors=True)
        self.slaves = []
