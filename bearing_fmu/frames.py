"""Bearing local frame (x, y) versus the global frame (s, t) of the gear system.

The film models assume the journal rotates about +z of their local frame (Fig. 3). A bearing on
a shaft turning about -z (the gear shaft, driven by the pinion) therefore uses a mirrored local
frame. ``LocalFrame(angle, rotation_sign)``:

    x = cos(angle) s + sin(angle) t
    y = rotation_sign * (-sin(angle) s + cos(angle) t)

i.e. ``local = Q global`` with ``Q = diag(1, rotation_sign) R(-angle)``. ``Q`` is orthogonal, so
vectors go back with ``Q^T`` and a 2x2 law ``dF/dX`` with ``Q^T A Q``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["LocalFrame"]


@dataclass(frozen=True)
class LocalFrame:
    """Orientation of a bearing's local frame in the global (s, t) plane.

    The journal-centre position ``OO' = x x_vec + y y_vec`` of Eq. (1) is expressed in this
    local frame (:meth:`to_local`), where the film models work.

    Parameters
    ----------
    angle : float
        Angle from the global s axis to the local x axis [rad].
    rotation_sign : int
        +1 if the shaft turns about +z, -1 if about -z.

    Examples
    --------
    >>> fr = LocalFrame(0.0, -1)
    >>> fr.to_local([1.0, 2.0])
    array([ 1., -2.])
    """

    angle: float = 0.0
    rotation_sign: int = 1
    q: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.rotation_sign not in (1, -1):
            raise ValueError(f"rotation_sign = {self.rotation_sign!r} must be +1 or -1")
        if not math.isfinite(self.angle):
            raise ValueError(f"frame angle = {self.angle!r} rad is not finite")
        c, s = math.cos(self.angle), math.sin(self.angle)
        q = np.array([[c, s], [-s * self.rotation_sign, c * self.rotation_sign]])
        object.__setattr__(self, "q", q)

    def to_local(self, vec) -> np.ndarray:
        """Global (s, t) components -> local (x, y)."""
        return self.q @ np.asarray(vec, dtype=float)

    def to_global(self, vec) -> np.ndarray:
        """Local (x, y) components -> global (s, t)."""
        return self.q.T @ np.asarray(vec, dtype=float)

    def matrix_to_global(self, mat) -> np.ndarray:
        """A local 2x2 law (e.g. Kb, Cb) expressed in global components."""
        return self.q.T @ np.asarray(mat, dtype=float) @ self.q
