"""export.json's ``parts``: the parts that are not the printed TPU body (the magnet, the insert
plate), each with its material and its box in the STL's frame, and the pause that places it.

An independent model reads the STL and these entries, so each box is the geometry's own
(:class:`~mst_cli.model.assembly.SensorGeometry`), turned into the print frame once here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mst_cli.cad.expected_body import insert_volume_mm3, to_print_frame
from mst_cli.model.components import INSERT_MATERIALS, NDFEB_ELASTIC

if TYPE_CHECKING:
    from mst_cli.model.assembly import SensorGeometry


def _print_box(g: SensorGeometry, lo, hi) -> dict:
    """A sensor-frame box (lo, hi) as export.json gives it: its corners in the print frame (the
    STL's) and in the sensor frame, mm."""
    corners = to_print_frame(g, [lo, hi])
    return {
        "box_min_mm": corners.min(axis=0).tolist(),
        "box_max_mm": corners.max(axis=0).tolist(),
        "sensor_box_min_mm": list(lo),
        "sensor_box_max_mm": list(hi),
    }


def parts_section(g: SensorGeometry) -> list[dict]:
    """export.json's ``parts``: every part that is not the printed TPU body, with its material
    (Young's modulus, Poisson's ratio), where it sits (boxes in the STL's frame, mm) and the
    pause that places it. The magnet's box bounds its disc; the insert's box is the plate, in
    the slot (``slot_*``) the STL leaves for it."""
    m = g.magnet
    lo = (-m.radius_mm, -m.radius_mm, g.z_magnet_bottom_mm)
    hi = (m.radius_mm, m.radius_mm, g.z_magnet_top_mm)
    magnet_pause, *rest = g.pauses
    out = [
        {
            "name": "magnet",
            "shape": "disc, axis along the sensor's z (print -y)",
            "material": {"name": f"NdFeB {m.grade}", **NDFEB_ELASTIC},
            **_print_box(g, lo, hi),
            "placed_at_pause": {"after_layer": magnet_pause.after_layer, "z_mm": magnet_pause.z_mm},
            "step": magnet_pause.why,
        }
    ]
    if g.has_insert:
        assert g.insert_plate is not None
        mat = INSERT_MATERIALS[g.insert_plate.material]
        slot = _print_box(g, *g.insert_slot_box_mm)
        out.append(
            {
                "name": "insert",
                "shape": "box",
                "material": {
                    "name": mat.name,
                    "youngs_modulus_MPa": mat.youngs_modulus_MPa,
                    "poisson_ratio": mat.poisson_ratio,
                    "source": mat.source,
                },
                "thickness_mm": g.insert_plate.thickness_mm,
                "volume_mm3": insert_volume_mm3(g),
                **_print_box(g, *g.insert_box_mm),
                "slot_min_mm": slot["box_min_mm"],
                "slot_max_mm": slot["box_max_mm"],
                "sensor_slot_min_mm": slot["sensor_box_min_mm"],
                "sensor_slot_max_mm": slot["sensor_box_max_mm"],
                "slot_roof_rise_mm": g.insert_slot_roof_rise_mm,
                "placed_at_pause": {"after_layer": rest[0].after_layer, "z_mm": rest[0].z_mm},
                "step": rest[0].why,
                "bonded": "held in its slot by the TPU around it (fills the slot's thickness)",
            }
        )
    return out


def crush_ribs_section(g: SensorGeometry) -> dict:
    """export.json's magnet_pocket.crush_ribs: the ribs on the pocket's face over the magnet that
    hold it on its floor (:attr:`~mst_cli.model.assembly.SensorGeometry.magnet_rib_reach_mm`)."""
    return {
        "x_mm": list(g.magnet_rib_x_mm),
        "base_width_mm": g.magnet_rib_width_mm,
        "reach_mm": g.magnet_rib_reach_mm,
        "interference_mm": g.magnet_rib_reach_mm - g.housing.pocket_clearance_mm,
        "y_mm": [-g.pocket_radius_mm, g.pocket_top_y_mm],
    }
