"""The section's sway: how far the TPU plates between the layers and the housing's base let the
magnet translate under a tangential force, regime by regime (issue 44, docs/design.md 4.7, "The
section's sway: built").

Under a force along x the walls of the layer under a plate and of the layer over it both bend the
plate at their ends, in the same sense, as a storey's columns load its beam in a sway frame. A
plate 0.8 to 1.6 mm thick across 20 to 30 mm turns at those ends and the walls above it swing:
the whole-part rung finds each plate adding 0.02 to 0.07 mm/N to the magnet's slide, less its
turn's share, while its layers are open (studies/plate_slide.py), which the layers' lateral rungs,
clamped between rigid plates, cannot see.

The closed form is a plane frame (plane strain, per the part's depth D; :mod:`model.plane_frame`):

* each layer's four walls are Timoshenko beams along their centre lines, t thick, from the wall's
  end on its pad's mid line (x = the wall head's, model.load_path.layer_supports) to the
  chevron's tip (W/2 - t / (2 sin theta), h/2); their stiffness is scaled, layer by layer, so that
  the layer alone between rigid plates (the plate above held from turning) has L0's k_x
  (model.mechanics.lateral): the frame carries the plates, L0 the walls;
* the plate under a wall's footprint, t / sin(theta) wide, is rigid; the part of a wall inside its
  pad (its end to the pad's face) is not (:data:`ZONES`);
* each plate is a beam on its mid-plane as thick as the plate and the pads it carries (a layer's
  pad, t thick, under |x| < its wall heads); the wall ends are tied to it by rigid offsets and
  turn into it against model.plate_joint's fitted root spring;
* the cap is rigid, but where its own lever under a pull is asked for (member n - 1): then a
  beam with model.load_path's section of it (its pocket and its insert); the cover is a beam too,
  layer 1's roots turning into it alike, on the board slot's two walls (model.housing_base's
  portal: Timoshenko columns, their roots and tops built in), or held where there is no slot;
* a locked layer is its filled block over |x| < its wall heads: a rigid core at mid-height on a
  bed of springs to the plates under and over it (the block's shear and squeeze, the oedometric
  modulus along z), on which a TPU plate bends; rigid only where the walls are scaled to L0 (the
  layers alone between rigid plates, :func:`wall_factors`).

A force of 1 N along +x at the top face. What a plate adds is its translation: the magnet's slide
with that plate in TPU less with it rigid, less the share of the cap's turn about the plate's
mid-plane (mst's stack already turns the plates with their layers), summed over the plates, each
alone in TPU (the rung's measure); the base's the same, about the cover's mid-plane. Along y (the
depth) nothing is added: the frame is the section's. Against the rung's measure
(studies/plate_frame.py) the plates are 0.88 to 1.22 times it on same-layer designs, 0.68 to 1.18
between open layers on the bundled ones and 1.21 to 1.73 beside a locked layer (0.43 to 0.84 with
the block rigid); the base is 0.83 to 1.04 in every regime of the bundled designs (0.76 to 1.11 with
the block and the walls' ends rigid), where the column form alone
(model.housing_base.base_sway_mm_per_N) was 0.50 to 1.35. The same solves, with a pure moment at
the cap beside the pull, give the members' turn ratio (:class:`SectionRegimes`) that
:mod:`mst_cli.model.counter_turn` takes. Pure numpy, no I/O.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from mst_cli.model.beams import SHEAR_FACTOR, section_EI_kGA
from mst_cli.model.cell import wall_centreline_length_mm
from mst_cli.model.housing_base import END_BUILT_IN
from mst_cli.model.load_path import CELL_KEYS, layer_supports, member_scene
from mst_cli.model.mechanics.lateral import lateral_stiffness_N_per_mm
from mst_cli.model.plane_frame import Frame
from mst_cli.model.plate_joint import root_spring_Nmm_per_rad

RIGID = 1e5  # a rigid member's factor on E'D: the figures within 0.1 % of 1e6's, the system better conditioned
# the rigid zones (under the walls' footprints on the plates, the walls' ends inside their pads):
# the first only. With the walls' ends rigid too (the form until late on 2026-12-02) the frame's plates
# read 0.228 rms log off the rung's translations against 0.203, its base 0.125 against 0.121
# (studies/plate_frame.py --check), and mst's turn per tangential newton on the forward design
# +36 / +18 / -14 % off the rung against +8 / +11 / -9 % (docs/design.md 4.7, "The walls' ends in
# their pads, elastic")
ZONES = (True, False)


@dataclass(frozen=True)
class StackSection:
    """The section the frame is built on: the layers bottom first (theta in rad, t, h, their wall
    heads' x and bottoms' z, mm; L0's k_x, N/mm) and the part's dimensions (mm), the TPU's plane-
    strain modulus and shear modulus (MPa)."""

    theta_rad: np.ndarray
    t_mm: np.ndarray
    h_mm: np.ndarray
    head_mm: np.ndarray
    bottom_mm: np.ndarray
    k_x_N_per_mm: np.ndarray
    width_mm: float
    depth_mm: float
    plate_mm: float
    cover_mm: float
    cap_above_stack_mm: float  # the cap over the top layer's top pad
    z_magnet_mm: float  # the magnet's centre
    E_prime_MPa: float
    G_MPa: float
    half_slot_mm: float = 0.0  # the board slot under the cover: its half width
    slot_wall_widths_mm: tuple[float, float] = (0.0, 0.0)  # its side walls (left, right)
    slot_height_mm: float = 0.0  # from the slot's floor to the cover's underside; 0: no slot (the base rigid)
    cap_EI_Nmm2: float = 0.0  # the cap's section with its pocket and insert (model.load_path's); 0: TPU plain
    cap_kGA_N: float = 0.0


def stack_section(geometry, material) -> StackSection:
    """The :class:`StackSection` of a part (a model.assembly.SensorGeometry and its material)."""
    s = member_scene(geometry, material)
    theta, t, h = (np.array([getattr(c, k) for c in geometry.layers], dtype=float) for k in CELL_KEYS)
    _, head, _, _ = layer_supports(s, theta, t, h)
    k_x = np.array([lateral_stiffness_N_per_mm(c, material)[0] for c in geometry.layers])
    z_magnet = geometry.z_magnet_bottom_mm + 0.5 * geometry.magnet.thickness_mm
    return StackSection(
        theta, t, h, np.asarray(head, dtype=float), np.array(geometry.layer_bottoms_mm), k_x, s.width_mm, s.depth_mm,
        s.plate_mm, s.cover_mm, s.cap_above_stack_mm, z_magnet, s.E_prime_MPa, s.G_MPa, s.half_slot_mm,
        s.slot_wall_widths_mm, s.slot_height_mm, *_cap_section(s, float(t[-1])),
    )  # fmt: skip


def _cap_section(s, t_top_mm: float) -> tuple[float, float]:
    """(E'I, kGA) of the cap over the top layer's pad ``t_top_mm`` thick, with its magnet pocket
    and insert: model.load_path's own cap section (scene ``s``, a MemberScene)."""
    z_pocket = t_top_mm + s.pocket_floor_mm
    EI, kGA = section_EI_kGA(
        s.depth_mm, t_top_mm + s.cap_above_stack_mm, s.E_prime_MPa, s.G_MPa, s.pocket_width_mm,
        (z_pocket, z_pocket + s.pocket_depth_mm), s.insert, t_top_mm + s.insert_above_pad_mm,
    )  # fmt: skip
    return float(EI), float(kGA)


def member_planes_mm(sec: StackSection) -> np.ndarray:
    """(n + 1,) the heights of the cover's, the plates' and the cap's mid-planes (the part's frame,
    as ``bottom_mm``): where each member turns."""
    return np.array(_beam_z_mm(sec))


def _beam_z_mm(sec: StackSection) -> list[float]:
    """The mid-planes of the cover (0), the plates (1 .. n - 1) and the cap's node (n)."""
    cap = sec.bottom_mm[-1] + sec.h_mm[-1] + 0.5 * sec.cap_above_stack_mm
    return [sec.bottom_mm[0] - 0.5 * sec.cover_mm, *(sec.bottom_mm[1:] - 0.5 * sec.plate_mm), cap]


def frame_pull(
    sec: StackSection, locked=(), tpu_plate: int | None = None, walls=None, guided: bool = False,
    zones: tuple[bool, bool] = ZONES, roots: bool = True, rigid_blocks: bool = False,
) -> tuple[float, float]:  # fmt: skip
    """(the magnet's slide, the cap's turn) per newton along +x at the top face: the first two of
    :func:`frame_response` (its arguments)."""
    slide, turn, _ = frame_response(sec, locked, tpu_plate, walls, guided, zones, roots, rigid_blocks)
    return slide, turn


def frame_response(
    sec: StackSection, locked=(), tpu_plate: int | None = None, walls=None, guided: bool = False,
    zones: tuple[bool, bool] = ZONES, roots: bool = True, rigid_blocks: bool = False,
) -> tuple[float, float, float]:  # fmt: skip
    """(the magnet's slide along +x, mm, the cap's turn, counter-clockwise from x to z, rad) per
    newton along +x at the top face, and the cap's turn per N mm of a pure moment (counter-
    clockwise) there, both on one factorisation, with layers ``locked`` (indices from 0) filled, plate
    ``tpu_plate`` (from 0: the plate over layer j; -1: the housing's base) in TPU and every other
    member rigid, the walls' stiffness times ``walls`` (n,) [1], the cap held from turning when ``guided``; ``zones``
    (under the walls' footprints on the plates, the walls' ends in their pads), ``roots``: the
    rigid zones and the root springs (module docstring; studies/plate_frame.py switches them);
    ``rigid_blocks``: a locked layer a rigid tie between its plates (the layers alone between
    rigid plates, :func:`wall_factors`), not its elastic block (:func:`_block`)."""
    n, s = len(sec.theta_rad), sec
    rigid = RIGID * s.E_prime_MPa * s.depth_mm
    f = Frame(tie_N_per_mm=rigid)
    beam_z = _beam_z_mm(s)
    L = wall_centreline_length_mm(s.theta_rad, s.t_mm, s.h_mm)
    k_root = root_spring_Nmm_per_rad(s.theta_rad, s.t_mm, L, s.depth_mm, s.E_prime_MPa)
    walls = np.ones(n) if walls is None else np.asarray(walls, dtype=float)
    blocks = () if rigid_blocks else tuple(locked)
    beams = [_plate_beam(f, s, j, z, locked, tpu_plate, zones, blocks) for j, z in enumerate(beam_z)]
    if tpu_plate == -1 and s.slot_height_mm > 0.0:
        _base(f, s, beams[0], beam_z[0])
    else:
        for node in beams[0].values():
            f.hold(node)
    for i in range(n):
        if i in blocks:
            _block(f, s, i, beams, tpu_plate)
            continue
        if i in locked:  # the filled block ties the two plates
            f.beam(beams[i][0.0], beams[i + 1][0.0], rigid, rigid, math.inf)
            continue
        _walls(f, s, i, beams, walls[i], k_root[i], tpu_plate, zones, roots)
    cap = beams[n][0.0]
    if guided:
        f.hold(cap, (2,))
    z_top = s.bottom_mm[-1] + s.h_mm[-1] + s.cap_above_stack_mm
    pull, moment = f.solve_cases([{3 * cap: 1.0, 3 * cap + 2: -(z_top - beam_z[n])}, {3 * cap + 2: 1.0}])
    turn = pull[3 * cap + 2]
    return float(pull[3 * cap] - turn * (s.z_magnet_mm - beam_z[n])), float(turn), float(moment[3 * cap + 2])


def _plate_beam(f: Frame, s: StackSection, j: int, z: float, locked, tpu_plate, zones, blocks=()) -> dict:
    """Beam j (0 the cover, n the cap) into ``f`` on its mid-plane z: {x: node} at its stations.
    Rigid but where it is plate ``tpu_plate``, outside the open walls' footprints (``zones[0]``)
    and outside any filled block beside it (a locked layer has no walls of its own) unless that
    block is elastic (``blocks``, :func:`_block`): then the plate over it bends on it, its
    stations the block's."""
    n, E, G, D = len(s.theta_rad), s.E_prime_MPa, s.G_MPa, s.depth_mm
    layers = [i for i in (j - 1, j) if 0 <= i < n]  # under beam j (its heads), over it (its feet)
    half_print = 0.5 * s.t_mm / np.sin(s.theta_rad)  # half a wall's footprint on its pad
    xs, zone = {0.0}, []
    for i in layers:
        for x in (-float(s.head_mm[i]), float(s.head_mm[i])):
            xs.add(x)
            if zones[0] and i not in locked:
                zone.append((x - half_print[i], x + half_print[i]))
                xs |= {x - half_print[i], x + half_print[i]}
    if _is_tpu(j, n, tpu_plate):  # it bends on the blocks beside it
        for i in set(layers) & set(blocks):
            xs |= {float(x) for x in block_stations_mm(s, i)}
    base = j == 0 and tpu_plate == -1
    if base:
        xs |= {-s.half_slot_mm, s.half_slot_mm}
    stations = {x: f.node(x, z) for x in sorted(xs)}
    tpu = _is_tpu(j, n, tpu_plate)  # j = n: the cap (tpu_plate n - 1)
    ordered = sorted(stations)
    for xa, xb in zip(ordered[:-1], ordered[1:]):
        mid = 0.5 * (xa + xb)
        own = s.cover_mm if j == 0 else s.cap_above_stack_mm if (j == n and tpu) else s.plate_mm
        # a closed layer's pads are its block's (_block), not the plate's
        thick = own + sum(s.t_mm[i] for i in layers if abs(mid) < s.head_mm[i] and i not in blocks)
        blocked = any(i in locked and i not in blocks and abs(mid) < s.head_mm[i] for i in layers)
        over_wall = base and abs(mid) > s.half_slot_mm  # the cover over the slot's walls
        if over_wall and s.half_slot_mm in (abs(xa), abs(xb)):
            continue  # it rides on the wall's top, not on the cover's end (_base ties it)
        blocked |= over_wall
        k = RIGID if (not tpu or blocked or any(a <= mid <= b for a, b in zone)) else 1.0
        if j == n and tpu and s.cap_EI_Nmm2 > 0.0:
            f.beam(stations[xa], stations[xb], k * E * thick * D, k * s.cap_EI_Nmm2, k * s.cap_kGA_N)
            continue
        f.beam(
            stations[xa], stations[xb], k * E * thick * D, k * E * D * thick**3 / 12.0, k * SHEAR_FACTOR * G * thick * D
        )
    return stations


BLOCK_STATIONS = 48  # across a block (docs/design.md 4.7): the plates' sway within 0.7 % of 192's


def block_stations_mm(s: StackSection, i: int) -> np.ndarray:
    """The x of the stations across locked layer i's block, |x| <= its wall heads."""
    # finer at the edges, where a wall's foot stands; sin gives 0 and +-1 exactly (the beams' keys)
    return s.head_mm[i] * np.sin(np.linspace(-0.5 * math.pi, 0.5 * math.pi, BLOCK_STATIONS + 1))


def oedometric_modulus_MPa(E_prime_MPa: float, G_MPa: float) -> float:
    """The constrained (oedometric) modulus E (1 - nu) / ((1 + nu) (1 - 2 nu)) of the material
    whose plane-strain modulus E' = E / (1 - nu^2) and shear modulus G = E / (2 (1 + nu)) are given:
    a layer bonded between plates and wide against its height cannot widen as it is squeezed."""
    nu = 1.0 - 2.0 * G_MPa / E_prime_MPa  # E'/G = 2 / (1 - nu)
    return 2.0 * G_MPa * (1.0 - nu) / (1.0 - 2.0 * nu)


def _block(f: Frame, s: StackSection, i: int, beams, tpu_plate) -> None:
    """Locked layer i as its filled block (the closed hexagon, |x| < its wall heads): a rigid core
    at its mid-height, tied to the plate under it and the plate over it by a bed of springs, each
    station's strip dx wide a column h/2 tall: M D dx / (h/2) along z (M the oedometric modulus,
    :func:`oedometric_modulus_MPa`), G D dx / (h/2) along x; taller by half the plate's thickness
    where that plate is TPU (its own squeeze and shear through its thickness), whose stations
    then bend on the bed; a rigid plate takes the bed at its centre, rigidly. In series the two
    halves give the block's shear G D 2 head / h (model.mechanics.lateral's closed block) and its
    rocking M D (2 head)^3 / (12 h); each spring's two ends are one point on the block's face."""
    n, G, D = len(s.theta_rad), s.G_MPa, s.depth_mm
    oedometric = oedometric_modulus_MPa(s.E_prime_MPa, G)
    xs = block_stations_mm(s, i)
    dx = np.diff(np.r_[xs[0], 0.5 * (xs[1:] + xs[:-1]), xs[-1]])  # each station's strip
    z_core = s.bottom_mm[i] + 0.5 * s.h_mm[i]
    core = f.node(0.0, z_core)
    for j, z_face in ((i, s.bottom_mm[i]), (i + 1, s.bottom_mm[i] + s.h_mm[i])):
        tpu = _is_tpu(j, n, tpu_plate)
        own = s.cover_mm if j == 0 else s.plate_mm
        tall = 0.5 * s.h_mm[i] + (0.5 * own if tpu else 0.0)
        z_plate = f.nodes[beams[j][0.0]][1]
        for x, w in zip(xs, dx):
            x = float(x)
            # both ends of each spring at one point, on the block's face: a rigid turn of the whole
            # stretches none of them (springs between points apart would resist it)
            node, at = (beams[j][x], (0.0, z_face - z_plate)) if tpu else (beams[j][0.0], (x, z_face - z_plate))
            f.link(core, node, G * D * w / tall, oedometric * D * w / tall, (x, z_face - z_core), at)


def _is_tpu(j: int, n: int, tpu_plate) -> bool:
    """Whether beam j (0 the cover, n the cap) is the member ``tpu_plate`` in TPU (the frame's
    numbering: -1 the base, j - 1 the plate over layer j - 1, n - 1 the cap)."""
    return (0 < j <= n and j - 1 == tpu_plate) or (j == 0 and tpu_plate == -1)


def _base(f: Frame, s: StackSection, cover: dict, z_cover: float) -> None:
    """The housing's base under the cover's beam ``cover`` ({x: node} on its mid-plane z_cover),
    as model.housing_base's portal frame (studies/base_frame.py): each slot wall a Timoshenko
    column from the slot's floor to the cover's underside, its root built into the floor
    (pi/8 E'D w^2) and its top, by a rigid offset to the cover's end at the wall's inner edge,
    into the cover (pi/8 E'D c^2); the cover beyond the slot's edges rides on the walls' tops."""
    E, G, D, L2, c = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.half_slot_mm, s.cover_mm
    rigid = RIGID * E * D
    z_root = z_cover - 0.5 * c - s.slot_height_mm
    for sign, w in zip((-1.0, 1.0), s.slot_wall_widths_mm):
        x = sign * (L2 + 0.5 * w)
        ground, root, top = f.node(x, z_root), f.node(x, z_root), f.node(x, z_cover - 0.5 * c)
        f.hold(ground)
        f.spring(ground, root, END_BUILT_IN * E * D * w * w)
        f.beam(root, top, E * w * D, E * D * w**3 / 12.0, SHEAR_FACTOR * G * w * D)
        edge = f.node(sign * L2, z_cover)
        f.beam(top, edge, rigid, rigid, math.inf)
        f.spring(edge, cover[sign * L2], END_BUILT_IN * E * D * c * c)
        beyond = [x_ for x_ in cover if sign * x_ > L2]
        if beyond:  # the cover over the wall: rides on its top
            f.beam(edge, cover[min(beyond, key=abs)], rigid, rigid, math.inf)


def _walls(f: Frame, s: StackSection, i: int, beams, factor, k_root, tpu_plate, zones, roots: bool) -> None:
    """Layer i's four walls, each from its end on a pad to the chevron's tip, into ``f``."""
    n, E, G, D, t = len(s.theta_rad), s.E_prime_MPa, s.G_MPa, s.depth_mm, s.t_mm[i]
    rigid = RIGID * E * D
    z0, tip_x = s.bottom_mm[i], 0.5 * s.width_mm - 0.5 * t / math.sin(s.theta_rad[i])
    for sign in (-1.0, 1.0):
        x = sign * s.head_mm[i]
        tip = f.node(sign * tip_x, z0 + 0.5 * s.h_mm[i])
        for j, z_end in ((i, z0 + 0.5 * t), (i + 1, z0 + s.h_mm[i] - 0.5 * t)):
            tpu = _is_tpu(j, n, tpu_plate)  # the cover's, the cap's too
            offset, end = f.node(x, z_end), f.node(x, z_end)
            f.beam(beams[j][float(x)], offset, rigid, rigid, math.inf)
            f.spring(offset, end, k_root if (roots and tpu) else rigid)
            start = end
            if zones[1]:  # the wall's end inside its pad, from the pad's mid line to its face
                frac = t / (s.h_mm[i] - t)
                (xe, ze), (xt, zt) = f.nodes[end], f.nodes[tip]
                start = f.node(xe + frac * (xt - xe), ze + frac * (zt - ze))
                f.beam(end, start, rigid, rigid, math.inf)
            f.beam(start, tip, factor * E * t * D, factor * E * D * t**3 / 12.0, factor * SHEAR_FACTOR * G * t * D)


def wall_factors(sec: StackSection, zones: tuple[bool, bool] = ZONES) -> np.ndarray:
    """(n,) the factor on each layer's walls that gives the frame's layer alone between rigid
    plates, the plate above held from turning, L0's k_x. The slide is c_w / f + c_r in the
    factor f (c_r: the rigid members' own), so two solves fix it."""
    n = len(sec.theta_rad)
    out = []
    for i in range(n):
        others = tuple(j for j in range(n) if j != i)
        once, twice = (
            frame_pull(sec, others, None, np.full(n, f), guided=True, zones=zones, roots=False, rigid_blocks=True)[0]
            for f in (1.0, 2.0)
        )
        walls = 2.0 * (once - twice)
        out.append(walls / (1.0 / sec.k_x_N_per_mm[i] - (once - walls)))
    return np.array(out)


@dataclass(frozen=True)
class MemberMotions:
    """What each of some members alone in TPU adds, per newton along +x at the top face (module
    docstring): the magnet's translation (mm/N), the cap's turn (rad/N, counter-clockwise from x
    to z) and the turn the pull's moment about the member's mid-plane alone would give it (rad/N),
    each less all rigid."""

    translation_mm_per_N: np.ndarray
    turn_rad_per_N: np.ndarray
    moment_turn_rad_per_N: np.ndarray


def member_motions(
    sec: StackSection,
    members,
    locked=(),
    walls=None,
    zones: tuple[bool, bool] = ZONES,
    roots: bool = True,
    rigid_blocks: bool = False,
) -> MemberMotions:
    """:class:`MemberMotions` of ``members`` (-1 the housing's base, j >= 0 the plate over layer
    j, n - 1 the cap), each alone in TPU, with layers ``locked`` filled; the all-rigid solve once
    for them all."""
    walls = wall_factors(sec, zones) if walls is None else walls
    beam_z = _beam_z_mm(sec)
    z_top = sec.bottom_mm[-1] + sec.h_mm[-1] + sec.cap_above_stack_mm
    slide0, turn0, per_moment0 = frame_response(
        sec, locked, None, walls, zones=zones, roots=roots, rigid_blocks=rigid_blocks
    )
    out = []
    for j in members:
        if j == -1 and sec.slot_height_mm <= 0.0:  # no slot: the base is solid
            out.append((0.0, 0.0, 0.0))
            continue
        slide, turn, per_moment = frame_response(
            sec, locked, j, walls, zones=zones, roots=roots, rigid_blocks=rigid_blocks
        )
        arm = sec.z_magnet_mm - beam_z[j + 1]
        # a turn counter-clockwise moves the magnet dz above the member by -turn dz: not a translation;
        # the pull's moment about the member's mid-plane is -(z_top - z) per newton
        out.append(
            (
                (slide - slide0) + (turn - turn0) * arm,
                turn - turn0,
                -(z_top - beam_z[j + 1]) * (per_moment - per_moment0),
            )
        )
    return MemberMotions(*(np.array(col, dtype=float) for col in zip(*out)))


def member_translations_mm_per_N(
    sec: StackSection, members, locked=(), walls=None, zones: tuple[bool, bool] = ZONES, roots: bool = True
) -> np.ndarray:
    """(len(members),) what each of ``members`` alone in TPU adds to the magnet's translation, mm
    per newton along x (:func:`member_motions`)."""
    return member_motions(sec, members, locked, walls, zones, roots).translation_mm_per_N


def plate_translations_mm_per_N(
    sec: StackSection, locked=(), walls=None, zones: tuple[bool, bool] = ZONES, roots: bool = True
) -> np.ndarray:
    """(n - 1,) what each plate alone in TPU adds (:func:`member_translations_mm_per_N`)."""
    return member_translations_mm_per_N(sec, range(len(sec.theta_rad) - 1), locked, walls, zones, roots)


def base_translation_mm_per_N(
    sec: StackSection, locked=(), walls=None, zones: tuple[bool, bool] = ZONES, roots: bool = True
) -> float:
    """What the housing's base alone in TPU adds (:func:`member_translations_mm_per_N`); 0 without
    a slot."""
    return float(member_translations_mm_per_N(sec, [-1], locked, walls, zones, roots)[0])


def base_turn_per_moment_rad_per_Nmm(sec: StackSection, locked=(), walls=None) -> float:
    """What the housing's base alone in TPU adds to the cap's turn per N mm of a pure moment at
    the cap (turns counter-clockwise per counter-clockwise moment), rad/(N mm), with layers
    ``locked`` (indices from 0) filled: the cover on the slot's walls as a portal; 0 without a slot."""
    if sec.slot_height_mm <= 0.0:
        return 0.0
    walls = wall_factors(sec) if walls is None else walls
    rigid = frame_response(sec, locked, None, walls)[2]
    return frame_response(sec, locked, -1, walls)[2] - rigid


@functools.lru_cache(maxsize=32)
def locked_base_turn_rad_per_Nmm(geometry, material) -> float | None:
    """:func:`base_turn_per_moment_rad_per_Nmm` of a part (a SensorGeometry in a Material) with
    its layer 1 locked, kept per part (the tilt rung asks for it with every stack); None without
    a slot (the closed form's cover stands)."""
    sec = stack_section(geometry, material)
    turn = base_turn_per_moment_rad_per_Nmm(sec, (0,))
    return turn if sec.slot_height_mm > 0.0 else None


@dataclass(frozen=True)
class SectionRegimes:
    """Per regime (regime r: the first r layers of a lock order locked), per newton along x: the
    base's and the plates' translation (mm/N), and the members' turn ratio: what the plates and
    the base turn the cap under the pull over what the pull's moment alone would turn them (1
    where they turn nothing). The walls' end moments, carrying the pull's shear into the plates,
    turn them against the moment's couple: the frame's counter-turn. ``member_arm_mm`` (regimes,
    n + 1), per member (the base, the plates over layers 0 .. n - 2, the cap): the pull's lever on
    it, its turn under the pull over its turn per N mm of a pure moment, mm; its own depth under
    the top face where the moment turns it less than TURN_FLOOR (it turns with the moment about its
    own mid-plane)."""

    base_sway_mm_per_N: np.ndarray
    plate_sway_mm_per_N: np.ndarray
    member_turn_ratio: np.ndarray
    member_arm_mm: np.ndarray


TURN_FLOOR_RAD_PER_N = 1e-9  # members that turn less than this under the moment: no ratio (1)


def section_regimes(sec: StackSection, lock_order) -> SectionRegimes:
    """:class:`SectionRegimes` of the section ``sec`` for the layers locking in ``lock_order``
    (layer indices, first to lock first)."""
    walls = wall_factors(sec)
    order = [int(i) for i in lock_order]
    n = len(sec.theta_rad)
    members = [-1, *range(n)]  # the base, the plates, the cap
    z_top = sec.bottom_mm[-1] + sec.h_mm[-1] + sec.cap_above_stack_mm
    depth = z_top - np.array(_beam_z_mm(sec))  # the base's, the plates', the cap's mid-planes under the top face
    base, plates, ratio, arms = [], [], [], []
    for r in range(len(order) + 1):
        m = member_motions(sec, members, order[:r], walls)
        base.append(m.translation_mm_per_N[0])
        plates.append(m.translation_mm_per_N[1:n].sum())
        moment = m.moment_turn_rad_per_N[:n].sum()
        ratio.append(m.turn_rad_per_N[:n].sum() / moment if abs(moment) > TURN_FLOOR_RAD_PER_N else 1.0)
        # moment_turn is the moment's turn times the depth: turn / moment_turn x depth is the arm
        turns = np.abs(m.moment_turn_rad_per_N) > TURN_FLOOR_RAD_PER_N
        own = np.where(turns, m.turn_rad_per_N / np.where(turns, m.moment_turn_rad_per_N, 1.0), 1.0) * depth
        arms.append(own)
    return SectionRegimes(np.array(base), np.array(plates), np.array(ratio), np.array(arms))
