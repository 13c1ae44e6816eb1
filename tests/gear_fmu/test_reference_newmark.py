"""The tests' generic Newmark step (:mod:`tests.gear_fmu.reference_newmark`) is a sound
reference where the structure's tests use it: its Newton converges quadratically on a nonlinear
force (cubic springs: the master emulation's bearings) to a step that satisfies Eq. (11), and
its contact loop ends on the contact set of its solution (the partial mesh contact). The
structure's own step is tested against exact solutions in ``test_newmark.py``."""

import math

import numpy as np

from gear_fmu.step.newmark import newmark_kinematics
from tests.gear_fmu.reference_newmark import NonlinearForce, newmark_step

M = np.diag([2.0, 1.0])
K = np.array([[3.0e4, -1.0e4], [-1.0e4, 1.0e4]])
C = 1e-3 * K + 0.5 * M  # Rayleigh damping


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
