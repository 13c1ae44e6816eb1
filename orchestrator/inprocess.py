"""In-process slaves: the physics objects behind the master's interface, no FMI layer."""

from __future__ import annotations

import numpy as np

from bearing_fmu.base import BearingModel, FilmBearingModel
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
        self.frames = [f if isinstance(f, LocalFrame) else LocalFrame(*f) for f in frames]
        self.omegas = [float(w) for w in omegas]
        for w in self.omegas:
            if not (np.isfinite(w) and w > 0.0):
                raise ValueError(f"shaft speed {w!r} rad/s must be finite and > 0")
        self._q = np.array([f.q for f in self.frames])
        self.models = models
        self.evaluations = 0

    def evaluate(self, states):
        nb = len(self.models)
        q = self._q
        loc = np.einsum("bij,bkj->bki", q, np.asarray(states, dtype=float).reshape(nb, 2, 2))
        force = np.empty((nb, 2))
        kb = np.empty((nb, 2, 2))
        cb = np.empty((nb, 2, 2))
        for b, (model, om) in enumerate(zip(self.models, self.omegas, strict=True)):
            (x, y), (xd, yd) = loc[b]
            if self._film[b]:
                # the dimensionless core once, the SI scaling of FilmBearingModel.evaluate here
                c = model.bearing.clearance
                ff = model.dimensionless(x / c, y / c, xd / (c * om), yd / (c * om), True)
                fs = self._fscale[b]
                force[b] = fs * ff.force
                kb[b] = (-fs / c) * ff.d_position
                cb[b] = (-fs / (c * om)) * ff.d_velocity
            else:
                r = model.evaluate(x, y, xd, yd, om)
                force[b], kb[b], cb[b] = r.force, r.stiffness, r.damping
        self.evaluations += nb
        # back to global components: f = Q^T f_loc, K = Q^T K_loc Q
        qt = np.transpose(q, (0, 2, 1))
        return (np.einsum("bij,bj->bi", qt, force), qt @ kb @ q, qt @ cb @ q)

    @property
    def models(self):
        """The bearing models (replaceable, e.g. by their linearisation at X0)."""
        return self._models

    @models.setter
    def models(self, models) -> None:
        models = list(models)
        for m in models:
            if not isinstance(m, BearingModel):
                raise TypeError(f"{m!r} is not a BearingModel")
        self._models = models
        self._film = [isinstance(m, FilmBearingModel) for m in models]
        self._fscale = [m.bearing.force_scale(om) if f else 0.0
                        for m, f, om in zip(models, self._film, self.omegas, strict=True)]

    def static_position(self, loads):
        pos = np.empty((len(self.models), 2))
        for b, (model, fr, om) in enumerate(zip(self.models, self.frames, self.omegas,
                                                strict=True)):
            sol = static_equilibrium(model, fr.to_local(loads[b]), om)
            pos[b] = fr.to_global((sol.x0, sol.y0))
        return pos
