"""A touch off the axis: the stack's compression and tilt, the magnet's pose, the field on all
three axes, and the force a reading taken as axial would give (issue 24).

Each layer answers the load at (x0, y0) with a compression and two tilts
(:mod:`mst_cli.model.mechanics.tilt`), with the part's members its walls load unless the
load path is the layers alone (:mod:`mst_cli.model.part_laws`). Small rotations add: layer j turns
everything above it by (phi_y, phi_x) about a pivot at its mid-height (a layer symmetric about
its mid-plane turns about its centre under a pure moment), so the magnet's centre moves down by
sum d_j and sideways by sum phi_j (z_magnet - z_mid,j), toward the load, and the magnet turns
by the summed tilts. The field at the chip is the exact cylinder field of the magnet in that
pose (magpylib). The sensor read as axial inverts the centred model's |B|(F): the difference
from the true force is what an uncorrected reading gets wrong.

Pure: no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.general_load import loaded_stack, pose_field_T
from mst_cli.model.material import Material
from mst_cli.model.mechanics.tilt import LayerTiltLaw, solve_layer_tilt
from mst_cli.model.member_pose import MemberPose
from mst_cli.model.part_laws import closure_limit_mm, part_units
from mst_cli.model.response import Response
from mst_cli.model.response import simulate as simulate_axial
from mst_cli.model.stack_pose import magnet_field_T, magnet_pose, stack_path, tilt_laws

SIDE_LOCK_BISECTIONS = 50  # halvings of the force bracket of a side's lock (to ~1e-15 of it)


@dataclass
class OffCentreResponse:
    """The sensor under a force at ``offset_mm``; arrays over the force samples (m,)."""

    offset_mm: tuple[float, float]
    mechanics: str
    force_N: np.ndarray  # (m,)
    layer_d_mm: np.ndarray  # (m, n) compression of each layer at the axis
    layer_tilt_rad: np.ndarray  # (m, n, 2) each layer's (phi_y, phi_x)
    magnet_shift_mm: np.ndarray  # (m, 3) the magnet centre's displacement (z down is negative)
    magnet_tilt_deg: np.ndarray  # (m, 2) the load-driven turn of the magnet axis toward +x and toward +y
    B_T: np.ndarray  # (m, 3) at the chip
    B_abs_T: np.ndarray  # (m,)
    force_read_axial_N: np.ndarray  # (m,) the force the centred model gives this |B|; nan beyond
    axial_reading_flag: np.ndarray  # (m,) AXIAL_READING_FLAGS: why force_read_axial_N is nan (ok: it is not)
    side_lock_N: np.ndarray  # (n, 2): force at which each layer's -x / +x side first locks
    axial: Response  # the centred model of the same sensor
    shear_ratio: tuple[float, float] = (0.0, 0.0)  # (Fx, Fy) / Fz along the curve
    layer_slide_mm: np.ndarray | None = None  # (m, n, 2) each layer's lateral slide (None: no shear)
    rotation_flag: np.ndarray | None = None  # (m,) ROTATION_FLAGS: where the model stops (set by simulate_offcentre)
    whole_part: bool = True  # the members ride with their layers (model.load_path: part), else the layers alone
    members_pose: MemberPose | None = None  # model.load_path: section: the rung's members beyond the closed form

    @property
    def force_x_N(self) -> np.ndarray:
        """The tangential force along x at each sample (N)."""
        return self.shear_ratio[0] * self.force_N

    @property
    def force_y_N(self) -> np.ndarray:
        """The tangential force along y at each sample (N)."""
        return self.shear_ratio[1] * self.force_N

    @property
    def read_error_N(self) -> np.ndarray:
        """Force read as axial minus the true force (N)."""
        return self.force_read_axial_N - self.force_N


def simulate_offcentre(
    geometry: SensorGeometry,
    material: Material,
    offset_mm: tuple[float, float],
    mechanics: str = "spring",
    field_model: str | None = None,
    points_per_regime: int = 100,
    overload: float = 0.25,
    shear_ratio: tuple[float, float] = (0.0, 0.0),
    whole_part: bool = True,
    section: bool = False,
) -> OffCentreResponse:
    """The response to a force pressed at ``offset_mm`` = (x0, y0) on the top face, over the
    centred model's force grid (0 to 1 + ``overload`` times the last lock), with a tangential
    force ``shear_ratio`` = (Fx, Fy) / Fz along it (:mod:`mst_cli.model.general_load`); the members
    with the layers unless ``whole_part`` is False, with ``section`` the whole-part rung's
    (:func:`section_members_pose`). Raises TiltError when a layer's equilibrium is not found."""
    grid: dict[str, Any] = {"points_per_regime": points_per_regime, "overload": overload, "whole_part": whole_part}
    axial = simulate_axial(geometry, material, mechanics, field_model, **grid, section=section)
    F = axial.force_N
    slide, stack = None, None
    if shear_ratio[0] == 0.0 and shear_ratio[1] == 0.0:
        layers = tilt_laws(geometry, material, mechanics, whole_part=whole_part)
        offsets = np.broadcast_to(np.asarray(offset_mm, dtype=float), (len(layers), 2))
    else:
        stack = loaded_stack(geometry, material, mechanics, whole_part=whole_part)
        layers, offsets = stack.tilt, stack.layer_offsets_mm(offset_mm, shear_ratio)
        slide = stack.slides_mm(F, shear_ratio)
    d, tilt = stack_path(layers, F, offsets)
    if stack is not None:  # the members' counter-turn under the tangential force (model.counter_turn)
        tilt = stack.tilts_with_counter_turn(F, tilt, shear_ratio[0])
    shift, rotvec = magnet_pose(geometry, d, tilt, slide)
    extra = section_members_pose(geometry, material, mechanics, whole_part and section)
    if extra is not None:  # the members' pose beyond the closed form, on the load's ray
        shift, rotvec = (a + b for a, b in zip((shift, rotvec), extra.pose(F, shear_ratio[0], offset_mm[0])))
    B = magnet_field_T(geometry, shift, rotvec)
    B_abs = np.linalg.norm(B, axis=-1)
    out = OffCentreResponse(
        offset_mm=(float(offset_mm[0]), float(offset_mm[1])),
        mechanics=mechanics,
        force_N=F,
        layer_d_mm=d,
        layer_tilt_rad=tilt,
        magnet_shift_mm=shift,
        magnet_tilt_deg=np.degrees(np.stack([rotvec[:, 1], -rotvec[:, 0]], axis=-1)),
        B_T=B,
        B_abs_T=B_abs,
        force_read_axial_N=_read_as_axial(axial, B_abs),
        axial_reading_flag=axial_reading_flags(axial, B_abs),
        side_lock_N=_side_locks_N(layers, offsets),
        axial=axial,
        shear_ratio=(float(shear_ratio[0]), float(shear_ratio[1])),
        layer_slide_mm=slide,
        whole_part=whole_part,
        members_pose=extra,
    )
    limits = _closure_limits_mm(geometry, material, mechanics, whole_part)
    out.rotation_flag = rotation_flags(out, geometry.layers, limits)
    return out


def _closure_limits_mm(geometry: SensorGeometry, material: Material, mechanics: str, whole_part: bool) -> np.ndarray:
    """(n,) each layer's closure at which its pads pass through each other: its cavity's height,
    with the part's members :func:`~mst_cli.model.part_laws.closure_limit_mm`."""
    cavity = [c.cavity_height_mm for c in geometry.layers]
    if whole_part:
        cavity = [closure_limit_mm(u, h) for u, h in zip(part_units(geometry, material, mechanics), cavity)]
    return np.array(cavity)


AXIAL_READING_FLAGS = ("ok", "below_no_load", "above_range")  # why a force read as axial is missing

# Where the general-load model stops (issue 44): its rotations add as small ones (sin a = a within
# 0.5 %, cos a = 1 within 1.5 % up to 10 deg), and a layer cannot turn so far that its pads pass
# through each other (its centred compression plus its tilt times the pad's half width past the
# cavity's height h - 2t). A sample past either is flagged; its numbers are not a prediction.
SMALL_ROTATION_DEG = 10.0
ROTATION_FLAGS = ("ok", "past_small_rotations", "past_closure")


def rotation_flags(r: OffCentreResponse, cells, closure_limit_mm: np.ndarray | None = None) -> np.ndarray:
    """(m,) ROTATION_FLAGS of each force sample: past_closure where some layer's pads would
    interpenetrate, else past_small_rotations where the magnet or a layer turns over
    SMALL_ROTATION_DEG, else ok. ``cells`` are the layers' HexCells, bottom to top;
    ``closure_limit_mm`` (n,): each layer's closure at which its pads pass through each other
    [default: its cavity's height; with the part's members,
    :func:`~mst_cli.model.part_laws.closure_limit_mm`]."""
    tilt = np.abs(r.layer_tilt_rad)  # (m, n, 2)
    p = np.array([c.p_mm for c in cells])
    cavity = np.array([c.cavity_height_mm for c in cells]) if closure_limit_mm is None else closure_limit_mm
    edge = r.layer_d_mm + tilt.max(axis=-1) * p  # the deepest pad edge's closure, mm
    closed = (edge > cavity + 1e-9).any(axis=-1)
    turned = (np.degrees(tilt.max(axis=(-1, -2))) > SMALL_ROTATION_DEG) | (
        np.abs(r.magnet_tilt_deg).max(axis=-1) > SMALL_ROTATION_DEG
    )
    return np.where(closed, "past_closure", np.where(turned, "past_small_rotations", "ok"))


def axial_reading_flags(axial: Response, B_abs_T: np.ndarray) -> np.ndarray:
    """Per |B|: ok (the centred model reads it), below_no_load (|B| under the centred model's
    no-load |B|: a tilt can take the field below B0) or above_range (beyond its curve's end): where
    :func:`_read_as_axial` gives nan."""
    B_ax = axial.B_abs_T
    flags = np.full(np.shape(B_abs_T), "ok", dtype=object)
    flags[B_abs_T < B_ax[0] * (1 - 1e-12)] = "below_no_load"
    flags[B_abs_T > B_ax[-1]] = "above_range"
    return flags


def _read_as_axial(axial: Response, B_abs_T: np.ndarray) -> np.ndarray:
    """The centred model's force at each |B| (its |B|(F) rises with F); nan outside its curve."""
    B_ax, F_ax = axial.B_abs_T, axial.force_N
    read = np.interp(B_abs_T, B_ax, F_ax)
    return np.where((B_abs_T < B_ax[0] * (1 - 1e-12)) | (B_abs_T > B_ax[-1]), np.nan, read)


def _side_locks_N(layers, offsets) -> np.ndarray:
    """(n, 2) where each layer locks on its -x and +x sides, pressed at its ``offsets`` (n, 2)."""
    return np.array([[_side_lock_N(layer, tuple(off), side) for side in (0, 1)] for layer, off in zip(layers, offsets)])


def _side_lock_N(layer: LayerTiltLaw, offset_mm, side: int) -> float:
    """The force at which the layer's pads first touch at their end on one side (0: -x, 1: +x):
    where that side locks (bisection on the force)."""

    def reached(f: float) -> bool:
        return solve_layer_tilt(layer, f, offset_mm).pads_touch[side]

    lo, hi = 0.0, layer.lock_force_N
    while not reached(hi):
        lo, hi = hi, 2.0 * hi
        if hi > 1e3 * layer.lock_force_N:
            return math.nan  # this side never locks (it lifts off)
    for _ in range(SIDE_LOCK_BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if reached(mid) else (mid, hi)
    return hi


@dataclass
class OffsetMap:
    """The axial reading's relative force error over the top face, at a few forces per regime."""

    x_mm: np.ndarray  # (nx,)
    y_mm: np.ndarray  # (ny,)
    force_N: np.ndarray  # (nf,) ascending
    regime: np.ndarray  # (nf,) the regime (from 1) each force lies in
    error_rel: np.ndarray  # (nf, ny, nx): (force read as axial - force) / force; nan off the curve
    flag: np.ndarray  # (nf, ny, nx): AXIAL_READING_FLAGS, why error_rel is nan (ok: it is not)


def offset_map(
    geometry: SensorGeometry,
    material: Material,
    mechanics: str = "spring",
    field_model: str | None = None,
    grid: tuple[int, int] = (9, 7),
    region_frac: float = 0.8,
    fractions: tuple[float, ...] = (0.25, 0.5, 0.75),
    region_mm: tuple[float, float] | None = None,
    whole_part: bool = True,
    section: bool = False,
) -> OffsetMap:
    """:class:`OffsetMap` over a ``grid`` (nx, ny) spanning ``region_frac`` of the top face
    (W x D), or +-``region_mm`` (half extents) when given, at ``fractions`` of every regime's
    force band; the part's members with the layers unless ``whole_part`` is False, corrected by the
    whole-part rung with ``section`` (as :func:`simulate_offcentre`)."""
    # dense: the map reads each force back by interpolating this curve (its error falls like 1/n^2)
    axial = simulate_axial(
        geometry, material, mechanics, field_model, points_per_regime=400, whole_part=whole_part, section=section
    )
    extra = section_members_pose(geometry, material, mechanics, whole_part and section)
    edges = np.concatenate([[0.0], np.asarray(axial.lock_forces_N)])
    F = np.array([lo + f * (hi - lo) for lo, hi in zip(edges[:-1], edges[1:]) for f in fractions])
    regime = np.repeat(np.arange(1, len(edges)), len(fractions))
    layers = tilt_laws(geometry, material, mechanics, whole_part=whole_part)
    half = region_mm or (0.5 * region_frac * geometry.width_mm, 0.5 * region_frac * geometry.depth_mm)
    xs = np.linspace(-1.0, 1.0, grid[0]) * half[0]
    ys = np.linspace(-1.0, 1.0, grid[1]) * half[1]
    err = np.full((len(F), len(ys), len(xs)), np.nan)
    flag = np.full(err.shape, "ok", dtype=object)
    for iy, y in enumerate(ys):
        for ix, x in enumerate(xs):
            B_abs = np.linalg.norm(pose_field_T(geometry, layers, F, (float(x), float(y)), extra), axis=-1)
            err[:, iy, ix] = _read_as_axial(axial, B_abs) / F - 1.0
            flag[:, iy, ix] = axial_reading_flags(axial, B_abs)
    return OffsetMap(xs, ys, F, regime, err, flag)


def worst_read_errors(m: OffsetMap) -> dict:
    """Per regime, the largest |error| of a force read as axial over the map, and where."""
    regimes: list[dict] = []
    for reg in np.unique(m.regime):
        err = np.abs(m.error_rel[m.regime == reg])  # (forces, ny, nx)
        k, iy, ix = np.unravel_index(int(np.nanargmax(err)), err.shape)
        regimes.append(
            {
                "regime": int(reg),
                "worst_read_error_rel": float(m.error_rel[m.regime == reg][k, iy, ix]),
                "at_mm": [float(m.x_mm[ix]), float(m.y_mm[iy])],
                "at_force_N": float(m.force_N[m.regime == reg][k]),
            }
        )
    return {
        "region_mm": [float(m.x_mm.max()), float(m.y_mm.max())],
        "regimes": regimes,
        "worst_read_error_rel": max(abs(float(r["worst_read_error_rel"])) for r in regimes),
    }


def section_members_pose(
    geometry: SensorGeometry, material: Material, mechanics: str, section: bool
) -> MemberPose | None:
    """What the whole-part rung's members add to the magnet's pose beyond their closed form
    (:func:`~mst_cli.model.section_pose.section_member_pose`, model.load_path: section), or None
    (``section`` False: the closed form alone)."""
    if not section:
        return None
    from mst_cli.model.section_pose import section_member_pose  # deferred: scikit-fem's rung

    return section_member_pose(geometry, material, mechanics)
