"""The stack's layers as the tilt rung sees them, their compressions and tilts along a force
curve, and the magnet's pose and exact field at a chip: the parts the off-centre press
(:mod:`mst_cli.model.offcentre`) and the general load (:mod:`mst_cli.model.general_load`) share.

Small rotations add: layer j turns everything above it by (phi_y, phi_x) about a pivot at its
mid-height, so the magnet's centre moves down by sum d_j and sideways by sum phi_j (z_magnet -
z_mid,j), plus every layer's lateral slide (its top plate's translation over its bottom one), and
the magnet turns by the summed tilts. The field at a chip is the exact cylinder field of the
magnet in that pose (magpylib).

Pure: no I/O.
"""

from __future__ import annotations

import math

import numpy as np

from mst_cli.model import magnet_field as fld
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.depth import in_web
from mst_cli.model.mechanics.tilt import LayerTiltLaw, solve_layer_tilt
from mst_cli.model.part_laws import part_units, unit_tilt_law
from mst_cli.model.plate_sway import locked_base_turn_rad_per_Nmm


def tilt_laws(
    geometry: SensorGeometry,
    material: Material,
    mechanics: str,
    lever_factor: float = 1.0,
    whole_part: bool = True,
) -> list[LayerTiltLaw]:
    """Every layer as the tilt rung sees it, from the named rung's laws; ``lever_factor`` scales
    every lever (1: the rung's own; a calibration's fitted value otherwise). ``whole_part``
    (model.load_path: part, as ``mst simulate``): each layer with the members its walls load,
    the cap, the plates and the cover of :func:`~mst_cli.model.load_path.members`
    (:mod:`mst_cli.model.part_laws`); False: the layers alone between rigid plates."""
    laws = part_units(geometry, material, mechanics) if whole_part else layer_laws(geometry.layers, material, mechanics)
    base = locked_base_turn_rad_per_Nmm(geometry, material) if whole_part else None  # the cover's portal
    return [
        unit_tilt_law(law, c, in_web(c, material).youngs_modulus_MPa, material.poisson_ratio, base).with_lever_factor(
            lever_factor
        )
        for law, c in zip(laws, geometry.layers)
    ]


def stack_path(
    layers: list[LayerTiltLaw], F, offset_mm, start: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(d (m, n), (phi_y, phi_x) (m, n, 2)) of every layer along the force samples, each
    solve started from the previous force's answer (the first from ``start`` (n, 3), when given,
    else from the centred answer). ``offset_mm``: (x0, y0), or one (x0, y0) per layer (n, 2),
    the lever of the moments that layer carries over the force (a tangential force adds its own)."""
    m, n = len(F), len(layers)
    offsets = np.broadcast_to(np.asarray(offset_mm, dtype=float), (n, 2))
    d = np.zeros((m, n))
    tilt = np.zeros((m, n, 2))
    for j, layer in enumerate(layers):
        guess = None if start is None else tuple(start[j])
        off = (float(offsets[j, 0]), float(offsets[j, 1]))
        for i, f in enumerate(F):
            if f == 0.0:
                continue
            lt = solve_layer_tilt(layer, float(f), off, guess)
            guess = (lt.d_mm, lt.phi_y_rad, lt.phi_x_rad)
            d[i, j], tilt[i, j] = lt.d_mm, (lt.phi_y_rad, lt.phi_x_rad)
    return d, tilt


def layer_pivots_mm(geometry: SensorGeometry) -> np.ndarray:
    """(n,) the height of every layer's pivot, its mid-plane."""
    return np.array([b + 0.5 * c.h_mm for b, c in zip(geometry.layer_bottoms_mm, geometry.layers)])


def magnet_pose(
    geometry: SensorGeometry, d_mm: np.ndarray, tilt_rad: np.ndarray, slide_mm: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(the magnet centre's displacement (m, 3) in mm, its rotation vector (m, 3) in rad) from
    every layer's compression (m, n), tilts (m, n, 2) and, when given, lateral slides (m, n, 2),
    small rotations added."""
    z_centre = geometry.z_magnet_bottom_mm + 0.5 * geometry.magnet.thickness_mm
    arm = z_centre - layer_pivots_mm(geometry)  # (n,) height of the magnet centre over each layer's pivot
    shift = np.stack(
        [tilt_rad[..., 0] @ arm, tilt_rad[..., 1] @ arm, -d_mm.sum(axis=-1)],
        axis=-1,
    )
    if slide_mm is not None:
        shift[..., :2] += slide_mm.sum(axis=-2)
    # phi_y turns +z toward +x (a right-handed turn about y); phi_x lowers +y, a turn of -phi_x about x
    rotvec = np.stack([-tilt_rad[..., 1].sum(axis=-1), tilt_rad[..., 0].sum(axis=-1), np.zeros(len(d_mm))], axis=-1)
    return shift, rotvec


def magnet_field_T(
    geometry: SensorGeometry,
    shift_mm: np.ndarray,
    rotvec_rad: np.ndarray,
    chip_mm: tuple[float, float] | np.ndarray | None = None,
) -> np.ndarray:
    """The field (m, 3) at the chip at ``chip_mm`` = (x, y), or one chip per row (m, 2) (the
    geometry's chip_offset_mm unless given), for the magnet displaced and turned (its own tilt
    about y added to the load's turn)."""
    mag = geometry.magnet
    r, rot = chip_from_magnet_mm(geometry, shift_mm, chip_mm), magnet_rotvec_rad(geometry, rotvec_rad)
    return fld.cylinder_pose_B_T(r, mag.diameter_mm, mag.thickness_mm, mag.remanence_T, rot)


def chip_from_magnet_mm(
    geometry: SensorGeometry, shift_mm: np.ndarray, chip_mm: tuple[float, float] | np.ndarray | None = None
) -> np.ndarray:
    """(m, 3) the chip at ``chip_mm`` (x, y), or one chip per row (m, 2) (the geometry's
    chip_offset_mm unless given), seen from the magnet's centre displaced by ``shift_mm`` (m, 3)."""
    half = 0.5 * geometry.magnet.thickness_mm
    chip = np.asarray(geometry.chip_offset_mm if chip_mm is None else chip_mm, dtype=float)
    cx, cy = chip[..., 0], chip[..., 1]
    return np.stack(
        [cx - shift_mm[:, 0], cy - shift_mm[:, 1], -(geometry.gap0_mm + half) - shift_mm[:, 2]],
        axis=-1,
    )


def magnet_rotvec_rad(geometry: SensorGeometry, rotvec_rad: np.ndarray) -> np.ndarray:
    """(m, 3) the magnet's turn: the load's ``rotvec_rad`` and its own tilt about y, small
    rotations added."""
    return rotvec_rad + np.array([0.0, math.radians(geometry.magnet_tilt_deg), 0.0])
