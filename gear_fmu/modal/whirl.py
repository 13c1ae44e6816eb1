"""Whirl direction of a damped mode and the stability threshold over speed.

Whirl
-----
A mode ``x(t) = Re(phi exp(lambda t))``, ``Im lambda > 0``, moves a shaft node on the ellipse
``u = Re(a exp(i w t))``, ``v = Re(b exp(i w t))`` (a, b its u and v entries). The ellipse is run
through counter-clockwise about +z when ``Im(a conj(b)) > 0``, and::

    w_n = 2 Im(a conj(b)) / (|a|^2 + |b|^2)  in [-1, 1]

is +1 on a counter-clockwise circle, -1 on a clockwise one, 0 on a line. Taken with the sign of
the node's shaft's spin (a shaft turning about -z whirls forward clockwise), the node whirls
forward (with its shaft) for ``w_n > 0`` and backward for ``w_n < 0``. A mode is **forward**
when every node whose orbit is at least :data:`SIGNIFICANT` of the mode's largest orbit whirls
forward, **backward** when every such node whirls backward, **mixed** otherwise (the
classification of ROSS's ``whirl_direction``); its signed **whirl** value is the average of
``w_n`` weighted by the orbit sizes ``|a|^2 + |b|^2``. A mode whose lateral DOFs (u, v, phi,
psi) carry less than :data:`LATERAL` of its kinetic energy ``phi^H M phi`` (an axial or a
torsional mode) does not whirl: **none**.

Stability threshold
-------------------
The lowest input speed where a mode's damping ratio turns negative (oil whirl or whip in film
bearings: the bearings' cross-coupled stiffness feeds a forward whirl): the smallest damping
ratio over the modes at each speed, interpolated linearly where it changes sign
(:func:`stability_threshold`).
"""

from __future__ import annotations

import numpy as np

from gear_fmu.dofs import DOF_PER_NODE, PHI, PSI, U, V

__all__ = ["LATERAL", "SIGNIFICANT", "stability_threshold", "whirl"]

#: nodes whose orbit size ``|a|^2 + |b|^2`` is at least this share of the mode's largest count
#: in its whirl direction [-]
SIGNIFICANT = 0.01
#: share of a mode's kinetic energy in the lateral DOFs below which it does not whirl [-]
LATERAL = 0.05


def whirl(system, shapes, directions) -> tuple[np.ndarray, list[str]]:
    """The signed whirl value and direction of each mode (module docstring).

    Parameters
    ----------
    system : GearShaftSystem
        Its nodes, the shaft of each and its mass matrix M.
    shapes : (n_dof, n_modes) complex array
        Mode shapes in the full numbering (:class:`gear_fmu.modal.damped_modes.DampedModes`).
    directions : (n_shafts,) array
        Each shaft's turning direction about +z (+1 or -1; the sign of its speed).

    Returns
    -------
    (whirl, direction) : ((n_modes,) array, list of str)
        Whirl value in [-1, 1] (+1: every node on a forward circle) and ``"forward"``,
        ``"backward"``, ``"mixed"`` or ``"none"``.
    """
    nodes = np.arange(system.n_nodes)
    a = shapes[DOF_PER_NODE * nodes + U]
    b = shapes[DOF_PER_NODE * nodes + V]
    sign = np.sign(np.asarray(directions, dtype=float))[system.node_shaft][:, None]
    size = np.abs(a) ** 2 + np.abs(b) ** 2
    signed = 2.0 * sign * np.imag(a * np.conj(b))
    total = size.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        value = np.where(total > 0.0, signed.sum(axis=0) / total, 0.0)
    lat = np.zeros(system.mass.shape[0], dtype=bool)
    lat[(DOF_PER_NODE * nodes[:, None] + np.array([U, V, PHI, PSI])).ravel()] = True
    mass = system.mass
    energy = np.einsum("ij,ij->j", shapes.conj(), mass @ shapes).real
    lateral = np.einsum("ij,ij->j", shapes[lat].conj(), mass[np.ix_(lat, lat)] @ shapes[lat]).real
    labels = []
    for m in range(shapes.shape[1]):
        seen = size[:, m] >= SIGNIFICANT * size[:, m].max()
        s = signed[seen, m]
        if not lateral[m] >= LATERAL * energy[m]:
            labels.append("none")
        else:
            labels.append("forward" if np.all(s > 0.0) else "backward" if np.all(s < 0.0)
                          else "mixed")
    return value, labels


def stability_threshold(speeds, damping_ratios) -> float | None:
    """The lowest speed where the smallest damping ratio turns negative (module docstring).

    Parameters
    ----------
    speeds : (n,) array
        Increasing speeds [rad/s].
    damping_ratios : sequence of arrays
        The damping ratios of the modes at each speed (any count per speed).

    Returns
    -------
    float or None
        The speed [rad/s], interpolated linearly between the last stable and the first
        unstable speed; the first speed when a mode is unstable there already; None when
        every mode is damped at every speed.

    Examples
    --------
    >>> stability_threshold([100.0, 200.0, 300.0], [[0.1, 0.05], [0.02], [-0.02, 0.3]])
    250.0
    """
    w = np.asarray(speeds, dtype=float)
    low = np.array([np.min(z) if len(z) else np.inf for z in damping_ratios])
    bad = np.flatnonzero(low < 0.0)
    if bad.size == 0:
        return None
    k = int(bad[0])
    if k == 0:
        return float(w[0])
    s = low[k - 1] / (low[k - 1] - low[k])
    return float(w[k - 1] + s * (w[k] - w[k - 1]))
