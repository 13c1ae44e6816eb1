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


@njit(cache=True)
def film_state_local(q, s, clearance, omega):
    """The global journal state ``s`` [m, m/s] as a film model's dimensionless local state
    ``(x/C, y/C, xdot/(C omega), ydot/(C omega))`` (Eq. 3; the order of
    :meth:`bearing_fmu.base.FilmBearingModel.evaluate`), and whether the model takes it: every
    component finite and the eccentricity ratio < 1 (else
    :func:`bearing_fmu.base.check_state` raises the error); compiled, for the film models'
    ``evaluate_global``."""
    x, y, xd, yd = state_to_local(q, s)
    cw = clearance * omega
    xb = x / clearance
    yb = y / clearance
    xdb = xd / cw
    ydb = yd / cw
    ok = (math.isfinite(xb) and math.isfinite(yb) and math.isfinite(xdb)
          and math.isfinite(ydb) and math.hypot(xb, yb) < 1.0)
    return xb, yb, xdb, ydb, ok


@njit(cache=True)
def film_law_global(q, res, fs, clearance, omega, out):
    """A film model's dimensionless law ``res`` (5, 2: Fbar, then the rows of dFbar/d(xbar,
    ybar) and of dFbar/d(xbar_dot, ybar_dot)) in SI units and global components into ``out``:
    F = fs Fbar [N], Kb = -fs/C dFbar/dxbar [N/m], Cb = -fs/(C omega) dFbar/dxbar_dot
    [N s/m] (:meth:`bearing_fmu.base.FilmBearingModel.evaluate`, ``fs`` its force scale [N]),
    then :func:`law_to_global`; compiled. ``res`` is scratch: it is scaled in place to the
    local law in SI units (no allocation, so the kernels that call this need no memory
    management, ``bearing_fmu.hybrid._workspace.kernel``)."""
    sk = -(fs / clearance)
    sc = -(fs / (clearance * omega))
    for c in range(2):
        res[0, c] = fs * res[0, c]
        for r in (1, 2):
            res[r, c] = sk * res[r, c]
            res[r + 2, c] = sc * res[r + 2, c]
    law_to_global(q, res, out)
