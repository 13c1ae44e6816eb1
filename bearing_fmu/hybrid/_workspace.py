"""Memory layout of the hybrid kernels (:mod:`bearing_fmu.hybrid._kernels`).

Everything a call needs is allocated once per model instance (:func:`new_workspace`):

* ``state``: a one-element record array of :data:`STATE` — the settings, the warm start kept
  between calls and the diagnostics of the last call, addressed by field name;
* ``active`` (bool, n): the pressurised set P of the LCP, kept between calls (warm start);
* ``ws`` (float, (:data:`WS_ROWS`, n)): work space, one named row per nodal quantity;
* ``iws`` (int, (2, 2n)): the node order of the Thomas factors and the runs of active nodes;
* ``trig`` (float, (8, n)): cos/sin at the 3 Gauss points of each element and at the nodes.

The axial integrals of Eq. (6) and their t-derivatives travel in a 9-vector ``g`` indexed by
:data:`G0` ... :data:`G2_TT` (``_T`` = d/dt, ``_TT`` = d^2/dt^2, t = (k lambda)^2).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit

#: the decorator of the kernels (``@kernel``, ``@kernel(inline="always")``): numba's
#: ``njit``, cached, and without numba's reference counting (NRT). The kernels work only in
#: the memory laid out here and never allocate, so counting references buys nothing, while it
#: cost an atomic increment and decrement for every row view such as ``ws[A]``: a quarter of
#: a profile of the paper's bearing calls (the calls ran 1.12-1.20 x faster without it). A
#: kernel that allocates does not compile under it.
kernel = functools.partial(njit, cache=True, _nrt=False)

# --- the state record --------------------------------------------------------------------------
STATE = np.dtype([
    # settings (set at construction)
    ("lam", np.float64),  # lambda = L/D
    ("tol", np.float64),  # Newton on t: relative step tolerance
    ("maxit", np.int64),  # Newton passes on t
    ("pinned", np.bool_),  # p = 0 on the line of maximum film thickness
    # warm start (kept between calls)
    ("t", np.float64),  # t = (k lambda)^2: warm start in, converged value out
    ("cold", np.bool_),  # initialise P from f > 0 (set by the caller; cleared by the kernel)
    ("predict", np.bool_),  # the predictor data below are valid
    ("dtdq", np.float64, (4,)),  # dt/d(x, y, xdot, ydot) of the last Jacobian call
    ("q_prev", np.float64, (4,)),  # the state of that call
    # diagnostics of the last call
    ("t_iterations", np.int64),  # Newton passes on t
    ("lcp_iterations", np.int64),  # active-set passes, summed over the Newton passes
    ("status", np.int64),  # 0 ok, 1 LCP not converged, 2 t not converged, 3 A not an M-matrix
    ("theta0", np.float64),  # angle of node 0 (nonzero only for the pinned variant)
    ("last_dt", np.float64),  # last Newton step on t
], align=True)

# --- work-space rows ---------------------------------------------------------------------------
KE, M11, M12, M22 = 0, 1, 2, 3  # element integrals, weight h^3
X0 = 4  # rows 4-7: the same for -3 h^2 cos(theta) (d/dx)
Y0 = 8  # rows 8-11: the same for -3 h^2 sin(theta) (d/dy)
KD, KL, MD, ML = 12, 13, 14, 15  # nodal K and M: diagonal and (i, i+1) entries
FB = 16  # F_i = int f l_i
D, LO, B = 17, 18, 19  # A = G2 K + G1 M (diagonal, (i, i+1)), b = G0 F
A = 20  # the nodal amplitudes a_i
CV, Z = 21, 22  # c = (A_t a - b_t)_P, z = A_PP^-1 c
CP, PIV = 23, 24  # Thomas factors
COS, SIN = 25, 26  # cos, sin at the nodes (solution frame)
NEW = 27  # next active set (0/1) during a PDAS pass
W = 28  # rows 28-29: the Jacobian's adjoint vectors A_PP^-1 (cos, sin)_P
SCR = 30  # rows 30-33: small scratch arrays (views, no allocation in the hot path), within
#   the first 16 columns (the smallest n): rows 0-1 jx, jv (0-3), row 0 the degenerate case's
#   four forces (4-11), row 1 c.da0 and dt_q (4-11), row 2 the axial integrals g (0-8) and the
#   force (9-10), row 3 s_q, cos.da0, sin.da0 (0-11)
WS_ROWS = 34

# --- the axial-integral vector g ---------------------------------------------------------------
G0, G1, G2 = 0, 1, 2  # G0 = lambda I0, G1 = I1 / lambda, G2 = lambda I2 (bearing_fmu.hybrid.axial)
G0_T, G1_T, G2_T = 3, 4, 5  # d/dt
G0_TT, G1_TT, G2_TT = 6, 7, 8  # d^2/dt^2

# Gauss rule on an element (3 points, exact to degree 5)
GT0 = 0.5 - math.sqrt(15.0) / 10.0
GT2 = 0.5 + math.sqrt(15.0) / 10.0
GW0 = 5.0 / 18.0
GW1 = 8.0 / 18.0


def make_trig(n: int) -> np.ndarray:
    """cos (rows 0-2) and sin (rows 3-5) at the Gauss points of element i = [theta_i,
    theta_i+1], cos and sin (rows 6-7) at the nodes theta_i = i 2 pi / n."""
    delta = 2.0 * math.pi / n
    gt = np.array([GT0, 0.5, GT2])
    thq = (np.arange(n)[None, :] + gt[:, None]) * delta
    thn = np.arange(n) * delta
    return np.vstack([np.cos(thq), np.sin(thq), np.cos(thn)[None], np.sin(thn)[None]])


def new_workspace(n: int, lam: float, tol: float, maxit: int, pinned: bool):
    """(state, active, ws, iws, trig) for n nodes, in the cold state."""
    state = np.zeros(1, dtype=STATE)
    state["lam"] = lam
    state["tol"] = tol
    state["maxit"] = maxit
    state["pinned"] = pinned
    state["cold"] = True
    state["t"] = 1.0
    return (state, np.zeros(n, dtype=np.bool_), np.zeros((WS_ROWS, n)),
            np.zeros((2, 2 * n), dtype=np.int64), make_trig(n))
