"""The one description of the sensor's geometry, in two modules re-exported here.

* :mod:`mst_cli.model.cell`: the collapsible "hex" cell -- its vectorised kernels (arrays in mm
  and radians, for the design loop) and :class:`HexCell`;
* :mod:`mst_cli.model.assembly`: the whole sensor -- :class:`SensorGeometry`, its
  :class:`Magnet` and :class:`Housing`, and the rules of the assembly;

with :class:`Printer` (:mod:`mst_cli.model.printer`) and the one shape of a broken rule,
:class:`Violation` (:mod:`mst_cli.model.violation`). ``from mst_cli.model import geometry as
geo; geo.HexCell(...)`` reads them all.
"""

from mst_cli.model.assembly import (
    Housing,
    Magnet,
    SensorGeometry,
    printer_violations,
    snap_to_layers_mm,
    unloaded_gap_mm,
)
from mst_cli.model.cell import (
    CELL_RULES,
    LENGTH_FLOOR_MM,
    HexCell,
    cavity_height_mm,
    cell_margins_mm,
    inner_pad_half_width_mm,
    inner_tip_half_width_mm,
    lock_stroke_mm,
    pad_half_width_mm,
    profile_area_mm2,
    wall_centreline_length_mm,
)
from mst_cli.model.components import Board
from mst_cli.model.printer import Printer
from mst_cli.model.violation import Violation

__all__ = [
    "CELL_RULES",
    "LENGTH_FLOOR_MM",
    "Board",
    "HexCell",
    "Housing",
    "Magnet",
    "Printer",
    "SensorGeometry",
    "Violation",
    "cavity_height_mm",
    "cell_margins_mm",
    "inner_pad_half_width_mm",
    "inner_tip_half_width_mm",
    "lock_stroke_mm",
    "pad_half_width_mm",
    "printer_violations",
    "profile_area_mm2",
    "snap_to_layers_mm",
    "unloaded_gap_mm",
    "wall_centreline_length_mm",
]
