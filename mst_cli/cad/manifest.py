"""``export.json``: what the exported body should measure, read by ``mst check``.

Every number is read from the geometry object (analytic, not measured on the CAD), so
``mst check`` compares the written mesh against the design itself. Units are in the keys.
No CAD library is imported here.
"""

from __future__ import annotations

from .. import __version__
from ..geometry import Printer, SensorGeometry

MANIFEST_NAME = "export.json"
MANIFEST_FORMAT = 1


def export_manifest(name: str, geometry: SensorGeometry, printer: Printer, stl_tolerance_mm: float,
                    files: list[str]) -> dict:
    """The expected dimensions of the exported body (see module docstring)."""
    g, h = geometry, geometry.housing
    bbox_min, bbox_max = g.body_bbox_mm
    x0, x1, y0, y1 = g.slot_xy_mm
    e0, e1 = g.cable_exit_y_mm
    cells = g.layers
    # A mesh with chord deviation <= delta misses at most delta x (curved area) of the pocket;
    # float32 STL coordinates add ~1e-7 relative per vertex.
    volume_tol = stl_tolerance_mm * g.pocket_curved_area_mm2 + 1e-5 * g.body_volume_mm3
    return {
        "format": MANIFEST_FORMAT,
        "mst_version": __version__,
        "name": name,
        "files": list(files),
        "units": "mm, deg",
        "stl_tolerance_mm": stl_tolerance_mm,
        "body": {
            "volume_mm3": g.body_volume_mm3,
            "volume_tolerance_mm3": volume_tol,
            "volume_parts_mm3": {
                "base": g.base_volume_mm3,
                "layers": [c.volume_mm3 for c in cells],
                "plates": g.plates_volume_mm3,
                "cap": g.cap_volume_mm3,
            },
            "bbox_min_mm": list(bbox_min),
            "bbox_max_mm": list(bbox_max),
            "bodies": 1,
            "internal_voids": 1,          # the closed magnet pocket
        },
        "magnet_pocket": {
            "diameter_mm": g.pocket_diameter_mm,
            "depth_mm": g.pocket_depth_mm,
            "chamfer_mm": h.pocket_chamfer_mm,
            "floor_z_mm": g.z_magnet_bottom_mm,
            "pause_height_mm": g.z_pause_mm,
            "volume_mm3": g.pocket_volume_mm3,
            "curved_area_mm2": g.pocket_curved_area_mm2,
            "magnet_diameter_mm": g.magnet.diameter_mm,
            "magnet_thickness_mm": g.magnet.thickness_mm,
        },
        "board_slot": {
            "board": g.board.key,
            "x0_mm": x0, "x1_mm": x1, "y0_mm": y0, "y1_mm": y1,
            "open_face": "-x",
            "width_y_mm": y1 - y0,
            "floor_z_mm": g.z_board_bottom_mm,
            "top_z_mm": g.z_cover_bottom_mm,
            "height_mm": g.slot_height_mm,
            "cable_exit_y_mm": [e0, e1],
            "board_thickness_mm": g.board.thickness_mm,
            "chip_height_mm": g.board.chip_height_mm,
            "chip_xy_mm": list(g.chip_offset_mm),
            "hall_z_mm": g.z_hall_mm,
            "cover_mm": h.cover_mm,
        },
        "gap0_mm": g.gap0_mm,
        "base_top_z_mm": g.z_base_top_mm,
        "layers": [
            {"z_bottom_mm": zb, "h_mm": c.h_mm, "theta_deg": c.theta_deg, "t_mm": c.t_mm,
             "b_mm": c.b_mm, "width_mm": c.width_mm, "strut_centres_y_mm": list(c.strut_centres_y_mm),
             "strut_gap_mm": c.strut_gap_mm, "cavity_height_mm": c.cavity_height_mm,
             "wall_horizontal_width_mm": c.wall_horizontal_width_mm}
            for c, zb in zip(cells, g.layer_bottoms_mm)
        ],
        "printer": {"nozzle_mm": printer.nozzle_mm, "min_wall_mm": printer.min_wall_mm,
                    "min_gap_mm": printer.min_gap_mm, "layer_height_mm": printer.layer_height_mm},
        "min_features": {
            "wall_mm": min(c.t_mm for c in cells),
            "strut_width_mm": min(c.b_mm for c in cells),
            "cavity_gap_mm": min(c.cavity_height_mm for c in cells),
            "strut_gap_mm": min(c.strut_gap_mm for c in cells),
        },
    }
