"""The housing's base in closed form (model.housing_base; docs/design.md 4.7): its limits and its
pieces by hand."""

from __future__ import annotations

import math
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.model import housing_base as hb
from mst_cli.model import load_path as lp
from mst_cli.model.beams import plain_section, section_EI_kGA
from mst_cli.model.plate_joint import root_joint_mm_per_N

FORWARD = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
EI, KGA, P = 60.0, 900.0, 0.5  # a cover of one section (N mm^2, N) and each side's share of 1 N


def scene():
    doc = mst.load(FORWARD)
    return replace(lp.member_scene(doc.geometry(), doc.material), slot_wall_widths_mm=(2.0, 2.0))


def test_the_feet_bear_on_the_slots_edge_fading_over_the_covers_thickness():
    """P/(c_b E'D) at the edge, the same a cover's thickness either side (exp(-1) of it), 1e-4 of
    it three thicknesses away."""
    s = scene()
    at_edge = P / (hb.BEARING * s.E_prime_MPa * s.depth_mm)
    c, edge = s.cover_mm, s.half_slot_mm
    assert hb.corner_mm_per_N(s, edge) == pytest.approx(at_edge, rel=1e-12)
    for e in (-c, c):
        assert hb.corner_mm_per_N(s, edge - e) == pytest.approx(at_edge / math.e, rel=1e-12)
    assert hb.corner_mm_per_N(s, edge - 3 * c) < 2e-4 * at_edge


def test_the_cover_ties_the_walls_tops_between_free_and_held():
    """A cantilever of E'I on a held foot, its top on a lateral spring k_s: its top's turn under a
    moment is M H/E'I (1 - (3/4) kappa/(1 + kappa)), kappa = k_s H^3/(3 E'I); no cover (k_s -> 0):
    E'I/H, free to sway; a rigid tie: 4 E'I/H, held."""
    s = scene()
    E, D, H, w = s.E_prime_MPa, s.depth_mm, s.slot_height_mm, 2.0
    EI = E * D * w**3 / 12
    assert hb.wall_turn_Nmm_per_rad(replace(s, cover_mm=1e-12), w) == pytest.approx(EI / H, rel=1e-9)
    assert hb.wall_turn_Nmm_per_rad(replace(s, cover_mm=1e9), w) == pytest.approx(4 * EI / H, rel=1e-6)
    thin, thick = (hb.wall_turn_Nmm_per_rad(replace(s, cover_mm=c), w) for c in (0.8, 3.0))
    assert EI / H < thin < thick < 4 * EI / H


def test_a_foot_on_the_walls_centre_line_only_squeezes_them():
    s = scene()
    over, walls, bend = hb.housing_mm_per_N(s, s.half_slot_mm + 1.0, s.half_slot_mm, (EI, KGA), (EI, KGA))
    squeeze = P * s.slot_height_mm / (s.E_prime_MPa * 2.0 * s.depth_mm)
    assert over == 0.0 and bend == 0.0 and walls == pytest.approx(squeeze, rel=1e-12)


def test_no_slot_walls_clamp_the_cover_and_rigid_ones_hold_its_built_in_ends():
    """Height 0: the clamped four-point beam. Walls 10 m wide (their turn ~ 1/w^3): the cover with
    its ends built into rigid walls, the third figure, to 1e-4; a cover 1 m thick (its ends' spring
    ~ c^2) on them: clamped again."""
    s = scene()
    L, e = 2 * s.half_slot_mm, 4.0
    head = s.half_slot_mm - e
    clamped = lp.two_load_mm_per_N(L, e, EI, KGA, "clamped")
    flat = hb.housing_mm_per_N(replace(s, slot_height_mm=0.0), head, s.half_slot_mm, (EI, KGA), (EI, KGA))
    assert flat[0] == pytest.approx(clamped, rel=1e-12) and flat[2] == pytest.approx(clamped, rel=1e-12)
    wide = replace(s, slot_wall_widths_mm=(1e4, 1e4))
    over, _, bend = hb.housing_mm_per_N(wide, head, s.half_slot_mm, (EI, KGA), (EI, KGA))
    assert over == pytest.approx(bend, rel=1e-4) and bend > clamped
    thick = replace(wide, cover_mm=1e3)
    assert hb.housing_mm_per_N(thick, head, s.half_slot_mm, (EI, KGA), (EI, KGA))[0] == pytest.approx(clamped, rel=1e-4)


def test_a_foot_over_the_slot_by_hand():
    """A cover of one section, e inside the slot's edge: by virtual work over the half span, C1 =
    e (L - e)/(2 E'I), C2 = e^2 (3L - 4e)/(6 E'I), B = L/(2 E'I); the end turns with the wall's
    top under P w/2 + M, k_w = E'I_w/H / (1 - (3/4) kappa/(1 + kappa)) (a cantilever whose top the
    cover ties, kappa = k_s H^3/(3 E'I_w), k_s = E'cD/(L/2)), and on its own built-in end, pi/8
    E'D c^2, under M: M = (P C1 - P (w/2)/k_w) / (B + 1/k_w + 1/k_end); the wall turns by
    (P w/2 + M)/k_w and drops its inner edge by w/2 x that."""
    s = scene()
    E, D, H, w, c = s.E_prime_MPa, s.depth_mm, s.slot_height_mm, 2.0, s.cover_mm
    L, e = 2 * s.half_slot_mm, 4.0
    B, C1, C2 = L / (2 * EI), e * (L - e) / (2 * EI), e**2 * (3 * L - 4 * e) / (6 * EI)
    EI_w = E * D * w**3 / 12
    kappa = (E * c * D / s.half_slot_mm) * H**3 / (3 * EI_w)  # the cover's stretch against the walls' sway
    k_wall, k_end = EI_w / H / (1 - 0.75 * kappa / (1 + kappa)), math.pi / 8 * E * D * c**2
    k = 1 / (1 / k_wall + 1 / k_end)
    M = (P * C1 - P * w / 2 / k_wall) / (B + 1 / k)
    turn = (P * w / 2 + M) / k_wall
    over, walls, bend = hb.housing_mm_per_N(s, s.half_slot_mm - e, s.half_slot_mm, (EI, KGA), (EI, KGA))
    assert over == pytest.approx(P * C2 - M * C1 + P * e / KGA + w / 2 * turn, rel=1e-12)
    assert walls == pytest.approx(P * H / (E * w * D), rel=1e-12)
    assert bend == pytest.approx(P * C2 - P * C1**2 / (B + 1 / k_end) + P * e / KGA, rel=1e-12)


def test_layer_1s_roots_turn_into_the_cover_until_it_locks():
    """Open: the walls' part is the housing's plus layer 1's roots as on a plate as thick as the
    cover and the feet's bearing at the slot's edge; the design loop's one call gives it and the
    locked form alike."""
    s = scene()
    doc = mst.load(FORWARD)
    cell = doc.geometry().layers[0]
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    theta, t, h = cell.theta_rad, cell.t_mm, cell.h_mm
    head, pad = s.half_slot_mm - 3.0, s.half_slot_mm - 2.5  # a foot over the slot
    alone = plain_section(D, s.cover_mm, E, G)
    over, walls, _ = hb.housing_mm_per_N(s, head, pad, section_EI_kGA(D, s.cover_mm + t, E, G), alone)
    roots = root_joint_mm_per_N(theta, t, h, s.cover_mm, D, E)
    edge = P * math.exp(-((3.0 / s.cover_mm) ** 2)) / (hb.BEARING * E * D)  # the feet 3 mm inside the edge
    assert hb.cover_parts_mm_per_N(s, t, pad, head, theta, h) == pytest.approx((over, walls + roots + edge), rel=1e-12)
    both = hb.cover_parts_both_mm_per_N(s, t, pad, head, theta, h)
    assert both[0] == pytest.approx((over, walls + roots + edge), rel=1e-12)
    assert both[1] == pytest.approx(hb.cover_parts_locked_mm_per_N(s, pad, head), rel=1e-12)
    # the members carry both: before and after layer 1's lock (model.load_path)
    parts = lp.members(doc.geometry(), doc.material)
    C, _, C_locked, delta = parts.cover_contact
    assert C > 0.0 and C_locked > 0.0 and parts.cover_mm_per_N + delta > 0.0
    assert np.isfinite(delta)


def test_a_locked_block_on_the_cover_by_hand():
    """Locked, the block rigid: the cover is a link a = L/2 - (pad - b c) long from the slot's
    edge to inside the block's edge (b = LINK_INTO_BLOCK), its end there turning as its end in the
    wall's top does (1/k_end). The feet's load reaches it at the block, so by virtual work over the
    link (m = P x - M): B = a/E'I + 1/k_end, C1 = a^2/(2 E'I) + a/k_end, C2 = a^3/(3 E'I) +
    a^2/k_end, shear P a/kGA; M and the wall's turn as over the slot (previous test); the feet's
    bearing at the edge and the block's, P/(c_b E'D), on the walls' part."""
    s = scene()
    E, G, D, H, w, c = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.slot_height_mm, 2.0, s.cover_mm
    EI_c, kGA_c = plain_section(D, c, E, G)
    head, pad = s.half_slot_mm - 3.0, s.half_slot_mm - 2.5
    a = s.half_slot_mm - (pad - hb.LINK_INTO_BLOCK * c)
    k_end = math.pi / 8 * E * D * c**2
    B, C1, C2 = a / EI_c + 1 / k_end, a * a / (2 * EI_c) + a / k_end, a**3 / (3 * EI_c) + a * a / k_end
    k_wall = hb.wall_turn_Nmm_per_rad(s, w)
    M = (P * C1 - P * w / 2 / k_wall) / (B + 1 / k_wall + 1 / k_end)
    turn = (P * w / 2 + M) / k_wall
    over = P * C2 - M * C1 + P * a / kGA_c + w / 2 * turn
    bearings = P * math.exp(-((3.0 / c) ** 2)) / (hb.BEARING * E * D) + P / (hb.BEARING * E * D)
    locked = hb.cover_parts_locked_mm_per_N(s, pad, head)
    assert locked == pytest.approx((over, P * H / (E * w * D) + bearings), rel=1e-12)
    # the block stiffens the base: below the open one, above the walls' squeeze and the bearings alone
    doc = mst.load(FORWARD)
    cell = doc.geometry().layers[0]
    opened = hb.cover_parts_mm_per_N(s, cell.t_mm, pad, head, cell.theta_rad, cell.h_mm)
    assert P * H / (E * w * D) + bearings < sum(locked) < sum(opened)


def test_the_base_is_smooth_as_its_feet_cross_the_slots_edge():
    """Swept across the slot's edge in 3001 steps of 1 um (layer 1's feet, or the locked block's
    end, from 1.5 mm inside it to 1.5 mm over the wall), open and locked: finite, positive, and no
    step more than twice the sweep's 95th-percentile step (a jump where the over-slot and the
    on-the-wall branches meet would be tens of times it; measured 1.13 for both)."""
    s = scene()
    cell = mst.load(FORWARD).geometry().layers[0]
    x = s.half_slot_mm + np.linspace(-1.5, 1.5, 3001)
    locked = np.sum(hb.cover_parts_locked_mm_per_N(s, x + hb.LINK_INTO_BLOCK * s.cover_mm, x - 0.05), axis=0)
    opened = np.sum(hb.cover_parts_mm_per_N(s, cell.t_mm, x + 0.05, x, cell.theta_rad, cell.h_mm), axis=0)
    for values in (locked, opened):
        assert np.all(np.isfinite(values)) and np.all(values > 0.0)
        steps = np.abs(np.diff(values))
        assert steps.max() < 2.0 * np.percentile(steps, 95)


def test_the_locked_base_follows_the_rung_over_the_box():
    """Against the whole-part rung's base under a locked layer 1 (every other member rigid) on the
    38 sampled designs of studies/data/member_regimes.csv with layer 1 locked in some regime: rms
    log error under 0.1 and each within 20 % (LINK_INTO_BLOCK was fitted on these rows,
    studies/locked_base.py --fit; the form before it was 0.76 to 1.25 of the rung)."""
    from studies import locked_base as lb

    csv_path = Path(__file__).resolve().parents[1] / "studies" / "data" / "member_regimes.csv"
    with tempfile.TemporaryDirectory() as tmp:
        ratios = []
        for path, rung in lb.box_rows(csv_path, Path(tmp)):
            _, s, _, _, pad, head = lb.layer_1(path)
            ratios.append(rung[3] / lb.now_locked(s, pad, head)[0])
    ratios = np.array(ratios)
    assert len(ratios) >= 30
    assert np.sqrt(np.mean(np.log(ratios) ** 2)) < 0.1
    assert np.all(np.abs(np.log(ratios)) < np.log(1.2))


def _column_by_stiffness(H, EI, kGA, k_top, k_root, F=1.0):
    """The same column by the stiffness method, independently of the flexibility form: one
    Timoshenko beam element (its textbook stiffness with phi = 12 EI / (kGA H^2)), the root's
    turn against a spring to the ground, the top's against one, the root held in sway."""
    phi = 12.0 * EI / (kGA * H * H)
    k = EI / (H**3 * (1.0 + phi))
    # dofs (root sway, root turn, top sway, top turn); the root's sway is held below
    K = k * np.array(
        [
            [12.0, 6.0 * H, -12.0, 6.0 * H],
            [6.0 * H, (4.0 + phi) * H * H, -6.0 * H, (2.0 - phi) * H * H],
            [-12.0, -6.0 * H, 12.0, -6.0 * H],
            [6.0 * H, (2.0 - phi) * H * H, -6.0 * H, (4.0 + phi) * H * H],
        ]
    )
    K[1, 1] += k_root
    K[3, 3] += k_top
    u = np.linalg.solve(K[1:, 1:], np.array([0.0, F, 0.0]))
    return u[1]


@pytest.mark.parametrize(
    ("H", "EI", "kGA", "k_top", "k_root"),
    [(5.2, 270.0, 30.0, 75.0, 570.0), (6.0, 90.0, 10.0, 1e3, 60.0), (3.0, 500.0, 5.0, 1.0, 1e4)],
)
def test_a_slot_wall_sways_as_the_stiffness_method_gives(H, EI, kGA, k_top, k_root):
    """The column's flexibility form against one Timoshenko element solved with its springs."""
    expected = _column_by_stiffness(H, EI, kGA, k_top, k_root)
    assert hb.column_sway_mm_per_N(H, EI, kGA, k_top, k_root) == pytest.approx(expected, rel=1e-10)


def test_a_slot_wall_sways_between_a_cantilever_and_a_guided_column():
    """Its top free: H^3/3EI + H/kGA (+ H^2/k_root with a turning root); held against a turn on a
    held root: H^3/12EI + H/kGA; the sway falls as the top's spring stiffens."""
    H, E_I, kGA, k_root = 5.2, 270.0, 30.0, 570.0
    free = H**3 / (3 * E_I) + H / kGA
    assert hb.column_sway_mm_per_N(H, E_I, kGA, 0.0, math.inf) == pytest.approx(free, rel=1e-12)
    assert hb.column_sway_mm_per_N(H, E_I, kGA, 0.0, k_root) == pytest.approx(free + H * H / k_root, rel=1e-12)
    guided = H**3 / (12 * E_I) + H / kGA
    assert hb.column_sway_mm_per_N(H, E_I, kGA, math.inf, math.inf) == pytest.approx(guided, rel=1e-12)
    sways = [hb.column_sway_mm_per_N(H, E_I, kGA, k, k_root) for k in (0.0, 10.0, 100.0, 1e3, math.inf)]
    assert all(a > b for a, b in zip(sways, sways[1:]))


def test_the_base_sways_as_its_two_walls_side_by_side():
    """Two like walls: half one column's sway, to the cover's mid-plane, each root built into the
    floor and each top into the cover (pi/8 E'D w^2, pi/8 E'D c^2); no slot walls: no sway."""
    s = scene()
    E, G, D, c, w = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.cover_mm, 2.0
    one = hb.column_sway_mm_per_N(
        s.slot_height_mm + 0.5 * c,
        E * D * w**3 / 12.0,
        5.0 / 6.0 * G * D * w,
        math.pi / 8.0 * E * D * c * c,
        math.pi / 8.0 * E * D * w * w,
    )
    assert hb.base_sway_mm_per_N(s) == pytest.approx(0.5 * one, rel=1e-12)
    assert hb.base_sway_mm_per_N(replace(s, slot_height_mm=0.0)) == 0.0


def test_a_rigid_cover_holds_the_walls_tops_at_its_underside():
    """tops_held: each wall a column to the cover's underside, its top guided, its root on the
    floor's spring k: H/kGA + H^2 u (u/12 + v/3) / (u + v), u = H/EI, v = 1/k (solved by hand:
    H^3/12EI for a built-in root, H^3/3EI for a hinged one); two like walls halve it."""
    s = scene()
    E, G, D, H, w = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.slot_height_mm, 2.0
    u, v = H / (E * D * w**3 / 12.0), 1.0 / (math.pi / 8.0 * E * D * w * w)
    one = H / (5.0 / 6.0 * G * D * w) + H * H * u * (u / 12.0 + v / 3.0) / (u + v)
    assert hb.base_sway_mm_per_N(s, tops_held=True) == pytest.approx(0.5 * one, rel=1e-12)
    assert hb.base_sway_mm_per_N(s, tops_held=True) < hb.base_sway_mm_per_N(s)
