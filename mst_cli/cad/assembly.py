"""The printed body (one fused TPU solid) and the STEP assembly (body + magnet + board)."""

from __future__ import annotations

from dataclasses import dataclass

from build123d import Compound, Solid

from ..geometry import SensorGeometry
from ..schema import InputError
from . import parts


def check_fits(geometry: SensorGeometry) -> None:
    """Raise :class:`InputError` when the pocket cannot be built inside the cap's footprint.

    The cell rules (HexCell.violations) are checked by the caller; these are the housing rules
    that only the CAD needs: the chamfered pocket must leave at least one side wall of
    material to the cap's sides.
    """
    h = geometry.housing
    outer_r = 0.5 * geometry.pocket_diameter_mm + h.pocket_chamfer_mm
    room = 0.5 * min(geometry.width_mm, geometry.depth_mm) - h.side_wall_mm
    if outer_r > room:
        raise InputError("magnet.diameter_mm", geometry.magnet.diameter_mm,
                         f"the pocket (radius {outer_r:g} mm incl. clearance and chamfer) needs "
                         f"<= {room:g} mm: min(width_mm, depth_mm)/2 minus housing.side_wall_mm")
    if h.pocket_chamfer_mm >= geometry.pocket_depth_mm:
        raise InputError("housing.pocket_chamfer_mm", h.pocket_chamfer_mm,
                         f"must be smaller than the pocket depth {geometry.pocket_depth_mm:g} mm")


def body_solids(geometry: SensorGeometry) -> tuple[list[Solid], list[Solid]]:
    """(solids to fuse, solids to cut) of the printed body, bottom to top."""
    keep = [parts.base_block(geometry)]
    for cell, z_bottom in zip(geometry.layers, geometry.layer_bottoms_mm):
        keep += parts.layer_struts(cell, z_bottom)
    keep += parts.plates(geometry)
    keep.append(parts.cap_block(geometry))
    cut = parts.base_cuts(geometry) + [parts.magnet_pocket(geometry)]
    return keep, cut


def build_body(geometry: SensorGeometry) -> Solid:
    """The one printed TPU body: every part fused in one boolean, then the cavities cut.

    The struts' pads touch the base, plates and cap face to face, so the fuse bonds them; one
    multi-argument fuse (not a growing loop) keeps it to a single boolean operation.
    """
    check_fits(geometry)
    keep, cut = body_solids(geometry)
    fused = keep[0].fuse(*keep[1:])
    body = fused.cut(*cut).clean()
    solids = body.solids()
    if len(solids) != 1:
        raise RuntimeError(f"the fused body has {len(solids)} solids, expected one")
    return solids[0]


@dataclass(frozen=True)
class SensorCAD:
    """The built parts: the printed body, the magnet and the board (PCB + chip)."""

    body: Solid
    magnet: Solid
    board: Compound

    def assembly(self, name: str) -> Compound:
        """Named STEP assembly: the body, the magnet and the board as separate parts."""
        body = Compound([self.body], label="sensor_body")
        magnet = Compound([self.magnet], label="magnet")
        return Compound(children=[body, magnet, self.board], label=name)


def build_sensor(geometry: SensorGeometry) -> SensorCAD:
    """Build the body, the magnet and the board of ``geometry`` in print orientation."""
    body = build_body(geometry)
    pcb, chip = parts.board_solids(geometry)
    board = Compound(children=[Compound([pcb], label="pcb"), Compound([chip], label="MLX90393")],
                     label=f"board_{geometry.board.key}")
    return SensorCAD(body=body, magnet=parts.magnet_solid(geometry), board=board)
