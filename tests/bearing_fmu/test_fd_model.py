"""The finite-difference reference solver: convergence, complementarity, symmetry, multigrid."""

import math

import numpy as np
import pytest

from bearing_fmu import EccentricityError
from bearing_fmu.fd.model import (
    FiniteDifferenceBearing,
    reynolds_operator,
    solve_complementarity,
)


def test_second_order_mesh_convergence():
    mags = []
    for nt, nx in ((48, 8), (96, 16), (192, 32), (384, 64)):
        m = FiniteDifferenceBearing.from_lambda(1.0, n_theta=nt, n_xi=nx, linear_solver="direct")
        mags.append(np.hypot(*m.dimensionless(0.6, 0.0, jacobian=False).force))
    d = np.diff(mags)
    order = np.log2(abs(d[:-1] / d[1:]))
    print(f"\n|F| on 48x8 ... 384x64: {mags}; observed orders {order}")
    assert np.all(order > 1.8) and np.all(order < 2.3)


def test_complementarity_holds_at_the_solution():
    A, b, *_ = reynolds_operator(0.72, 0.5, -0.3, 0.05, 0.02, 96, 16)
    p, active, _ = solve_complementarity(A, b, b > 0, method="direct")
    w = A @ p - b
    scale = np.abs(b).max()
    assert p.min() >= 0.0
    assert w[~active].min() >= -1e-12 * scale
    assert np.abs(w[active]).max() <= 1e-10 * scale
    assert 0.3 < active.mean() < 0.7  # roughly half the film carries pressure


def test_multigrid_and_direct_agree_and_multigrid_is_mesh_independent():
    import pyamg

    iters = []
    for nt, nx in ((96, 16), (192, 32), (384, 64)):
        A, b, *_ = reynolds_operator(0.72, 0.6, 0.0, 0.0, 0.0, nt, nx)
        P = np.flatnonzero(b > 0)
        ml = pyamg.smoothed_aggregation_solver(A[P][:, P], symmetry="symmetric", max_coarse=64)
        res = []
        ml.solve(b[P], tol=1e-10, accel="cg", residuals=res)
        iters.append(len(res) - 1)
        factor = (res[-1] / res[0]) ** (1.0 / (len(res) - 1))
        print(f"\n{nt}x{nx}: {len(res) - 1} AMG-CG iterations, mean factor {factor:.3f}")
        assert factor < 0.3
    assert max(iters) <= 2 * min(iters)
    fm = FiniteDifferenceBearing.from_lambda(0.72, n_theta=96, n_xi=16)
    fd = FiniteDifferenceBearing.from_lambda(0.72, n_theta=96, n_xi=16, linear_solver="direct")
    np.testing.assert_allclose(fm.dimensionless(0.6, 0.1).force, fd.dimensionless(0.6, 0.1).force,
                               rtol=1e-9)


def test_pressure_symmetric_about_mid_plane():
    m = FiniteDifferenceBearing.from_lambda(0.5, n_theta=96, n_xi=16)
    _, xi, p = m.pressure(0.5, 0.2, 0.03, -0.01)
    np.testing.assert_allclose(p, p[:, ::-1], rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(xi, -xi[::-1])


def test_isotropy_on_the_grid():
    n = 96
    x, y = 0.55, 0.1
    base = FiniteDifferenceBearing.from_lambda(0.72, n_theta=n, n_xi=16).dimensionless(x, y).force
    a = 2 * math.pi * 17 / n
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    got = FiniteDifferenceBearing.from_lambda(0.72, n_theta=n, n_xi=16).dimensionless(
        *(rot @ [x, y])).force
    np.testing.assert_allclose(got, rot @ base, rtol=1e-9)


def test_jacobian_schemes_agree():
    m = FiniteDifferenceBearing.from_lambda(0.72, n_theta=96, n_xi=16)
    c = m.dimensionless(0.5, -0.2, 0.01, 0.02)
    f = FiniteDifferenceBearing.from_lambda(0.72, n_theta=96, n_xi=16, jacobian_scheme="forward",
                                            jacobian_step=1e-7).dimensionless(0.5, -0.2, 0.01, 0.02)
    np.testing.assert_allclose(f.d_position, c.d_position, rtol=1e-4,
                               atol=1e-4 * np.abs(c.d_position).max())
    np.testing.assert_allclose(f.d_velocity, c.d_velocity, rtol=1e-4,
                               atol=1e-4 * np.abs(c.d_velocity).max())


def test_bad_input():
    with pytest.raises(EccentricityError):
        FiniteDifferenceBearing.from_lambda(0.5).dimensionless(1.0, 0.0)
    with pytest.raises(ValueError, match="even"):
        FiniteDifferenceBearing.from_lambda(0.5, n_xi=15)
