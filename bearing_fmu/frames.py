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
from numba import njit

__all__ = ["LocalFrame", "law_to_global", "state_to_local"]


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


@njit(cache=True)
def state_to_local(q, s):
    """A global journal state ``s`` [s, t, sdot, tdot] in the local frame of ``q`` (``local = q
    global``): ``(x, y, xdot, ydot)``, compiled, for the models' ``evaluate_global``."""
    return (q[0, 0] * s[0] + q[0, 1] * s[1], q[1, 0] * s[0] + q[1, 1] * s[1],
            q[0, 0] * s[2] + q[0, 1] * s[3], q[1, 0] * s[2] + q[1, 1] * s[3])


@njit(cache=True)
def law_to_global(q, loc, out):
    """A local law ``loc`` (5, 2: force, then the rows of Kb and of Cb) in global components
    into ``out``: ``q^T F``, ``q^T Kb q``, ``q^T Cb q``, each product in the order of
    :meth:`LocalFrame.to_global` and :meth:`LocalFrame.matrix_to_global` (``(q^T M) q``);
    compiled, for the models' ``evaluate_global``."""
    out[0, 0] = q[0, 0] * loc[0, 0] + q[1, 0] * loc[0, 1]
    out[0, 1] = q[0, 1] * loc[0, 0] + q[1, 1] * loc[0, 1]
    for r in (1, 3):
        a00 = q[0, 0] * loc[r, 0] + q[1, 0] * loc[r + 1, 0]
        a01 = q[0, 0] * loc[r, 1] + q[1, 0] * loc[r + 1, 1]
        a10 = q[0, 1] * loc[r, 0] + q[1, 1] * loc[r + 1, 0]
        a11 = q[0, 1] * loc[r, 1] + q[1, 1] * loc[r + 1, 1]
        out[r, 0] = a00 * q[0, 0] + a01 * q[1, 0]
        out[r, 1] = a00 * q[0, 1] + a01 * q[1, 1]
        out[r + 1, 0] = a10 * q[0, 0] + a11 * q[1, 0]
        out[r + 1, 1] = a10 * q[0, 1] + a11 * q[1, 1]
