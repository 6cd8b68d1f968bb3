"""The assembled sensor: :class:`SensorGeometry` (base with the board, the layers and plates, the
cap with the magnet), its :class:`Magnet` and :class:`Housing`, and the rules of the whole.

Everything that needs a dimension -- the mechanics, the magnet-to-chip distance, the CAD and
the checks -- reads it from these objects and :class:`~mst_cli.model.cell.HexCell`; no other
module stores a dimension. Sizes along y are whole numbers of print layers; the few that are
not set by the user (slot floor, pocket top) are snapped to the layer grid here, and the
snapping is reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from mst_cli.model import board_slots
from mst_cli.model.cell import HexCell
from mst_cli.model.components import INSERT_MATERIALS, MAGNET_GRADES_T, Board, default_board
from mst_cli.model.file_keys import spec
from mst_cli.model.insert_plate import InsertPlate as InsertPlate  # re-exported: the file's `insert` section
from mst_cli.model.insert_plate import PrintPause, insert_violations
from mst_cli.model.load_path import Insert
from mst_cli.model.printer import Printer
from mst_cli.model.violation import Violation

if TYPE_CHECKING:
    from mst_cli.model.arrays import Floats  # annotations only: not loaded at run time


def unloaded_gap_mm(sum_h_mm: Floats, n_layers: int, housing: Housing, board: Board) -> Floats:
    """Magnet pole face to Hall plates with no load, for arrays of total layer height.

    Hall plates at the package centre -> chip top -> the board's taller parts (headroom) -> air
    clearance -> cover -> layers with plates between them -> pocket floor -> magnet face.
    :class:`SensorGeometry` reads this too.
    """
    return (
        board.headroom_mm
        - 0.5 * board.chip_height_mm
        + housing.chip_clearance_mm
        + housing.cover_mm
        + sum_h_mm
        + (n_layers - 1) * housing.plate_mm
        + housing.pocket_floor_mm
    )


def printer_violations(printer: Printer, housing: Housing, contact_allowance_mm: float) -> list[Violation]:
    """Broken rules of the printer's deviations (``Violation.of_field``: field, value, what is allowed): every cell the
    printing rules allow must still print with a wall and an open cavity (so that the drawn
    rules guarantee the printed cell works), and the gap offset must fit the housing's
    clearance, pocket floor and cover (what ``calibration.fit.apply_parameters`` can close)."""
    out = []
    hi = 0.5 * (printer.min_gap_mm - contact_allowance_mm)
    if not -printer.min_wall_mm < printer.wall_offset_mm < hi:
        out.append(
            Violation.of_field(
                "printer.wall_offset_mm",
                printer.wall_offset_mm,
                f"must lie between -{printer.min_wall_mm:g} mm (printer.min_wall_mm: a wall of one line "
                f"would print to nothing) and {hi:g} mm ((printer.min_gap_mm - family.contact_allowance_mm)/2: "
                "the narrowest cavity would print closed), both excluded",
            )
        )
    lo = -(housing.chip_clearance_mm + housing.pocket_floor_mm + housing.cover_mm - 0.02)
    if printer.gap_offset_mm < lo:
        out.append(
            Violation.of_field(
                "printer.gap_offset_mm",
                printer.gap_offset_mm,
                f"must be >= {lo:g} mm for this housing: the gap cannot close by more than "
                "housing.chip_clearance_mm + pocket_floor_mm + cover_mm (less 0.01 mm each)",
            )
        )
    return out


@dataclass(frozen=True)
class Magnet:
    """Axially magnetised NdFeB disc (default: diameter 6 x 2 mm, N42, Br = 1.3 T)."""

    diameter_mm: float = spec(6.0, lo=0.1, hi=100.0, unit="mm", meaning="diameter of the disc")
    thickness_mm: float = spec(2.0, lo=0.1, hi=100.0, unit="mm", meaning="thickness of the disc, along its axis")
    remanence_T: float = 1.3  # Br; the file's key (null: the grade's value) is declared in sensor.sections
    grade: str = spec("N42", choices=tuple(MAGNET_GRADES_T), meaning="NdFeB grade: sets Br when `remanence_T` is null")

    @property
    def radius_mm(self) -> float:
        return 0.5 * self.diameter_mm

    @property
    def volume_mm3(self) -> float:
        return math.pi * self.radius_mm**2 * self.thickness_mm


@dataclass(frozen=True)
class Housing:
    """Base (board housing), plates and top cap (magnet pocket), mm, in the sensor frame.

    The defaults are as thin as a 0.4 mm nozzle prints solid (two extrusion lines; the pocket
    floor one line, because the top layer's pad, at least one line itself, lies under it): every
    tenth of a millimetre here is part height and magnet-chip gap not spent on the layers
    (:meth:`SensorGeometry.height_budget_mm` reports the split).

    The base holds the board face-up on ``base_floor_mm`` of material; above the board's
    tallest part an air clearance, then the cover on which the first layer sits. The board
    slides into its slot through the face that is on top in the print (+y), down to a floor;
    connector cables leave through windows in the side walls. The cap holds the magnet in a
    pocket that is open upwards in the print until the pause, then closed by a 45 deg roof.
    """

    # clearances may be zero; walls and floors are at least 0.01 mm
    base_floor_mm: float = spec(
        0.8, lo=0.01, hi=100.0, unit="mm", meaning="material under the board (two extrusion lines)"
    )
    board_clearance_mm: float = spec(0.2, lo=0.0, hi=100.0, unit="mm", meaning="all round the board in its slot")
    chip_clearance_mm: float = spec(
        0.3,
        lo=0.0,
        hi=100.0,
        unit="mm",
        meaning="air between the board's tallest part (chip or connector) and the cover",
    )
    cover_mm: float = spec(
        0.8, lo=0.01, hi=100.0, unit="mm", meaning="solid cover between that air and layer 1 (two lines)"
    )
    side_wall_mm: float = spec(
        1.2,
        lo=0.01,
        hi=100.0,
        unit="mm",
        meaning="thinnest wall beside and under the board slot and above the pocket's roof",
    )
    plate_mm: float = spec(0.8, lo=0.01, hi=100.0, unit="mm", meaning="solid plate between two layers (two lines)")
    pocket_floor_mm: float = spec(
        0.4,
        lo=0.01,
        hi=100.0,
        unit="mm",
        meaning="material between the top layer's pad and the magnet (one line; the pad under it is at least one more)",
    )
    pocket_clearance_mm: float = spec(
        0.1, lo=0.0, hi=100.0, unit="mm", meaning="radial and axial clearance around the magnet"
    )
    cap_top_mm: float = spec(
        0.8, lo=0.01, hi=100.0, unit="mm", meaning="material above the magnet (printed after the pause)"
    )


# Crush ribs hold the magnet in its pocket (issue 44: loose with 0.1 mm clearance, the cap closed
# on it after a few newtons and what moved it changed). Two ribs on the pocket's face over the
# magnet, along the print's build direction, so the magnet slides down them at the pause; each
# reaches the clearance plus this interference into the pocket. 0.1 mm: the thickness tolerance of
# a stock 2 mm NdFeB disc (+-0.05 to +-0.1 mm) plus a slit's shrink in print (about half a line
# width's error, 0.05 mm), so the rib touches the magnet whatever the tolerances; squeezing 0.1 of
# a 0.2 mm TPU rib two lines wide over 3 mm presses the magnet onto its floor with a few newtons,
# which a finger overcomes to push it in.
MAGNET_RIB_INTERFERENCE_MM = 0.1


def snap_to_layers_mm(height_mm: float, layer_height_mm: float, mode: str) -> float:
    """A print height snapped to the layer grid: mode "down", "up" or "nearest" (halves up).
    Heights within 1e-9 layers of a boundary count as on it (float noise)."""
    n = height_mm / layer_height_mm
    if abs(n - round(n)) < 1e-9:
        n = float(round(n))
    whole = {"down": math.floor, "up": math.ceil, "nearest": lambda v: math.floor(v + 0.5 + 1e-9)}[mode](n)
    return round(whole * layer_height_mm, 9)


@dataclass(frozen=True)
class SensorGeometry:
    """The whole stacked sensor: base + layers (bottom to top) separated by plates + cap.

    Sensor frame (used everywhere but the printed mesh): z up the stack from the base's
    underside, x across the cell width, y along the depth, the magnet axis on x = y = 0. The
    magnet-to-chip distance follows from these numbers; it is never an independent input.

    Print frame (STL/3MF): the part lies on its -y face, rotated +90 deg about x:
    print (x, y, z) = (x, -z, y + D/2). Heights along the build direction are sensor y + D/2.
    """

    layers: tuple[HexCell, ...]
    magnet: Magnet = Magnet()
    # None (the default) is the default board, which __post_init__ puts here: a Board after
    board: Board = None  # type: ignore[assignment]
    housing: Housing = Housing()
    chip_offset_mm: tuple[float, float] = spec(
        (0.0, 0.0),
        kind="pair",
        lo=-100.0,
        hi=100.0,
        unit="mm",
        meaning="chip centre relative to the magnet axis (x, y); non-zero selects the `cylinder` field model",
    )
    magnet_tilt_deg: float = spec(
        0.0,
        lo=-45.0,
        hi=45.0,
        unit="deg",
        meaning="tilt of the magnet axis about y; non-zero selects the `cylinder` field model",
    )
    printer: Printer = Printer()
    # every chip's (x, y) when more than one reads the magnet (magnetometer.positions_mm, the
    # first at chip_offset_mm); None: one chip, at chip_offset_mm
    chip_positions_mm: tuple[tuple[float, float], ...] | None = None
    # the stiff plate in the cap (the file's `insert` section); None: none, the cap is TPU alone
    insert_plate: InsertPlate | None = None

    def __post_init__(self):
        if self.board is None:
            object.__setattr__(self, "board", default_board())

    # -- footprint
    @property
    def width_mm(self) -> float:
        return self.layers[0].width_mm

    @property
    def depth_mm(self) -> float:
        """D: the depth of every part of the body, and its height as printed."""
        return self.layers[0].depth_mm

    @property
    def layer_height_mm(self) -> float:
        return self.printer.layer_height_mm

    def print_height_mm(self, y_mm: float) -> float:
        """Height above the bed, in the print, of the sensor-frame coordinate y."""
        return y_mm + 0.5 * self.depth_mm

    def snapped_y_mm(self, y_mm: float, mode: str) -> float:
        """The sensor-frame y whose print height is snapped to the layer grid (``mode`` as in
        :func:`snap_to_layers_mm`)."""
        return snap_to_layers_mm(self.print_height_mm(y_mm), self.layer_height_mm, mode) - 0.5 * self.depth_mm

    @property
    def base_length_mm(self) -> float:
        """Base size along x, centred on the magnet axis: the cell width, or wider when the
        board slots (which need not be centred: the chips are) need side walls around them."""
        return board_slots.base_length_mm(self)

    @property
    def base_width_mm(self) -> float:
        """Base size along y: the depth D, like every other part (the body is one prism)."""
        return self.depth_mm

    # -- board slots: one per chip (mst_cli.model.board_slots); the first chip's as properties
    @property
    def chips_xy_mm(self) -> tuple[tuple[float, float], ...]:
        """Every chip's nominal (x, y): ``chip_positions_mm``, else the one at chip_offset_mm."""
        return tuple(self.chip_positions_mm) if self.chip_positions_mm else (self.chip_offset_mm,)

    @property
    def board_slots(self) -> tuple[board_slots.BoardSlot, ...]:
        """Every chip's board slot and cable windows, in the order of the chips."""
        return board_slots.layout(self)

    @property
    def slot_floor_y_mm(self) -> float:
        """y of the slot floor the board rests on: where the chip puts the board's lower edge,
        snapped to the nearest layer boundary (an up-facing face prints on one)."""
        return board_slots.chip_floor_y_mm(self, self.chip_offset_mm)

    @property
    def board_origin_xy_mm(self) -> tuple[float, float]:
        """Board's lower-left corner as printed: x from the chip offset, y on the slot floor."""
        return self.board_slots[0].board_origin_xy_mm

    @property
    def chip_xy_printed_mm(self) -> tuple[float, float]:
        """Where the chip sits in the printed housing (y differs from the nominal chip offset
        by the floor's snap to the layer grid, at most half a layer)."""
        return self.board_slots[0].chip_xy_printed_mm

    @property
    def slot_x_mm(self) -> tuple[float, float]:
        """Board slot (x0, x1): the board outline plus the clearance on both sides."""
        return board_slots.chip_slot_x_mm(self, self.chip_offset_mm)

    @property
    def slot_height_mm(self) -> float:
        """Clear height of the slot: board + its tallest part + air clearance, up to the cover."""
        return self.z_cover_bottom_mm - self.z_board_bottom_mm

    @property
    def cable_windows(self) -> tuple[tuple[float, float, float, float, float], ...]:
        """Windows through the base's side walls for the first board's connector cables, as
        (x_inner, x_outer, y_floor, z0, z1): from the slot wall out through the base's x face (or
        into the next slot), from a floor just below the connector (snapped down to the layer
        grid) up through the face on top in the print, over the slot's height above the board."""
        return self.board_slots[0].windows

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
        return self.z_board_top_mm + self.board.headroom_mm + self.housing.chip_clearance_mm

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
    def pocket_radius_mm(self) -> float:
        return self.magnet.radius_mm + self.housing.pocket_clearance_mm

    @property
    def pocket_depth_mm(self) -> float:
        """Pocket size along the magnet axis (sensor z): magnet thickness + clearance."""
        return self.magnet.thickness_mm + self.housing.pocket_clearance_mm

    @property
    def z_magnet_bottom_mm(self) -> float:
        """Lower pole face of the magnet (it rests on the pocket floor)."""
        return self.z_stack_top_mm + self.housing.pocket_floor_mm

    @property
    def z_magnet_top_mm(self) -> float:
        return self.z_magnet_bottom_mm + self.magnet.thickness_mm

    @property
    def magnet_rib_x_mm(self) -> tuple[float, ...]:
        """The crush ribs' centres across the pocket: half way out to its sides; none in a pocket
        narrower than two ribs' bases (each must stand wholly on the pocket's face)."""
        r = self.pocket_radius_mm
        return (-0.5 * r, 0.5 * r) if r >= self.magnet_rib_width_mm else ()

    @property
    def magnet_rib_width_mm(self) -> float:
        """A crush rib's base across the pocket: two extrusion lines."""
        return 2.0 * self.printer.nozzle_mm

    @property
    def magnet_rib_reach_mm(self) -> float:
        """How far a crush rib reaches from the pocket's face over the magnet towards it: the
        clearance plus the interference (MAGNET_RIB_INTERFERENCE_MM)."""
        return self.housing.pocket_clearance_mm + MAGNET_RIB_INTERFERENCE_MM

    @property
    def pocket_top_y_mm(self) -> float:
        """y where the pocket's straight sides end (it is a U open towards +y: a half disc
        below y = 0, straight sides above): the pocket radius, snapped up to the layer grid,
        so the magnet is wholly below the layer printed after the pause."""
        return self.snapped_y_mm(self.pocket_radius_mm, "up")

    @property
    def pocket_roof_rise_mm(self) -> float:
        """Rise of the pocket's gable roof: half the pocket depth (45 deg), rounded up to whole
        layers so that the ridge closes on a layer boundary (the last layer before it then
        leaves a slit narrower than a line, not a slot to bridge along the ridge)."""
        return snap_to_layers_mm(0.5 * self.pocket_depth_mm, self.layer_height_mm, "up")

    @property
    def pocket_roof_apex_y_mm(self) -> float:
        """Apex (ridge) of the pocket's gable roof, at least 45 deg from horizontal."""
        return self.pocket_top_y_mm + self.pocket_roof_rise_mm

    @property
    def pause_height_mm(self) -> float:
        """Print height at which to pause and drop the magnet in: the top of the last layer
        before the roof (a layer boundary)."""
        return self.print_height_mm(self.pocket_top_y_mm)

    @property
    def pause_after_layer(self) -> int:
        """Number (from 1) of the print layer after which the print pauses."""
        return int(round(self.pause_height_mm / self.layer_height_mm))

    @property
    def z_pocket_top_mm(self) -> float:
        """The pocket's face above the magnet (the magnet, its axial clearance)."""
        return self.z_magnet_top_mm + self.housing.pocket_clearance_mm

    @property
    def has_insert(self) -> bool:
        return self.insert_plate is not None and self.insert_plate.present

    @property
    def total_height_mm(self) -> float:
        """The top face: cap_top_mm over the pocket, or over the insert when there is one."""
        top = self.insert_slot_box_mm[1][2] if self.has_insert else self.z_pocket_top_mm
        return top + self.housing.cap_top_mm

    # -- the insert: its slot and the plate, computed here once (CAD, closed form, FE read them)
    @property
    def insert_slot_roof_rise_mm(self) -> float:
        """Rise of the 45 deg gable over the slot (half the plate's thickness, whole layers), as
        :attr:`pocket_roof_rise_mm` is over the pocket."""
        assert self.insert_plate is not None
        return snap_to_layers_mm(0.5 * self.insert_plate.thickness_mm, self.layer_height_mm, "up")

    @property
    def insert_slot_box_mm(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(lo, hi) of the insert's slot, sensor frame, without its gable: across the face with
        side_wall_mm left at each x face; from a floor on the layer grid side_wall_mm above the
        -y face up to a layer boundary (the pause) that leaves side_wall_mm over the gable; along
        z from cap_top_mm over the pocket, the plate's thickness."""
        ip, h = self.insert_plate, self.housing
        assert ip is not None and ip.present, "no insert"
        a = 0.5 * self.width_mm - h.side_wall_mm
        d2 = 0.5 * self.depth_mm
        y0 = self.snapped_y_mm(-d2 + h.side_wall_mm, "up")
        y1 = self.snapped_y_mm(d2 - h.side_wall_mm - self.insert_slot_roof_rise_mm, "down")
        z0 = self.z_pocket_top_mm + h.cap_top_mm
        return (-a, y0, z0), (a, y1, z0 + ip.thickness_mm)

    @property
    def insert_box_mm(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(lo, hi) of the plate as it sits, sensor frame: the slot less the clearance at each x
        side and at the top (it rests on the slot's floor, fills the slot's thickness)."""
        assert self.insert_plate is not None
        (x0, y0, z0), (x1, y1, z1) = self.insert_slot_box_mm
        c = self.insert_plate.clearance_mm
        return (x0 + c, y0, z0), (x1 - c, y1 - c, z1)

    @property
    def insert(self) -> Insert | None:
        """The plate as the closed form takes it (:class:`~mst_cli.model.load_path.Insert`: its
        plane-strain modulus, its underside above the top pad's underside), or None."""
        if not self.has_insert:
            return None
        assert self.insert_plate is not None
        m = INSERT_MATERIALS[self.insert_plate.material]
        (_, y0, z0), (_, y1, _) = self.insert_box_mm
        z = self.layers[-1].t_mm + z0 - self.z_stack_top_mm
        return Insert(m.name, m.plane_strain_modulus_MPa, m.poisson_ratio, self.insert_plate.thickness_mm, z, y1 - y0)

    @property
    def insert_pause(self) -> PrintPause | None:
        """The pause that drops the plate in: at the top of its slot (a layer boundary)."""
        if not self.has_insert:
            return None
        z = self.print_height_mm(self.insert_slot_box_mm[1][1])
        return PrintPause(int(round(z / self.layer_height_mm)), z, "drop the insert plate into its slot")

    @property
    def pauses(self) -> tuple[PrintPause, ...]:
        """Every pause of the print, lowest first: the magnet's, then the insert's when there is one."""
        magnet = PrintPause(self.pause_after_layer, self.pause_height_mm, "drop the magnet into its pocket")
        return (magnet,) if self.insert_pause is None else (magnet, self.insert_pause)

    @property
    def gap0_mm(self) -> float:
        """Unloaded distance from the magnet's lower pole face to the Hall plates."""
        return float(unloaded_gap_mm(sum(c.h_mm for c in self.layers), len(self.layers), self.housing, self.board))

    def height_budget_mm(self) -> dict:
        """Where the part's height and the magnet-chip gap go (mm): the housing overhead is
        everything not spent on the collapsible layers; the gap splits into the chip side
        (Hall plates to layer 1: board parts, air, cover), the stack (layers and plates) and
        the magnet side (pocket floor)."""
        layers = sum(c.h_mm for c in self.layers)
        plates = (len(self.layers) - 1) * self.housing.plate_mm
        chip_side = self.z_base_top_mm - self.z_hall_mm
        magnet_side = self.z_magnet_bottom_mm - self.z_stack_top_mm
        return {
            "total_height_mm": self.total_height_mm,
            "layers_mm": layers,
            "plates_mm": plates,
            "base_mm": self.z_base_top_mm,
            "cap_mm": self.total_height_mm - self.z_stack_top_mm,
            "housing_overhead_mm": self.total_height_mm - layers,
            "board_headroom_mm": self.board.headroom_mm,
            "gap0_mm": self.gap0_mm,
            "gap_chip_side_mm": chip_side,
            "gap_stack_mm": layers + plates,
            "gap_magnet_side_mm": magnet_side,
        }

    def violations(self, printer: Printer | None = None) -> list[Violation]:
        """Broken cell rules, each with its ``layer`` (index from 0), ``field`` (``layers[i]``) and
        ``value`` (the cell's theta_deg, t_mm, h_mm), judged by ``printer`` (default: the
        printer this geometry is printed on, not a default one)."""
        printer = self.printer if printer is None else printer
        return [
            replace(
                v,
                layer=i,
                field=f"layers[{i}]",
                value={"theta_deg": c.theta_deg, "t_mm": c.t_mm, "h_mm": c.h_mm},
            )
            for i, c in enumerate(self.layers)
            for v in c.violations(printer)
        ]

    def housing_violations(self) -> list[Violation]:
        """Broken housing rules (``Violation.of_field``: field, value, what is allowed): what the
        body needs to be one printable solid with a closed pocket and a slot that holds the board."""
        h, D, lh = self.housing, self.depth_mm, self.layer_height_mm
        out = printer_violations(self.printer, h, self.layers[0].contact_allowance_mm)
        if abs(D / lh - round(D / lh)) > 1e-6:
            out.append(
                Violation.of_field(
                    "family.depth_mm",
                    D,
                    f"must be a whole number of print layers "
                    f"(printer.layer_height_mm = {lh:g}): D is the printed height",
                )
            )
        room_x = 0.5 * self.width_mm - h.side_wall_mm
        if self.pocket_radius_mm > room_x:
            out.append(
                Violation.of_field(
                    "magnet.diameter_mm",
                    self.magnet.diameter_mm,
                    f"the pocket radius {self.pocket_radius_mm:g} mm (with clearance) must be <= "
                    f"{room_x:g} mm: width_mm/2 minus housing.side_wall_mm",
                )
            )
        floor_room = self.slot_floor_y_mm + 0.5 * D
        if floor_room < h.side_wall_mm - 1e-9:
            out.append(
                Violation.of_field(
                    "family.depth_mm",
                    D,
                    f"the board {self.board.key} hangs {self.board.chip_y_mm:g} mm below its chip: "
                    f"its slot floor needs depth_mm >= "
                    f"{2 * (self.board.chip_y_mm - self.chip_offset_mm[1] + h.side_wall_mm):g} mm "
                    f"(housing.side_wall_mm under it), or another board",
                )
            )
        low = min((w[2] for w in self.cable_windows), default=None)  # the lowest window floor
        if low is not None and low + 0.5 * D < h.side_wall_mm - 1e-9:
            most = h.board_clearance_mm - (h.side_wall_mm - (low + 0.5 * D))
            out.append(
                Violation.of_field(
                    "housing.board_clearance_mm",
                    h.board_clearance_mm,
                    f"the cable windows reach {low:g} mm, through the body's -y face: "
                    f"housing.side_wall_mm must stay under them (here a clearance of at most "
                    f"about {max(most, 0.0):.3g} mm), or a deeper family.depth_mm",
                )
            )
        roof_room = 0.5 * D - self.pocket_roof_apex_y_mm
        if roof_room < h.side_wall_mm - 1e-9:
            out.append(
                Violation.of_field(
                    "family.depth_mm",
                    D,
                    f"the magnet pocket's roof needs depth_mm >= "
                    f"{2 * (self.pocket_roof_apex_y_mm + h.side_wall_mm):g} mm "
                    "(housing.side_wall_mm above its apex)",
                )
            )
        return board_slots.chip_off_face_violations(self) + out + insert_violations(self)  # a chip off the face first
