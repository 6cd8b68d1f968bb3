"""``export.json``: what the exported body should measure, read by ``mst check`` and ``mst slice``.

Every number is read from the geometry object (analytic, not measured on the CAD), so
``mst check`` compares the written mesh against the design itself. Units are in the keys.
Dimensions are in the sensor frame (z up the stack) except in the ``print`` section, which
describes the mesh files as they lie on the bed. No CAD library is imported here.
"""

from __future__ import annotations

from mst_cli import __version__
from mst_cli.model.geometry import Printer, SensorGeometry

MANIFEST_NAME = "export.json"
MANIFEST_FORMAT = 2


def print_section(g: SensorGeometry) -> dict:
    """How the part lies on the bed, where the print pauses, and the designed cavity gaps along
    lines of the print frame (what ``mst slice`` compares with the G-code)."""
    lo, hi = g.body_bbox_mm
    corners = g.to_print_frame([lo, hi])
    lh = g.layer_height_mm
    # measure the cavities a quarter of the depth up, mid-layer (away from pocket and slot)
    z_measure = round((round(0.25 * g.depth_mm / lh) + 0.5) * lh, 9)
    cavity_lines = []
    for i, (cell, zb) in enumerate(zip(g.layers, g.layer_bottoms_mm)):
        # print y = -sensor z: the cavity between the pads, on the axis x = 0
        cavity_lines.append({"layer": i + 1, "x_mm": 0.0, "z_mm": z_measure,
                             "y_low_mm": -(zb + cell.h_mm - cell.t_mm), "y_high_mm": -(zb + cell.t_mm),
                             "gap_mm": cell.cavity_height_mm})
    return {
        "orientation": "lying on the sensor's -y face: print (x, y, z) = (x, -z, y + depth/2)",
        "rotation": [[1, 0, 0], [0, 0, -1], [0, 1, 0]],
        "translation_mm": [0.0, 0.0, 0.5 * g.depth_mm],
        "layer_height_mm": lh,
        "height_mm": g.depth_mm,
        "layers": int(round(g.depth_mm / lh)),
        "bbox_min_mm": corners.min(axis=0).tolist(),
        "bbox_max_mm": corners.max(axis=0).tolist(),
        "pause": {"after_layer": g.pause_after_layer, "z_mm": g.pause_height_mm,
                  "why": "drop the magnet into its pocket"},
        "magnet_top_z_mm": g.print_height_mm(g.magnet.radius_mm),
        "cavity_lines": cavity_lines,
    }


def export_manifest(name: str, geometry: SensorGeometry, printer: Printer, stl_tolerance_mm: float,
                    files: list[str]) -> dict:
    """The expected dimensions of the exported body (see module docstring)."""
    g, h = geometry, geometry.housing
    bbox_min, bbox_max = g.body_bbox_mm
    x0, x1 = g.slot_x_mm
    cells = g.layers
    # A mesh with chord deviation <= delta misses at most delta x (curved area) of the pocket;
    # float32 STL coordinates add ~1e-7 relative per vertex.
    volume_tol = stl_tolerance_mm * g.pocket_curved_area_mm2 + 1e-5 * g.body_volume_mm3
    z_pocket_mid = g.z_magnet_bottom_mm + 0.5 * g.pocket_depth_mm
    return {
        "format": MANIFEST_FORMAT,
        "mst_version": __version__,
        "name": name,
        "files": list(files),
        "units": "mm, deg",
        "stl_tolerance_mm": stl_tolerance_mm,
        "print": print_section(g),
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
            "radius_mm": g.pocket_radius_mm,
            "depth_mm": g.pocket_depth_mm,
            "top_y_mm": g.pocket_top_y_mm,
            "roof_apex_y_mm": g.pocket_roof_apex_y_mm,
            "roof_rise_mm": g.pocket_roof_rise_mm,
            "floor_z_mm": g.z_magnet_bottom_mm,
            "section_z_mm": z_pocket_mid,
            "section_area_mm2": g.pocket_section_area_mm2(z_pocket_mid),
            "volume_mm3": g.pocket_volume_mm3,
            "curved_area_mm2": g.pocket_curved_area_mm2,
            "magnet_diameter_mm": g.magnet.diameter_mm,
            "magnet_thickness_mm": g.magnet.thickness_mm,
        },
        "board_slot": {
            "board": g.board.key,
            "x0_mm": x0, "x1_mm": x1,
            "floor_y_mm": g.slot_floor_y_mm,
            "open_face": "+y",
            "floor_z_mm": g.z_board_bottom_mm,
            "top_z_mm": g.z_cover_bottom_mm,
            "height_mm": g.slot_height_mm,
            "headroom_mm": g.board.headroom_mm,
            "cable_windows": [{"x_inner_mm": a, "x_outer_mm": b, "floor_y_mm": yf, "z0_mm": z0, "z1_mm": z1}
                              for a, b, yf, z0, z1 in g.cable_windows],
            "board_thickness_mm": g.board.thickness_mm,
            "chip_height_mm": g.board.chip_height_mm,
            "chip_xy_mm": list(g.chip_xy_printed_mm),
            "chip_xy_nominal_mm": list(g.chip_offset_mm),
            "hall_z_mm": g.z_hall_mm,
            "cover_mm": h.cover_mm,
        },
        "gap0_mm": g.gap0_mm,
        "base_top_z_mm": g.z_base_top_mm,
        "layers": [
            {"z_bottom_mm": zb, "h_mm": c.h_mm, "theta_deg": c.theta_deg, "t_mm": c.t_mm,
             "web_depth_mm": c.b_mm, "width_mm": c.width_mm, "cavity_height_mm": c.cavity_height_mm,
             "wall_horizontal_width_mm": c.wall_horizontal_width_mm}
            for c, zb in zip(cells, g.layer_bottoms_mm)
        ],
        "printer": {"nozzle_mm": printer.nozzle_mm, "min_wall_mm": printer.min_wall_mm,
                    "min_gap_mm": printer.min_gap_mm, "layer_height_mm": printer.layer_height_mm},
        "min_features": {
            "wall_mm": min(c.t_mm for c in cells),
            "cavity_gap_mm": min(c.cavity_height_mm for c in cells),
        },
    }
