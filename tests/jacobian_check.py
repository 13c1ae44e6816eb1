"""Central differences of a film model's force: the independent check of analytic Jacobians."""

import numpy as np


def numeric_jacobian(model, state, h=1e-6):
    """(2, 4) central-difference dFbar/d(xbar, ybar, xbar_dot, ybar_dot) at ``state``."""
    out = np.zeros((2, 4))
    for j in range(4):
        sp, sm = list(state), list(state)
        sp[j] += h
        sm[j] -= h
        out[:, j] = (model.dimensionless(*sp, jacobian=False).force
                     - model.dimensionless(*sm, jacobian=False).force) / (2 * h)
    return out
