"""Contact location in a Newmark step (:mod:`gear_fmu.structure`, ``locate_contact``): the
kinematic contact events that fall inside a step, and the step cut at them.

A contact line enters or leaves the path of contact at pinion angles known from the
rigid-body kinematics (:meth:`gear_fmu.mesh.element.MeshElement.event_angles`), which recur
with the mesh period. :meth:`ContactEvents.cuts` cuts a step at the events of one mesh, and
:func:`train_pieces` at those of every mesh of a train into sub-steps, each ending on its
events; the structure solves a sub-step with the contact set before its events (each mesh
evaluated :data:`EVENT_SIDE` base pitch before its own) and then resets the acceleration to
the one after them (:func:`gear_fmu.step.kernel.contact_events`).
"""

from __future__ import annotations

import bisect
import math

import numpy as np

__all__ = ["EVENT_SIDE", "EVENT_SNAP", "ContactEvents", "quiet_steps", "step_times",
           "train_pieces"]

#: the side of an event the mesh is evaluated on, in base pitches (above the mesh kernel's snap
#: of 1e-9 pitch, :mod:`gear_fmu.mesh.element`)
EVENT_SIDE = 1e-8
#: no sub-step is shorter than this fraction of dt. Newmark's acceleration update
#: ``4 (x1 - x0 - h v0) / h^2 - a0`` amplifies the round-off of the solved x1 by 4 / h^2: a
#: sub-step of 1e-7 dt turns 1e-20 m of round-off into accelerations of order 1e2 m/s^2 at the
#: paper's step, and runs at a step a few 1e-8 off the mesh period's divisor went wrong or
#: failed. At 1e-3 dt it is below 1e-4 m/s^2; an event moved by at most 1e-3 dt. (On the
#: coarse grain of :data:`DRIFT_FRACTION` a piece may be one grain, 9.8e-4 dt.)
EVENT_SNAP = 1e-3
#: sub-step fractions of dt are rounded to multiples of 2**-16 (an event moved by at most
#: 8e-6 dt), so that the condensations of the recurring sub-steps are computed once
#: (``gear_fmu.structure.Structure._dynamic``). A step starts at the structure's time, a sum of
#: steps whose round-off drifts from k dt (2.4e-8 dt after the helical case's 65,536 steps):
#: rounded much finer (2**-30), the fractions would follow that drift and the helical case's
#: 54 recurring lengths would become hundreds, each condensed anew
FRACTION = 2.0**16
#: the grain of a step that does not recur with the mesh period, one whose events move through
#: it by more than a 2**-16 grain in 16 mesh periods (:meth:`ContactEvents.fraction_grain`):
#: a host's rounded step (libcosim keeps whole nanoseconds: the paper's step rounded so moves
#: the events by 5.1e-4 dt per mesh period). Rounded to 2**-16, nearly every step cut at an
#: event would be a new sub-step length to condense (0.55 ms each, 4 per mesh period there,
#: 28 % of the run); to 2**-10 about one per mesh period. An event moves by at most 4.9e-4 dt
#: (half of EVENT_SNAP), a cut piece is at least 2**-10 dt (9.8e-4 dt, about EVENT_SNAP)
DRIFT_FRACTION = 2.0**10


class ContactEvents:
    """The contact events of a mesh element for a pinion turning as ``pinion_angle``.

    Parameters
    ----------
    mesh : gear_fmu.mesh.element.MeshElement
        Gives the event angles of one mesh period and the base pitch.
    pinion_angle : callable
        ``pinion_angle(t)``: the rigid-body pinion angle [rad] at time t [s].
    """

    def __init__(self, mesh, pinion_angle):
        self.mesh = mesh
        self.pinion_angle = pinion_angle
        self._phases = None  # (mesh period [rad], event angles in it), when first needed

    def sides(self, angle: float, events) -> tuple[float, float]:
        """The angles [rad] at which the mesh is evaluated before and after ``events``
        ``(first, last)`` that a sub-step ending at pinion ``angle`` ends on: their outer
        sides (:data:`EVENT_SIDE`), wherever they were snapped."""
        pair = self.mesh.pair
        side = EVENT_SIDE * pair.base_pitch / pair.base_radius[0]
        first, last = events
        before = angle - side if angle <= first + side else first - side
        after = angle + side if angle >= last - side else last + side
        return before, after

    def cuts(self, t: float, dt: float) -> list | None:
        """``[(h, end fraction of dt, (first, last) event angle it ends on, or None)]`` of the
        step from t to t + dt [s] with contact events (None without): the step cut at the
        event angles, fractions rounded to ``2**-16`` (``2**-10`` for a step that does not
        recur with the mesh period: :meth:`fraction_grain`), none shorter than
        :data:`EVENT_SNAP` dt (events that close to the step's ends or to each other taken
        together; the mesh is then evaluated on the outer sides of the events, not of the
        cut)."""
        a0 = self.pinion_angle(t)
        a1 = self.pinion_angle(t + dt)
        tol = self._tolerance()
        snap = max(tol, EVENT_SNAP * (a1 - a0))
        events = self.between(a0 - tol, a1 + snap)
        if not events:
            return None
        grain = self.fraction_grain(a1 - a0)
        cuts = []  # [end fraction, first event, last event]
        for e in events:
            if e - a0 <= snap:
                continue  # at the step's start: the previous step ended on it
            frac = 1.0 if a1 - e <= snap else round((e - a0) / (a1 - a0) * grain) / grain
            if cuts and frac - cuts[-1][0] <= EVENT_SNAP:  # one cut for events that close
                cuts[-1][0] = max(cuts[-1][0], frac)
                cuts[-1][2] = e
            elif 0.0 < frac:
                cuts.append([frac, e, e])
        if not cuts:
            return None
        ends = cuts + ([] if cuts[-1][0] == 1.0 else [[1.0, None, None]])
        out, prev = [], 0.0
        for frac, first, last in ends:
            out.append(((frac - prev) * dt, frac, None if first is None else (first, last)))
            prev = frac
        return out

    def _tolerance(self) -> float:
        """The pinion angle [rad] within which :meth:`cuts` takes an event at a step's start
        as the previous step's (1e-9 base pitch), which :meth:`quiet` widens."""
        pair = self.mesh.pair
        return 1e-9 * pair.base_pitch / pair.base_radius[0]

    def fraction_grain(self, step_angle: float) -> float:
        """How finely the cut fractions of a step of ``step_angle`` [rad] of pinion are rounded
        (their inverse grain): :data:`FRACTION`, or :data:`DRIFT_FRACTION` when the events
        move through the steps by more than a grain of it in 16 mesh periods (the step does
        not recur with the mesh period)."""
        period, _ = self._event_phases()
        steps = period / step_angle
        drift = abs(steps - round(steps))  # of a step, per mesh period
        return FRACTION if 16.0 * drift * FRACTION <= 1.0 else DRIFT_FRACTION

    def _event_phases(self) -> tuple:
        """(mesh period [rad], the event angles in it), computed once."""
        if self._phases is None:
            period = self.mesh.event_period
            self._phases = (period, self.mesh.event_angles(0.0, period).tolist())
        return self._phases

    def quiet(self, angles: np.ndarray) -> np.ndarray:
        """Whether the steps from pinion angle ``angles[k]`` to ``angles[k + 1]`` [rad] surely
        have none of this mesh's events (:meth:`cuts` gives None), for many steps at once.
        The interval :meth:`cuts` searches is widened by far more than the round-off of the
        angles and of the count (1e-6 of the step's angle, 1e-12 of the angle): a step said
        quiet has no event; a step with none may be said not quiet (then cut as usual)."""
        a0, a1 = angles[:-1], angles[1:]
        tol = self._tolerance()
        step = a1 - a0
        margin = tol + 1e-6 * np.abs(step) + 1e-12 * np.maximum(np.abs(a0), np.abs(a1))
        lo = a0 - tol - margin
        hi = a1 + np.maximum(tol, EVENT_SNAP * step) + margin
        return self._count_to(hi) <= self._count_to(lo)

    def _count_to(self, x: np.ndarray) -> np.ndarray:
        """How many event angles are <= ``x`` [rad], counted from the period holding angle
        0 (differences of two counts are what matters)."""
        period, phases = self._event_phases()
        k = np.floor(x / period)
        return k * len(phases) + np.searchsorted(phases, x - k * period, side="right")

    def between(self, lo: float, hi: float) -> list:
        """Contact event angles in ``(lo, hi]`` [rad]: those of one mesh period
        (:meth:`gear_fmu.mesh.element.MeshElement.event_angles`, computed once) repeated with
        the period ``2 pi / z1`` (the events of every slice recur with it)."""
        period, phases = self._event_phases()
        out = []
        k = math.floor(lo / period)
        while True:
            base = k * period
            for e in phases[bisect.bisect_right(phases, lo - base):]:
                if base + e > hi:
                    return out
                out.append(base + e)
            k += 1


def step_times(t: float, dt: float, n: int) -> np.ndarray:
    """The start of ``n`` steps of dt from ``t`` [s] and the end of the last, (n + 1,): each
    step starts where the one before ended, ``t + dt`` in sequence as the steps taken one by
    one reach it (``np.add.accumulate`` adds in order), the same bits."""
    return np.add.accumulate(np.concatenate(([t], np.full(n, dt))))


def quiet_steps(events: list, times: np.ndarray) -> np.ndarray:
    """Whether each step from ``times[k]`` to ``times[k + 1]`` [s] surely has no contact event
    of any mesh of ``events`` (:meth:`ContactEvents.quiet`): :func:`train_pieces` would give
    it one piece. Their pinion angles must take arrays (a constant speed)."""
    quiet = np.ones(len(times) - 1, dtype=bool)
    for ev in events:
        quiet &= ev.quiet(ev.pinion_angle(times))
    return quiet


def train_pieces(events: list, t: float, dt: float) -> list:
    """``[(h [s], end time [s], before, after)]`` of the step from t to t + dt [s] of a train
    whose meshes have the contact events ``events`` (one :class:`ContactEvents` each):
    ``before[m]`` the angle [rad] mesh m is evaluated at during the sub-step, ``after[m]``
    the one after its events at the sub-step's end (NaN: none there). The step is cut at the
    events of every mesh (:meth:`ContactEvents.cuts`); cuts of different meshes closer than
    :data:`EVENT_SNAP` dt are one, at the later of them. One piece without events."""
    t1 = t + dt
    ends: list[list] = []  # [end fraction, {mesh: (first, last)}]
    for m, ev in enumerate(events):
        for _, frac, where in ev.cuts(t, dt) or ():
            if where is None:
                continue
            for end in ends:
                if abs(end[0] - frac) <= EVENT_SNAP:
                    end[0] = max(end[0], frac)
                    first, last = end[1].get(m, where)
                    end[1][m] = (min(first, where[0]), max(last, where[1]))
                    break
            else:
                ends.append([frac, {m: where}])
    ends.sort(key=lambda e: e[0])
    if not ends or ends[-1][0] != 1.0:
        ends.append([1.0, {}])
    out, prev = [], 0.0
    for frac, where in ends:
        te = t1 if frac == 1.0 else t + frac * dt
        before, after = [], []
        for m, ev in enumerate(events):
            angle = ev.pinion_angle(te)
            if m in where:
                b, a = ev.sides(angle, where[m])
            else:
                b, a = angle, math.nan
            before.append(b)
            after.append(a)
        out.append(((frac - prev) * dt, te, before, after))
        prev = frac
    return out
