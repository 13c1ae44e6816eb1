"""One Newmark (sub-)step of the condensed structure in one compiled call (the hot path).

:meth:`gear_fmu.structure.Structure.step` with the distributed mesh element
(:class:`gear_fmu.mesh.element.MeshElement`) spends most of its time between kernels when the pieces
are called from Python: the right-hand side and tangent
(:func:`~gear_fmu.step.assembly.prepare_step`, Eq. 12, 14, 16), the Newton/contact loop of
:func:`~gear_fmu.step.contact_loop.solve_condensed` (a mesh evaluation, the residual and a 20 x 20
solve per pass, Fig. 4) and the recovery of the eliminated DOFs with the Newmark update
(:func:`~gear_fmu.step.assembly.finish_step`, Eq. 12). :func:`advance` runs the same kernels in
the same order with the same arithmetic in one call, so it gives the Python loop's results bit
for bit (the norms use ``np.dot`` as the loop does); the loop stays the reference and serves
any other mesh object and the benchmark timers (``Structure.timing``).

The outcome is a status (0 converged, 1 not converged in ``max_iter`` passes, 2 singular
tangent) with the residual history, from which the caller raises the loop's own errors.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gear_fmu.loads import unbalance_into
from gear_fmu.mesh.element import _mesh_kernel
from gear_fmu.step.assembly import prepare_step
from gear_fmu.step.condensation import N_GEAR, NC
from gear_fmu.step.contact_loop import ROUNDOFF, _newton_solve, _residual_norm, _same_set
from gear_fmu.step.newmark import newmark_kinematics

__all__ = ["CONVERGED", "NOT_CONVERGED", "SINGULAR", "advance", "advance_pieces", "contact_event",
           "sum_squares"]

CONVERGED, NOT_CONVERGED, SINGULAR = 0, 1, 2


@njit(cache=True)
def sum_squares(f0):
    """Sum of the squares of the (4, 2) bearing forces, added in numpy's pairwise order for
    eight contiguous values (``((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))``): the value
    of ``np.sum(f0 * f0)``, bit for bit."""
    s = np.empty(8)
    for b in range(4):
        for r in range(2):
            s[2 * b + r] = f0[b, r] * f0[b, r]
    return ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]))


@njit(cache=True)
def advance(mc, g, g_const, s0, w, x, v, a, f_c, unb_coef, t1, f0, kb, cb, h,  # Eq. 12-16
            angle, err, has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2,
            cache, tangent, used0, has_used, f_scale, tol, max_iter,  # contact loop (Fig. 4)
            force, stiff, active, inside, delta, load, xis, zout, residuals,  # mesh state out
            x1, v1, a1, memo):  # state out; the history products' memo
    """One Newmark step of length ``h`` with the mesh element at pinion ``angle`` [rad]:
    Eq. (12), (14), (16) assembled, Newton-Raphson with the contact loop, Eq. (13), (15).

    Inputs as :func:`gear_fmu.step.assembly.prepare_step` (``g``, ``g_const``, ``s0``, ``w``
    from the condensation at h, ``memo`` that of its history products; the unbalance of
    Eq. (10) at the step's end ``t1`` [s] from ``unb_coef``,
    :func:`gear_fmu.loads.unbalance_into`) and
    :func:`gear_fmu.step.contact_loop.solve_condensed`
    (``used0`` / ``has_used``: the contact set the first iterate is consistent with); ``err``
    the error displacement of the gear nodes added to the mesh's input (runout, mounting) when
    ``has_err``; ``f_scale`` the largest external load [N], raised to the norm of the bearing
    forces ``f0`` when larger (the residual's scale). Writes the final mesh evaluation into
    ``force`` ... ``zout``, the residual of each pass into ``residuals`` (max_iter + 1,) and
    the new state into ``x1, v1, a1``.

    Returns ``(status, passes, total mesh load [N], contact length [m])``.
    """
    unb = np.empty(4)
    unbalance_into(unb_coef, t1, unb)
    s_lin, z0, y = prepare_step(mc, g, g_const, x, v, a, f_c, unb, f0, kb, cb, s0, h, N_GEAR,
                                 memo)
    f_scale = max(f_scale, math.sqrt(sum_squares(f0)))
    xc = x[:NC] + h * v[:NC]
    used = used0.copy()
    q = np.empty(N_GEAR)
    z_norm = -1.0
    total = 0.0
    length = 0.0
    for k in range(max_iter + 1):
        for i in range(N_GEAR):
            q[i] = xc[i] + err[i] if has_err else xc[i]
        total, length = _mesh_kernel(angle, q, geo, xi_tab, k_tab, zs, dl, n_lines, dev,
                                     pitch1, pitch2, cache, tangent, force, stiff, active,
                                     inside, delta, load, xis, zout)
        ff = np.dot(force, force)
        scale = max(f_scale, math.sqrt(ff))
        scale = scale if scale > 0.0 else 1.0
        r = _residual_norm(s_lin, z0, xc, force) / scale
        residuals[k] = r
        limit = tol
        if r > tol:  # the round-off floor at this iterate (gear_fmu.step.contact_loop)
            if z_norm < 0.0:
                z_norm = math.sqrt(np.dot(z0, z0))
            limit = max(tol, ROUNDOFF * (z_norm + math.sqrt(ff)) / scale)
        if r <= limit and has_used and _same_set(active, used):
            # X_r = y - W X_c, then Newmark velocities and accelerations (Eq. 12)
            x1[:NC] = xc
            x1[NC:] = y - w @ xc
            vv, aa = newmark_kinematics(x1, x, v, a, h)
            v1[:] = vv
            a1[:] = aa
            return CONVERGED, k, total, length
        if k == max_iter:
            break
        xc, ok = _newton_solve(s_lin, z0, xc, force, stiff)
        if not ok:
            return SINGULAR, k, total, length
        if used.shape == active.shape:
            used[:] = active
        else:
            used = active.copy()
        has_used = True
    return NOT_CONVERGED, max_iter, total, length


@njit(cache=True)
def contact_event(angle, x1, err, has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1,
                  pitch2, cache, tangent, m_gear, force_before, a1, force, stiff, active,
                  inside, delta, load, xis, zout):
    """A contact event at the end of a sub-step (:mod:`gear_fmu.structure`, contact
    location): the mesh evaluated at pinion ``angle`` [rad] (after the event) at the gear DOFs
    of ``x1`` (plus ``err`` when ``has_err``), into ``force`` ... ``zout``, and the
    acceleration ``a1`` raised by ``M^-1 (F_mesh+ - F_mesh-)`` at the same X and Xd
    (``m_gear``: M^-1 restricted to the gear-node columns, (n, 12); ``force_before``: the mesh
    force before the event, which may be ``force`` itself). Returns ``(total mesh load [N],
    contact length [m])`` after the event."""
    q = np.empty(N_GEAR)
    jump = np.empty(N_GEAR)
    for i in range(N_GEAR):
        q[i] = x1[i] + err[i] if has_err else x1[i]
        jump[i] = force_before[i]
    total, length = _mesh_kernel(angle, q, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1,
                                 pitch2, cache, tangent, force, stiff, active, inside, delta,
                                 load, xis, zout)
    for i in range(N_GEAR):
        jump[i] = force[i] - jump[i]
    for i in range(a1.shape[0]):
        acc = 0.0
        for j in range(N_GEAR):
            acc += m_gear[i, j] * jump[j]
        a1[i] = a1[i] + acc
    return total, length


@njit(cache=True)
def advance_pieces(n_pieces, mc, g, g_const, s0, w, table, event, err, err_after, x, v, a,
                   f_c, unb_coef, f0, kb, cb, has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev,
                   pitch1, pitch2, cache, tangent, used0, has_used, f_scale, tol, max_iter,
                   m_gear, force, stiff, active, inside, delta, load, xis, zout, residuals, x1,
                   v1, a1, memo):
    """A step cut at its contact events (:meth:`gear_fmu.structure.Structure.step`) in one
    call: sub-step ``p < n_pieces`` is :func:`advance` of length ``table[p, 0]`` [s] to
    ``table[p, 1]`` [s] with the mesh at pinion angle ``table[p, 2]`` [rad] (``g[p]`` ...
    ``w[p]`` its condensation, ``err[p]`` its error displacement), from the state the sub-step
    before left, then :func:`contact_event` at ``table[p, 3]`` (error displacement
    ``err_after[p]``) where ``event[p]``; the arithmetic of the Python loop over the
    sub-steps. Only the first sub-step starts from the step's state, the same at each of the
    master's iterations: it alone uses ``memo``
    (:func:`gear_fmu.step.assembly.history_products`).

    Returns ``(status, sub-step, passes, total mesh load [N], contact length [m])``: the
    status of the last :func:`advance` and which sub-step it was; the final state in ``x1,
    v1, a1`` and the final mesh evaluation in ``force`` ... ``zout``.
    """
    xs, vs, as_ = x, v, a
    used = used0
    status, k, total, length = CONVERGED, 0, 0.0, 0.0
    for p in range(n_pieces):
        memo_p = memo if p == 0 else memo[:0]
        status, k, total, length = advance(
            mc, g[p], g_const[p], s0[p], w[p], xs, vs, as_, f_c, unb_coef, table[p, 1], f0, kb,
            cb, table[p, 0], table[p, 2], err[p], has_err, geo, xi_tab, k_tab, zs, dl,
            n_lines, dev, pitch1, pitch2, cache, tangent, used, has_used, f_scale, tol,
            max_iter, force, stiff, active, inside, delta, load, xis, zout, residuals, x1, v1,
            a1, memo_p)
        if status != CONVERGED:
            return status, p, k, total, length
        if event[p]:
            total, length = contact_event(
                table[p, 3], x1, err_after[p], has_err, geo, xi_tab, k_tab, zs, dl, n_lines,
                dev, pitch1, pitch2, cache, tangent, m_gear, force, a1, force, stiff, active,
                inside, delta, load, xis, zout)
        if p + 1 < n_pieces:
            xs, vs, as_ = x1.copy(), v1.copy(), a1.copy()
            used = active.copy()
            has_used = True
    return status, n_pieces - 1, k, total, length
