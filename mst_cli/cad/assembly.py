"""The printed body (one fused TPU solid) and the STEP assembly (body + magnet + board)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from build123d import Compound, Solid

from mst_cli.cad import mesh_io, parts, shapes
from mst_cli.cad.expected_body import to_print_frame
from mst_cli.cad.shapes import check_fits as check_fits  # re-exported: the callers check first
from mst_cli.model.assembly import SensorGeometry

if TYPE_CHECKING:
    import numpy as np


def body_solids(geometry: SensorGeometry) -> tuple[list[Solid], list[Solid]]:
    """(solids to fuse, solids to cut) of the printed body, bottom to top
    (:func:`mst_cli.cad.shapes.body_plan`)."""
    plan = shapes.body_plan(geometry)
    keep = [parts.solid(s) for s in plan.keep]
    pocket = parts.fused(plan.pocket)
    if plan.pocket_ribs:  # the crush ribs stay standing in the pocket
        pocket = pocket.cut(*(parts.solid(s) for s in plan.pocket_ribs))
    cut = [parts.solid(s) for s in plan.cut] + [pocket]
    if plan.insert_slot:
        cut.append(parts.fused(plan.insert_slot))
    return keep, cut


def build_body(geometry: SensorGeometry) -> Solid:
    """The one printed TPU body: every part fused in one boolean, then the cavities cut.

    The webs' pads touch the base, plates and cap face to face, so the fuse bonds them; one
    multi-argument fuse (not a growing loop) keeps it to a single boolean operation.
    """
    keep, cut = body_solids(geometry)
    fused = keep[0].fuse(*keep[1:])
    body = fused.cut(*cut).clean()
    solids = body.solids()
    if len(solids) != 1:
        raise RuntimeError(f"the fused body has {len(solids)} solids, expected one")
    return solids[0]


@dataclass(frozen=True)
class SensorCAD:
    """The built parts: the printed body, the magnet, the board (PCB + chip) and the insert
    plate (None without one)."""

    body: Solid
    magnet: Solid
    board: Compound
    insert: Solid | None = None
    insert_label: str = "insert"

    def assembly(self, name: str) -> Compound:
        """Named STEP assembly: the body, the magnet, the insert and the board as separate parts."""
        children = [Compound([self.body], label="sensor_body"), Compound([self.magnet], label="magnet")]
        if self.insert is not None:
            children.append(Compound([self.insert], label=self.insert_label))
        return Compound(children=children + [self.board], label=name)


def _board_compound(geometry: SensorGeometry, chip: int, label: str) -> Compound:
    pcb, chip_solid, *sockets = parts.board_solids(geometry, chip)
    children = [Compound([pcb], label="pcb"), Compound([chip_solid], label="MLX90393")]
    children += [Compound([s], label=f"connector_{i + 1}") for i, s in enumerate(sockets)]
    return Compound(children=children, label=label)


def build_sensor(geometry: SensorGeometry) -> SensorCAD:
    """Build the body, the magnet and the board of ``geometry`` in the sensor frame (with more
    than one chip, ``board`` holds one board per chip)."""
    body = build_body(geometry)
    label = f"board_{geometry.board.key}"
    n = len(geometry.board_slots)
    if n == 1:
        board = _board_compound(geometry, 0, label)
    else:
        board = Compound(children=[_board_compound(geometry, i, f"{label}_chip_{i}") for i in range(n)], label="boards")
    insert = parts.solid(shapes.insert_plate(geometry)) if geometry.has_insert else None
    label = f"insert_{geometry.insert_plate.material}" if geometry.insert_plate is not None else "insert"
    return SensorCAD(body=body, magnet=parts.magnet_solid(geometry), board=board, insert=insert, insert_label=label)


def print_mesh(geometry: SensorGeometry, body: Solid, tolerance_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of the body as it lies on the bed (the STL/3MF frame): the
    tessellation, closed and outward-oriented, turned into the print frame."""
    vertices, triangles = mesh_io.tessellate(body, tolerance_mm)
    if not mesh_io.is_closed_oriented(vertices, triangles):
        raise RuntimeError("the tessellated body is not closed: please report this design")
    return to_print_frame(geometry, vertices), triangles  # a rotation: winding is kept
