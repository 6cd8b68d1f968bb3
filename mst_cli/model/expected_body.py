"""What the printed body is expected to measure: the numbers ``cad/`` checks an exported mesh
against (volumes, areas, the bounding box, the wall centre lines a slice is read across) and
the sensor-to-print frame. No model computation reads them; they live here, apart from the
cell's and the assembly's dimensions, as mixins of :class:`~mst_cli.model.cell.HexCell`
(:class:`ExpectedCell`) and :class:`~mst_cli.model.assembly.SensorGeometry`
(:class:`ExpectedBody`), so that ``geometry.body_volume_mm3`` and the like keep working
wherever they are read. They belong to ``cad/`` (issue 23): move them there as functions of a
geometry when their readers (cad/manifest.py, cad/shapes.py, cad/mesh_body.py,
cad/assembly.py, cli/export.py and the tests) change with them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


class _Cell(Protocol):
    """What :class:`ExpectedCell` reads of a cell."""

    @property
    def theta_rad(self) -> float: ...
    @property
    def t_mm(self) -> float: ...
    @property
    def b_mm(self) -> float: ...
    @property
    def profile_area_mm2(self) -> float: ...

    def outer_profile_xz(self) -> list[tuple[float, float]]: ...
    def inner_profile_xz(self) -> list[tuple[float, float]]: ...


class _Layer(Protocol):
    @property
    def volume_mm3(self) -> float: ...


class _Housing(Protocol):
    @property
    def plate_mm(self) -> float: ...


class _Assembly(Protocol):
    """What :class:`ExpectedBody` reads of a sensor."""

    @property
    def layers(self) -> Sequence[_Layer]: ...
    @property
    def housing(self) -> _Housing: ...
    @property
    def width_mm(self) -> float: ...
    @property
    def depth_mm(self) -> float: ...
    @property
    def base_length_mm(self) -> float: ...
    @property
    def total_height_mm(self) -> float: ...
    @property
    def z_base_top_mm(self) -> float: ...
    @property
    def z_stack_top_mm(self) -> float: ...
    @property
    def z_magnet_bottom_mm(self) -> float: ...
    @property
    def slot_x_mm(self) -> tuple[float, float]: ...
    @property
    def slot_floor_y_mm(self) -> float: ...
    @property
    def slot_height_mm(self) -> float: ...
    @property
    def cable_windows(self) -> tuple[tuple[float, float, float, float, float], ...]: ...
    @property
    def pocket_radius_mm(self) -> float: ...
    @property
    def pocket_depth_mm(self) -> float: ...
    @property
    def pocket_top_y_mm(self) -> float: ...
    @property
    def pocket_roof_rise_mm(self) -> float: ...
    @property
    def pocket_volume_mm3(self) -> float: ...
    @property
    def base_volume_mm3(self) -> float: ...
    @property
    def plates_volume_mm3(self) -> float: ...
    @property
    def cap_volume_mm3(self) -> float: ...


class ExpectedCell:
    """A cell's expected material volume and the lines across its walls (mixin of HexCell)."""

    @property
    def wall_horizontal_width_mm(self: _Cell) -> float:
        """Width of an inclined wall in a horizontal section of the sensor: t / sin(theta)."""
        return self.t_mm / math.sin(self.theta_rad)

    @property
    def volume_mm3(self: _Cell) -> float:
        """Material volume of the layer: profile area x web width D."""
        return self.profile_area_mm2 * self.b_mm

    def wall_centrelines_xz(
        self: _Cell, keep: float = 0.5
    ) -> list[tuple[str, tuple[float, float], tuple[float, float]]]:
        """The four inclined walls as (name, start, end) of the middle ``keep`` of each wall's
        centre line where both its faces are free (cavity inside, air outside), so a line across
        the wall there crosses the wall alone, not the pad, plate or tip it joins (mm).

        A wall shorter than it is thick has no such stretch: its centre line's midpoint, twice."""
        outer, inner = self.outer_profile_xz(), self.inner_profile_xz()
        out = []
        for name, (k0, k1) in (
            ("lower right", (0, 1)),
            ("upper right", (1, 2)),
            ("upper left", (3, 4)),
            ("lower left", (4, 5)),
        ):
            o0, o1, i0, i1 = (np.asarray(v, dtype=float) for v in (outer[k0], outer[k1], inner[k0], inner[k1]))
            u = (o1 - o0) / np.hypot(*(o1 - o0))
            m0 = 0.5 * (o0 + i0)  # on the centre line: midway between parallel faces
            s_lo = max(float((o0 - m0) @ u), float((i0 - m0) @ u))
            s_hi = min(float((o1 - m0) @ u), float((i1 - m0) @ u))
            mid, half = 0.5 * (s_lo + s_hi), max(0.0, 0.5 * keep * (s_hi - s_lo))
            a, b = m0 + (mid - half) * u, m0 + (mid + half) * u
            out.append((name, (float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
        return out


class ExpectedBody:
    """The printed body's expected volumes, pocket areas and bounding box, and the print frame
    (mixin of SensorGeometry)."""

    @property
    def body_bbox_mm(self: _Assembly) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Bounding box (min, max) of the body in the sensor frame: base or cells, whichever
        is wider."""
        x = 0.5 * max(self.base_length_mm, self.width_mm)
        y = 0.5 * self.depth_mm
        return (-x, -y, 0.0), (x, y, self.total_height_mm)

    def pocket_section_area_mm2(self: _Assembly, z_mm: float) -> float:
        """Area of the pocket in the x-y plane at height z (inside the pocket's z range): the
        lower half disc, the straight-sided part up to the pocket top and the strip of the
        45 deg roof, which reaches its apex at the pocket's mid height."""
        r, d = self.pocket_radius_mm, self.pocket_depth_mm
        roof = self.pocket_roof_rise_mm * max(1.0 - abs(z_mm - (self.z_magnet_bottom_mm + 0.5 * d)) / (0.5 * d), 0.0)
        return 0.5 * math.pi * r * r + 2 * r * (self.pocket_top_y_mm + roof)

    @property
    def pocket_volume_mm3(self: _Assembly) -> float:
        """The U-shaped pocket (its x-y section times the depth) plus the roof: a triangular
        prism of base ``pocket_depth`` and height ``pocket_roof_rise_mm``, 2 r long."""
        r, d = self.pocket_radius_mm, self.pocket_depth_mm
        return (0.5 * math.pi * r * r + 2 * r * self.pocket_top_y_mm) * d + r * d * self.pocket_roof_rise_mm

    @property
    def pocket_curved_area_mm2(self: _Assembly) -> float:
        """Curved surface of the pocket (the half cylinder): a mesh of chord deflection delta
        changes the pocket volume by at most delta times this area."""
        return math.pi * self.pocket_radius_mm * self.pocket_depth_mm

    @property
    def base_volume_mm3(self: _Assembly) -> float:
        """Base block minus the board slot and the cable windows (open through the +y face)."""
        L, D = self.base_length_mm, self.depth_mm
        x0, x1 = self.slot_x_mm
        y_top = 0.5 * D
        slot = (x1 - x0) * (y_top - self.slot_floor_y_mm) * self.slot_height_mm
        windows = sum(abs(x_out - x_in) * (y_top - yf) * (z1 - z0) for x_in, x_out, yf, z0, z1 in self.cable_windows)
        return L * D * self.z_base_top_mm - slot - windows

    @property
    def plates_volume_mm3(self: _Assembly) -> float:
        """Solid plates between layers, each W x D x plate thickness."""
        return (len(self.layers) - 1) * self.width_mm * self.depth_mm * self.housing.plate_mm

    @property
    def cap_volume_mm3(self: _Assembly) -> float:
        """Cap (W x D, from the stack top to the total height) minus the magnet pocket."""
        return self.width_mm * self.depth_mm * (self.total_height_mm - self.z_stack_top_mm) - self.pocket_volume_mm3

    @property
    def body_volume_mm3(self: _Assembly) -> float:
        """Volume of the one printed TPU body: analytic sum of its parts."""
        return (
            self.base_volume_mm3 + sum(c.volume_mm3 for c in self.layers) + self.plates_volume_mm3 + self.cap_volume_mm3
        )

    def to_print_frame(self: _Assembly, points_mm: ArrayLike) -> np.ndarray:
        """Sensor-frame points (..., 3) to the print frame: (x, -z, y + D/2)."""
        p = np.asarray(points_mm, dtype=float)
        return np.stack([p[..., 0], -p[..., 2], p[..., 1] + 0.5 * self.depth_mm], axis=-1)
