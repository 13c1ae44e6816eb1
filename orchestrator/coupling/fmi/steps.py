"""The FMUs' part of the coupled step (:func:`orchestrator.coupling.step.coupled_steps`): the
gear-shaft FMU's and the bearing FMUs' FMI calls, made from compiled code.

Through the FMUs each coupled iteration is a handful of FMI calls (the gear-shaft FMU's laws,
doStep and journals, each bearing FMU's state and law, the state restored), and the Python
around them (ctypes' conversions, the slaves' wrappers) cost about as much as the bearings'
compiled laws. These functions make the calls through the functions' addresses
(:mod:`orchestrator.coupling.fmi.calls`), the laws packed by
:func:`fmu_src.contract.pack_law_arrays`: the iteration around them is the one of every
transport. The gear-shaft FMU's doStep and its state's save and restore still run its slave's
Python; the bearing FMUs and the gear-shaft FMU's laws and journals are served by their native
layer (``fmu_src/native/patches``) without Python.

A call that fails returns which call with its status;
:class:`~orchestrator.coupling.fmi.structure.FmuStructure` and
:class:`~orchestrator.coupling.fmi.bearings.FmuBearings` raise the error with the FMU's log
(``raise_compiled_failure``, ``raise_failure``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from fmu_src.contract import pack_law_arrays
from orchestrator.coupling.fmi.calls import fmi_do_step, fmi_real, fmi_state

__all__ = ["fmu_bearing_group", "fmu_structure_accept", "fmu_structure_begin",
           "fmu_structure_end", "fmu_structure_retry", "fmu_structure_solve"]

#: where the gear-shaft FMU's functions and component sit in its arguments' first array
SET_REAL, GET_REAL, DO_STEP, GET_STATE, SET_STATE, FREE_STATE, COMPONENT = range(7)
#: the gear-shaft FMU's failure codes (which call failed)
(GET_STATE_FAILED, LAWS_FAILED, STEP_FAILED, JOURNALS_FAILED, JOURNALS_NOT_FINITE,
 RESTORE_FAILED, OUTPUTS_FAILED) = range(1, 8)
#: a bearing FMU's failure statuses (which call failed)
BEARING_SET_FAILED, BEARING_GET_FAILED, BEARING_NOT_FINITE = 1, 2, 3
_DOUBLE, _VR = 8, 4  # bytes of an fmi2Real and an fmi2ValueReference


@njit(cache=True)
def _finite(values) -> bool:
    for x in values:
        if not math.isfinite(x):
            return False
    return True


@njit(cache=True)
def fmu_structure_begin(structure):
    """fmi2GetFMUstate into the arguments' ``saved``: 0, or :data:`GET_STATE_FAILED`."""
    gear, saved = structure[0], structure[7]
    status = fmi_state(gear[GET_STATE], gear[COMPONENT], saved.ctypes.data)
    return GET_STATE_FAILED if status > 1 else 0


@njit(cache=True)
def fmu_structure_solve(structure, i, f0, kb, cb, x0, force0, expanded, states):
    """The laws into the gear-shaft FMU (their expansion, as its bearing inputs carry them;
    a law given by ``f0`` alone as its expansion about zero), doStep ``i`` of the block
    (from ``times[i]``, of ``dt``), the journal states read into ``states`` (nb, 4).
    Returns ``(0 or the failed call, its status, 0, 0)``."""
    gear, law_vr, law_val, journal_vr, journal_val = structure[:5]
    times, dt = structure[8], structure[9]
    comp = gear[COMPONENT]
    nb = states.shape[0]
    rows = law_val.reshape(nb, 14)
    if expanded:
        pack_law_arrays(x0, force0, kb, cb, rows)
    else:
        pack_law_arrays(np.zeros((nb, 4)), f0, kb, cb, rows)
    status = fmi_real(gear[SET_REAL], comp, law_vr.ctypes.data, law_vr.size,
                      law_val.ctypes.data)
    if status > 1:
        return LAWS_FAILED, status, 0, 0
    status = fmi_do_step(gear[DO_STEP], comp, times[i], dt)
    if status != 0:
        return STEP_FAILED, status, 0, 0
    status = fmi_real(gear[GET_REAL], comp, journal_vr.ctypes.data, journal_vr.size,
                      journal_val.ctypes.data)
    if status > 1:
        return JOURNALS_FAILED, status, 0, 0
    if not _finite(journal_val):
        return JOURNALS_NOT_FINITE, 0, 0, 0
    states[:] = journal_val.reshape(nb, 4)
    return 0, 0, 0, 0


@njit(cache=True)
def fmu_structure_retry(structure):
    """fmi2SetFMUstate of the state saved at the step's start: 0 or :data:`RESTORE_FAILED`."""
    gear, saved = structure[0], structure[7]
    status = fmi_state(gear[SET_STATE], gear[COMPONENT], saved[0])
    return RESTORE_FAILED if status > 1 else 0


@njit(cache=True)
def fmu_structure_accept(structure, row):
    """The gear-shaft FMU's step outputs (mesh forces, transmission errors, gear nodes' u, v:
    :func:`fmu_src.contract.step_output_names`) into ``row``: 0 or :data:`OUTPUTS_FAILED`."""
    gear, output_vr, output_val = structure[0], structure[5], structure[6]
    status = fmi_real(gear[GET_REAL], gear[COMPONENT], output_vr.ctypes.data, output_vr.size,
                      output_val.ctypes.data)
    if status > 1:
        return OUTPUTS_FAILED
    row[:] = output_val
    return 0


@njit(cache=True)
def fmu_structure_end(structure):
    """fmi2FreeFMUstate of the state saved at the step's start."""
    gear, saved = structure[0], structure[7]
    fmi_state(gear[FREE_STATE], gear[COMPONENT], saved.ctypes.data)


@njit(cache=True)
def fmu_bearing_group(args, states, out):
    """Bearing FMUs with the Jacobian outputs at their journal states ``states`` (k, 4) into
    ``out`` (k, 5, 2): per bearing its fmi2SetReal of the state and fmi2GetReal of the force,
    Kb and Cb (``args``: their functions and component (k, 3), the state and law value
    references (k, 4), (k, 10), and buffers (k, 4), (k, 10)). Returns ``(failed bearing of the
    group or -1, 8 * which call (BEARING_SET_FAILED ...) + its fmi2Status)``."""
    calls, state_vr, law_vr, state_buf, law_buf = args
    for b in range(states.shape[0]):
        state_buf[b] = states[b]
        status = fmi_real(calls[b, 0], calls[b, 2], state_vr.ctypes.data + b * 4 * _VR, 4,
                          state_buf.ctypes.data + b * 4 * _DOUBLE)
        if status > 1:
            return b, 8 * BEARING_SET_FAILED + status
        status = fmi_real(calls[b, 1], calls[b, 2], law_vr.ctypes.data + b * 10 * _VR, 10,
                          law_buf.ctypes.data + b * 10 * _DOUBLE)
        if status > 1:
            return b, 8 * BEARING_GET_FAILED + status
        if not _finite(law_buf[b]):
            return b, 8 * BEARING_NOT_FINITE
        for r in range(5):
            for c in range(2):
                out[b, r, c] = law_buf[b, 2 * r + c]
    return -1, 0
