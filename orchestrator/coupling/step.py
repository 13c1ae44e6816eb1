"""The coupled step of the master, defined once: Newton on the structure-bearing system
(docs/design.md section 4, paper Fig. 4), compiled, for every transport.

Each step of :func:`coupled_steps`, from the state and the affine laws of Eq. (17) the step
before accepted:

1. the structure takes a Newmark step with the laws (its state before the step kept: nothing
   to save in-process, where every iteration starts from the same (X, Xd, Xdd) and writes
   into buffers; fmi2GetFMUstate through the gear-shaft FMU);
2. every bearing is evaluated at its new journal state (:func:`evaluate_set`: groups of
   bearings, each of one kind, whatever their mix of models);
3. if the film forces differ from the laws by more than ``tol`` (relative to the force norm,
   ``bearing_fmu.affine._relinearise``), the laws are linearised at the new iterate (or,
   once the iteration stalls, relaxed: :func:`relaxed_law`), the structure's state restored
   and the step taken again; else the step is accepted.

The structure's own Newton/contact loop converges the rest of the system exactly for each law
and the law is the exact linearisation of the bearings at the current iterate (Eq. 14, 16),
so this is Newton-Raphson on the bearing nonlinearity: a converged co-simulated step is the
monolithic step to ``tol``, and an affine bearing (linear, lumped) converges in one pass.

A bearing force can be continuous with a slope that jumps: the hybrid model's is where a node
of its film enters or leaves the pressurised zone. Near such a kink Newton can fall into a
two-cycle between iterates on either side (the paper's case at 300, 400, 800 and 900 rad/s:
the mismatch alternating between two values above ``tol`` until the step fails). When the
mismatch has not halved over two iterations, the rest of the step is relaxed: each new law is
the mean of the linearisation at the new iterate and the law just used
(:data:`RELAXATION`). The acceptance test is unchanged (the law used against the bearings at
the new iterate), so a relaxed step is still the monolithic step to ``tol``.

What a transport changes is where the structure and the bearings are, not the iteration: the
structure's arguments (``structure``) are the in-process structure's planned steps
(:meth:`gear_fmu.structure.Structure.steps_plan`) or the gear-shaft FMU's functions and value
references (:mod:`orchestrator.coupling.fmi.steps`), each with its own compiled operations
(:func:`structure_solve`, ...); the bearings' (``bearings``) are groups of in-process models
(hybrid sets, short sets, affine laws), of bearing FMUs called through their functions, or of
Python evaluations (a model or FMU without a compiled form: finite differences, a force-only
FMU), called back through numba's object mode. The transmission FMU runs the in-process
transport. :class:`CoupledSteps` prepares a block of steps, calls :func:`coupled_steps` and
turns its outcome into the master's counters, laws and errors.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numba import literal_unroll, njit, objmode
from numba.extending import overload

from bearing_fmu.affine import AffineLaws, _relinearise, affine_set_arguments, affine_set_global
from bearing_fmu.borrowed import borrowed
from bearing_fmu.hybrid._kernels import hybrid_set_global, hybrid_set_threads
from bearing_fmu.short_bearing import short_set_global
from fmu_src.lifecycle import step_output_row
from gear_fmu.step.contact_loop import CONVERGED
from gear_fmu.step.kernel import advance_pieces, keep_evaluation
from orchestrator.coupling.fmi.steps import (
    fmu_bearing_group,
    fmu_structure_accept,
    fmu_structure_begin,
    fmu_structure_end,
    fmu_structure_retry,
    fmu_structure_solve,
)
from orchestrator.coupling.master import (
    NotConvergedError,
    not_converged,
    python_evaluate,
    python_structure_call,
)

__all__ = ["RELAXATION", "STALL", "CoupledSteps", "StepBlock", "bearing_slots", "compile_step",
           "coupled_steps", "evaluate_set", "relaxed_law"]

#: weight of the new linearisation in a relaxed iteration (module docstring): the law used next
#: is ``RELAXATION * new + (1 - RELAXATION) * last used``
RELAXATION = 0.5
#: a step is relaxed from the iteration whose mismatch exceeds STALL times the one two
#: iterations earlier (Newton's mismatch falls quadratically; a two-cycle's repeats)
STALL = 0.5
#: the outcomes of a step of :func:`coupled_steps`
ACCEPTED, STRUCTURE_FAILED, BEARING_FAILED, NOT_CONVERGED = 0, 1, 2, 3
#: the lengths of the tuples that tell the kinds apart in compiled code: a structure's
#: arguments in-process
#: (:meth:`~orchestrator.coupling.inprocess.InProcessStructure.compiled_block`) and through
#: the gear-shaft FMU; a bearing group's arguments: hybrid, hybrid on threads, short, affine,
#: FMUs, Python
IN_PROCESS, THROUGH_FMU, PYTHON_STRUCTURE = 5, 10, 1
HYBRID, THREADED, SHORT, AFFINE, FMUS, PYTHON = 11, 12, 7, 4, 5, 1


@njit(cache=True)
def relaxed_law(it, mismatch, mismatches, relaxed, stall, relaxation, f0_new, kb_new, cb_new,
                f0, kb, cb):
    """The rule after iteration ``it`` (1-based) of a step: its ``mismatch`` goes into
    ``mismatches[it - 1]``; the step is relaxed from the iteration whose mismatch exceeds
    ``stall`` times the one two iterations earlier (or stays so); the next law is the new
    linearisation ``f0_new, kb_new, cb_new``, or once relaxed the blend
    ``relaxation * new + (1 - relaxation) * used`` (:meth:`bearing_fmu.affine.AffineLaws.blend`)
    with the law used ``f0, kb, cb``. Returns ``(relaxed, f0, kb, cb)``."""
    mismatches[it - 1] = mismatch
    if not relaxed and it >= 3 and mismatch > stall * mismatches[it - 3]:
        relaxed = True
    if not relaxed:
        return relaxed, f0_new, kb_new, cb_new
    r = 1.0 - relaxation
    return (relaxed, relaxation * f0_new + r * f0, relaxation * kb_new + r * kb,
            relaxation * cb_new + r * cb)


# --- the structure's operations, one implementation per transport ---------------------------
# Inlined into coupled_steps (numba's IR), with the in-process solve and accept and the bearing
# set's slots and groups: a compiled call receives every array of a tuple by value (about ten
# words each, ~90 arrays for the structure), which cost more than these thin layers do. A
# bearing group's kernel is not inlined: a Python group's objmode block cannot be.
def structure_begin(structure, i):
    """Before step i: keep the structure's state (returns 0, or a failure code)."""
    raise NotImplementedError("compiled code only")


def structure_solve(structure, i, f0, kb, cb, x0, force0, expanded, states):
    """Step i with the laws (``f0, kb, cb``; their expansion ``x0, force0`` when
    ``expanded``), the journal states into ``states`` (nb, 4). Returns ``(code, d1, d2,
    d3)``: code 0, or a failure code of the transport and three details of it (in-process:
    the step kernel's status, the sub-step and its passes)."""
    raise NotImplementedError("compiled code only")


def structure_retry(structure, i):
    """Restore the state kept by :func:`structure_begin` (returns 0 or a failure code)."""
    raise NotImplementedError("compiled code only")


def structure_accept(structure, i, row):
    """Take the step just solved; its outputs (mesh forces, transmission errors, gear nodes'
    u, v) into ``row``. Returns 0 or a failure code."""
    raise NotImplementedError("compiled code only")


def structure_end(structure):
    """After a step, accepted or not: release what :func:`structure_begin` kept."""
    raise NotImplementedError("compiled code only")


@njit(cache=True, inline="always")
def _in_process_solve(structure, i, f0, kb, cb, states):
    head, state, tail, work, _ = structure
    counts, slots, mc, g_k, gc_k, s0_k, w_k, table, angles, after, errs, errs_after = head
    x, v, a = state
    unb_coef, unb_idx, f_c, has_err, meshes, f_scale, tol, max_iter, m_inv_g, memo = tail
    fc, kc, totals, lengths, residuals, x1, v1, a1 = work
    row = i if has_err else 0
    status, piece, k = advance_pieces(
        counts[i], slots[i], mc, g_k, gc_k, s0_k, w_k, table[i], angles[i], after[i],
        errs[row], errs_after[row], x, v, a, f_c, unb_coef, unb_idx, f0, kb, cb, has_err,
        meshes, fc, kc, totals, lengths, f_scale, tol, max_iter, m_inv_g, residuals, x1, v1,
        a1, memo)
    if status != CONVERGED:
        return 1, status, piece, k
    ng = fc.size
    for b in range(states.shape[0]):  # Structure.journal_states
        for c in range(2):
            states[b, c] = x1[ng + 2 * b + c]
            states[b, 2 + c] = v1[ng + 2 * b + c]
    return 0, 0, 0, 0


@njit(cache=True, inline="always")
def _in_process_accept(structure, row):
    _, state, tail, work, rec = structure
    x, v, a = state
    meshes = tail[4]
    totals, lengths, x1, v1, a1 = work[2], work[3], work[5], work[6], work[7]
    gear_uv, kept_totals, kept_lengths, te_idx, te_coef = rec
    x[:] = x1
    v[:] = v1
    a[:] = a1
    keep_evaluation(meshes)
    for m in range(totals.size):
        kept_totals[m] = totals[m]
        kept_lengths[m] = lengths[m]
    step_output_row(te_idx, te_coef, gear_uv, totals, x1, row)
    return 0


@njit(cache=True)
def _python_structure(structure, op, i, f0, kb, cb, x0, force0, expanded, out):
    """A structure operation called back in Python (:class:`orchestrator.coupling.master
    .PythonStructure`)."""
    key = structure[0][0]
    with objmode(code="int64"):
        code = python_structure_call(key, op, i, f0, kb, cb, x0, force0, expanded, out)
    return code


@njit(cache=True)
def _python_operation(structure, op, i, out):
    """:func:`_python_structure` for an operation that takes no laws (begin, retry, accept,
    end): placeholder laws; ``out`` accept's row (a placeholder for the others)."""
    z2, z22 = np.zeros((1, 2)), np.zeros((1, 2, 2))
    return _python_structure(structure, op, i, z2, z22, z22, np.zeros((1, 4)), z2, np.bool_(False),
                             out)


@overload(structure_begin, inline="always")
def _begin(structure, i):
    if len(structure) == PYTHON_STRUCTURE:
        def python(structure, i):
            return _python_operation(structure, np.int64(0), i, np.zeros((1, 4)))
        return python
    if len(structure) == IN_PROCESS:
        return lambda structure, i: 0
    if len(structure) == THROUGH_FMU:
        return lambda structure, i: fmu_structure_begin(structure)
    return None


@overload(structure_solve, inline="always")
def _solve(structure, i, f0, kb, cb, x0, force0, expanded, states):
    if len(structure) == PYTHON_STRUCTURE:
        def python(structure, i, f0, kb, cb, x0, force0, expanded, states):
            code = _python_structure(structure, np.int64(1), i, f0, kb, cb, x0, force0, expanded,
                                     states)
            return code, 0, 0, 0
        return python
    if len(structure) == IN_PROCESS:
        def in_process(structure, i, f0, kb, cb, x0, force0, expanded, states):
            return _in_process_solve(structure, i, f0, kb, cb, states)
        return in_process
    if len(structure) == THROUGH_FMU:
        def fmu(structure, i, f0, kb, cb, x0, force0, expanded, states):
            return fmu_structure_solve(structure, i, f0, kb, cb, x0, force0, expanded, states)
        return fmu
    return None


@overload(structure_retry, inline="always")
def _retry(structure, i):
    if len(structure) == PYTHON_STRUCTURE:
        def python(structure, i):
            return _python_operation(structure, np.int64(2), i, np.zeros((1, 4)))
        return python
    if len(structure) == IN_PROCESS:
        return lambda structure, i: 0
    if len(structure) == THROUGH_FMU:
        return lambda structure, i: fmu_structure_retry(structure)
    return None


@overload(structure_accept, inline="always")
def _accept(structure, i, row):
    if len(structure) == PYTHON_STRUCTURE:
        def python(structure, i, row):
            return _python_operation(structure, np.int64(3), i, row)
        return python
    if len(structure) == IN_PROCESS:
        return lambda structure, i, row: _in_process_accept(structure, row)
    if len(structure) == THROUGH_FMU:
        return lambda structure, i, row: fmu_structure_accept(structure, row)
    return None


@overload(structure_end, inline="always")
def _end(structure):
    if len(structure) == PYTHON_STRUCTURE:
        def python(structure):
            _python_operation(structure, np.int64(4), np.int64(0), np.zeros((1, 4)))
        return python
    if len(structure) == IN_PROCESS:
        return lambda structure: None
    if len(structure) == THROUGH_FMU:
        return lambda structure: fmu_structure_end(structure)
    return None


# --- the bearings: groups of one kind each --------------------------------------------------
def evaluate_group(args, states, out):
    """One group's kernel on its states (k, 4) into its rows (k, 5, 2): ``(failed bearing of
    the group or -1, its status)``; chosen by the length of ``args`` when
    :func:`coupled_steps` compiles, so each kind has its own compiled (and cached) code."""
    raise NotImplementedError("compiled code only")


@overload(evaluate_group)
def _evaluate_group(args, states, out):
    n = len(args)
    if n == HYBRID:
        def hybrid(args, states, out):
            b = args
            return hybrid_set_global(b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8],
                                     b[9], b[10], states, out)
        return hybrid
    if n == THREADED:
        def threaded(args, states, out):
            b = args
            return hybrid_set_threads(b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8],
                                      b[9], b[10], b[11], states, out)
        return threaded
    if n == SHORT:
        def short(args, states, out):
            b = args
            return short_set_global(b[0], b[1], b[2], b[3], b[4], b[5], b[6], states, out)
        return short
    if n == AFFINE:
        def affine(args, states, out):
            b = args
            return affine_set_global(b[0], b[1], b[2], b[3], states, out)
        return affine
    if n == FMUS:
        def fmus(args, states, out):
            return fmu_bearing_group(args, states, out)
        return fmus
    if n == PYTHON:
        def python(args, states, out):
            key = args[0]
            with objmode(bad="int64"):
                bad = python_evaluate(key, states, out)
            return bad, 1
        return python
    return None


@njit(cache=True, inline="always")
def _group(args, index, states, out):
    """A group's kernel on the rows ``index`` of the set's ``states`` and ``out`` (nothing for
    an empty ``index``: :func:`bearing_slots`' placeholder); the failed bearing as the set's
    index."""
    k = index.size
    if k == 0:
        return np.int64(-1), np.int64(0)
    whole = k == states.shape[0]  # every bearing, in order: no copies
    for g in range(k):
        whole = whole and index[g] == g
    if whole:
        bad, status = evaluate_group(args, states, out)
        return np.int64(bad), np.int64(status)
    sub_states = np.empty((k, 4))
    sub_out = np.empty((k, 5, 2))
    for g in range(k):
        sub_states[g] = states[index[g]]
    bad, status = evaluate_group(args, sub_states, sub_out)
    for g in range(k):
        out[index[g]] = sub_out[g]
    return (np.int64(index[bad]) if bad >= 0 else np.int64(-1)), np.int64(status)


@njit(cache=True, inline="always")
def _evaluate_slot(slot, states, out, failed, why):
    """The groups of one kind (a tuple of groups of one type), into ``out``; returns the
    failed bearing of lowest index so far (``failed``, -1 for none) and its status."""
    for group in slot:
        bad, status = _group(group[0], group[1], states, out)
        if bad >= 0 and (failed < 0 or bad < failed):
            failed, why = bad, status
    return failed, why


@njit(cache=True)
def evaluate_set(slots, states, out):
    """Every bearing at its journal state ``states`` (nb, 4) [m, m/s] into ``out`` (nb, 5, 2)
    (force [N], Kb [N/m], Cb [N s/m], global frame), kind by kind: ``slots`` from
    :func:`bearing_slots`. Returns ``(failed bearing or -1, its status)``: of the bearings
    that failed, the one of lowest index (each group stops at its first failure)."""
    failed, why = np.int64(-1), np.int64(0)
    for slot in literal_unroll(slots):
        failed, why = _evaluate_slot(slot, states, out, failed, why)
    return failed, why


#: the kinds of group in the order of :func:`bearing_slots`; a group on threads
#: (``THREADED``) gets a slot only when there is one: its kernel loads numba's threading
#: layer, which no other run (nor an FMU's host) should carry
SLOT_KINDS = (HYBRID, SHORT, AFFINE, FMUS, PYTHON)


@functools.cache
def _placeholders() -> dict:
    """A group of each kind of :data:`SLOT_KINDS` with no bearing: arguments of the types the
    real groups have (the hybrid and short ones from a set of one bearing), an empty index."""
    from bearing_fmu import BearingData
    from bearing_fmu.hybrid.model import HybridBearing, HybridSet
    from bearing_fmu.short_bearing import ShortBearing, ShortSet
    from orchestrator.coupling.fmi.bearings import group_arguments

    b, q, none = BearingData(0.07, 0.05, 150e-6, 0.0288), np.eye(2)[None].copy(), np.empty(0,
                                                                                    np.int64)
    args = {HYBRID: HybridSet([HybridBearing(b, n=16)], q, [1.0]).kernel_arguments(),
            SHORT: ShortSet([ShortBearing(b)], q, [1.0]).kernel_arguments(),
            AFFINE: affine_set_arguments(np.empty((0, 2, 2)), []),
            FMUS: group_arguments([], [], []),
            PYTHON: (np.int64(-1),)}
    return {kind: ((a, none),) for kind, a in args.items()}


def bearing_slots(groups) -> tuple:
    """The bearing groups ``((arguments, indices), ...)`` of
    :meth:`orchestrator.coupling.master.BearingSet.compiled_groups` as :func:`evaluate_set`
    takes them: one slot per kind of :data:`SLOT_KINDS`, each the tuple of that kind's groups
    or a placeholder with no bearing, then the groups on threads if any. The slots' types
    then do not depend on the mix of models: :func:`coupled_steps` is compiled once per
    transport (and number of meshes), not once for each mix; only hybrid bearings of two
    grids (two hybrid groups) or on threads make another type."""
    by_kind: dict[int, list] = {}
    for group in groups:
        by_kind.setdefault(len(group[0]), []).append(group)
    unknown = set(by_kind) - {*SLOT_KINDS, THREADED}
    if unknown:
        raise TypeError(f"bearing groups of {sorted(unknown)} arguments: not a kind of "
                        f"orchestrator.coupling.step (lengths {(*SLOT_KINDS, THREADED)})")
    slots = tuple(tuple(by_kind[k]) if k in by_kind else _placeholders()[k]
                  for k in SLOT_KINDS)
    return slots + ((tuple(by_kind[THREADED]),) if THREADED in by_kind else ())


def compile_step(structure) -> None:
    """Compile :func:`coupled_steps` (or load it from numba's cache) for a transport's
    structure arguments ``structure`` (the gear-shaft FMU's:
    :func:`orchestrator.coupling.fmi.structure.block_arguments` of empty lists) and bearing
    slots of any mix, taking no step: what a warm-up calls before runs start at once (the
    tests' conftest)."""
    z = np.zeros
    coupled_steps(0, structure, bearing_slots(()), z((1, 2)), z((1, 2, 2)), z((1, 2, 2)),
                  z((1, 4)), z((1, 2)), False, 1e-6, 1, RELAXATION, STALL, z(1), z((1, 4)),
                  z((1, 5, 2)), z((0, 1, 4)), z((0, 1, 2)), z((0, 1)), z(0, dtype=np.int64))


# --- the iteration --------------------------------------------------------------------------
@njit(cache=True)
def coupled_steps(n, structure, bearings, f0, kb, cb, x0, force0, expanded, tol,
                  max_iterations, relaxation, stall, mismatches, states, out, rec_states,
                  rec_force, rec_outputs, rec_iterations):
    """``n`` coupled steps (module docstring), each from the state and the affine laws of
    Eq. (17) ``f0, kb, cb`` (nb, 2), (nb, 2, 2) [N, N/m, N s/m] the step before accepted
    (their expansion point ``x0`` (nb, 4) and force there ``force0`` (nb, 2) when
    ``expanded``, what a gear-shaft FMU's law inputs carry), until one is not accepted.

    ``structure``: the structure's arguments (:func:`structure_solve`); ``bearings``: the
    bearing slots (:func:`bearing_slots`); ``mismatches`` (max_iterations,) each iteration's
    relative mismatch; ``states`` (nb, 4) and ``out`` (nb, 5, 2) the iterate's journal states
    and the bearings' results there. Step i writes its accepted journal states, bearing
    forces, the structure's outputs and iterations into row i of ``rec_states`` ...
    ``rec_iterations``.

    Returns ``(accepted steps, relaxed steps, outcome, iterations, structure code, its three
    details, failed bearing, its status, mismatch, relaxed, f0, kb, cb, x0, force0)``: for the
    last step its outcome (:data:`ACCEPTED` ...), iterations, the structure's failure code
    and details, the bearing set's, its mismatch and whether it was relaxed; and the laws the
    next step starts from.
    """
    # the callers keep these arrays alive: no reference counts in the layers below
    structure, bearings = borrowed(structure), borrowed(bearings)
    relaxed_steps = 0
    outcome, it, code, d1, d2, d3, bad, b_status = ACCEPTED, 0, 0, 0, 0, 0, -1, 0
    # np.bool_(False), np.int64(k): plain values, not numba's literals, so that a callee is
    # compiled once for all of them rather than once per constant (and again for the variable)
    relaxed, mismatch = np.bool_(False), 0.0
    for i in range(n):
        code = structure_begin(structure, i)
        if code != 0:
            return (i, relaxed_steps, STRUCTURE_FAILED, 0, code, 0, 0, 0, -1, 0, mismatch,
                    False, f0, kb, cb, x0, force0)
        law_f0, law_kb, law_cb, law_x, law_force, law_exp = f0, kb, cb, x0, force0, expanded
        outcome, relaxed, mismatch, bad = NOT_CONVERGED, np.bool_(False), np.inf, -1
        for it in range(1, max_iterations + 1):
            code, d1, d2, d3 = structure_solve(structure, i, law_f0, law_kb, law_cb, law_x,
                                               law_force, law_exp, states)
            if code != 0:
                outcome = STRUCTURE_FAILED
                break
            bad, b_status = evaluate_set(bearings, states, out)
            if bad >= 0:
                outcome = BEARING_FAILED
                break
            force = np.ascontiguousarray(out[:, 0])
            mismatch, f0_new, kb_new, cb_new = _relinearise(
                states, force, np.ascontiguousarray(out[:, 1:3]),
                np.ascontiguousarray(out[:, 3:5]), law_f0, law_kb, law_cb)
            if mismatch <= tol:
                outcome = ACCEPTED
                f0, kb, cb, x0, force0, expanded = (f0_new, kb_new, cb_new, states.copy(),
                                                    force.copy(), True)
                break
            was_relaxed = relaxed
            relaxed, law_f0, law_kb, law_cb = relaxed_law(
                it, mismatch, mismatches, relaxed, stall, relaxation, f0_new, kb_new, cb_new,
                law_f0, law_kb, law_cb)
            relaxed_steps += relaxed and not was_relaxed
            if relaxed:  # a blended law is given by f0 alone
                law_exp = False
            else:
                law_x, law_force, law_exp = states.copy(), force.copy(), True
            code = structure_retry(structure, i)
            if code != 0:
                outcome = STRUCTURE_FAILED
                d1, d2, d3 = 0, 0, 0
                break
        if outcome == ACCEPTED:
            code = structure_accept(structure, i, rec_outputs[i])
            if code != 0:
                outcome = STRUCTURE_FAILED
                d1, d2, d3 = 0, 0, 0
        structure_end(structure)
        if outcome != ACCEPTED:
            return (i, relaxed_steps, outcome, it, code, d1, d2, d3, bad, b_status, mismatch,
                    relaxed, f0, kb, cb, x0, force0)
        for b in range(states.shape[0]):
            for c in range(4):
                rec_states[i, b, c] = states[b, c]
            for c in range(2):
                rec_force[i, b, c] = force0[b, c]
        rec_iterations[i] = it
    return (n, relaxed_steps, outcome, it, code, d1, d2, d3, bad, b_status, mismatch, relaxed,
            f0, kb, cb, x0, force0)


@dataclass
class StepBlock:
    """Steps taken by one call of :meth:`orchestrator.coupling.master.Master.steps`: what the
    runner records of each accepted step, rows in step order, and the error of the step that
    ended the block early (None when all were accepted)."""

    count: int
    states: np.ndarray  # (count, nb, 4) accepted journal states [m, m/s]
    bearing_force: np.ndarray  # (count, nb, 2) [N]
    mesh_force: np.ndarray  # (count, n_meshes) [N]
    transmission_error: np.ndarray  # (count, n_meshes) [m]
    gear_nodes: np.ndarray  # (count, n_gears, 2) u, v of each gear's node [m]
    iterations: np.ndarray  # (count,)
    mismatch: float  # the last step's relative mismatch (at its acceptance, or failure)
    error: Exception | None = None


class CoupledSteps:
    """A block of the master's steps in one :func:`coupled_steps` call, for any structure
    slave and bearing set that give their compiled arguments
    (:meth:`orchestrator.coupling.master.StructureSlave.compiled_block`,
    :meth:`orchestrator.coupling.master.BearingSet.compiled_groups`)."""

    def __init__(self, structure, bearings):
        self.structure = structure
        self.bearings = bearings
        self._mismatches = None

    def block(self, master, t: float, dt: float, n: int, time_of) -> StepBlock:
        """Up to ``n`` steps of dt from t [s] (the structure's time) until one fails (its
        error in the block, after the steps before it are taken); ``time_of(k)``: the time
        [s] of the block's step k, as the caller's messages give it."""
        speeds = self.structure.bearing_speeds_after(dt)
        if speeds is not None:  # a run-up: the bearings' speeds change at every step
            self.bearings.set_speeds(speeds)
            n = 1
        structure, m, finish = self.structure.compiled_block(t, dt, n, time_of)
        groups = bearing_slots(self.bearings.compiled_groups())
        nb = self.bearings.count
        n_out = self.structure.output_width
        if self._mismatches is None or self._mismatches.size != master.max_iterations:
            self._mismatches = np.empty(master.max_iterations)
        states, out = np.empty((nb, 4)), np.empty((nb, 5, 2))
        rec = (np.empty((m, nb, 4)), np.empty((m, nb, 2)), np.empty((m, n_out)),
               np.empty(m, dtype=np.int64))
        laws = master.laws
        x0, force_at, kb, cb = laws.expansion()
        c = np.ascontiguousarray
        (count, relaxed_steps, outcome, it, code, d1, d2, d3, bad, b_status, mismatch, _,
         f0, kb, cb, x0, force0) = coupled_steps(
            m, structure, groups, c(laws.f0, dtype=float), c(kb, dtype=float),
            c(cb, dtype=float), c(x0, dtype=float), c(force_at, dtype=float),
            laws.states is not None, master.tol, master.max_iterations, RELAXATION, STALL,
            self._mismatches, states, out, *rec)
        done = int(rec[3][:count].sum())
        master.total_iterations += done
        master.total_bearing_evaluations += done
        master.relaxed_steps += relaxed_steps
        self.bearings.evaluations += nb * done
        if count:
            master.laws = AffineLaws(f0, kb, cb, x0, force0)
            self.bearings.record_states(rec[0][count - 1])
        finish(count)
        outputs, n_meshes = rec[2][:count], self.structure.n_meshes
        block = StepBlock(count, rec[0][:count], rec[1][:count],
                          outputs[:, :n_meshes].copy(), outputs[:, n_meshes:2 * n_meshes].copy(),
                          outputs[:, 2 * n_meshes:].reshape(count, self.structure.n_gears, 2),
                          rec[3][:count], mismatch)
        if count < m:
            self._count(master, outcome, it)
            try:
                self._raise(master, time_of(count), dt, count, outcome, (code, d1, d2, d3),
                            bad, b_status, mismatch, states)
            except Exception as exc:  # handed to the caller with the rows
                block.error = exc
        return block

    def _count(self, master, outcome, it) -> None:
        """The counters of a step that ended with ``outcome`` after ``it`` iterations: the
        master's iterations and evaluations as its iteration made them."""
        if outcome == ACCEPTED:
            return
        evaluated = it - (outcome == STRUCTURE_FAILED)
        master.total_iterations += it - (outcome in (STRUCTURE_FAILED, BEARING_FAILED))
        master.total_bearing_evaluations += evaluated
        self.bearings.evaluations += self.bearings.count * (
            evaluated - (outcome == BEARING_FAILED))

    def _raise(self, master, t, dt, k, outcome, failure, bad, b_status, mismatch,
               states) -> None:
        """The error of the block's step ``k`` from t [s] that :func:`coupled_steps` did not
        accept, with the slaves' messages (``failure``: the structure's code and details)."""
        if outcome == STRUCTURE_FAILED:
            self.structure.raise_compiled_failure(k, *failure, t, dt)
        if outcome == BEARING_FAILED:
            self.bearings.raise_failure(bad, b_status, states)
        self.bearings.record_states(states)
        raise NotConvergedError(not_converged(t, dt, master.max_iterations, mismatch,
                                              master.tol))
