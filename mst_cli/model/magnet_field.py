"""Field of the disc magnet at the chip: three models, cheapest first.

Frame: the chip's Hall plates sit at the origin; the magnet's axis is z, its lower pole face
at height ``gap_mm`` above the chip, magnetised +z. Lengths in mm, fields in tesla.

* ``dipole``   point dipole m = Br V / mu0 at the magnet's centre. Cheap, and too high at the
               short gaps this sensor uses (docs/design.md section 4).
* ``axial``    exact on-axis closed form of a uniformly magnetised cylinder,
               B_z(z) = (Br/2) [ (z+L)/sqrt(R^2+(z+L)^2) - z/sqrt(R^2+z^2) ],
               z from the pole face (e.g. Furlani, "Permanent Magnet and Electromechanical
               Devices", Academic Press 2001, section 4.3). Exact for a chip on the axis.
* ``cylinder`` exact field anywhere (magpylib's analytic cylinder; Caciagli et al., J. Magn.
               Magn. Mater. 456, 423 (2018)), for a chip off the axis or a tilted magnet.

The kernels are pure numpy over arrays of gaps. :func:`choose_field_model` picks the cheapest
model that is exact for the scene.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from mst_cli.model.assembly import Magnet

FIELD_MODELS = ("dipole", "axial", "cylinder")


def axial_Bz_T(z_mm: ArrayLike, radius_mm: float, thickness_mm: float, remanence_T: float) -> np.ndarray:
    """Exact B_z on the axis at distance z_mm (>= 0) below the pole face."""
    z = np.asarray(z_mm, dtype=float)
    R2 = radius_mm**2
    zL = z + thickness_mm
    return 0.5 * remanence_T * (zL / np.sqrt(R2 + zL**2) - z / np.sqrt(R2 + z**2))


def axial_dBz_dz_T_per_mm(z_mm: ArrayLike, radius_mm: float, thickness_mm: float, remanence_T: float) -> np.ndarray:
    """d B_z / d z of :func:`axial_Bz_T` (negative: the field falls with distance)."""
    z = np.asarray(z_mm, dtype=float)
    R2 = radius_mm**2
    zL = z + thickness_mm
    return 0.5 * remanence_T * (R2 / (R2 + zL**2) ** 1.5 - R2 / (R2 + z**2) ** 1.5)


def dipole_B_T(
    r_mm: ArrayLike, radius_mm: float, thickness_mm: float, remanence_T: float, axis: ArrayLike = (0.0, 0.0, 1.0)
) -> np.ndarray:
    """Point-dipole field at positions ``r_mm`` (..., 3) relative to the magnet centre.

    B = mu0/(4 pi r^3) [3 (m.r^) r^ - m] with m = Br V / mu0, so mu0 m = Br V: the magnet's
    remanence and volume fix it, no mu0 needed.
    """
    r = np.asarray(r_mm, dtype=float)
    axis = np.asarray(axis, dtype=float)
    volume = np.pi * radius_mm**2 * thickness_mm
    moment = remanence_T * volume * axis  # mu0 * m, T mm^3
    dist = np.linalg.norm(r, axis=-1, keepdims=True)
    unit = r / dist
    m_dot = np.sum(unit * moment, axis=-1, keepdims=True)
    return (3.0 * m_dot * unit - moment) / (4.0 * np.pi * dist**3)


def cylinder_B_T(
    r_mm: ArrayLike, diameter_mm: float, thickness_mm: float, remanence_T: float, tilt_deg: float = 0.0
) -> np.ndarray:
    """Exact field of the cylinder at positions ``r_mm`` (..., 3) relative to its centre.

    The magnet is tilted by ``tilt_deg`` about the y axis. magpylib works in metres.
    """
    from scipy.spatial.transform import Rotation  # deferred: the exact model's libraries load only when used

    r = np.atleast_2d(np.asarray(r_mm, dtype=float))
    orientation = Rotation.from_euler("y", tilt_deg, degrees=True) if tilt_deg else None
    return np.reshape(_magpylib_cylinder_T(r, diameter_mm, thickness_mm, remanence_T, orientation), np.shape(r))


def cylinder_pose_B_T(
    r_mm: ArrayLike, diameter_mm: float, thickness_mm: float, remanence_T: float, rotvec_rad: ArrayLike
) -> np.ndarray:
    """Exact field of the cylinder at positions ``r_mm`` (m, 3) relative to its centre, the magnet
    turned by the rotation vectors ``rotvec_rad`` (m, 3) (axis times angle, about its centre):
    one pose per position, for a magnet that tilts as the load moves (:mod:`mst_cli.model.offcentre`)."""
    from scipy.spatial.transform import Rotation  # deferred: as cylinder_B_T

    r = np.atleast_2d(np.asarray(r_mm, dtype=float))
    rot = Rotation.from_rotvec(np.array(np.broadcast_to(np.asarray(rotvec_rad, dtype=float), r.shape)))
    return np.reshape(_magpylib_cylinder_T(r, diameter_mm, thickness_mm, remanence_T, rot), r.shape)


def _magpylib_cylinder_T(r_mm: np.ndarray, diameter_mm: float, thickness_mm: float, remanence_T: float, orientation):
    """magpylib's cylinder field at ``r_mm`` (n, 3), magnetised along its own axis, in the given
    orientation (None: upright). magpylib works in metres."""
    import magpylib as magpy  # deferred: as cylinder_B_T

    return magpy.func.cylinder_field(
        field="B",
        observers=r_mm * 1e-3,
        dimensions=(diameter_mm * 1e-3, thickness_mm * 1e-3),
        polarizations=(0.0, 0.0, remanence_T),
        orientations=orientation,
        squeeze=False,
    )


def choose_field_model(
    offset_mm: tuple[float, float] = (0.0, 0.0), tilt_deg: float = 0.0, requested: str | None = None
) -> str:
    """The cheapest exact model for the scene, unless the user asked for one."""
    if requested is not None:
        if requested not in FIELD_MODELS:
            raise ValueError(f"unknown field model {requested!r}; choose from {', '.join(FIELD_MODELS)}")
        return requested
    on_axis = offset_mm[0] == 0.0 and offset_mm[1] == 0.0 and tilt_deg == 0.0
    return "axial" if on_axis else "cylinder"


def field_at_chip_T(
    gap_mm: ArrayLike, magnet: Magnet, model: str, offset_mm: tuple[float, float] = (0.0, 0.0), tilt_deg: float = 0.0
) -> np.ndarray:
    """Field vector (..., 3) at the Hall plates for every magnet-face-to-chip gap (mm).

    ``offset_mm`` is the chip's (x, y) position relative to the magnet axis; ``tilt_deg`` tilts
    the magnet about y around its centre.
    """
    gap = np.asarray(gap_mm, dtype=float)
    half = 0.5 * magnet.thickness_mm
    if model == "axial":
        if offset_mm[0] or offset_mm[1] or tilt_deg:
            raise ValueError("the axial field model is exact only on the axis: use 'cylinder'")
        Bz = axial_Bz_T(gap, magnet.radius_mm, magnet.thickness_mm, magnet.remanence_T)
        return np.stack([np.zeros_like(Bz), np.zeros_like(Bz), Bz], axis=-1)
    # chip position relative to the magnet's centre
    r = np.stack(
        np.broadcast_arrays(np.full_like(gap, offset_mm[0]), np.full_like(gap, offset_mm[1]), -(gap + half)), axis=-1
    )
    if model == "dipole":
        tilt = np.radians(tilt_deg)
        axis = (np.sin(tilt), 0.0, np.cos(tilt))
        return dipole_B_T(r, magnet.radius_mm, magnet.thickness_mm, magnet.remanence_T, axis)
    if model == "cylinder":
        return cylinder_B_T(r, magnet.diameter_mm, magnet.thickness_mm, magnet.remanence_T, tilt_deg)
    raise ValueError(f"unknown field model {model!r}; choose from {', '.join(FIELD_MODELS)}")
