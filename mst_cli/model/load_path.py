"""The part's load path: the compliance of the members that are not layers, in closed form.

Rung L0 (and L1, L2) model the layers between rigid plates. The exported part's cap, the plates
between layers and the housing's cover are TPU too (docs/design.md section 4.6). A centred
press reaches the layers through them, so the magnet's drop relative to the chip is the
layers' compression plus each member's bending:

* **cap** -- the cap (pocket floor, magnet pocket, cap top) bonded to the top layer's top pad:
  a beam of depth b = D across the top layer's two wall heads, loaded by the press's contact
  patch (a centred strip ``patch_mm`` wide, all of the depth). The section is the pad plus the
  cap, less the magnet pocket over its width 2r (the magnet's own stiffness is left out: an
  upper bound on the compliance, by the pocket's share of the section); the top layer's roots
  turn into it as into a plate (model.plate_joint.cap_root_mm_per_N).
* **plates** -- each plate bonded to the pads above and below it, loaded by the upper layer's
  wall feet, held by the lower layer's wall heads, its turn resisted by both layers' walls; when
  they stand at the same x the load goes straight down and the plate does not bend; past the
  nearer pair only the outer layer's pad is bonded to it. Over locked layers, model.past_lock.
* **cover and slot walls** (the housing's base) -- the cover over the board's slot, bonded to
  layer 1's bottom pad and loaded by its wall feet, and the slot's two walls under it: the walls'
  squeeze and turn, the cover's bending with its ends built into them, layer 1's roots turning
  into it, and once layer 1 is locked its block, rigid, on a short link of the cover to the
  walls and bearing on it (model.housing_base). The side walls carry it over the whole depth
  but at the cable windows, which end just above their sockets (docs/design.md section 10): the
  cover spans a window's 6-7 mm along the depth with wall on both sides, no cantilever.

Each beam is a plane-strain Timoshenko beam (E' = E/(1 - nu^2) in bending, G in shear, shear
factor 5/6); the cap's supports are simply supported (the default: the wall heads turn with the
slender walls) or clamped (the stiff bound). Pure numpy, no I/O.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mst_cli.model.beams import (
    END_BUILT_IN,
    end_fixity,
    offset_pair_mm_per_N,
    strip_bending_pair_mm_per_N,
    strip_shear_mm_per_N,
)
from mst_cli.model.beams import SHEAR_FACTOR as SHEAR_FACTOR  # the section's and one-support forms, re-exported
from mst_cli.model.beams import section_EI_kGA as section_EI_kGA
from mst_cli.model.beams import strip_bending_mm_per_N as strip_bending_mm_per_N
from mst_cli.model.beams import two_load_mm_per_N as two_load_mm_per_N
from mst_cli.model.cell import pad_half_width_mm, wall_centreline_length_mm
from mst_cli.model.housing_base import cover_parts_both_mm_per_N
from mst_cli.model.housing_base import cover_parts_locked_mm_per_N as cover_parts_locked_mm_per_N
from mst_cli.model.housing_base import cover_parts_mm_per_N as cover_parts_mm_per_N
from mst_cli.model.housing_base import housing_mm_per_N as housing_mm_per_N
from mst_cli.model.past_lock import by_regime, scene_locked_plates_mm_per_N
from mst_cli.model.plate_joint import (
    cap_root_mm_per_N,
    joint_scene,
    layer_joints_mm_per_N,
    plates_beside,
    root_joint_mm_per_N,
)
from mst_cli.model.stack import contact_force_N
from mst_cli.model.wall_thrust import scene_thrust_mm_per_N

# a fingertip pressed on the face: a contact patch about 6 mm wide (the width the issue's
# independent check presses over); the press runs the whole depth (a strip, in plane strain)
FINGERTIP_PATCH_MM = 6.0
SUPPORTS = ("simple", "clamped")
# a wall's far end (the hexagon's side vertex) for its restraint of the pad's turn, c in c EI/L:
# by the cell's symmetry the vertex does not turn; it either moves freely across the wall (1, the
# soft bound: the cell's vertices spread as it is pressed) or is held (4, the stiff bound)
WALL_FAR_END = {"simple": 1.0, "clamped": 4.0}
CELL_KEYS = ("theta_rad", "t_mm", "h_mm")  # a cell's attributes the kernels take, in their order


def wall_head_restraint_Nmm_per_rad(theta_rad, t_mm, h_mm, depth_mm, E_prime_MPa, support: str) -> np.ndarray:
    """A layer's wall resisting the turn of the pad at its head: a beam of the wall's centre-line
    length L_w and thickness t, c E'I/L_w with its far end (the hexagon's side vertex, where it
    meets the other wall, kept from turning by the cell's symmetry) free to move across the wall
    (c = 1, ``support`` "simple": the soft bound) or held (c = 4, "clamped": the stiff bound)."""
    c = WALL_FAR_END[support]
    t = np.asarray(t_mm, dtype=float)
    return c * E_prime_MPa * depth_mm * t**3 / 12.0 / wall_centreline_length_mm(theta_rad, t, h_mm)


@dataclass(frozen=True)
class Insert:
    """A stiff plate bonded in the cap over the whole face (a load-path option, section 4.6)."""

    name: str
    modulus_MPa: float
    poisson_ratio: float
    thickness_mm: float
    z_mm: float = 0.0  # its underside above the cap beam's bottom (the top pad's underside)
    depth_mm: float | None = None  # along the depth (y); None: the whole depth D

    @property
    def shear_modulus_MPa(self) -> float:
        return self.modulus_MPa / (2.0 * (1.0 + self.poisson_ratio))


def wall_head_x_mm(cell) -> float:
    """Where a layer's walls meet its pad: the mid-point of the pad's outer (p) and inner
    (p - t tan(theta/2)) corners, the beam's support."""
    return 0.5 * (cell.p_mm + cell.p_inner_mm)


@dataclass(frozen=True)
class Members:
    """Compliance of each member that is not a layer, mm/N, for a centred press."""

    cap_mm_per_N: float
    plates_mm_per_N: tuple[float, ...]  # bottom to top, one per plate
    cover_mm_per_N: float
    patch_mm: float
    support: str
    # the cover's bending over the slot (part of cover_mm_per_N), which stops when the cover has
    # dropped the air under it onto the board (cover_travel_mm; inf: never)
    cover_contact_mm_per_N: float = 0.0
    cover_travel_mm: float = math.inf
    # per regime of the part, what the whole-part rung adds to the closed form above (mm/N, may be
    # negative; mechanics.whole_part.section_correction, docs/design.md 4.7); (): the closed form alone
    regime_extra_mm_per_N: tuple[float, ...] = ()
    # each layer's walls' joints with the plates beside it (model.plate_joint), bottom to top: they
    # close that layer's cavity and stop when it locks; (): none (the layer rungs' rigid plates)
    joints_mm_per_N: tuple[float, ...] = ()
    # each plate over a locked layer under an open one, past its closed form (model.past_lock):
    # it moves while the layer under it is locked and the one above open; (): none
    locked_plates_mm_per_N: tuple[float, ...] = ()
    # the cover and its part over the slot once layer 1 is locked on it, its closed block on the
    # cover's link to the walls (cover_parts_locked_mm_per_N); None: as before the lock
    cover_locked_mm_per_N: float | None = None
    cover_contact_locked_mm_per_N: float | None = None
    # each plate while the layer under that one is locked too (model.past_lock.over_two_locked_mm_per_N,
    # the bottom plate's as above); (): the same as locked_plates_mm_per_N
    two_locked_plates_mm_per_N: tuple[float, ...] = ()
    # of each of the two above, the top layer's walls' thrust (model.wall_thrust) and the feet's
    # press into the locked block's edge (model.past_lock.foot_press_mm_per_N): a centred press's
    # terms, which ride with no member's lever (model.part_laws.unit_members); (): none
    thrust_mm_per_N: tuple[float, ...] = ()
    press_mm_per_N: tuple[float, ...] = ()

    @property
    def cover_contact(self) -> tuple[float, float, float, float]:
        """(the cover's part over the slot, mm/N; the air it closes, mm; that part once layer 1 is
        locked; the change of the whole cover at that lock, mm/N): model.stack's contact."""
        C, C_locked = self.cover_contact_mm_per_N, self.cover_contact_locked_mm_per_N
        locked = self.cover_mm_per_N if self.cover_locked_mm_per_N is None else self.cover_locked_mm_per_N
        return C, self.cover_travel_mm, C if C_locked is None else C_locked, locked - self.cover_mm_per_N

    @property
    def total_mm_per_N(self) -> float:
        return self.cap_mm_per_N + sum(self.plates_mm_per_N) + sum(self.joints_mm_per_N) + self.cover_mm_per_N

    @classmethod
    def rigid(cls, patch_mm: float = FINGERTIP_PATCH_MM, n_plates: int = 0) -> Members:
        """The members of the layer rungs: no bending (L0/L2 exactly)."""
        return cls(0.0, (0.0,) * n_plates, 0.0, patch_mm, "rigid")


@dataclass(frozen=True)
class MemberScene:
    """Everything the members' compliance depends on besides the cells: the part's fixed
    dimensions (mm), the TPU's plane-strain bending modulus and shear modulus (MPa), the
    insert, the press and the supports. One per design problem: the design loop evaluates
    thousands of candidate stacks against it in one numpy call (:func:`member_compliances`)."""

    depth_mm: float
    width_mm: float
    cap_above_stack_mm: float  # the cap over the top layer's top pad: pocket floor, pocket, cap top
    pocket_floor_mm: float  # the pocket's floor above the top pad
    pocket_width_mm: float  # 2 x the pocket's radius
    pocket_depth_mm: float
    plate_mm: float
    cover_mm: float
    half_slot_mm: float  # the board slot's half width: the cover's span over it
    E_prime_MPa: float
    G_MPa: float
    insert: Insert | None = None
    insert_above_pad_mm: float = 0.0  # the insert's underside above the top pad's top face
    patch_mm: float = FINGERTIP_PATCH_MM
    support: str = "simple"
    # the slot's side walls (columns from the slot's floor to the cover, out to the base's
    # sides): widths (left, right) and height, mm; 0: rigid (the layers' own rungs)
    slot_wall_widths_mm: tuple[float, float] = (0.0, 0.0)
    slot_height_mm: float = 0.0
    cover_air_mm: float = math.inf  # between the cover and the board's tallest part: its bending's travel


def member_scene(
    geometry, material, patch_mm: float = FINGERTIP_PATCH_MM, support: str = "simple", insert: Insert | None = None
) -> MemberScene:
    """The :class:`MemberScene` of ``geometry`` (a SensorGeometry) in ``material``; ``insert``
    [default: the geometry's own, when it declares one]."""
    if support not in SUPPORTS:
        raise ValueError(f"support must be one of {SUPPORTS}")
    insert = getattr(geometry, "insert", None) if insert is None else insert
    top = geometry.layers[-1]
    x0, x1 = geometry.board_slots[0].x_mm
    return MemberScene(
        depth_mm=geometry.depth_mm,
        width_mm=top.width_mm,
        cap_above_stack_mm=geometry.total_height_mm - geometry.z_stack_top_mm,
        pocket_floor_mm=geometry.housing.pocket_floor_mm,
        pocket_width_mm=2.0 * geometry.pocket_radius_mm,
        pocket_depth_mm=geometry.pocket_depth_mm,
        plate_mm=geometry.housing.plate_mm,
        cover_mm=geometry.housing.cover_mm,
        half_slot_mm=0.5 * (x1 - x0),
        E_prime_MPa=material.youngs_modulus_MPa / (1.0 - material.poisson_ratio**2),
        G_MPa=material.shear_modulus_MPa,
        insert=insert,
        insert_above_pad_mm=0.0 if insert is None else insert.z_mm - top.t_mm,
        patch_mm=patch_mm,
        support=support,
        slot_wall_widths_mm=(x0 + 0.5 * geometry.base_length_mm, 0.5 * geometry.base_length_mm - x1),
        slot_height_mm=geometry.z_cover_bottom_mm - geometry.z_board_bottom_mm,
        cover_air_mm=geometry.housing.chip_clearance_mm,
    )


def member_compliances(scene: MemberScene, theta_rad, t_mm, h_mm) -> tuple:
    """(cap (...), plates (..., n - 1), cover (...)) in mm/N of stacks of cells given as arrays
    (..., n) of theta (rad), t and h (mm), bottom to top (module docstring); the kernel both
    :func:`members` and the design loop use."""
    cap, plates, over_slot, slot_walls = member_parts(scene, theta_rad, t_mm, h_mm)
    return cap, plates, over_slot + slot_walls


def layer_caps_mm_per_N(scene: MemberScene, theta_rad, t_mm, h_mm) -> tuple:
    """((..., n) what closes each layer's cavity with it: the plate above it (the cap on the top
    one) and its joints with the plates; the cover's bending over the slot; its slot walls; (...,
    n - 1) the plates over locked layers, model.past_lock; (the bending and the walls) once layer
    1 is locked, :func:`cover_parts_locked_mm_per_N`) of stacks given as arrays (..., n), mm/N:
    the design loop's members."""
    cap, plates, over_slot, slot_walls, joints, locked, cover_locked = all_member_parts(scene, theta_rad, t_mm, h_mm)
    caps = np.concatenate([plates, np.asarray(cap)[..., None]], axis=-1)
    return caps + joints, over_slot, slot_walls, locked, cover_locked


def all_member_parts(scene: MemberScene, theta_rad, t_mm, h_mm) -> tuple:
    """(:func:`member_parts`, each layer's joints with the plates beside it (model.plate_joint),
    the plates over locked layers (model.past_lock: over one block, over two; each with the top
    layer's walls' thrust, model.wall_thrust, which is the third, and the feet's press, the
    fourth), the cover's two parts once layer 1 is locked (:func:`cover_parts_locked_mm_per_N`))
    of stacks given as arrays (..., n): the layers' supports and root joints computed once for
    all."""
    t = np.asarray(t_mm, dtype=float)
    supports = layer_supports(scene, theta_rad, t, h_mm)
    one = np.asarray(root_joint_mm_per_N(theta_rad, t, h_mm, *joint_scene(scene)))  # a root on one plate
    one_block, two_blocks, press = scene_locked_plates_mm_per_N(scene, theta_rad, t, h_mm, supports[1], one)
    thrust = scene_thrust_mm_per_N(scene, theta_rad, t, h_mm, supports[1])  # moves as the plate it bends
    locked = (one_block + thrust, two_blocks + thrust, thrust, press)
    first = (t[..., 0], supports[0][..., 0], supports[1][..., 0], np.asarray(theta_rad, dtype=float)[..., 0])
    cover, cover_locked = cover_parts_both_mm_per_N(scene, *first, np.asarray(h_mm, dtype=float)[..., 0])
    parts = member_parts(scene, theta_rad, t, h_mm, supports, cover)
    return *parts, one * plates_beside(t.shape[-1]), locked, cover_locked


def member_parts(
    scene: MemberScene, theta_rad, t_mm, h_mm, supports: tuple | None = None, cover: tuple | None = None
) -> tuple:
    """:func:`member_compliances` with the cover's two parts apart: (cap, plates, the cover's
    bending over the slot (which stops on the board), the slot walls' squeeze and turn);
    ``supports``: the layers' :func:`layer_supports`, ``cover``: the cover's two parts
    (:func:`cover_parts_mm_per_N`), when the caller has them."""
    t = np.asarray(t_mm, dtype=float)
    pad, head, walls, sway = layer_supports(scene, theta_rad, t, h_mm) if supports is None else supports
    top = (np.asarray(theta_rad, dtype=float)[..., -1], np.asarray(h_mm, dtype=float)[..., -1])
    cap = cap_mm_per_N(scene, t[..., -1], head[..., -1], walls[..., -1], *top)
    plates = plates_mm_per_N(
        scene, t[..., :-1], t[..., 1:], head[..., :-1], head[..., 1:], sway[..., :-1], sway[..., 1:]
    )
    if cover is None:
        bottom = (np.asarray(theta_rad, dtype=float)[..., 0], np.asarray(h_mm, dtype=float)[..., 0])
        cover = cover_parts_mm_per_N(scene, t[..., 0], pad[..., 0], head[..., 0], *bottom)
    return cap, np.asarray(plates), *cover


def layer_supports(scene: MemberScene, theta_rad, t_mm, h_mm) -> tuple:
    """What the members take from each layer, cell by cell (theta in rad, t, h in mm): (its outer
    pad's half width, its wall heads' x (wall_head_x_mm), its walls' restraint of a pad's turn
    and of a plate's turn (:func:`plates_mm_per_N`), N mm/rad). A member rests on one layer or
    two, so stacks that differ in one layer need these of that layer's cells only."""
    theta, t = np.asarray(theta_rad, dtype=float), np.asarray(t_mm, dtype=float)
    pad = pad_half_width_mm(theta, h_mm, scene.width_mm)
    head = pad - 0.5 * t * np.tan(0.5 * theta)
    walls = wall_head_restraint_Nmm_per_rad(theta, t, h_mm, scene.depth_mm, scene.E_prime_MPa, scene.support)
    return pad, head, walls, walls * (12.0 / WALL_FAR_END[scene.support])  # 12 E'I/L_w


def cap_mm_per_N(scene: MemberScene, t_top_mm, head_mm, walls_Nmm_per_rad, theta_top_rad, h_top_mm) -> Any:
    """The cap's compliance, mm/N, over the top layer (its t, wall heads and walls' restraint,
    :func:`layer_supports`; its theta in rad and h in mm): a beam across the wall heads under the
    press's strip, its ends turning against the walls (end_fixity), and the top layer's roots
    turning into it (:func:`~mst_cli.model.plate_joint.cap_root_mm_per_N`)."""
    s = scene
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    z_pocket = t_top_mm + s.pocket_floor_mm
    EI, kGA = section_EI_kGA(
        D, t_top_mm + s.cap_above_stack_mm, E, G, s.pocket_width_mm, (z_pocket, z_pocket + s.pocket_depth_mm),
        s.insert, t_top_mm + s.insert_above_pad_mm,
    )  # fmt: skip
    span = 2.0 * head_mm
    fix = end_fixity(walls_Nmm_per_rad, EI, span)
    simple, clamped = strip_bending_pair_mm_per_N(span, s.patch_mm, EI)
    roots = cap_root_mm_per_N(theta_top_rad, t_top_mm, h_top_mm, D, E)
    return simple - fix * (simple - clamped) + strip_shear_mm_per_N(span, s.patch_mm, kGA) + roots


def plates_mm_per_N(
    scene: MemberScene, t_below_mm, t_above_mm, head_below_mm, head_above_mm, sway_below, sway_above
) -> Any:
    """A plate's compliance, mm/N, between the layer below it and the one above it (their
    :func:`layer_supports`): the plate with both pads, loaded by the upper layer's wall feet and
    held by the lower layer's wall heads (:func:`~mst_cli.model.beams.offset_pair_mm_per_N`: the
    same whichever pair stands outside), its turn resisted by both layers' walls: the turn swings
    a wall's far end (the side vertex) across it by L_w a radian, against its sway stiffness
    12 E'I/L_w^3 (ends held from turning), so 12 E'I/L_w (studies/unlike_plates.py --per-plate
    measures 12.9 per wall, docs/design.md 4.7). Between the two pairs of walls only the outer
    layer's pad is bonded to the plate (the inner layer's pad ends at its own walls), so the
    overhang bends as the plate with that pad alone, as a plate over a locked layer's does
    (model.past_lock), and its root, an end of that section built into the thicker span, turns
    against pi/8 E'D d^2 (d the overhang's thickness; :data:`~mst_cli.model.beams.END_BUILT_IN`,
    as the cover's ends in the slot's walls): held there, the plates between open layers read
    0.87-1.38 times the rung's over the box (median 1.11), 0.85-1.22 (1.05) with it
    (studies/member_closed_form.py; docs/design.md 4.7, "The overhang's root")."""
    s = scene
    t_below, t_above = np.asarray(t_below_mm, dtype=float), np.asarray(t_above_mm, dtype=float)
    EI_p, kGA_p = section_EI_kGA(s.depth_mm, t_below + s.plate_mm + t_above, s.E_prime_MPa, s.G_MPa)
    outer = np.where(head_below_mm > head_above_mm, t_below, t_above) + s.plate_mm  # the overhang's thickness
    overhang = section_EI_kGA(s.depth_mm, outer, s.E_prime_MPa, s.G_MPa)
    root = END_BUILT_IN * s.E_prime_MPa * s.depth_mm * outer * outer
    near, offset = np.minimum(head_below_mm, head_above_mm), head_below_mm - head_above_mm
    return offset_pair_mm_per_N(near, offset, EI_p, kGA_p, sway_below + sway_above, overhang, root)


def members_total_mm_per_N(scene: MemberScene, theta_rad, t_mm, h_mm) -> np.ndarray:
    """The cap's, the plates' (with the layers' joints with them) and the cover's compliance in
    series (...), mm/N: every member at a small load."""
    cap, plates, cover = member_compliances(scene, theta_rad, t_mm, h_mm)
    return cap + plates.sum(axis=-1) + layer_joints_mm_per_N(scene, theta_rad, t_mm, h_mm).sum(axis=-1) + cover


def members(
    geometry, material, patch_mm: float = FINGERTIP_PATCH_MM, support: str = "simple", insert: Insert | None = None
) -> Members:
    """The cap's, the plates' and the cover's compliance of ``geometry`` (a SensorGeometry) in
    ``material`` under a centred press ``patch_mm`` wide (module docstring); ``insert``, a stiff
    plate in the cap (its own modulus, in plane strain as given)."""
    scene = member_scene(geometry, material, patch_mm, support, insert)
    theta, t, h = (np.array([getattr(c, k) for c in geometry.layers]) for k in CELL_KEYS)
    return scene_members(scene, theta, t, h)


def scene_members(scene: MemberScene, theta_rad, t_mm, h_mm, scale: float = 1.0, regime_extra: tuple = ()) -> Members:
    """:func:`members` of the scene's stack (arrays (n,) of theta in rad, t and h in mm, bottom to
    top), every compliance times ``scale``, with the rung's correction ``regime_extra``."""
    cap, plates, over_slot, slot_walls, joints, locked_parts, cover = all_member_parts(scene, theta_rad, t_mm, h_mm)
    (one, two, thrust, press), (over_locked, walls_locked) = locked_parts, cover
    locked, two_locked = np.atleast_1d(one), np.atleast_1d(two)
    s, air = scale, scene.cover_air_mm  # the cover's bending over the slot stops on the board
    return Members(
        s * float(cap), tuple(s * float(p) for p in plates), s * float(over_slot + slot_walls), scene.patch_mm,
        scene.support, s * float(over_slot), air, regime_extra, tuple(s * float(j) for j in joints),
        tuple(s * float(x) for x in locked), s * float(over_locked + walls_locked), s * float(over_locked),
        tuple(s * float(x) for x in two_locked), tuple(s * float(x) for x in np.atleast_1d(thrust)),
        tuple(s * float(x) for x in np.atleast_1d(press)),
    )  # fmt: skip


@dataclass(frozen=True)
class CappedLayer:
    """The top layer with the cap bonded to its top pad (a layer law, the protocol of
    :mod:`mst_cli.model.mechanics`): the cap bends into the layer's cavity, C x F at its centre,
    on top of the layer's own compression, until the cavity closes there (``lock_force_N``,
    below the layer's own R); past it both are locked. C = 0 is the layer itself."""

    law: Any  # a layer law of any rung (k_N_per_mm, d_lock_mm, lock_force_N, knots_N, displacement_mm ...)
    cap_mm_per_N: float

    @functools.cached_property  # the forward model and its report ask each layer's dozens of times
    def lock_force_N(self) -> float:
        """Where law.d(F) + C F reaches d_lock: exact on the law's piecewise-linear knots."""
        law, C = self.law, self.cap_mm_per_N
        R = float(law.lock_force_N)
        if C <= 0.0:
            return R
        knots = np.array([0.0, *(f for f in law.knots_N if f < R), R], dtype=float)
        reach = law.displacement_mm(knots) + C * knots
        return float(np.interp(law.d_lock_mm, reach, knots))

    @property
    def k_N_per_mm(self) -> float:  # the layer and the cap in series, at small load
        return 1.0 / (1.0 / self.law.k_N_per_mm + self.cap_mm_per_N)

    @property
    def d_lock_mm(self) -> float:
        return self.law.d_lock_mm

    @property
    def k_locked_N_per_mm(self) -> float:
        return self.law.k_locked_N_per_mm

    @property
    def knots_N(self) -> tuple[float, ...]:
        R = self.lock_force_N
        return tuple(f for f in self.law.knots_N if f < R) + (R,)

    @property
    def min_stretch_at_lock(self) -> float | None:  # the wall's squeeze at its own lock, when the cap lets it get there
        return getattr(self.law, "min_stretch_at_lock", None) if self.cap_mm_per_N <= 0.0 else None

    def displacement_mm(self, force_N) -> np.ndarray:
        F, R = np.asarray(force_N, dtype=float), self.lock_force_N
        closed = self.d_lock_mm + (F - R) / self.k_locked_N_per_mm
        return np.where(F <= R, self.law.displacement_mm(F) + self.cap_mm_per_N * F, closed)


def moving_share(stop_N, edges_N) -> np.ndarray:
    """(..., bands): the share of each force band between ``edges_N`` (..., bands + 1) over which
    a member that moves until ``stop_N`` (...; inf: it never stops) still moves, clip(stop - F_lo,
    0, band) / band: its compliance's mean over the band, what a secant over the band sees (a
    band of zero width: 1 if it still moves just past it). The one rule of the forward model for
    the members (model.response.part_stack): the cap and plate j bend until the layer under them
    locks, the cover's bending over the slot until it lands on the board, its slot walls always.
    The report's shares (:func:`motion_shares`) and the design's diagnosis use it alike."""
    F = np.asarray(edges_N, dtype=float)
    lo, band = F[..., :-1], np.diff(F, axis=-1)
    stop = np.asarray(stop_N, dtype=float)[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        part = np.clip(stop - lo, 0.0, band) / np.where(band > 0, band, 1.0)
    return np.where(band > 0, part, (stop > lo).astype(float))


def capped_units(laws: tuple, parts: Members) -> list:
    """The layer laws ``laws`` (bottom to top) each with the plate or cap above it bonded to its
    top pad (:class:`CappedLayer`; a rigid one leaves the law itself): the units of the part's
    stack (model.response.part_stack, model.part_laws)."""
    n = len(laws)
    plates = (*parts.plates_mm_per_N, *(0.0,) * (n - 1 - len(parts.plates_mm_per_N)))
    joints = (*parts.joints_mm_per_N, *(0.0,) * (n - len(parts.joints_mm_per_N)))
    caps = [c + j for c, j in zip((*plates[: n - 1], parts.cap_mm_per_N), joints)]
    return [CappedLayer(law, c) if c > 0 else law for law, c in zip(laws, caps)]


def cover_landing_N(parts: Members, first_lock_N: float = math.inf) -> float:
    """The centred press (N) at which the cover's bending over the slot has closed its air onto
    the board's tallest part (inf: it never bends there), layer 1 locking at ``first_lock_N`` (its
    capped unit's, :func:`capped_units`; inf: never, or the landing comes first). Past it the press
    bears on the board, the chip and its connectors: a support only the assembled sensor has, not
    the printed body."""
    C, travel, C_locked, _ = parts.cover_contact
    return float(contact_force_N(first_lock_N, C, C_locked, travel))


def first_lock_N(laws: tuple, parts: Members) -> float:
    """Layer 1's lock force in the part (its capped unit's, :func:`capped_units`; ``laws``: the
    layers', bottom to top): where the cover under it stiffens (:func:`cover_parts_locked_mm_per_N`)."""
    return float(capped_units(laws, parts)[0].lock_force_N)


def member_band_compliances(stack, parts: Members) -> tuple[np.ndarray, np.ndarray, dict]:
    """(the part's regime edges (n + 1,) in N: 0 and the units' lock forces, sorted; each layer's
    own secant compliance per regime (n, n) in mm/N; {member: its compliance per regime (n,)}) as
    the forward model moves them (:func:`moving_share`): the drop of the part over each regime is
    the sum of all of them times the regime's width, exactly (part_stack's force-displacement)."""
    units = capped_units(stack.layers, parts)
    R = np.array([u.lock_force_N for u in units], dtype=float)
    edges = np.concatenate([[0.0], np.sort(R)])
    # a regime of zero width (two layers locking together): the slope just past its start
    hi = np.maximum(edges[1:], edges[:-1] + 1e-9 * max(float(edges[-1]), 1e-12))
    lo, width = edges[:-1], hi - edges[:-1]
    bands = np.stack([lo, hi], axis=-1)  # (n, 2): each regime as its own band
    caps = np.array([getattr(u, "cap_mm_per_N", 0.0) for u in units])
    share = moving_share(R[:, None], bands)[..., 0]  # (units, regimes): what closes each unit's cavity moves
    own = np.array([(u.displacement_mm(hi) - u.displacement_mm(lo)) / width for u in units]) - caps[:, None] * share
    C, _, C_locked, delta = parts.cover_contact  # past layer 1's lock, the cover under its closed block
    past = lo >= R[0]
    C_now = np.where(past, C_locked, C)
    bending = C_now * moving_share(cover_landing_N(parts, float(R[0])), bands)[..., 0]
    cover = parts.cover_mm_per_N + np.where(past, delta, 0.0) - C_now + bending
    cap = parts.cap_mm_per_N * share[-1]  # the plates' moving: the rest of the caps', the joints' with them
    locked = parts.locked_plates_mm_per_N or np.zeros(len(R) - 1)  # the plates over locked layers (past_lock)
    over = by_regime(locked, R, parts.two_locked_plates_mm_per_N or None)[:-1]
    plates = (caps[:, None] * share).sum(axis=0) - cap + over
    moving = {"cap": cap, "plates": plates, "housing": cover}
    if parts.regime_extra_mm_per_N:
        moving["section_correction"] = np.asarray(parts.regime_extra_mm_per_N, dtype=float)
    return edges, own.T, moving


def small_load_layers_mm_per_N(stack, parts: Members) -> np.ndarray:
    """(n,) per regime of the part (``stack``: its layers alone, locking in the part's order), the
    layers' compliance as a linear model of the part gives it: the layers locked before the
    regime on their locked branch, the others at their small-load stiffness (the whole-part
    rung's and the issue's independent model's kind of figure; the secant over the regime
    includes the open layers' softening before their lock)."""
    k = np.array([law.k_N_per_mm for law in stack.layers], dtype=float)
    k_locked = np.array([law.k_locked_N_per_mm for law in stack.layers], dtype=float)
    order = np.argsort([u.lock_force_N for u in capped_units(stack.layers, parts)], kind="stable")  # the part's
    position = np.empty(len(order), dtype=int)
    position[order] = np.arange(len(order))
    locked = position[None, :] < np.arange(len(order))[:, None]  # (regime, layer): locked before the regime
    return np.where(locked, 1.0 / k_locked, 1.0 / k).sum(axis=1)


def motion_shares(stack, parts: Members) -> list[dict]:
    """Per regime of the part (its layers as the forward model locks them, with the cap and
    plates bending into their cavities): the share of the magnet's drop over the regime from
    each layer, the cap, the plates and the housing's cover (they sum to 1), each as the forward
    model moves it there (:func:`member_band_compliances`), and the share outside the layers.
    ``stack``: the layers alone (model.stack.Stack)."""
    edges, layers, moving = member_band_compliances(stack, parts)
    linear = small_load_layers_mm_per_N(stack, parts)
    out = []
    for i, row in enumerate(layers):
        members_i = {k: float(v[i]) for k, v in moving.items()}
        outside = sum(members_i.values())
        total = float(row.sum()) + outside
        shares = {f"layer_{j + 1}": float(c) / total for j, c in enumerate(row)}
        shares |= {k: v / total for k, v in members_i.items()}
        out.append(
            {
                "regime": i + 1,
                "force_N": [float(edges[i]), float(edges[i + 1])],
                "compliance_mm_per_N": total,
                "layers_compliance_mm_per_N": float(row.sum()),
                # a linear model's: the open layers' small-load, the locked ones' locked compliance
                "small_load_compliance_mm_per_N": float(linear[i]) + outside,
                "members_mm_per_N": members_i,
                "shares": shares,
                "outside_layers": outside / total,
            }
        )
    return out


# the accuracy an independent model of the part asks of the field change per newton: before the
# first lock, after one, after two or more (issue 44; that model's own uncertainty on a closed layer)
ACCURACY_BUDGET_REL = (0.05, 0.08, 0.20)
