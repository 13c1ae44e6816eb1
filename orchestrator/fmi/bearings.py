"""The bearing FMUs behind the master's :class:`~orchestrator.master.BearingSet` interface."""

from __future__ import annotations

import ctypes

import numpy as np

from bearing_fmu.static import newton_equilibrium
from fmu_src.contract import BEARING_VARIABLES, DAMPING_NAMES, FORCE_NAMES, STIFFNESS_NAMES
from orchestrator.fmi.instance import FmuError, FmuInstance
from orchestrator.master import BearingSet

__all__ = ["FmuBearings"]


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
            s = FmuInstance(path, f"bearing{b + 1}")
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
        """Per-bearing Newton on F(X) + W = 0 through the FMU, from the centre, kept inside
        0.95 C (:func:`bearing_fmu.static.newton_equilibrium`).

        Each iterate evaluates the whole set with the other journals at the centre, as this
        transport always has: the hybrid FMUs' warm starts, and so the run's last digits,
        depend on that sequence (issue 10 revisits the FMU's first guess)."""
        pos = np.zeros((len(self.slaves), 2))
        for b, s in enumerate(self.slaves):
            clearance = float(s.fmu.getReal([s.vr["C"]])[0])
            states = np.zeros((len(self.slaves), 4))

            def law(x, b=b, states=states):
                states[b, :2] = x
                f, k, _ = self.evaluate(states)
                return f[b], k[b], None

            pos[b], _, _ = newton_equilibrium(law, loads[b], np.zeros(2), 0.95 * clearance,
                                              tol=1e-10, maxit=100,
                                              what=f"(bearing {b + 1}, first guess of X0)")
        return pos

    def exit_initialization(self) -> None:
        """Leave initialisation mode (the linear FMU freezes its coefficients here)."""
        for s in self.slaves:
            s.fmu.exitInitializationMode()
        self.in_init = False

    def close(self) -> None:
        """Terminate and free every instance, remove the extracted FMU folders."""
        for s in self.slaves:
            s.close()
        self.slaves = []


