"""One board slot per chip: where each carrier board sits in the base and where its cables leave.

Every chip of ``magnetometer.positions_mm`` (else the one at ``chip_offset_mm``) gets the slot
the single chip always had, shifted to that chip: the board outline plus the clearance, from its
own floor under the board (snapped to the print layer grid) out through the face on top in the
print (+y), so each board slides in along -y. Slots lie side by side along x, a side wall at
least ``housing.side_wall_mm`` thick between two; their floors may differ (chips at different
y), each keeping the one-chip rule's side wall under it.

Each connector's cable window runs from its slot's side wall towards the side it faces, out
through the base's x face -- or, when another slot lies that way, into that slot: the windows
between two neighbouring slots join them, so one short cable links the facing sockets (an I2C
daisy chain; the boards need different addresses) and the outermost sockets reach the faces.
Two facing windows span the same wall, so the link is one box from the lower of their two
floors to the higher of their tops: the union of both sockets' own windows, which clears both
plugs and is no deeper than a window the rules already allow.

A window ends just above its socket under a 45 deg gable (nothing bridged), so the side wall
stands over it up to the +y face and the cover rests on the wall on both sides of the window
(issue 44: a window open through the face left the cover on a cantilever over the open slot);
only where the wall above would be thinner than housing.side_wall_mm does it open through the face.
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
    def depth_mm(self) -> float: ...

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
    # each window's top (y where its box ends, under a 45 deg gable), or None where the wall over
    # it is too short for the gable and the window stays open through the +y face
    window_tops_y_mm: tuple[float | None, ...] = ()


def window_roof_apex_y_mm(g: SensorGeometry, top_y_mm: float, z0_mm: float, z1_mm: float) -> float:
    """The ridge of a window's 45 deg gable over its top: half the window's height, snapped up
    to the layer grid (as the pocket's roof)."""
    return g.snapped_y_mm(top_y_mm + 0.5 * (z1_mm - z0_mm), "up")


def _window_top_y_mm(g: SensorGeometry, top_y_mm: float, z0_mm: float, z1_mm: float) -> float | None:
    """The window's top when the side wall over its gable keeps housing.side_wall_mm under the
    +y face (the cover then rests on the wall on both sides of the window), else None (open)."""
    apex = window_roof_apex_y_mm(g, top_y_mm, z0_mm, z1_mm)
    return top_y_mm if apex + g.housing.side_wall_mm <= 0.5 * g.depth_mm + 1e-9 else None


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
    """Base size along x: the face's width. The footprint (width x depth) is the spec's; a chip
    layout that would need a wider body is refused (:func:`face_violations`), never widened."""
    return g.width_mm


def _chip_field(g: SensorGeometry) -> tuple[str, object]:
    """The field that sets the chips, and its value: positions_mm, else the one chip_offset_mm."""
    if len(g.chips_xy_mm) > 1:
        return POSITIONS_FIELD, [list(p) for p in g.chips_xy_mm]
    return "magnetometer.chip_offset_mm", list(g.chips_xy_mm[0])


def chip_off_face_violations(g: SensorGeometry) -> list[Violation]:
    """A chip whose centre lies off the face (|x| > W/2 or |y| > D/2): no part can hold it, and
    no field model of this part describes it. Judged at load, for every command."""
    half_w, half_d = 0.5 * g.width_mm, 0.5 * g.depth_mm
    field, value = _chip_field(g)
    for i, (x, y) in enumerate(g.chips_xy_mm):
        if abs(x) > half_w + 1e-9 or abs(y) > half_d + 1e-9:
            return [
                Violation.of_field(
                    field,
                    value,
                    f"chip {i} at ({x:g}, {y:g}) mm lies off the face: every chip must lie within "
                    f"|x| <= {half_w:g} mm and |y| <= {half_d:g} mm (family.width_mm {g.width_mm:g} x "
                    f"family.depth_mm {g.depth_mm:g}, centred on the magnet axis)",
                )
            ]
    return []


def face_violations(g: SensorGeometry) -> list[Violation]:
    """A board slot that, with ``housing.side_wall_mm`` outside it, reaches past the face's width:
    the layout would need a wider body than the spec's, which is the user's to choose. Judged at
    design and at export (the reading side models any chip on the face)."""
    half, wall = 0.5 * g.width_mm, g.housing.side_wall_mm
    field, value = _chip_field(g)
    for i, chip in enumerate(g.chips_xy_mm):
        x0, x1 = chip_slot_x_mm(g, chip)
        if x0 - wall < -half - 1e-9 or x1 + wall > half + 1e-9:
            need = 2 * (max(-x0, x1) + wall)
            return [
                Violation.of_field(
                    field,
                    value,
                    f"chip {i}'s board slot spans x = {x0:.4g}..{x1:.4g} mm (board {g.board.key} "
                    f"{g.board.length_mm:g} mm long): with housing.side_wall_mm it needs a face {need:.4g} mm wide, "
                    f"but family.width_mm is {g.width_mm:g} mm (the footprint is the spec's): move the chip, "
                    "take a shorter board, or widen the face",
                )
            ]
    return []


def _window_end_mm(x_in: float, facing: str, walls: list[tuple[float, float]], half_mm: float) -> float:
    """Where a window facing ``facing`` from the slot wall ``x_in`` ends: the nearest other
    slot's facing wall that way, else the base's face."""
    if facing == "-x":
        return max([x1 for _, x1 in walls if x1 <= x_in], default=-half_mm)
    return min([x0 for x0, _ in walls if x0 >= x_in], default=half_mm)


def _own_windows(g: SensorGeometry, chip: tuple[float, float], walls: list[tuple[float, float]]) -> list[Window]:
    """The windows of the chip's own sockets: each from a floor just below its socket (snapped
    down to the layer grid) to the base's face or the nearest other slot's wall."""
    return [w for w, _ in _own_windows_and_tops(g, chip, walls)]


def _own_windows_and_tops(
    g: SensorGeometry, chip: tuple[float, float], walls: list[tuple[float, float]]
) -> list[tuple[Window, float]]:
    """Each own window and the top its socket needs: just above the socket (snapped up)."""
    bd, c, L2 = g.board, g.housing.board_clearance_mm, 0.5 * g.base_length_mm
    x0, x1 = chip_slot_x_mm(g, chip)
    floor = chip_floor_y_mm(g, chip)
    others = [w for w in walls if w != (x0, x1)]
    out = []
    for con in bd.connectors:
        y_floor = g.snapped_y_mm(floor + con.y0_mm - c, "down")
        x_in = x0 if con.facing == "-x" else x1
        x_out = _window_end_mm(x_in, con.facing, others, L2)
        top = g.snapped_y_mm(floor + con.y1_mm + c, "up")
        out.append(((x_in, x_out, y_floor, g.z_board_top_mm, g.z_cover_bottom_mm), top))
    return out


def layout(g: SensorGeometry) -> tuple[BoardSlot, ...]:
    """Every chip's :class:`BoardSlot`, in the order of the chips. A window between two slots
    takes the lower of the two facing windows' floors (their union, one box)."""
    bd = g.board
    walls = [chip_slot_x_mm(g, chip) for chip in g.chips_xy_mm]
    own = [_own_windows_and_tops(g, chip, walls) for chip in g.chips_xy_mm]
    lowest: dict[tuple[float, float], float] = {}  # a window's span (low x, high x) -> its floor
    highest: dict[tuple[float, float], float] = {}  # ... -> its top
    for w, top in (wt for ws in own for wt in ws):
        span = (min(w[0], w[1]), max(w[0], w[1]))
        lowest[span] = min(lowest.get(span, w[2]), w[2])
        highest[span] = max(highest.get(span, top), top)
    out = []
    for chip, x_mm, windows in zip(g.chips_xy_mm, walls, own):
        floor = chip_floor_y_mm(g, chip)
        origin = (chip[0] - bd.chip_x_mm, floor)
        printed = (origin[0] + bd.chip_x_mm, origin[1] + bd.chip_y_mm)
        spans = [(min(a, b), max(a, b)) for (a, b, *_), _ in windows]
        joined = tuple((a, b, lowest[span], z0, z1) for ((a, b, _, z0, z1), _), span in zip(windows, spans))
        tops = tuple(_window_top_y_mm(g, highest[span], w[3], w[4]) for w, span in zip(joined, spans))
        out.append(BoardSlot((chip[0], chip[1]), origin, printed, x_mm, floor, joined, tops))
    return tuple(out)


def _floor_violation(g: SensorGeometry, i: int, walls: list[tuple[float, float]], value: list) -> Violation | None:
    """Chip ``i``'s slot or own windows reaching into the side wall under the body (the -y face):
    the one-chip rule (``housing_violations``) for a chip after the first. A link window takes
    one of its two sockets' own floors, so judging every chip's own windows covers it."""
    h, half, chip = g.housing, 0.5 * g.depth_mm, g.chips_xy_mm[i]
    low = min([chip_floor_y_mm(g, chip)] + [w[2] for w in _own_windows(g, chip, walls)])
    if low + half >= h.side_wall_mm - 1e-9:
        return None
    least = chip[1] + h.side_wall_mm - (low + half)  # raised by what the wall lacks
    return Violation.of_field(
        POSITIONS_FIELD,
        value,
        f"chip {i}'s board slot and cable windows reach y = {low:g} mm, {low + half:.3g} mm above the body's -y face: "
        f"housing.side_wall_mm ({h.side_wall_mm:g} mm) must stay under them; chip {i}'s y must be about "
        f"{least:.3g} mm or more",
    )


def slot_violations(g: SensorGeometry) -> list[Violation]:
    """Broken rules of the chips' slots: every slot inside the face (:func:`face_violations`), and
    for several chips a side wall under every slot (the first chip's is judged by
    ``housing_violations``) and between any two slots.
    Judged at design and at export (not at load, as the other housing rules are): the reading
    side models any chip on the face, housed or not."""
    chips = g.chips_xy_mm
    off_face = face_violations(g)
    if off_face or len(chips) < 2:
        return off_face
    value = [list(p) for p in chips]
    h, bd = g.housing, g.board
    walls_x = [chip_slot_x_mm(g, chip) for chip in chips]
    for i in range(1, len(chips)):
        v = _floor_violation(g, i, walls_x, value)
        if v is not None:
            return [v]
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
