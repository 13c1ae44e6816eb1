"""Newmark (gamma 1/2, beta 1/4) + Newton-Raphson + contact loop (Eq. 11-16)."""

import math

import numpy as np
import pytest
import scipy.linalg

from gear_fmu.newmark import (
    NewmarkConvergenceError,
    NonlinearForce,
    newmark_kinematics,
    newmark_step,
)

M = np.diag([2.0, 1.0])
K = np.array([[3.0e4, -1.0e4], [-1.0e4, 1.0e4]])
C = 1e-3 * K + 0.5 * M  # Rayleigh damping


def exact_free(x0, v0, t, c):
    """x(t) of M x'' + c x' + K x = 0 from the matrix exponential of the first-order system."""
    minv = np.linalg.inv(M)
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ K, -minv @ c]])
    return (scipy.linalg.expm(a * t) @ np.concatenate([x0, v0]))[:2]


def run_linear(c, dt, n_steps, x0, v0):
    x, v = x0.copy(), v0.copy()
    a = np.linalg.solve(M, -c @ v - K @ x)
    traj = []
    for i in range(n_steps):
        x, v, a, info = newmark_step(M, c, K, dt, (i + 1) * dt, x, v, a, tol=1e-10)
        assert info.iterations <= 1  # linear: one Newton solve
        traj.append(x)
    return np.array(traj)


def test_second_order_convergence_in_dt_against_exact_solution():
    """Max error over [0, 0.2 s] (about 3 periods of the slow mode) at the coarse-grid times."""
    x0, v0 = np.array([1e-3, -2e-3]), np.array([0.0, 0.1])
    t_end = 0.2
    n0 = 50
    ref = np.array([exact_free(x0, v0, t_end * (i + 1) / n0, C) for i in range(n0)])
    errs = []
    for refine in (1, 2, 4, 8):
        traj = run_linear(C, t_end / (n0 * refine), n0 * refine, x0, v0)[refine - 1 :: refine]
        errs.append(np.abs(traj - ref).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    print(f"\nNewmark observed orders in dt: {orders}")
    assert np.all(np.abs(orders - 2.0) < 0.1)


def test_energy_is_conserved_without_damping():
    x, v = np.array([1e-3, -2e-3]), np.array([0.0, 0.1])
    a = np.linalg.solve(M, -K @ x)
    energy0 = 0.5 * v @ M @ v + 0.5 * x @ K @ x
    dt = 2e-3  # ~ 1/9 of the shortest period: energy is conserved at any dt (trapezoidal rule)
    for i in range(2000):
        x, v, a, _ = newmark_step(M, np.zeros((2, 2)), K, dt, (i + 1) * dt, x, v, a, tol=1e-10)
    energy = 0.5 * v @ M @ v + 0.5 * x @ K @ x
    assert energy == pytest.approx(energy0, rel=1e-10)


def test_forced_response_matches_steady_state_harmonic_solution():
    """Harmonic force from rest: compare after the transient has decayed (damped system)."""
    f_amp = np.array([1.0, 0.5])
    w = 90.0
    c = 5.0 * C

    def force(t):
        return f_amp * math.cos(w * t)

    # steady state x = Re(X e^{iwt}), (K - w^2 M + i w C) X = F
    xh = np.linalg.solve(K - w**2 * M + 1j * w * c, f_amp)
    dt = 2 * math.pi / w / 400
    x, v = np.zeros(2), np.zeros(2)
    a = np.linalg.solve(M, force(0.0))
    n = 4000
    for i in range(n):
        x, v, a, _ = newmark_step(M, c, K, dt, (i + 1) * dt, x, v, a, force=force, tol=1e-10)
    ref = np.real(xh * np.exp(1j * w * n * dt))
    assert np.linalg.norm(x - ref) < 2e-3 * np.linalg.norm(xh)


def duffing(k3):
    """Hardening cubic springs to ground on both DOFs: F = -k3 x^3."""
    def nl(x, v):
        return NonlinearForce(-k3 * x**3, np.diag(-3 * k3 * x**2), None, None)
    return nl


def test_newton_converges_quadratically_on_cubic_springs():
    dt = 1e-3
    x0, v0 = np.array([0.02, -0.03]), np.array([1.0, -2.0])
    a0 = np.linalg.solve(M, -K @ x0 - 1e8 * -(x0**3))
    x, _, _, info = newmark_step(M, C, K, dt, dt, x0, v0, a0, nonlinear=duffing(1e8),
                                 tol=1e-14, max_iter=30)
    r = np.array(info.residuals)
    print(f"\nNewton relative residuals (cubic springs): {', '.join(f'{e:.2e}' for e in r)}")
    assert r[-1] <= 1e-14
    # convergence order log(r_{k+1}/r_k) / log(r_k/r_{k-1}), where r_{k+1} is above round-off
    orders = [math.log(r[k + 1] / r[k]) / math.log(r[k] / r[k - 1])
              for k in range(1, len(r) - 1) if r[k + 1] > 1e-13]
    print(f"Newton convergence orders: {orders}")
    assert len(orders) >= 1
    assert min(orders) >= 1.8
    # and the converged step satisfies Eq. (11) with the Newmark kinematics of Eq. (12)
    vv, aa = newmark_kinematics(x, x0, v0, a0, dt)
    g = M @ aa + C @ vv + K @ x + 1e8 * x**3
    assert np.linalg.norm(g) <= 1e-10 * np.linalg.norm(K @ x)


def unilateral(k_c, gap):
    """Contact springs to ground: F_i = -k_c (x_i - gap_i) where x_i > gap_i (closed)."""
    def nl(x, v):
        act = x > gap
        f = np.where(act, -k_c * (x - gap), 0.0)
        return NonlinearForce(f, np.diag(np.where(act, -k_c, 0.0)), None, act)
    return nl


def test_contact_loop_finds_a_consistent_active_set():
    """A force pushes DOF 1 into a stiff stop; the converged set must match the solution."""
    gap = np.array([5e-4, 1e-2])
    k_c = 1e7

    def force(t):
        return np.array([200.0, 0.0])

    dt = 1e-3
    x, v = np.zeros(2), np.zeros(2)
    a = np.linalg.solve(M, force(0.0))
    act = np.zeros(2, dtype=bool)
    contact_steps = 0
    for i in range(400):
        x, v, a, info = newmark_step(M, 20 * C, K, dt, (i + 1) * dt, x, v, a, force=force,
                                     nonlinear=unilateral(k_c, gap), active0=act, tol=1e-10)
        act = info.active
        np.testing.assert_array_equal(act, x > gap)
        contact_steps += bool(act[0])
    assert contact_steps > 0
    # static limit: stiff stop carries the force beyond the gap
    ks = K.copy()
    ks[0, 0] += k_c
    xs = np.linalg.solve(ks, force(0.0) + np.array([k_c * gap[0], 0.0]))
    np.testing.assert_allclose(x, xs, rtol=1e-3)


def test_non_convergence_names_step_time_and_residual():
    x0, v0 = np.array([0.02, -0.03]), np.array([1.0, -2.0])
    with pytest.raises(NewmarkConvergenceError, match=r"step 7, t = 0\.007 s.*residual"):
        newmark_step(M, C, K, 1e-3, 7e-3, x0, v0, np.zeros(2), nonlinear=duffing(1e10),
                     tol=1e-14, max_iter=2, step_index=7)
    with pytest.raises(ValueError, match="dt"):
        newmark_step(M, C, K, -1.0, 0.0, x0, v0, np.zeros(2))
