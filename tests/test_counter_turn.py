"""The members' turn under a tangential force (model.counter_turn; docs/design.md 4.7, "The
members' turn under a tangential force: built"): its parts against independent paths through the
same equations, its path integral's continuity, and mst's turn per tangential newton against the
whole-part rung's, an independent plane-strain FE of the part's section (its figures stored by
``benchmarks/bench_whole_part.py --general --out studies/data/general_regimes.csv``)."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.cad.whole_part_check import stated_shear_figures
from mst_cli.model.counter_turn import CounterTurn, regime_start_N
from mst_cli.model.general_load import linear_response, loaded_stack
from mst_cli.model.mechanics.tilt import solve_layer_tilt, tilt_compliance_rad_per_Nmm
from mst_cli.model.plane_frame import Frame
from mst_cli.model.stack_pose import tilt_laws

ROOT = Path(__file__).resolve().parents[1]
RUNG = ROOT / "studies" / "data" / "general_regimes.csv"


def designed(name: str):
    doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
    return doc.geometry(), doc.material


def test_a_frame_solves_its_load_cases_on_one_factorisation_as_one_by_one():
    """Frame.solve_cases: each case's displacements are the lone solve's, and a sum of cases the
    sum of their displacements (a linear frame)."""
    f = Frame(tie_N_per_mm=1e9)
    a, b, c = f.node(0.0, 0.0), f.node(0.0, 5.0), f.node(4.0, 5.0)
    f.beam(a, b, 1e5, 300.0, 900.0)
    f.beam(b, c, 1e5, 80.0, 700.0)
    f.spring(b, f.node(0.0, 5.0), 50.0)
    f.hold(a)
    cases = [{3 * c: 1.0}, {3 * c + 2: 2.5}, {3 * c: 1.0, 3 * c + 2: 2.5}]
    u = f.solve_cases(cases)
    for case, row in zip(cases, u):
        np.testing.assert_allclose(row, f.solve(case), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(u[2], u[0] + u[1], rtol=1e-10, atol=1e-15)


@pytest.mark.parametrize("fraction", [0.3, 0.9, 1.05, 3.0])
def test_a_layers_tilt_compliance_is_its_off_centre_solve(fraction):
    """The equilibrium's tangent at the centred state is the tilt per moment that Newton's solve of
    a press 0.05 mm off centre gives (the law is piecewise linear: the same to round-off), before
    and past each layer's lock, the layer's member included."""
    g, m = designed("mohammadi2021-forward")
    for layer in tilt_laws(g, m, "spring"):
        F = fraction * layer.lock_force_N
        lt = solve_layer_tilt(layer, F, (0.05, 0.0))
        assert tilt_compliance_rad_per_Nmm(layer, F) == pytest.approx(lt.phi_y_rad / (F * 0.05), rel=1e-6)


def test_the_counter_turn_integrates_its_rates_along_the_ray_without_a_jump():
    """On a ray (Fx = r Fz) the tilt is r x the integral of the regimes' rates: swept finely over
    the normal force across every lock, it has no jump (each step within its rate x the step), its
    slope in each regime is that regime's rate, and a small tangential force at one normal force
    gives the rate itself."""
    ct = CounterTurn(np.array([1.0, 4.0]), np.array([[2e-3, -1e-3], [5e-4, 3e-3], [-2e-3, 1e-3]]))
    F = np.linspace(0.0, 8.0, 8001)
    tilt = ct.tilt_rad(F, 0.3)[..., 0]
    step = np.abs(np.diff(tilt, axis=0))
    assert np.all(step <= 0.3 * np.abs(ct.tilt_rad_per_N).max(axis=0) * (F[1] - F[0]) * (1 + 1e-9))
    for r, (lo, hi) in enumerate([(0.2, 0.8), (1.5, 3.5), (5.0, 7.0)]):
        i, j = np.searchsorted(F, [lo, hi])
        np.testing.assert_allclose((tilt[j] - tilt[i]) / (F[j] - F[i]), 0.3 * ct.tilt_rad_per_N[r], rtol=1e-9)
    np.testing.assert_allclose(ct.tilt_rad(np.array([2.0]), 1.0)[0, :, 0], [2e-3 + 5e-4, -1e-3 + 3e-3])
    np.testing.assert_allclose(ct.tangent_tilt_rad(np.array([2.0]), 0.1)[0, :, 0], [5e-5, 3e-4])
    assert np.all(ct.tilt_rad(F, 0.3)[..., 1] == 0.0)  # along y nothing: the frame is the section's


def test_without_members_nothing_turns_back():
    """The layers alone (model.load_path: layers) carry no counter-turn: their figures are the
    tilt rung's, the pull's moment at each layer's pivot."""
    g, m = designed("fingertip")
    alone = loaded_stack(g, m, "spring", whole_part=False)
    assert alone.counter_turn is None
    tilt = np.ones((2, len(g.layers), 2))
    assert alone.tilts_with_counter_turn(np.array([1.0, 2.0]), tilt, 0.5) is tilt


def rung_rows() -> dict[tuple[str, int], dict]:
    with RUNG.open() as fh:
        return {(row["design"], int(row["regime"])): row for row in csv.DictReader(fh)}


def stated(stack, force_N: float) -> float:
    """mst's turn per tangential newton at ``force_N``, mrad/N in the rung's sign."""
    return stated_shear_figures(linear_response(stack, force_N))["turn_per_tangential_mrad_per_N"]


BUDGET_REL = 0.10  # issue 44: the turn per tangential newton within 10 % of the whole-part rung


@pytest.mark.parametrize("name", ["mohammadi2021-forward", "mohammadi2021", "fingertip", "mohammadi2021-compact"])
def test_the_counter_turn_takes_the_turn_per_tangential_newton_toward_the_rung(name):
    """Against the whole-part rung as printed (stored), in every regime where the counter-turn
    moves mst's turn per tangential newton by more than 5 % of the rung's, it moves it closer or
    leaves it within the issue's 10 % budget; past two locks of the three designed specs it is
    within that budget (each member turned at its own lever under the pull, the frame's, since
    2026-12-02: they read -17, -23 and -32 % with one ratio for all members); the forward design's
    there is the next test's."""
    g, m = designed(name)
    part = loaded_stack(g, m, "spring")
    without = replace(part, counter_turn=None)
    locks = np.sort([t.lock_force_N for t in part.tilt])
    rows = rung_rows()
    for r in range(len(locks)):
        rung = float(rows[(name, r + 1)]["turn_per_tangential_mrad_per_N"])
        F = regime_start_N(locks, r)
        now, before = stated(part, F), stated(without, F)
        if abs(now - before) > 0.05 * abs(rung):
            closer = abs(now - rung) < abs(before - rung)
            assert closer or abs(now - rung) < BUDGET_REL * abs(rung), (name, r + 1, rung, now, before)
        if r == 2 and name != "mohammadi2021-forward":  # the forward design's: the test below
            assert now == pytest.approx(rung, rel=BUDGET_REL), (name, rung, now)


@pytest.mark.xfail(strict=True, reason="on a thin cover the frame's 5 % in the portal's sway is 35 % in the net")
def test_the_forward_designs_turn_per_tangential_newton_past_two_locks_is_within_budget():
    """A known miss, kept in view: the forward design's turn per tangential newton past two locks,
    within 10 % of the rung's (-9 % before the walls' thrust, +3 % with it; +16 % with the feet's
    press, model.past_lock, and -31 % since the base's portal, 2026-12-04). Under a moment the
    base is now the rung's (the section frame's, within 3 %; the members' turn per moment there
    -0.206 against -0.215 mrad/(N mm)), but under the pull the frame turns that base 1.55 times
    as far as the rung does (0.578 against 0.361 mrad/N), where it is within 2 % on
    mohammadi2021; the figure was within budget only while the cover's C / x_c^2, 0.65 of the
    rung's turn, cancelled that. Under the pull the base's turn is the pull's moment's less the
    portal's sway turning it back, and on the 0.8 mm cover the sway cancels all but a seventh of
    it: the frame's sway, 5 % above the rung's (as on the specs, where it does not matter), is 35 %
    in the net (studies/base_portal.py). The whole figure is -0.422 mrad/N made of terms whose
    sizes sum to 15 times that: within 10 % it asks every member within 1.2 %, and 0.05 mm of
    printed cover moves the part's own by 4-5 % (studies/pull_turn_conditioning.py). Strict: it
    fails the run once the figure is within budget."""
    g, m = designed("mohammadi2021-forward")
    part = loaded_stack(g, m, "spring")
    locks = np.sort([t.lock_force_N for t in part.tilt])
    rung = float(rung_rows()[("mohammadi2021-forward", 3)]["turn_per_tangential_mrad_per_N"])
    assert stated(part, regime_start_N(locks, 2)) == pytest.approx(rung, rel=BUDGET_REL)


def test_the_counter_turns_gradient_is_its_differences():
    """tilt_gradient_rad (the two-chip reader's chain rule): d(Fx U(Fz) / Fz)/d(Fz, Fx) against
    central differences off the locks, nothing in Fy, x, y."""
    ct = CounterTurn(np.array([1.0, 4.0]), np.array([[2e-3, -1e-3], [5e-4, 3e-3], [-2e-3, 1e-3]]))
    theta = np.array([[0.5, 0.2, -0.1, 1.0, 2.0], [2.5, -0.4, 0.3, 0.0, 0.0], [6.0, 1.1, 0.0, -3.0, 1.0]])
    grad = ct.tilt_gradient_rad(theta)

    def phi(t):
        return ct.tilt_rad(t[:, 0], t[:, 1] / t[:, 0])[..., 0]

    for k in range(5):
        h = np.zeros(5)
        h[k] = 1e-5
        np.testing.assert_allclose(grad[:, k], (phi(theta + h) - phi(theta - h)) / 2e-5, rtol=1e-7, atol=1e-12)


def test_mst_simulate_with_a_shear_ratio_is_the_batched_forward_model():
    """The off-centre curve with a tangential force (``mst simulate --shear-ratio``) and the one
    batched forward model (general_load.path_fields_T) are one model: the counter-turn in both."""
    from mst_cli.model.general_load import path_fields_T
    from mst_cli.model.offcentre import simulate_offcentre

    g, m = designed("mohammadi2021-forward")
    curve = simulate_offcentre(g, m, (2.0, 0.0), shear_ratio=(0.3, 0.0))
    stack = loaded_stack(g, m, "spring")
    np.testing.assert_allclose(
        path_fields_T(stack, curve.force_N, (2.0, 0.0), (0.3, 0.0)), curve.B_T, rtol=1e-9, atol=1e-15
    )
    without = path_fields_T(replace(stack, counter_turn=None), curve.force_N, (2.0, 0.0), (0.3, 0.0))
    assert np.max(np.abs(without - curve.B_T)) > 1e-6  # the counter-turn moves the field


def covers(steps: int) -> list:
    """The forward design with its cover 0.8 to 3 mm thick in ``steps``: (geometry, material, the
    layers' lock order), the order of the design as bundled."""
    doc = mst.load(ROOT / "configs" / "mohammadi2021-forward.yaml")
    g, m = doc.geometry(), doc.material
    order = np.argsort([t.lock_force_N for t in tilt_laws(g, m, "spring")], kind="stable")
    return [(replace(g, housing=replace(g.housing, cover_mm=float(c))), m, order) for c in np.linspace(0.8, 3.0, steps)]


def test_the_turn_ratio_moves_smoothly_with_the_cover():
    """Swept over the cover's thickness (0.8 to 3 mm, the forward design's layers), each regime's
    turn ratio has no jump or sawtooth: at every point of the 0.2 mm sweep, halving the step takes
    the second difference down by about four, as a smooth curve's; a jump of 0.005 anywhere, or a
    sawtooth, leaves it at half or more (checked by adding one to the ratios). Before the first
    lock the ratio is least near a 1 mm cover (curvature about 1.7 per mm^2 there). Past layer 1's
    lock it rises: the thinner the cover on the slot's walls, the further they turn it back against
    the moment."""
    from mst_cli.model import plate_sway as ps

    def ratios(steps: int) -> np.ndarray:  # (steps, 4): regimes 1, 2, 3 and past the last lock
        return np.array([ps.section_regimes(ps.stack_section(p, m), o).member_turn_ratio for p, m, o in covers(steps)])

    coarse, fine = ratios(12), ratios(23)  # steps of 0.2 and 0.1 mm: coarse point i is fine point 2i
    at_coarse = np.diff(coarse, 2, axis=0)  # centred on coarse points 1 to 10
    at_fine = fine[1:-2:2] - 2.0 * fine[2:-1:2] + fine[3::2]  # on fine points 2 to 20, the same places
    assert np.all(np.abs(at_fine) <= 0.5 * np.abs(at_coarse) + 1e-3)
    assert np.all(np.diff(coarse[:, 1:], axis=0) > 0.0)


def test_every_member_rides_with_one_unit_in_every_regime():
    """model.part_laws.unit_members against model.load_path's own sums: with nothing locked the
    units carry the cap, every plate, every joint and the cover once each (Members.total); with every
    layer locked only the cover is left, on its host; a plate over a locked layer rides with the
    layer over it while that one is open."""
    from mst_cli.model.load_path import members
    from mst_cli.model.mechanics import layer_laws
    from mst_cli.model.part_laws import unit_members

    for name in ("mohammadi2021-forward", "fingertip"):
        g, m = designed(name)
        parts = members(g, m)
        order = np.argsort([t.lock_force_N for t in tilt_laws(g, m, "spring")], kind="stable")
        riding = unit_members(layer_laws(g.layers, m, "spring"), parts, order)
        carried = [sum(c for unit in regime for c, _ in unit) for regime in riding]
        assert carried[0] == pytest.approx(parts.total_mm_per_N, rel=1e-12)
        assert carried[-1] == pytest.approx(parts.cover_mm_per_N, rel=1e-12)
        assert [k for unit in riding[-1] for _, k in unit] == [-1]
        assert list(order[:2]) == [0, 1]  # layer 1 locks first: the plate over it rides with layer 2
        # the plate at its lever, the feet's press into the block at the layer's own (OWN_LEVER)
        over, press = parts.locked_plates_mm_per_N[0], parts.press_mm_per_N[0]
        assert press > 0.0
        assert (pytest.approx(over - press, rel=1e-12), 0) in riding[1][1]
        assert (pytest.approx(press, rel=1e-12), None) in riding[1][1]
        assert (pytest.approx(over - press, rel=1e-12), 0) not in riding[0][1] + riding[2][1]
        # past both locks the top layer carries the walls' thrust and its feet's press at its own lever
        own = parts.thrust_mm_per_N[-1] + parts.press_mm_per_N[-1]
        assert [k for _, k in riding[2][2]].count(None) == (1 if own > 0.0 else 0)


def test_a_member_at_the_pulls_own_lever_is_not_turned_back():
    """The counter-turn adds (arm - lever) x dC: members turned by the pull at the lever the tilt
    rung already gives them add nothing; at half of it, half their turn under the pull's moment
    comes back (analytic)."""
    from mst_cli.model.counter_turn import counter_turn

    g, m = designed("mohammadi2021-forward")
    part, alone = (tilt_laws(g, m, "spring", 1.0, whole) for whole in (True, False))
    lever = np.array([15.0, 11.0, 7.0])
    same = counter_turn(part, alone, lever, np.tile(lever, (4, 1)))
    assert np.all(same.tilt_rad_per_N == 0.0)
    half = counter_turn(part, alone, lever, np.tile(0.5 * lever, (4, 1)))
    F = regime_start_N(np.sort([t.lock_force_N for t in part]), 0)
    dC = np.array([tilt_compliance_rad_per_Nmm(p, F) - tilt_compliance_rad_per_Nmm(a, F) for p, a in zip(part, alone)])
    np.testing.assert_allclose(half.tilt_rad_per_N[0], -0.5 * lever * dC, rtol=1e-12)


def test_the_members_levers_move_smoothly_with_the_cover():
    """Swept over the cover's thickness (0.8 to 3 mm in 24 steps, the forward design's layers), the
    levers at which the pull turns each unit's members (model.counter_turn.unit_arms_mm) move
    without a jump: the second differences within 5 % of each lever's range; the units that do not
    carry the cover do not move but by the rigid members' own give (each member's frame solve holds
    the others at plate_sway.RIGID = 1e5 times TPU: 1e-4)."""
    from mst_cli.model import plate_sway as ps
    from mst_cli.model.counter_turn import unit_arms_mm
    from mst_cli.model.load_path import members
    from mst_cli.model.mechanics import layer_laws
    from mst_cli.model.part_laws import unit_members

    rows = []
    for part, m, order in covers(24):
        regimes = ps.section_regimes(ps.stack_section(part, m), order)
        riding = unit_members(layer_laws(part.layers, m, "spring"), members(part, m), order)
        rows.append(unit_arms_mm(riding, regimes.member_arm_mm, np.zeros(3)))
    arms = np.array(rows)  # (24, regimes, units)
    host = arms[:, :, 0]
    assert np.all(np.abs(np.diff(host, 2, axis=0)) < 0.05 * np.ptp(host, axis=0))
    np.testing.assert_allclose(arms[:, :, 1:], np.broadcast_to(arms[:1, :, 1:], arms[:, :, 1:].shape), rtol=1e-4)


def test_a_member_turns_the_magnet_about_its_own_plane():
    """A member turned by phi under a pull moves the magnet phi x (its height over the member's
    mid-plane), not over its layer's pivot (rigid rotation about y): stack_pose.magnet_pose's slide
    from the layer's tilt plus counter_turn.own_plane_slide_mm_per_N's is that, for the cover, a
    plate and the cap, whatever unit carries them."""
    from mst_cli.model import plate_sway as ps
    from mst_cli.model.counter_turn import own_plane_slide_mm_per_N
    from mst_cli.model.stack_pose import layer_pivots_mm, magnet_pose

    g, m = designed("mohammadi2021-forward")
    planes = ps.member_planes_mm(ps.stack_section(g, m))
    z_magnet = g.z_magnet_bottom_mm + 0.5 * g.magnet.thickness_mm
    phi, lever = 2e-3, 1.7  # the member's turn per newton of Fx, as its lever x its tilt per N mm
    for unit, member in ((0, -1), (1, 0), (2, 1), (2, 2)):
        tilt = np.zeros((1, 3))
        tilt[0, unit] = phi / lever
        riding = [[[(1.0, member)] if j == unit else [] for j in range(3)]]
        arms = np.full((1, 4), lever)
        extra = own_plane_slide_mm_per_N(riding, arms, tilt, layer_pivots_mm(g), planes)[0]
        tilts = np.zeros((1, 3, 2))
        tilts[0, unit, 0] = phi
        shift, _ = magnet_pose(g, np.zeros((1, 3)), tilts)
        assert shift[0, 0] + extra == pytest.approx(phi * (z_magnet - planes[member + 1]), rel=1e-12)
