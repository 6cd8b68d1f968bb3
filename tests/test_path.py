"""The shared path-following driver of rungs L1 and L2 on analytic problems whose event is known."""

import numpy as np
import pytest

from mst_cli.model.mechanics.path import PathError, PathTolerances, StepControl, follow_to_event


def _exact(iterations=1):
    """A 'model' whose equilibrium at d is d itself; it counts its solves and checks that every
    solve starts from a converged point behind the one asked for (the path only goes forward)."""
    calls = []

    def solve(state, d):
        assert state < d
        calls.append(d)
        return d, iterations

    return solve, calls


def _force(state, d):
    # a piecewise-linear force law, kinked at d = 0.3
    return 2.0 * d if d <= 0.3 else 0.6 + 0.5 * (d - 0.3)


def test_linear_margin_event_is_exact_and_observations_follow_the_law():
    solve, _ = _exact()
    path = follow_to_event(solve, lambda s, d: (0.7 - d, "pad"), _force, 0.0, d_ref_mm=1.0, d_max_mm=2.0)
    assert path.d_mm[-1] == pytest.approx(0.7, rel=1e-12)
    assert path.event_at == "pad" and path.state == path.d_mm[-1]
    assert path.observations == [_force(None, d) for d in path.d_mm]
    # steps that converge at once grow by 1.5: 0.125, 0.1875, 0.28125, ... up to the bracket
    assert np.diff([0.0] + path.d_mm[:-1]) == pytest.approx(0.125 * 1.5 ** np.arange(len(path.d_mm) - 1))


def test_cubic_margin_event_within_the_gap_tolerance():
    # m(d) = (d_e - d)(1 + 5 d^2): curved, single root at d_e
    d_e = 0.61803
    solve, calls = _exact()
    tol = PathTolerances()
    path = follow_to_event(
        solve, lambda s, d: ((d_e - d) * (1 + 5 * d * d), "wall"), _force, 0.0, d_ref_mm=1.0, d_max_mm=2.0, tol=tol
    )
    # |m| <= 1e-9 and |dm/dd| >= 1 near the root: d within 1e-9 of d_e
    assert abs(path.d_mm[-1] - d_e) <= tol.event_gap_rel
    assert path.event_at == "wall"
    assert len(calls) < 20  # regula falsi, not bisection


def test_loose_tolerance_stops_the_secant_early():
    d_e = 0.61803
    margin = lambda s, d: ((d_e - d) * (1 + 5 * d * d), "wall")  # noqa: E731
    solve_tight, tight = _exact()
    follow_to_event(solve_tight, margin, _force, 0.0, 1.0, 2.0)
    solve_loose, loose = _exact()
    path = follow_to_event(solve_loose, margin, _force, 0.0, 1.0, 2.0, tol=PathTolerances(event_gap_rel=1e-3))
    assert len(loose) < len(tight) and abs(path.d_mm[-1] - d_e) < 1e-3


def test_event_at_the_cap_is_located_at_the_stroke():
    # L1's rigid pads: the gap closes at d_nom exactly and the path is capped just beyond it
    d_nom = 0.3
    solve, _ = _exact()
    path = follow_to_event(solve, lambda s, d: (d_nom - d, "pad"), _force, 0.0, d_nom, d_nom * (1 + 1e-9) + 1e-12)
    assert path.d_mm[-1] == pytest.approx(d_nom, rel=1e-9)


def test_failed_steps_are_halved_and_many_iterations_shrink_the_next():
    # solves fail for steps longer than 0.05; the first converged one reports 8 iterations
    # (> 6: halve the next), the others 5 (hold)
    def solve(state, d):
        if d - state > 0.05 + 1e-15:
            raise FloatingPointError("too far")
        return d, 8 if state == 0.0 else 5

    path = follow_to_event(solve, lambda s, d: (0.2 - d, "pad"), _force, 0.0, 1.0, 2.0, StepControl(first_step_rel=0.1))
    steps = np.diff([0.0] + path.d_mm[:-1])
    assert steps == pytest.approx([0.05] + [0.025] * (len(steps) - 1))
    assert abs(path.d_mm[-1] - 0.2) <= PathTolerances().event_gap_rel


def test_a_stalled_path_is_an_error():
    def solve(state, d):
        raise np.linalg.LinAlgError("singular")

    with pytest.raises(PathError, match="stalled at d = 0"):
        follow_to_event(solve, lambda s, d: (1.0 - d, "pad"), _force, 0.0, 1.0, 2.0)


def test_no_event_before_the_cap_is_an_error():
    solve, _ = _exact()
    with pytest.raises(PathError, match="no event up to d = 1.5"):
        follow_to_event(solve, lambda s, d: (5.0 - d, "pad"), _force, 0.0, 1.0, 1.5)
    with pytest.raises(PathError, match="within 3 steps"):
        follow_to_event(solve, lambda s, d: (5.0 - d, "pad"), _force, 0.0, 1.0, 100.0, StepControl(max_steps=3))


def test_a_failed_solve_while_locating_the_event_is_an_error():
    def solve(state, d):
        if 0.3 < d < 0.5:
            raise FloatingPointError("no equilibrium")
        return d, 1

    with pytest.raises(PathError, match="locating the event"):
        follow_to_event(solve, lambda s, d: (0.4 - d, "pad"), _force, 0.0, 1.0, 2.0, StepControl(first_step_rel=0.3))


def _jump_at(d_e):
    # a margin that jumps at d_e (a tangent stiffness as a contact engages: L2's lock)
    return lambda s, d: (1.0, "wall") if d < d_e else (-1.0, "pad")


JUMP_TOL = PathTolerances(event_gap_rel=0.0, event_width_rel=1e-5, max_event_iterations=40, bisect=True)


@pytest.mark.parametrize("curvature", [-20.0, -1.0, 1.0, 20.0])
def test_a_guessed_jump_is_located_to_the_width(curvature):
    """A guess of the jump as a gap's linear prediction makes it, off by curvature x (d_e - d_lo)^2
    (a Newton step on a smooth gap), locates it to the bracket tolerance, with the label of the
    side past the jump: a guess short of the jump (the gap closing slower than its tangent says)
    in a third of bisection's trials, one past it in no more than bisection's and two."""
    d_e = 0.61803
    solve_b, bisected = _exact()
    follow_to_event(solve_b, _jump_at(d_e), _force, 0.0, 1.0, 2.0, tol=JUMP_TOL)
    solve_g, guessed = _exact()
    path = follow_to_event(
        solve_g,
        _jump_at(d_e),
        _force,
        0.0,
        1.0,
        2.0,
        tol=JUMP_TOL,
        guess=lambda s, lo, hi: d_e + curvature * (d_e - lo) ** 2,
    )
    assert abs(path.d_mm[-1] - d_e) <= JUMP_TOL.event_width_rel
    assert path.event_at == "pad"
    trials_b = len(bisected) - len(path.d_mm)  # the steps up to the bracket are shared
    trials_g = len(guessed) - len(path.d_mm)
    assert trials_b >= 15  # log2(bracket / 1e-5)
    assert trials_g <= (trials_b / 3 if curvature < 0 else trials_b + 2)


def test_a_guess_outside_the_bracket_is_ignored():
    d_e = 0.61803
    solve_b, bisected = _exact()
    follow_to_event(solve_b, _jump_at(d_e), _force, 0.0, 1.0, 2.0, tol=JUMP_TOL)
    solve_g, guessed = _exact()
    path = follow_to_event(solve_g, _jump_at(d_e), _force, 0.0, 1.0, 2.0, tol=JUMP_TOL, guess=lambda s, lo, hi: 5.0)
    assert guessed == bisected and abs(path.d_mm[-1] - d_e) <= JUMP_TOL.event_width_rel
