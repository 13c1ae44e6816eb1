"""In-process slaves: the physics objects behind the master's interface, no FMI layer."""

from __future__ import annotations

import numpy as np

from bearing_fmu.base import BearingModel
from bearing_fmu.frames import LocalFrame
from bearing_fmu.static import static_equilibrium
from orchestrator.master import BearingSet

__all__ = ["ModelBearings"]


class ModelBearings(BearingSet):
    """Bearing models evaluated directly, converted between local and global frames.

    Parameters
    ----------
    models : sequence of BearingModel
        One per bearing node.
    frames : sequence of LocalFrame
        Local frame of each bearing in the global (s, t) plane.
    omegas : sequence of float
        Shaft speed magnitude at each bearing [rad/s].
    """

    def __init__(self, models, frames, omegas):
        if not (len(models) == len(frames) == len(omegas)):
            raise ValueError("models, frames and omegas must have one entry per bearing")
        for m in models:
            if not isinstance(m, BearingModel):
                raise TypeError(f"{m!r} is not a BearingModel")
        self.models = list(models)
        self.frames = [f if isinstance(f, LocalFrame) else LocalFrame(*f) for f in frames]
        self.omegas = [float(w) for w in omegas]
        self.evaluations = 0

    def evaluate(self, states):
        nb = len(self.models)
        force = np.empty((nb, 2))
        kb = np.empty((nb, 2, 2))
        cb = np.empty((nb, 2, 2))
        for b, (model, fr, om) in enumerate(zip(self.models, self.frames, self.omegas,
                                                strict=True)):
            x, y = fr.to_local(states[b, :2])
            xd, yd = fr.to_local(states[b, 2:])
            r = model.evaluate(x, y, xd, yd, om)
            force[b] = fr.to_global(r.force)
            kb[b] = fr.matrix_to_global(r.stiffness)
            cb[b] = fr.matrix_to_global(r.damping)
        self.evaluations += nb
        return force, kb, cb

    def static_position(self, loads):
        pos = np.empty((len(self.models), 2))
        for b, (model, fr, om) in enumerate(zip(self.models, self.frames, self.omegas,
                                                strict=True)):
            sol = static_equilibrium(model, fr.to_local(loads[b]), om)
            pos[b] = fr.to_global((sol.x0, sol.y0))
        return pos
