"""The one description of the sensor's geometry.

Everything that needs a dimension -- the mechanics, the magnet-to-chip distance, the CAD and
the checks -- reads it from the objects in this module; no other module stores a dimension.

Two layers of code live here, in the magpylib style:

* pure, vectorised kernels (``pad_half_width_mm`` ...) that take numpy arrays in mm / radians
  and return arrays, used by the design loop on thousands of candidate cells at once;
* frozen dataclasses (:class:`HexCell`, :class:`SensorGeometry`) that wrap the kernels for one
  concrete design and add validity checks that name the violated rule.

The "hex" cell (DESIGN.md section 3), profile in the x-z plane, x across the width W::

        (-p,h) ____________ (p,h)
              /            \\
    (-W/2,h/2)              (W/2,h/2)
              \\____________/
        (-p,0)              (p,0)

with p = W/2 - (h/2)/tan(theta). The inner boundary is that hexagon offset inward by the wall
thickness t. The profile is extruded by the strut width b, n_s times along the depth D.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# Lengths are floored at this value inside the kernels so that every point of the design
# bounds -- valid or not -- gives finite numbers; the validity checks report the violation.
LENGTH_FLOOR_MM = 1e-6


# --------------------------------------------------------------------------- kernels
def pad_half_width_mm(theta_rad, h_mm, width_mm):
    """Half width p of the outer top/bottom pad: p = W/2 - (h/2)/tan(theta)."""
    return 0.5 * width_mm - 0.5 * h_mm / np.tan(theta_rad)


def inner_pad_half_width_mm(theta_rad, t_mm, h_mm, width_mm):
    """Half width of the inner (cavity-side) pad: the outer vertex offset inward by t.

    Offsetting the hexagon's edges by t moves the bottom vertex (p, 0) to
    (p - t tan(theta/2), t).
    """
    return pad_half_width_mm(theta_rad, h_mm, width_mm) - t_mm * np.tan(0.5 * theta_rad)


def inner_tip_half_width_mm(theta_rad, t_mm, width_mm):
    """x of the inner hexagon's side vertex: the tip W/2 offset inward by t/sin(theta)."""
    return 0.5 * width_mm - t_mm / np.sin(theta_rad)


def wall_centreline_length_mm(theta_rad, t_mm, h_mm):
    """Length of one inclined wall along its centre line (offset t/2 from the outside).

    The centre line rises (h - t)/2 at angle theta: L = (h - t) / (2 sin theta). Floored at
    LENGTH_FLOOR_MM so that degenerate cells (h <= t) still give finite stiffness.
    """
    return np.maximum(0.5 * (h_mm - t_mm) / np.sin(theta_rad), LENGTH_FLOOR_MM)


def cavity_height_mm(t_mm, h_mm):
    """Clear height of the cavity at the centre, h - 2t (negative for an invalid cell)."""
    return h_mm - 2.0 * t_mm


def lock_stroke_mm(t_mm, h_mm, contact_allowance_mm):
    """Compression d_lock at which the cavity closes: h - 2t - allowance, floored > 0."""
    return np.maximum(cavity_height_mm(t_mm, h_mm) - contact_allowance_mm, LENGTH_FLOOR_MM)


def strut_gap_mm(depth_mm, strut_width_mm, struts_per_chevron):
    """Clear gap between neighbouring struts, struts centred at pitch D/n_s."""
    return depth_mm / struts_per_chevron - strut_width_mm


def profile_area_mm2(theta_rad, t_mm, h_mm, width_mm):
    """Area of the hex profile's material (outer hexagon minus inner hexagon), mm^2.

    A hexagon with pad half-width a, tip half-width c and height H has area (2a + 2c)/2 * H
    ... i.e. two trapezoids: H * (a + c). The inner hexagon has a_in, c_in = W/2 - t/sin(theta)
    and height h - 2t.
    """
    a_out = pad_half_width_mm(theta_rad, h_mm, width_mm)
    c_out = 0.5 * width_mm
    a_in = inner_pad_half_width_mm(theta_rad, t_mm, h_mm, width_mm)
    c_in = inner_tip_half_width_mm(theta_rad, t_mm, width_mm)
    h_in = np.maximum(cavity_height_mm(t_mm, h_mm), 0.0)
    return h_mm * (a_out + c_out) - h_in * (a_in + c_in)


# Names of the cell validity rules, in the order :func:`cell_margins_mm` stacks them.
CELL_RULES = ("wall", "strut_width", "cavity_gap", "lock_stroke", "pad_width", "strut_spacing")


def cell_margins_mm(theta_rad, t_mm, h_mm, b_mm, width_mm, depth_mm, struts_per_chevron,
                    contact_allowance_mm, min_wall_mm, min_gap_mm, nozzle_mm):
    """Signed margins (mm, >= 0 satisfied) of every cell rule, stacked on a last axis.

    Shape (..., len(CELL_RULES)), order :data:`CELL_RULES`. :meth:`HexCell.margins` reads this
    kernel; the design loop calls it on thousands of candidates at once.
    """
    cavity = cavity_height_mm(t_mm, h_mm)
    parts = (
        t_mm - min_wall_mm,
        b_mm - min_wall_mm,
        cavity - min_gap_mm,
        cavity - contact_allowance_mm,
        inner_pad_half_width_mm(theta_rad, t_mm, h_mm, width_mm) - nozzle_mm,
        strut_gap_mm(depth_mm, b_mm, struts_per_chevron) - min_gap_mm,
    )
    return np.stack(np.broadcast_arrays(*parts), axis=-1).astype(float)


def unloaded_gap_mm(sum_h_mm, n_layers, housing: "Housing", board: "Board"):
    """Magnet pole face to Hall plates with no load, for arrays of total layer height.

    Hall plates at the package centre -> chip top -> air clearance -> cover -> layers with
    plates between them -> pocket floor -> magnet face. :class:`SensorGeometry` reads this too.
    """
    return (0.5 * board.chip_height_mm + housing.chip_clearance_mm + housing.cover_mm
            + sum_h_mm + (n_layers - 1) * housing.plate_mm + housing.pocket_floor_mm)


# --------------------------------------------------------------------------- objects
@dataclass(frozen=True)
class Printer:
    """What the printer can make. Defaults: 0.4 mm nozzle, 0.2 mm layers.

    min_wall_mm: one extrusion line of TPU (= nozzle) is the thinnest reliable wall.
    min_gap_mm: the narrowest slot that stays open when printed (= nozzle).
    """

    nozzle_mm: float = 0.4
    layer_height_mm: float = 0.2
    min_wall_mm: float = 0.4
    min_gap_mm: float = 0.4


@dataclass(frozen=True)
class Violation:
    """One broken validity rule: its name, the signed margin (mm, < 0) and a sentence."""

    rule: str
    margin_mm: float
    message: str


@dataclass(frozen=True)
class HexCell:
    """One collapsible layer of the "hex" family (DESIGN.md section 3).

    Parameters are the design variables theta (deg), t (mm), h (mm) and the family constants.
    ``strut_width_mm`` None means b = t.
    """

    theta_deg: float
    t_mm: float
    h_mm: float
    width_mm: float = 30.0
    depth_mm: float = 20.0
    struts_per_chevron: int = 4
    strut_width_mm: float | None = None
    contact_allowance_mm: float = 0.1

    # -- derived quantities (all read the kernels above)
    @property
    def theta_rad(self) -> float:
        return math.radians(self.theta_deg)

    @property
    def b_mm(self) -> float:
        """Strut width along the depth (default: equal to the wall thickness)."""
        return self.t_mm if self.strut_width_mm is None else self.strut_width_mm

    @property
    def p_mm(self) -> float:
        return float(pad_half_width_mm(self.theta_rad, self.h_mm, self.width_mm))

    @property
    def p_inner_mm(self) -> float:
        return float(inner_pad_half_width_mm(self.theta_rad, self.t_mm, self.h_mm, self.width_mm))

    @property
    def wall_length_mm(self) -> float:
        return float(wall_centreline_length_mm(self.theta_rad, self.t_mm, self.h_mm))

    @property
    def cavity_height_mm(self) -> float:
        return float(cavity_height_mm(self.t_mm, self.h_mm))

    @property
    def d_lock_mm(self) -> float:
        return float(lock_stroke_mm(self.t_mm, self.h_mm, self.contact_allowance_mm))

    @property
    def strut_pitch_mm(self) -> float:
        return self.depth_mm / self.struts_per_chevron

    @property
    def strut_gap_mm(self) -> float:
        return float(strut_gap_mm(self.depth_mm, self.b_mm, self.struts_per_chevron))

    @property
    def strut_centres_y_mm(self) -> tuple[float, ...]:
        """y of each strut's mid-plane, measured from the cell's centre (symmetric)."""
        pitch = self.strut_pitch_mm
        n = self.struts_per_chevron
        return tuple((j + 0.5) * pitch - 0.5 * self.depth_mm for j in range(n))

    @property
    def wall_horizontal_width_mm(self) -> float:
        """Width of an inclined wall in a horizontal section (one printed layer): t / sin(theta)."""
        return self.t_mm / math.sin(self.theta_rad)

    @property
    def profile_area_mm2(self) -> float:
        return float(profile_area_mm2(self.theta_rad, self.t_mm, self.h_mm, self.width_mm))

    @property
    def volume_mm3(self) -> float:
        """Material volume of the layer: profile area x strut width x number of struts."""
        return self.profile_area_mm2 * self.b_mm * self.struts_per_chevron

    def outer_profile_xz(self) -> list[tuple[float, float]]:
        """Outer hexagon, counter-clockwise from the bottom-right pad corner (mm)."""
        p, w2, h = self.p_mm, 0.5 * self.width_mm, self.h_mm
        return [(p, 0.0), (w2, 0.5 * h), (p, h), (-p, h), (-w2, 0.5 * h), (-p, 0.0)]

    def inner_profile_xz(self) -> list[tuple[float, float]]:
        """Inner (cavity) hexagon: the outer one offset inward by t, same vertex order."""
        t, h = self.t_mm, self.h_mm
        a = self.p_inner_mm
        c = float(inner_tip_half_width_mm(self.theta_rad, t, self.width_mm))
        return [(a, t), (c, 0.5 * h), (a, h - t), (-a, h - t), (-c, 0.5 * h), (-a, t)]

    def violations(self, printer: Printer = Printer()) -> list[Violation]:
        """Every broken validity rule (empty when the cell is printable and works)."""
        return [v for v in self.margins(printer) if v.margin_mm < 0.0]

    def margins(self, printer: Printer = Printer()) -> list[Violation]:
        """Signed margin of every rule in mm (>= 0 satisfied); used as optimiser constraints.

        The margins come from :func:`cell_margins_mm` (one source of truth with the design loop).
        """
        margins = cell_margins_mm(self.theta_rad, self.t_mm, self.h_mm, self.b_mm, self.width_mm,
                                  self.depth_mm, self.struts_per_chevron, self.contact_allowance_mm,
                                  printer.min_wall_mm, printer.min_gap_mm, printer.nozzle_mm)
        messages = {
            "wall": f"wall t = {self.t_mm:g} mm is thinner than the printable minimum {printer.min_wall_mm:g} mm",
            "strut_width": f"strut width b = {self.b_mm:g} mm is below the printable minimum {printer.min_wall_mm:g} mm",
            "cavity_gap": f"cavity h - 2t = {self.cavity_height_mm:g} mm is below the printable gap {printer.min_gap_mm:g} mm",
            "lock_stroke": (f"cavity h - 2t = {self.cavity_height_mm:g} mm leaves no stroke after the "
                            f"{self.contact_allowance_mm:g} mm contact allowance"),
            "pad_width": (f"inner pad half-width {self.p_inner_mm:g} mm is below one nozzle "
                          f"({printer.nozzle_mm:g} mm): theta too small for this h and W"),
            "strut_spacing": (f"gap between struts {self.strut_gap_mm:g} mm is below the printable gap "
                              f"{printer.min_gap_mm:g} mm: too many or too wide struts for D = {self.depth_mm:g} mm"),
        }
        return [Violation(name, float(m), messages[name]) for name, m in zip(CELL_RULES, margins)]


@dataclass(frozen=True)
class Magnet:
    """Axially magnetised NdFeB disc (default: diameter 6 x 2 mm, N42, Br = 1.3 T)."""

    diameter_mm: float = 6.0
    thickness_mm: float = 2.0
    remanence_T: float = 1.3
    grade: str = "N42"

    @property
    def radius_mm(self) -> float:
        return 0.5 * self.diameter_mm

    @property
    def volume_mm3(self) -> float:
        return math.pi * self.radius_mm ** 2 * self.thickness_mm


@dataclass(frozen=True)
class Board:
    """A magnetometer carrier board (catalogue in :mod:`mst_cli.components`)."""

    key: str
    name: str
    length_mm: float           # along x (the cell width direction)
    width_mm: float            # along y
    thickness_mm: float
    chip_x_mm: float           # chip centre from the board's lower-left corner
    chip_y_mm: float
    holes_xy_mm: tuple[tuple[float, float], ...] = ()
    hole_diameter_mm: float = 2.5
    chip_size_mm: float = 3.0       # QFN-16, 3 x 3 x 1 mm, Hall plates at its centre
    chip_height_mm: float = 1.0


@dataclass(frozen=True)
class Housing:
    """Base (board housing) and top cap (magnet pocket) dimensions, mm.

    z runs up from the build plate. The base holds the board face-up on ``base_floor_mm`` of
    material; above the chip an air clearance, then the cover on which the first layer sits.
    The cap holds the magnet in a closed pocket: the print is paused at the pocket's top to
    drop the magnet in.
    """

    base_floor_mm: float = 1.0
    board_clearance_mm: float = 0.2      # all round the board in its slot
    chip_clearance_mm: float = 0.3       # air between chip top and the cover's underside
    cover_mm: float = 0.8                # solid TPU between that air gap and layer 1
    side_wall_mm: float = 1.2            # thinnest wall of the base around the board slot
    plate_mm: float = 1.2                # solid plate between two collapsible layers
    pocket_floor_mm: float = 0.6         # TPU between the top layer and the magnet's face
    pocket_clearance_mm: float = 0.1     # radial and axial clearance around the magnet
    pocket_chamfer_mm: float = 0.3       # entry chamfer at the pocket's top edge
    cap_top_mm: float = 0.8              # TPU above the magnet (printed after the pause)
    cable_exit_width_mm: float = 8.0     # opening in the base side wall for the cable


@dataclass(frozen=True)
class SensorGeometry:
    """The whole stacked sensor: base + layers (bottom to top) separated by plates + cap.

    Every z below is measured from the build plate, mm. The magnet-to-chip distance follows
    from these numbers; it is never an independent input.
    """

    layers: tuple[HexCell, ...]
    magnet: Magnet = Magnet()
    board: Board | None = None
    housing: Housing = Housing()
    chip_offset_mm: tuple[float, float] = (0.0, 0.0)   # chip centre relative to magnet axis
    magnet_tilt_deg: float = 0.0                        # tilt of the magnet axis about y

    def __post_init__(self):
        if self.board is None:
            from .components import default_board  # late: the catalogue imports this module
            object.__setattr__(self, "board", default_board())

    # -- footprint
    @property
    def width_mm(self) -> float:
        return self.layers[0].width_mm

    @property
    def depth_mm(self) -> float:
        return self.layers[0].depth_mm

    @property
    def base_length_mm(self) -> float:
        """Base size along x, centred on the magnet axis: the cell width, or wider when the
        board slot (which need not be centred: the chip is) needs side walls around it."""
        x0, x1, _, _ = self.slot_xy_mm
        need = 2 * (max(-x0, x1) + self.housing.side_wall_mm)
        return max(self.width_mm, need)

    @property
    def base_width_mm(self) -> float:
        """Base size along y, centred on the magnet axis (see :attr:`base_length_mm`)."""
        _, _, y0, y1 = self.slot_xy_mm
        need = 2 * (max(-y0, y1) + self.housing.side_wall_mm)
        return max(self.depth_mm, need)

    @property
    def board_origin_xy_mm(self) -> tuple[float, float]:
        """Board's lower-left corner, placed so that the chip sits at ``chip_offset_mm``."""
        return (self.chip_offset_mm[0] - self.board.chip_x_mm,
                self.chip_offset_mm[1] - self.board.chip_y_mm)

    @property
    def slot_xy_mm(self) -> tuple[float, float, float, float]:
        """Board slot (x0, x1, y0, y1): the board outline plus the clearance all round.

        The slot is open through the base's -x face (the board slides in along +x until it
        stops at x1, which locates the chip); the cable exit leaves through the +x wall.
        """
        bx, by = self.board_origin_xy_mm
        c = self.housing.board_clearance_mm
        return (bx - c, bx + self.board.length_mm + c, by - c, by + self.board.width_mm + c)

    @property
    def slot_height_mm(self) -> float:
        """Clear height of the slot: board + chip + air clearance, up to the cover."""
        return self.z_cover_bottom_mm - self.z_board_bottom_mm

    @property
    def cable_exit_y_mm(self) -> tuple[float, float]:
        """y range of the cable exit through the +x wall: centred on the chip, inside the slot."""
        _, _, y0, y1 = self.slot_xy_mm
        half = 0.5 * self.housing.cable_exit_width_mm
        yc = self.chip_offset_mm[1]
        return (max(y0, yc - half), min(y1, yc + half))

    # -- base
    @property
    def z_board_bottom_mm(self) -> float:
        return self.housing.base_floor_mm

    @property
    def z_board_top_mm(self) -> float:
        return self.z_board_bottom_mm + self.board.thickness_mm

    @property
    def z_chip_top_mm(self) -> float:
        return self.z_board_top_mm + self.board.chip_height_mm

    @property
    def z_hall_mm(self) -> float:
        """Height of the Hall plates (centre of the QFN package, MLX90393 datasheet)."""
        return self.z_board_top_mm + 0.5 * self.board.chip_height_mm

    @property
    def z_cover_bottom_mm(self) -> float:
        return self.z_chip_top_mm + self.housing.chip_clearance_mm

    @property
    def z_base_top_mm(self) -> float:
        return self.z_cover_bottom_mm + self.housing.cover_mm

    # -- layers and plates
    @property
    def layer_bottoms_mm(self) -> tuple[float, ...]:
        z = self.z_base_top_mm
        out = []
        for i, cell in enumerate(self.layers):
            if i:
                z += self.housing.plate_mm
            out.append(z)
            z += cell.h_mm
        return tuple(out)

    @property
    def z_stack_top_mm(self) -> float:
        return self.layer_bottoms_mm[-1] + self.layers[-1].h_mm

    # -- cap and magnet
    @property
    def pocket_diameter_mm(self) -> float:
        return self.magnet.diameter_mm + 2 * self.housing.pocket_clearance_mm

    @property
    def pocket_depth_mm(self) -> float:
        return self.magnet.thickness_mm + self.housing.pocket_clearance_mm

    @property
    def z_magnet_bottom_mm(self) -> float:
        """Lower pole face of the magnet (it rests on the pocket floor)."""
        return self.z_stack_top_mm + self.housing.pocket_floor_mm

    @property
    def z_pause_mm(self) -> float:
        """Print height at which to pause and insert the magnet: the pocket's top."""
        return self.z_magnet_bottom_mm + self.pocket_depth_mm

    @property
    def total_height_mm(self) -> float:
        return self.z_pause_mm + self.housing.cap_top_mm

    @property
    def body_bbox_mm(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Bounding box (min, max) of the printed body: base or cells, whichever is wider."""
        x = 0.5 * max(self.base_length_mm, self.width_mm)
        y = 0.5 * max(self.base_width_mm, self.depth_mm)
        return (-x, -y, 0.0), (x, y, self.total_height_mm)

    @property
    def pocket_volume_mm3(self) -> float:
        """Magnet pocket: cylinder of pocket diameter and depth, plus the 45 deg entry chamfer
        c at its top (a frustum of radii r and r + c minus the cylinder it replaces)."""
        r, c = 0.5 * self.pocket_diameter_mm, self.housing.pocket_chamfer_mm
        frustum = math.pi * c / 3.0 * (r * r + r * (r + c) + (r + c) ** 2)
        return math.pi * r * r * self.pocket_depth_mm + frustum - math.pi * r * r * c

    @property
    def pocket_curved_area_mm2(self) -> float:
        """Curved surface of the pocket (cylinder wall + chamfer cone): a mesh of chord
        deflection delta changes the pocket volume by at most delta times this area."""
        r, c = 0.5 * self.pocket_diameter_mm, self.housing.pocket_chamfer_mm
        return (2 * math.pi * r * (self.pocket_depth_mm - c)
                + math.pi * (2 * r + c) * c * math.sqrt(2.0))

    @property
    def base_volume_mm3(self) -> float:
        """Base block minus the board slot (open to -x) and the cable exit (through +x)."""
        L, Wb = self.base_length_mm, self.base_width_mm
        _, x1, y0, y1 = self.slot_xy_mm
        e0, e1 = self.cable_exit_y_mm
        slot = (x1 + 0.5 * L) * (y1 - y0) * self.slot_height_mm
        exit_ = (0.5 * L - x1) * max(e1 - e0, 0.0) * self.slot_height_mm
        return L * Wb * self.z_base_top_mm - slot - exit_

    @property
    def plates_volume_mm3(self) -> float:
        """Solid plates between layers, each W x D x plate thickness."""
        return (len(self.layers) - 1) * self.width_mm * self.depth_mm * self.housing.plate_mm

    @property
    def cap_volume_mm3(self) -> float:
        """Cap (W x D, from the stack top to the total height) minus the magnet pocket."""
        return (self.width_mm * self.depth_mm * (self.total_height_mm - self.z_stack_top_mm)
                - self.pocket_volume_mm3)

    @property
    def body_volume_mm3(self) -> float:
        """Volume of the one printed TPU body: analytic sum of its parts."""
        return (self.base_volume_mm3 + sum(c.volume_mm3 for c in self.layers)
                + self.plates_volume_mm3 + self.cap_volume_mm3)

    @property
    def gap0_mm(self) -> float:
        """Unloaded distance from the magnet's lower pole face to the Hall plates."""
        return float(unloaded_gap_mm(sum(c.h_mm for c in self.layers), len(self.layers),
                                     self.housing, self.board))

    @property
    def total_lock_stroke_mm(self) -> float:
        return sum(c.d_lock_mm for c in self.layers)

    def violations(self, printer: Printer = Printer()) -> list[tuple[int, Violation]]:
        """Broken cell rules as (layer index from 0, violation)."""
        return [(i, v) for i, c in enumerate(self.layers) for v in c.violations(printer)]
