"""One board slot per chip: where each carrier board sits in the base and where its cables leave.

Every chip of ``magnetometer.positions_mm`` (else the one at ``chip_offset_mm``) gets the slot
the single chip always had, shifted to that chip: the board outline plus the clearance, from a
floor under the board (snapped to the print layer grid) out through the face on top in the
print (+y), so each board slides in along -y. Slots therefore lie side by side along x, all on
one floor: their chips' y must put every board on the first chip's floor, and a side wall at
least ``housing.side_wall_mm`` thick must stand between two slots.

Each connector's cable window runs from its slot's side wall towards the side it faces, out
through the base's x face -- or, when another slot lies that way, into that slot: the windows
between two neighbouring slots join them, so one short cable links the facing sockets (an I2C
daisy chain; the boards need different addresses) and the outermost sockets reach the faces.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from mst_cli.model.components import Board
from mst_cli.model.violation import Violation

POSITIONS_FIELD = "magnetometer.positions_mm"

# (x_inner, x_outer, y_floor, z0, z1), mm: from the slot wall to the base face or the next slot
Window = tuple[float, float, float, float, float]


class _Housing(Protocol):
    @property
    def board_clearance_mm(self) -> float: ...

    @property
    def side_wall_mm(self) -> float: ...


class SensorGeometry(Protocol):
    """What the slots read of :class:`mst_cli.model.assembly.SensorGeometry` (which imports
    this module: a Protocol, not an import, keeps the two out of a cycle)."""

    @property
    def board(self) -> Board: ...

    @property
    def housing(self) -> _Housing: ...

    @property
    def width_mm(self) -> float: ...

    @property
    def base_length_mm(self) -> float: ...

    @property
    def z_board_top_mm(self) -> float: ...

    @property
    def z_cover_bottom_mm(self) -> float: ...

    @property
    def chips_xy_mm(self) -> tuple[tuple[float, float], ...]: ...

    def snapped_y_mm(self, y_mm: float, mode: str) -> float: ...


@dataclass(frozen=True)
class BoardSlot:
    """One chip's board in its slot, in the sensor frame (mm)."""

    chip_xy_mm: tuple[float, float]  # the chip's nominal centre (magnetometer.positions_mm)
    board_origin_xy_mm: tuple[float, float]  # board's lower-left corner as printed
    chip_xy_printed_mm: tuple[float, float]  # where the chip sits (y moved by the floor's snap)
    x_mm: tuple[float, float]  # slot (x0, x1): board outline plus the clearance
    floor_y_mm: float
    windows: tuple[Window, ...]


def chip_slot_x_mm(g: SensorGeometry, chip_xy_mm: tuple[float, float]) -> tuple[float, float]:
    """Slot (x0, x1) of the board whose chip is at ``chip_xy_mm``."""
    bx = chip_xy_mm[0] - g.board.chip_x_mm
    c = g.housing.board_clearance_mm
    return (bx - c, bx + g.board.length_mm + c)


def chip_floor_y_mm(g: SensorGeometry, chip_xy_mm: tuple[float, float]) -> float:
    """y of the slot floor: where the chip puts its board's lower edge, snapped to the nearest
    layer boundary (an up-facing face prints on one)."""
    return g.snapped_y_mm(chip_xy_mm[1] - g.board.chip_y_mm, "nearest")


def base_length_mm(g: SensorGeometry) -> float:
    """Base size along x, centred on the magnet axis: the cell width, or wider when the slots
    (which need not be centred) need side walls around them."""
    reach = max(max(-x0, x1) for x0, x1 in (chip_slot_x_mm(g, c) for c in g.chips_xy_mm))
    return max(g.width_mm, 2 * (reach + g.housing.side_wall_mm))


def _window_end_mm(x_in: float, facing: str, walls: list[tuple[float, float]], half_mm: float) -> float:
    """Where a window facing ``facing`` from the slot wall ``x_in`` ends: the nearest other
    slot's facing wall that way, else the base's face."""
    if facing == "-x":
        return max([x1 for _, x1 in walls if x1 <= x_in], default=-half_mm)
    return min([x0 for x0, _ in walls if x0 >= x_in], default=half_mm)


def layout(g: SensorGeometry) -> tuple[BoardSlot, ...]:
    """Every chip's :class:`BoardSlot`, in the order of the chips."""
    bd, c = g.board, g.housing.board_clearance_mm
    L2 = 0.5 * g.base_length_mm
    walls = [chip_slot_x_mm(g, chip) for chip in g.chips_xy_mm]
    out = []
    for chip, (x0, x1) in zip(g.chips_xy_mm, walls):
        floor = chip_floor_y_mm(g, chip)
        origin = (chip[0] - bd.chip_x_mm, floor)
        others = [w for w in walls if w != (x0, x1)]
        windows = []
        for con in bd.connectors:
            y_floor = g.snapped_y_mm(floor + con.y0_mm - c, "down")
            x_in = x0 if con.facing == "-x" else x1
            x_out = _window_end_mm(x_in, con.facing, others, L2)
            windows.append((x_in, x_out, y_floor, g.z_board_top_mm, g.z_cover_bottom_mm))
        printed = (origin[0] + bd.chip_x_mm, origin[1] + bd.chip_y_mm)
        out.append(BoardSlot((chip[0], chip[1]), origin, printed, (x0, x1), floor, tuple(windows)))
    return tuple(out)


def slot_violations(g: SensorGeometry) -> list[Violation]:
    """Broken rules of several chips' slots: every board on the first one's floor, and a side
    wall between any two slots. One chip breaks neither. Judged on export only (not at load,
    as the other housing rules are): the reading side models chips anywhere."""
    chips = g.chips_xy_mm
    if len(chips) < 2:
        return []
    value = [list(p) for p in chips]
    h, bd = g.housing, g.board
    floor0 = chip_floor_y_mm(g, chips[0])
    for i, chip in enumerate(chips[1:], start=1):
        floor = chip_floor_y_mm(g, chip)
        if abs(floor - floor0) > 1e-9:
            return [
                Violation.of_field(
                    POSITIONS_FIELD,
                    value,
                    f"chip {i}'s board would rest on a slot floor at y = {floor:g} mm, chip 0's at {floor0:g} mm: "
                    "every chip's y must put its board on chip 0's floor (the same print layer), "
                    "the boards sliding in side by side through the +y face",
                )
            ]
    walls = sorted((chip_slot_x_mm(g, chip), i) for i, chip in enumerate(chips))
    for ((_, a1), i), ((b0, _), j) in zip(walls, walls[1:]):
        if b0 - a1 < h.side_wall_mm - 1e-9:
            need = bd.length_mm + 2 * h.board_clearance_mm + h.side_wall_mm
            return [
                Violation.of_field(
                    POSITIONS_FIELD,
                    value,
                    f"the board slots of chips {min(i, j)} and {max(i, j)} leave {b0 - a1:.3g} mm between them: "
                    f"chips must be at least {need:g} mm apart along x (board {bd.key} {bd.length_mm:g} mm long, "
                    "2 housing.board_clearance_mm and a housing.side_wall_mm between the slots)",
                )
            ]
    return []
