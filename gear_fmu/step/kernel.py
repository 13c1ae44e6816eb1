"""One Newmark step of the condensed structure in one compiled call (the hot path).

:func:`advance` is one Newmark (sub-)step: the right-hand side and tangent
(:func:`~gear_fmu.step.assembly.prepare_step`, Eq. 12, 14, 16), the Newton/contact loop over
the train's meshes (:func:`~gear_fmu.step.contact_loop.contact_newton`, Fig. 4) and the
recovery of the eliminated DOFs with the Newmark update (Eq. 12). :func:`advance_pieces` is a
step cut at its contact events (:mod:`gear_fmu.step.events`): its sub-steps, each followed by
the acceleration jump of the meshes whose contact lines entered or left the path of contact
there (:func:`contact_events`). Every structural step, in-process or inside the gear-shaft
FMU, alone or inside the master's compiled coupled steps, is this call.

The outcome is a status (:data:`~gear_fmu.step.contact_loop.CONVERGED`, ``NOT_CONVERGED``
after ``max_iter`` passes, ``SINGULAR`` tangent) with the residual history, from which the
caller raises its errors.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.affine import pairwise_sum
from bearing_fmu.borrowed import borrowed
from gear_fmu.loads import unbalance_into
from gear_fmu.mesh.element import _mesh_kernel
from gear_fmu.step.assembly import matvec_t, prepare_step
from gear_fmu.step.contact_loop import (
    _ACTIVE,
    _DELTA,
    _IDX,
    _INSIDE,
    _LOAD,
    _OUT,
    _STIFF,
    _XI,
    _Z,
    CONVERGED,
    contact_newton,
    use_sets,
)
from gear_fmu.step.newmark import newmark_kinematics

__all__ = ["advance", "advance_pieces", "advance_step", "contact_events", "keep_evaluation",
           "sum_squares"]


@njit(cache=True)
def sum_squares(f0):
    """Sum of the squares of the bearing forces (nb, 2), added in numpy's pairwise order
    (:func:`bearing_fmu.affine.pairwise_sum`)."""
    nb = f0.shape[0]
    s = np.empty(2 * nb)
    for b in range(nb):
        for r in range(2):
            s[2 * b + r] = f0[b, r] * f0[b, r]
    return pairwise_sum(s)


@njit(cache=True)
def advance(mc, g_t, g_const, s0, w_t, x, v, a, f_c, unb_coef, unb_idx, t1, f0, kb, cb,
            h, angles, errs, has_err, meshes, fc, kc, totals, lengths, has_used, f_scale, tol,
            max_iter, residuals, x1, v1, a1, memo):
    """One Newmark step of length ``h`` [s] to ``t1`` [s], the meshes at their pinion angles
    ``angles`` [rad]: Eq. (12), (14), (16) assembled, Newton-Raphson with the contact loop,
    Eq. (13), (15).

    Inputs as :func:`gear_fmu.step.assembly.prepare_step` (``g_t``, ``g_const``, ``s0``,
    ``w_t`` from the condensation at h, :class:`gear_fmu.step.condensation.Condensation`,
    ``memo`` that of its history products; the unbalances of Eq. (10) at ``t1`` from
    ``unb_coef``, :func:`gear_fmu.loads.unbalance_into`, on the condensed DOFs ``unb_idx``)
    and :func:`gear_fmu.step.contact_loop.contact_newton`
    (``errs`` (n_meshes, 12) the error displacements when ``has_err``; ``f_scale`` the largest
    external load [N], raised to the norm of the bearing forces ``f0`` when larger). Writes
    the residual of each pass into ``residuals`` and the new state into ``x1, v1, a1``.

    Returns ``(status, passes)``.
    """
    unb = np.empty((unb_coef.shape[0], 2))
    unbalance_into(unb_coef, t1, unb)
    ng = fc.size
    s_lin, z0, y = prepare_step(mc, g_t, g_const, x, v, a, f_c, unb, unb_idx, f0, kb, cb, s0, h,
                                 ng, memo)
    f_scale = max(f_scale, math.sqrt(sum_squares(f0)))
    nc = s0.shape[0]
    xc = x[:nc] + h * v[:nc]
    status, k, xc = contact_newton(s_lin, z0, xc, angles, errs, has_err, meshes, fc, kc, totals,
                                   lengths, has_used, f_scale, tol, max_iter, residuals)
    if status == CONVERGED:
        # X_r = y - W X_c, then Newmark velocities and accelerations (Eq. 12)
        x1[:nc] = xc
        x1[nc:] = y - matvec_t(w_t, xc)
        vv, aa = newmark_kinematics(x1, x, v, a, h)
        v1[:] = vv
        a1[:] = aa
    return status, k


@njit(cache=True, _nrt=False)
def _jump(after, errs_after, has_err, meshes, x1, jump, q, totals, lengths):
    """:func:`contact_events`' meshes evaluated after their events, ``jump`` (ng,) receiving
    ``F_mesh+ - F_mesh-``; whether any mesh had an event (no reference counting:
    :func:`gear_fmu.step.contact_loop.evaluate_train`)."""
    jumped = False
    for m in range(len(meshes)):
        if not after[m] == after[m]:
            continue
        wk = meshes[m]
        idx, force = wk[_IDX], wk[_OUT]
        for i in range(12):
            jump[idx[i]] -= force[i]
            q[i] = x1[idx[i]] + errs_after[m, i] if has_err else x1[idx[i]]
        totals[m], lengths[m] = _mesh_kernel(
            after[m], q, wk[0], wk[1], wk[2], wk[3], wk[4], wk[5], wk[6], wk[7], wk[8], wk[9],
            wk[10], wk[11], wk[_OUT], wk[_STIFF], wk[_ACTIVE], wk[_INSIDE], wk[_DELTA],
            wk[_LOAD], wk[_XI], wk[_Z])
        for i in range(12):
            jump[idx[i]] += force[i]
        jumped = True
    return jumped


@njit(cache=True)
def contact_events(after, errs_after, has_err, meshes, x1, m_inv_g, a1, totals, lengths):
    """Contact events at the end of a sub-step (:mod:`gear_fmu.structure`, contact location):
    each mesh m whose ``after[m]`` is a number (not NaN) is evaluated again at that pinion
    angle [rad] after its events, at the gear DOFs of ``x1`` (plus ``errs_after[m]`` when
    ``has_err``), and the acceleration ``a1`` is raised by ``M^-1 (F_mesh+ - F_mesh-)`` at the
    same X and Xd (``m_inv_g``: M^-1 restricted to the condensed gear-node columns, (n, ng));
    ``totals[m]``, ``lengths[m]`` become the mesh's after the events."""
    ng = m_inv_g.shape[1]
    jump = np.zeros(ng)
    jumped = _jump(after, errs_after, has_err, meshes, x1, jump, np.empty(12), totals, lengths)
    if jumped:
        for i in range(a1.shape[0]):
            acc = 0.0
            for j in range(ng):
                acc += m_inv_g[i, j] * jump[j]
            a1[i] = a1[i] + acc


@njit(cache=True, _nrt=False)
def _copy(dst, src):
    for i in range(src.size):
        dst.flat[i] = src.flat[i]


@njit(cache=True, _nrt=False)
def keep_evaluation(meshes):
    """Each mesh's last evaluation becomes the one its state ended on (the ``kept``
    buffers of :class:`gear_fmu.step.contact_loop.MeshWork`)."""
    for m in range(len(meshes)):
        wk = meshes[m]
        # (literal indices: a compiled tuple is indexed by constants only; _KEPT ... _KEPT + 7)
        _copy(wk[23], wk[_OUT])
        _copy(wk[24], wk[_STIFF])
        _copy(wk[25], wk[_ACTIVE])
        _copy(wk[26], wk[_INSIDE])
        _copy(wk[27], wk[_DELTA])
        _copy(wk[28], wk[_LOAD])
        _copy(wk[29], wk[_XI])
        _copy(wk[30], wk[_Z])


@njit(cache=True)
def advance_pieces(n_pieces, slots, mc, g_k, g_const_k, s0_k, w_k, table, angles, after, errs,
                   errs_after, x, v, a, f_c, unb_coef, unb_idx, f0, kb, cb, has_err, meshes,
                   fc, kc, totals, lengths, f_scale, tol, max_iter, m_inv_g, residuals, x1,
                   v1, a1, memo):
    """A step cut at its contact events in one call (Eq. 11-16, the Newton iteration of
    Eq. 13 in each sub-step): sub-step ``p < n_pieces`` is
    :func:`advance` of length ``table[p, 0]`` [s] to ``table[p, 1]`` [s] with the
    condensation of slot ``slots[p]`` of ``g_k`` ... ``w_k``
    (:class:`gear_fmu.step.condensation.CondensationSlots`), the meshes at ``angles[p]``
    (their error displacements ``errs[p]``), from the state the sub-step before left, then
    :func:`contact_events` with ``after[p]`` (``errs_after[p]``). The first sub-step starts
    from ``x, v, a`` and each mesh from the contact set of its ``kept`` evaluation (the
    state's), the same at each of the master's iterations: it alone uses ``memo``
    (:func:`gear_fmu.step.assembly.history_products`).

    Returns ``(status, sub-step, passes)``: the status of the last :func:`advance` and which
    sub-step it was; the final state in ``x1, v1, a1``, the meshes' final evaluations in their
    ``out`` buffers and ``totals``, ``lengths``.
    """
    use_sets(meshes, np.bool_(True))  # (a plain bool, not a literal: use_sets compiled once)
    xs, vs, as_ = x, v, a
    status, k = CONVERGED, 0
    # a boolean, not the literal True, so that contact_newton is compiled once for this and
    # the static solution (numba compiles a callee again for each literal argument)
    has_used = np.bool_(True)
    for p in range(n_pieces):
        memo_p = memo if p == 0 else memo[:0]
        s = slots[p]
        status, k = advance(mc, g_k[s], g_const_k[s], s0_k[s], w_k[s], xs, vs, as_, f_c,
                            unb_coef, unb_idx, table[p, 1], f0, kb, cb, table[p, 0], angles[p],
                            errs[p], has_err, meshes, fc, kc, totals, lengths, has_used, f_scale,
                            tol, max_iter, residuals, x1, v1, a1, memo_p)
        if status != CONVERGED:
            return status, p, k
        contact_events(after[p], errs_after[p], has_err, meshes, x1, m_inv_g, a1, totals,
                       lengths)
        if p + 1 < n_pieces:
            xs, vs, as_ = x1.copy(), v1.copy(), a1.copy()
            use_sets(meshes, np.bool_(False))
    return status, n_pieces - 1, k


@njit(cache=True)
def advance_step(n_pieces, held, x, v, a, f_c, unb_coef, f0, kb, cb, has_err, f_scale, tol,
                 max_iter, x1, v1, a1):
    """:func:`advance_pieces` for a step taken alone (not iterated by a master), called from
    Python at each of the gear-shaft FMU's steps: the arrays that may change from step to
    step are arguments (the state, the laws, and the loads and unbalances, which follow a
    speed profile), the others ``held.arrays`` (:func:`bearing_fmu.borrowed.held`, one object
    to unbox instead of about 50 arrays): ``(slots, table, angles, after, errs, errs_after,
    mc, g_k, g_const_k, s0_k, w_k, unb_idx, meshes, fc, kc, totals, lengths, residuals,
    m_inv_g, memo, kept_totals, kept_lengths)``. On success the meshes'
    evaluations are kept (:func:`keep_evaluation`) with their total loads and contact
    lengths in ``kept_totals``, ``kept_lengths``, in the same call. Returns as
    :func:`advance_pieces`."""
    # the caller (Python) keeps the arrays alive: no reference counts in the layers below
    (slots, table, angles, after, errs, errs_after, mc, g_k, g_const_k, s0_k, w_k, unb_idx,
     meshes, fc, kc, totals, lengths, residuals, m_inv_g, memo, kept_totals,
     kept_lengths) = borrowed(held.arrays)
    status, piece, k = advance_pieces(*borrowed((
        n_pieces, slots, mc, g_k, g_const_k, s0_k, w_k, table, angles, after, errs,
        errs_after, x, v, a, f_c, unb_coef, unb_idx, f0, kb, cb, has_err, meshes, fc, kc,
        totals, lengths, f_scale, tol, max_iter, m_inv_g, residuals, x1, v1, a1, memo)))
    if status == CONVERGED:
        keep_evaluation(meshes)
        kept_totals[:] = totals
        kept_lengths[:] = lengths
    return status, piece, k
