"""The housing's base under a centred press, in closed form: the cover over the board's slot and
the slot's two walls (a member of model.load_path; issue 44, docs/design.md 4.7).

The base is a block with the board's slot cut under its cover. Layer 1's bottom pad is bonded on
the cover; its walls' feet load it at |x| = head, P = F/2 on each side. The slot's walls are
TPU columns w wide and H tall from the held floor to the cover. Each piece below is a mechanism
the whole-part rung shows on its own (studies/member_regimes.py, its base split into the cover
alone and the walls alone; studies/member_closed_form.py):

* **the walls' squeeze**, P H / (E' w D): the walls alone, the cover rigid, within 5-30 % above
  it (the floor under them squeezes too);
* **the cover over the slot**, a beam of two sections (with layer 1's pad under |x| < pad, the
  cover alone beyond) spanning the slot between the walls' tops, its ends built into them: each
  end turns against the wall's top as an end built into a body of the same modulus, pi/8 E'D c^2
  (c the cover's thickness; the tilted rigid flat punch on an elastic half-plane, Johnson,
  Contact Mechanics, 1985, chapter 2, the form model.plate_joint cites), in series with the
  wall's own turn;
* **the walls' turn**: a wall is a column on a held foot whose top the cover ties to the
  other's (the cover stretches as both tops move out: k_s = E'cD / (L/2)), so its top resists a
  turn between E'I/H (free to sway) and 4 E'I/H (held), by how stiff that tie is against the
  column's own sway (:func:`wall_turn_Nmm_per_rad`: a thin cover lets the walls turn further);
  the cover's reaction sits at its inner edge (lever w/2), which drops (w/2) x the turn. A foot
  standing on the wall (e <= 0), a from its centre line, turns it by P a against the wall and
  the cover and drops by a x that;
* **layer 1's roots** turning into the cover, as into a plate as thick as the cover
  (model.plate_joint.cover_root_mm_per_N), while layer 1 is open;
* **the feet's bearing at the slot's edge**: a foot near the edge, on either side, bears on
  the corner of the wall under the cover, P / (c_b E'D), fading as exp(-(e/c)^2) with its
  distance e from the edge over the cover's thickness c (a local compliance of the form of a
  line load's on a half-plane, whose displacement grows as 2P / (pi E'D) per e-fold of distance);
* **past layer 1's lock** its cavity is closed and the layer a block h_1 tall bonded on the
  cover under its pad. With the plate over it the block and the cover under it go down as one
  body (the whole-part rung's profile, studies/locked_base.py --profile), so the block is rigid
  here and the cover is a short link from the slot's wall to inside the block's edge: it reaches
  b c into the block (the cover under the block's edge, held on its top face only, shears with
  the link; b = LINK_INTO_BLOCK), and its end there turns as its end in the wall's top does,
  pi/8 E'D c^2. The feet's load reaches the link at the block's edge, the walls squeeze and turn
  under it as before the lock, the roots no longer turn, and the block bears on the cover,
  P / (c_b E'D).

Under a tangential force along x the base sways as a portal frame (:func:`base_sway_mm_per_N`):
the slot's walls are Timoshenko columns from the floor to the cover's mid-plane, each root built
into the floor (pi/8 E'D w^2) and each top into the cover's end (pi/8 E'D c^2), the two side by
side; the cover's own stretch and the frame's turn are left out (the general load turns the cover
with layer 1 under the force's moment).

Over the slot the cover's bending (and its edges' drop) stops when it lands on the board; the
squeeze, the turn of a wall under a foot standing on it, the roots and the bearings do not.
Fitted: c_b (0.8), the one value for both bearings, on a grid of 0.6-2.0 by the base's rms
log error against the whole-part rung's over the three regimes of 40 sampled designs
(studies/member_closed_form.py; docs/design.md 4.7); and b (0.225), by the locked base's rms log
error against the rung's (every other member rigid) on the 38 of them with layer 1 locked in some
regime (studies/locked_base.py --fit: 0.070, where the form before it, a free deep block, was
0.76-1.25 of the rung). Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mst_cli.model.beams import END_BUILT_IN as END_BUILT_IN  # the cover's end in the wall's top, pi/8 E'D c^2
from mst_cli.model.beams import SHEAR_FACTOR, as_value, plain_section, section_EI_kGA
from mst_cli.model.plate_joint import cover_root_mm_per_N

WALL_LEVER = 0.5  # the cover's reaction at the wall's inner edge, w/2 from its centre line
BEARING = 0.8  # fitted (module docstring): a local bearing on the cover, P / (c_b E'D)
# fitted (module docstring, studies/locked_base.py --fit): how far into a locked layer 1's
# block, in cover thicknesses, the cover's link to the slot's wall reaches
LINK_INTO_BLOCK = 0.225
RIGID_SECTION = (math.inf, math.inf)  # (E'I, kGA) of a section that does not bend


def cover_parts_mm_per_N(scene, t_bottom_mm, pad_mm, head_mm, theta_bottom_rad, h_bottom_mm) -> tuple:
    """(what stops when the cover lands on the board, the rest) of the base's drop per newton under
    an open layer 1 (its t, outer pad and wall heads, model.load_path.layer_supports; its theta in
    rad and h in mm), for a model.load_path.MemberScene ``scene`` (module docstring)."""
    s = scene
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    over_slot, walls, _ = housing_mm_per_N(
        s, head_mm, pad_mm, section_EI_kGA(D, s.cover_mm + t_bottom_mm, E, G), plain_section(D, s.cover_mm, E, G)
    )
    roots = cover_root_mm_per_N(theta_bottom_rad, t_bottom_mm, h_bottom_mm, s.cover_mm, D, E)
    return over_slot, walls + roots + corner_mm_per_N(s, head_mm)


def corner_mm_per_N(scene, head_mm) -> Any:
    """The feet's bearing at the slot's edge, mm/N: P / (c_b E'D) fading as exp(-(e/c)^2) with
    their distance e from the edge (either side) over the cover's thickness c (module docstring)."""
    e = scene.half_slot_mm - np.asarray(head_mm, dtype=float)
    return as_value(0.5 * np.exp(-((e / scene.cover_mm) ** 2)) / (BEARING * scene.E_prime_MPa * scene.depth_mm))


def cover_parts_locked_mm_per_N(scene, pad_mm, head_mm) -> tuple:
    """:func:`cover_parts_mm_per_N` once layer 1 is locked (module docstring), its pad's and its
    wall heads' half widths given: :func:`locked_link_mm_per_N`'s first two parts, the feet's
    bearing at the edge and the block's on the walls' part."""
    over, walls, _ = locked_link_mm_per_N(scene, pad_mm, head_mm)
    return over, walls + locked_bearings_mm_per_N(scene, head_mm)


def locked_bearings_mm_per_N(scene, head_mm) -> Any:
    """The feet's bearing at the slot's edge and the locked block's on the cover (module docstring)."""
    return corner_mm_per_N(scene, head_mm) + 0.5 / (BEARING * scene.E_prime_MPa * scene.depth_mm)


def locked_link_mm_per_N(scene, pad_mm, head_mm) -> tuple:
    """:func:`housing_mm_per_N`'s three parts under a locked layer 1 (module docstring): the block
    rigid, the cover a link from the slot's walls to LINK_INTO_BLOCK c inside the block's edge,
    jointed there, the feet's load reaching it at the block."""
    s = scene
    edge = np.asarray(pad_mm, dtype=float) - LINK_INTO_BLOCK * s.cover_mm  # the link's end in the block
    at_edge = np.minimum(np.asarray(head_mm, dtype=float), edge)
    alone = plain_section(s.depth_mm, s.cover_mm, s.E_prime_MPa, s.G_MPa)
    return housing_mm_per_N(s, at_edge, edge, RIGID_SECTION, alone, pad_joint=True)


def cover_parts_both_mm_per_N(scene, t_bottom_mm, pad_mm, head_mm, theta_bottom_rad, h_bottom_mm) -> tuple:
    """(:func:`cover_parts_mm_per_N`, :func:`cover_parts_locked_mm_per_N`) of the same layer 1
    (the design loop asks for both)."""
    opened = cover_parts_mm_per_N(scene, t_bottom_mm, pad_mm, head_mm, theta_bottom_rad, h_bottom_mm)
    return opened, cover_parts_locked_mm_per_N(scene, pad_mm, head_mm)


def wall_turn_Nmm_per_rad(scene, w_mm: float) -> float:
    """A slot wall's top against a turn, N mm/rad: a column w wide and H tall on a held foot, its
    top tied to the other wall's by the cover's stretch (k_s = E'cD / (L/2): both tops move out
    alike): E'I/H / (1 - (3/4) kappa / (1 + kappa)), kappa = k_s H^3 / (3 E'I); E'I/H free to sway
    (kappa = 0), 4 E'I/H held (kappa infinite)."""
    s = scene
    E, D, H = s.E_prime_MPa, s.depth_mm, s.slot_height_mm
    EI = E * D * w_mm**3 / 12.0
    kappa = (E * s.cover_mm * D / s.half_slot_mm) * H**3 / (3.0 * EI)
    return EI / H / (1.0 - 0.75 * kappa / (1.0 + kappa))


def housing_mm_per_N(scene, head_mm, pad_mm, cover_pad, cover_alone, pad_joint: bool = False) -> tuple:
    """(the cover's part over the slot: its bending and its edges' drop; the walls' part: their
    squeeze and the turn under a foot standing on them; the cover's bending alone, its ends built
    into rigid walls) of the drop per newton (P = F/2 on each side) of layer 1's wall feet at
    |x| = ``head_mm``, the mean of the two walls (module docstring). The cover is a beam of two
    sections: (E'I, kGA) ``cover_pad`` under |x| < ``pad_mm``, ``cover_alone`` beyond.

    A foot over the slot, e inside its edge: by virtual work over the half span (x from the edge,
    m(x) = P min(x, e) - M), the end slope P C1 - M B and the drop at the foot P C2 - M C1, C_j =
    int min(x, e)^j / E'I dx, B = int dx / E'I, plus shear P int_0^e dx / kGA. The end turns by
    the wall's turn (P w/2 + M) / k_w (:func:`wall_turn_Nmm_per_rad`) plus the end's own M /
    (pi/8 E'D c^2), which sets M; the wall's turn drops its inner edge by w/2 x it. A foot on
    the wall, a from its centre line: the turn P a / (k_w + 1/(B + 1/k_end)) (the cover's end
    turning into the wall's top as over the slot: the two meet as the foot crosses the edge), the
    drop a x the turn. No slot walls (height 0): the cover clamped on rigid supports.
    ``pad_joint``: the cover's section changes at |x| = ``pad_mm`` (at the slot's edge at the
    latest) through a joint that turns as its end in the wall's top does (a locked block's edge)."""
    s, P = scene, 0.5
    head = np.asarray(head_mm, dtype=float)
    L2, H, D, E = s.half_slot_mm, s.slot_height_mm, s.depth_mm, s.E_prime_MPa
    e, B, C1, C2, shear = integrals = _cover_integrals(s, head, pad_mm, cover_pad, cover_alone, pad_joint)
    bend = _bending_on_rigid_walls(s, integrals)
    if H <= 0.0:
        return bend, as_value(0.0 * head), bend
    k_end = END_BUILT_IN * E * D * s.cover_mm**2
    over = e > 0  # the foot over the slot, else on the wall
    on_wall = np.maximum(head, L2)
    over_slot, walls = [], []
    for w in s.slot_wall_widths_mm:
        k_wall = wall_turn_Nmm_per_rad(s, w)
        k = 1.0 / (1.0 / k_wall + 1.0 / k_end)
        arm = WALL_LEVER * w
        # the end's slope is the wall's turn (under P arm + M) plus the end's own (under M)
        M = np.where(over, (P * C1 - P * arm / k_wall) / (B + 1.0 / k), 0.0)
        a = (L2 + 0.5 * w) - on_wall  # a foot on the wall: its lever about the centre line
        turn = np.where(over, (P * arm + M) / k_wall, P * a / (k_wall + 1.0 / (B + 1.0 / k_end)))
        over_slot.append(P * C2 - M * C1 + shear + np.where(over, 0.5 * w * turn, 0.0))
        walls.append(P * H / (E * w * D) + np.where(over, 0.0, a * turn))
    return as_value(0.5 * (over_slot[0] + over_slot[1])), as_value(0.5 * (walls[0] + walls[1])), bend


def _bending_on_rigid_walls(scene, integrals: tuple) -> Any:
    """The cover's bending from its :func:`_cover_integrals`, its ends built into rigid walls
    (pi/8 E'D c^2), 0 for a foot on the wall; no slot walls (height 0): clamped, wherever the foot."""
    e, B, C1, C2, shear = integrals
    P = 0.5
    if scene.slot_height_mm <= 0.0:
        return as_value(P * C2 - P * C1 / B * C1 + shear)
    k_end = END_BUILT_IN * scene.E_prime_MPa * scene.depth_mm * scene.cover_mm**2
    return as_value(np.where(e > 0, P * C2 - P * C1 * C1 / (B + 1.0 / k_end) + shear, 0.0))


def _cover_integrals(scene, head: np.ndarray, pad_mm, cover_pad, cover_alone, pad_joint: bool = False) -> tuple:
    """(e, B, C1, C2, shear) of :func:`housing_mm_per_N`'s virtual work over the half span: the
    foot's distance inside the slot's edge, int dx / E'I, int min(x, e)^j / E'I dx (j = 1, 2) and
    P int_0^e dx / kGA, the section changing where the pad starts (P = 1/2); ``pad_joint``: a
    joint there of stiffness pi/8 E'D c^2 adds min(x_pad, e)^j to each (a point of 1/E'I)."""
    P, L2 = 0.5, scene.half_slot_mm
    e = np.clip(L2 - head, 0.0, L2)  # the foot's distance inside the slot's edge
    x_pad = np.clip(L2 - np.asarray(pad_mm, dtype=float), 0.0, L2)  # where the pad starts, from the edge
    (EI_in, kGA_in), (EI_out, kGA_out) = cover_pad, cover_alone

    # int_0^{L/2} min(x, e)^j / E'I dx, the section changing at x_pad, through the antiderivative
    # prim_j(x) = min(x, e)^(j+1) / (j+1) + e^j max(x - e, 0); prim_j(0) = 0 (e is finite, >= 0)
    inside_pad, inside_L2 = np.minimum(x_pad, e), np.minimum(L2, e)
    beyond_pad, beyond_L2 = np.maximum(x_pad - e, 0.0), np.maximum(L2 - e, 0.0)

    def over_half_span(j: int):
        at_pad = inside_pad ** (j + 1) / (j + 1) + e**j * beyond_pad
        return at_pad / EI_out + (inside_L2 ** (j + 1) / (j + 1) + e**j * beyond_L2 - at_pad) / EI_in

    shear = P * (np.minimum(e, x_pad) / kGA_out + np.maximum(e - x_pad, 0.0) / kGA_in)
    B, C1, C2 = over_half_span(0), over_half_span(1), over_half_span(2)
    if pad_joint:
        k = END_BUILT_IN * scene.E_prime_MPa * scene.depth_mm * scene.cover_mm**2
        at = np.minimum(x_pad, e)  # at the slot's edge where the block reaches over the wall
        B, C1, C2 = B + 1.0 / k, C1 + at / k, C2 + at * at / k
    return e, B, C1, C2, shear


def base_sway_mm_per_N(scene, tops_held: bool = False) -> float:
    """The cover's slide per newton of tangential force along x at it, mm/N: the slot's walls as a
    portal frame (module docstring), the two columns side by side; 0 without slot walls. With
    ``tops_held`` the cover is rigid: the columns end at its underside with their tops held (the
    whole-part rung's rigid-cover control, benchmarks/bench_whole_part.py --base-sway)."""
    s = scene
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    if s.slot_height_mm <= 0.0:
        return 0.0
    if tops_held:
        H, k_top = s.slot_height_mm, math.inf
    else:
        H = s.slot_height_mm + 0.5 * s.cover_mm  # to the cover's mid-plane, the frame's beam line
        k_top = END_BUILT_IN * E * D * s.cover_mm**2
    walls = [w for w in s.slot_wall_widths_mm if w > 0.0]
    if not walls:
        raise ValueError("the housing's cover stands on no slot wall: the board slot spans the base")
    stiffness = sum(
        1.0 / column_sway_mm_per_N(H, E * D * w**3 / 12.0, SHEAR_FACTOR * G * D * w, k_top, END_BUILT_IN * E * D * w**2)
        for w in walls
    )
    return 1.0 / stiffness


def column_sway_mm_per_N(H_mm, EI_Nmm2, kGA_N, k_top_Nmm_per_rad, k_root_Nmm_per_rad) -> float:
    """A Timoshenko column H tall's top sway per newton of a force along it there, mm/N, its root
    turning against ``k_root`` and its top held against a turn by ``k_top`` (the top's moment
    M = k_top phi): b0 - k_top a1^2 / (1 + k_top a2), with the top's turn per unit force
    a1 = H^2 / 2EI + H / k_root and per unit moment a2 = H / EI + 1 / k_root, b0 the free
    cantilever's H^3 / 3EI + H / kGA + H^2 / k_root. H^3 / 12EI + H / kGA held at both ends."""
    H, EI, kr = H_mm, EI_Nmm2, k_root_Nmm_per_rad
    a1 = H * H / (2.0 * EI) + H / kr
    a2 = H / EI + 1.0 / kr
    free = H**3 / (3.0 * EI) + H / kGA_N + H * H / kr
    if math.isinf(k_top_Nmm_per_rad):
        return free - a1 * a1 / a2
    return free - k_top_Nmm_per_rad * a1 * a1 / (1.0 + k_top_Nmm_per_rad * a2)
