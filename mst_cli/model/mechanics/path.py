"""Path-following shared by rungs L1 (frame) and L2 (continuum): displacement control with
adaptive steps up to an event (the cavity closing), located by secant bracketing.

The driver knows nothing of beams or finite elements. A model hands it three functions of its
own state (whatever it needs to restart a solve: a displacement vector, plus an active contact
set for L2):

* ``solve(state, d_mm) -> (state, iterations)``: the equilibrium at compression d, started from
  ``state``; raises one of ``failures`` (FloatingPointError, LinAlgError) when it does not
  converge. ``iterations`` counts the residual checks after the first (predictor) solve: 1
  when the predictor already satisfied equilibrium.
* ``margin(state, d_mm) -> (m, where)``: the distance to the event, m > 0 before it and
  m <= 0 at or past it (for the layers: the smallest clear gap minus the contact allowance, mm),
  and a label of what closed ("pad" or "wall").
* ``observe(state, d_mm)``: what to record at each accepted point (the layer force, ...).

Stepping: from d = 0 the compression grows by ``step``; a step whose solve fails is halved and
retried (``PathError`` once it falls below ``min_step_rel`` of the stroke scale); after a
converged step the next is 1.5x as long when Newton needed few iterations, the same after a
few more, half after many. A step that ends at or past the event brackets it between the last
two converged points; the event is then found by regula falsi on m(d), each trial solved from
the bracket's near (converged, pre-event) end, its guess held a fraction ``event_clamp_rel``
of the bracket inside it so the bracket always shrinks (or by bisection, for a margin that
jumps), and, where the model offers a ``guess`` of the event (L2: the next contact point's
touch), by trials at that guess first. The located point is the last sample.

Tolerances (:class:`PathTolerances`) are relative to the model's stroke scale d_ref (the pads'
nominal stroke h - 2t - allowance). Before this module L1 and L2 each had their own loop, and
their tolerances had drifted apart (stall 1e-7 vs 1e-6 of the stroke, event gap 1e-9 vs 1e-4,
bracket width 1e-12 vs 1e-6, 30 vs 20 secant iterations); the shared values are the tighter
ones of each pair.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np


class PathError(RuntimeError):
    """The path could not be followed to the event (steps stalled, or no event in range)."""


@dataclass(frozen=True)
class PathTolerances:
    """Tolerances of :func:`follow_to_event`, as fractions of the stroke scale d_ref."""

    # give up when a step halved after failed solves is shorter than this
    min_step_rel: float = 1e-7
    # the event is located when |margin| is at most this (a gap error, mm per mm of stroke) ...
    event_gap_rel: float = 1e-9
    # ... or when the bracket around it is narrower than this
    event_width_rel: float = 1e-12
    # each secant guess stays this fraction of the bracket inside it (the bracket must shrink)
    event_clamp_rel: float = 1e-3
    # secant trials at most; then the last trial is taken (it is within the bracket anyway)
    max_event_iterations: int = 30
    # halve the bracket instead of the secant guess: for a margin that jumps at the event (a
    # tangent stiffness as a contact closes), where regula falsi creeps from one side
    bisect: bool = False


# The laws of the rungs that follow a path (L1, L2) join its samples by straight lines: a step
# is kept only while that line bows off the curve by at most this share of the force
# (docs/design.md section 4, "The law between its knots")
LAW_CHORD_TOL_REL = 2e-3

# trials of :func:`_locate_event` taken from the model's guess, at most (then its default search)
MAX_EVENT_GUESSES = 12


@dataclass(frozen=True)
class StepControl:
    """Adaptive displacement steps of :func:`follow_to_event`."""

    first_step_rel: float = 0.125  # first step, fraction of d_ref
    grow_at_most_iterations: int = 3  # a step converged in at most this many: next x grow
    hold_at_most_iterations: int = 6  # ... in at most this many: next the same; else x shrink
    grow: float = 1.5
    shrink: float = 0.5  # also the factor of a failed step
    max_steps: int = 400  # converged, failed or rejected steps before the event, at most
    # with a ``chord`` callback: the largest error of the straight line between two accepted
    # points (the tabulated law between its knots), relative to the force at the step's end; a
    # step over it is rejected, and the next is sized to about 0.8 of it
    chord_tol_rel: float | None = None


@dataclass
class PathResult:
    """The accepted points of a path, the event point last (d = 0 is not included)."""

    d_mm: list[float]
    observations: list[Any]
    event_at: str  # the margin's label at the event
    iterations: int  # sum of the solves' iteration counts
    state: Any = field(repr=False)  # the state at the event


def follow_to_event(
    solve: Callable,
    margin: Callable,
    observe: Callable,
    state0: Any,
    d_ref_mm: float,
    d_max_mm: float,
    steps: StepControl = StepControl(),
    tol: PathTolerances = PathTolerances(),
    failures: tuple[type[BaseException], ...] = (FloatingPointError, np.linalg.LinAlgError),
    chord: Callable | None = None,
    guess: Callable | None = None,
) -> PathResult:
    """Follow the equilibrium path from ``state0`` at d = 0 until ``margin`` reaches 0.

    ``d_max_mm`` caps the compression; reaching it without the event is a :class:`PathError`
    (a cap just past a stroke where the event is certain, as L1's rigid pads, never raises).
    See the module docstring for ``solve``, ``margin`` and ``observe``. ``chord(state, d,
    state_new, d_new)``, optional: the estimated largest error of the chord between two
    converged points, relative to the force, which ``steps.chord_tol_rel`` bounds.
    ``guess(state_lo, d_lo, d_hi)``, optional: where in the event's bracket the model expects
    the event (None: no idea); see :func:`_locate_event`.
    """
    d, step, total_it = 0.0, steps.first_step_rel * d_ref_mm, 0
    state = state0
    m_prev, _ = margin(state0, 0.0)
    ds, obs = [], []
    for _ in range(steps.max_steps):
        if d >= d_max_mm:
            raise PathError(f"no event up to d = {d_max_mm:.4g} mm")
        d_try = min(d + step, d_max_mm)
        try:
            state_new, it = solve(state, d_try)
        except failures:
            step *= steps.shrink
            if step < tol.min_step_rel * d_ref_mm:
                raise PathError(f"steps stalled at d = {d:.4g} mm") from None
            continue
        total_it += it
        m_new, where = margin(state_new, d_try)
        err = chord(state, d, state_new, d_try) if chord is not None and m_new > 0.0 else 0.0
        # a step under 1e-4 of the stroke is kept whatever its chord: there the curve has a kink
        # (a contact point engaging), which no shorter step straightens
        if steps.chord_tol_rel and err > steps.chord_tol_rel and step > 1e3 * tol.min_step_rel * d_ref_mm:
            step *= max(steps.shrink, 0.8 * (steps.chord_tol_rel / err) ** 0.5)  # error ~ step^2
            continue
        if m_new <= 0.0:
            state_ev, d_ev, where, it = _locate_event(
                solve, margin, d_ref_mm, tol, failures, d, m_prev, state, d_try, m_new, state_new, where, guess
            )
            ds.append(d_ev)
            obs.append(observe(state_ev, d_ev))
            return PathResult(ds, obs, where, total_it + it, state_ev)
        ds.append(d_try)
        obs.append(observe(state_new, d_try))
        state, d, m_prev = state_new, d_try, m_new
        step *= _step_factor(steps, it, err)
    raise PathError(f"no event within {steps.max_steps} steps (d = {d:.4g} mm)")


def _step_factor(steps: StepControl, iterations: int, chord_err: float) -> float:
    """The next step over this one: by Newton's iterations, and no longer than keeps the chord
    within about 0.8 of its tolerance."""
    factor = steps.grow if iterations <= steps.grow_at_most_iterations else 1.0
    if iterations > steps.hold_at_most_iterations:
        factor = steps.shrink
    if steps.chord_tol_rel and chord_err > 0.0:
        factor = min(factor, max(steps.shrink, 0.8 * (steps.chord_tol_rel / chord_err) ** 0.5))
    return factor


def _locate_event(solve, margin, d_ref_mm, tol, failures, lo, m_lo, s_lo, hi, m_hi, s_hi, where_hi, guess=None):
    """Locate margin(d) = 0 in [lo, hi] (m_lo > 0 >= m_hi), every trial solved from the
    pre-event end. Returns (state, d, iterations) of the last trial, and the label of the
    nearest trial past the event (what closed: the last trial may fall short of it).

    Trials come from ``guess`` while it helps, else by regula falsi (or bisection, ``tol.bisect``).
    A trial is aimed half the width tolerance past the guess; one that lands past the event is
    followed by a probe half the tolerance short of it (at the guess): when the guess was right
    that probe closes the bracket; when it was not, one default trial comes before the next
    guess, which is then taken from nearer. Where a contact point engaging makes the margin jump
    (L2's lock), the guess is that point's touch predicted from its gap and the path's tangent:
    a Newton step on a smooth gap, so a trial or two per engaging point replace the dozen or so
    bisections of a 1e-5 bracket.
    """
    sc, dc, mc, total_it = s_hi, hi, m_hi, 0
    width_tol = tol.event_width_rel * d_ref_mm
    guesses_left, probe_below, skip_guess = (MAX_EVENT_GUESSES if guess is not None else 0), None, False
    for _ in range(tol.max_event_iterations):
        if abs(mc) <= tol.event_gap_rel * d_ref_mm or hi - lo <= width_tol:
            break
        inset = tol.event_clamp_rel * (hi - lo)
        proposed, kind = None, ""
        if probe_below is not None:
            proposed, kind = max(probe_below - 0.5 * width_tol, lo + 0.5 * (probe_below - lo)), "probe"
            probe_below = None
        elif guesses_left > 0 and not skip_guess:
            guesses_left -= 1
            expected = guess(s_lo, lo, hi)
            if expected is not None and lo < expected < hi:  # aimed half the tolerance past it
                proposed, kind = min(expected + 0.5 * width_tol, hi - 0.5 * width_tol), "guess"
        skip_guess = False
        if proposed is not None:
            dc = proposed
        elif tol.bisect:
            dc = 0.5 * (lo + hi)
        else:
            dc = lo + m_lo / max(m_lo - m_hi, 1e-300) * (hi - lo)
            dc = min(max(dc, lo + inset), hi - inset)
        try:
            sc, it = solve(s_lo, dc)
        except failures as exc:
            raise PathError(f"no equilibrium at d = {dc:.4g} mm while locating the event: {exc}") from None
        total_it += it
        mc, where = margin(sc, dc)
        if mc > 0.0:
            lo, m_lo, s_lo = dc, mc, sc
        else:
            hi, m_hi, where_hi = dc, mc, where
            if kind == "guess":
                probe_below = dc  # a guess past the event: probe just short of it
            elif kind == "probe":  # past the event too: the guess was taken from too far back,
                skip_guess = True  # so one default trial first, for a nearer pre-event end
    return sc, dc, where_hi, total_it
