"""The insert plate: the spec's ``insert`` section (a stiff plate in the cap over the magnet,
docs/design.md section 10) and the print's pauses. Its slot and box in the part are computed
once, by :class:`~mst_cli.model.assembly.SensorGeometry`, from these values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from mst_cli.model.components import INSERT_MATERIALS, NO_INSERT
from mst_cli.model.file_keys import spec
from mst_cli.model.violation import Violation


class _Geometry(Protocol):
    """What the insert's rule reads of :class:`mst_cli.model.assembly.SensorGeometry` (which
    imports this module: a Protocol, not an import, keeps the two out of a cycle)."""

    @property
    def insert_plate(self) -> InsertPlate | None: ...

    @property
    def has_insert(self) -> bool: ...

    @property
    def insert_box_mm(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]: ...

    @property
    def pocket_radius_mm(self) -> float: ...


# The insert's default, chosen with benchmarks/bench_load_path.py (docs/design.md section 10): a
# 2 mm PLA plate, which any printer that prints the body prints flat in minutes and the user drops
# in at a pause, takes the share of the magnet's motion outside the layers of the bundled forward
# design from 60/82/93 % to 9/23/45 % (regimes 1/2/3); a 1 mm steel shim reaches 4/11/25 % but
# must be cut to size from sheet. `insert.material: steel` selects it.
DEFAULT_INSERT_MATERIAL = "pla"
DEFAULT_INSERT_THICKNESS_MM = 2.0


@dataclass(frozen=True)
class InsertPlate:
    """The spec's ``insert`` section: a stiff plate in the cap over the magnet (docs/design.md
    section 10), dropped into a closed slot at its own print pause. The slot is as wide and as
    deep as the face allows with ``housing.side_wall_mm`` of TPU around it; through its
    thickness it fits the plate exactly (the press then bears on the plate from the first
    newton), along its width and height ``clearance_mm`` lets it drop in."""

    material: str = spec(
        DEFAULT_INSERT_MATERIAL,
        choices=tuple(INSERT_MATERIALS) + (NO_INSERT,),
        meaning="the plate: `pla` or `petg` (printed flat, 100 % infill) or `steel` (a shim cut to size); "
        "`none`: no insert, the TPU cap spans the face alone",
    )
    thickness_mm: float = spec(
        DEFAULT_INSERT_THICKNESS_MM, lo=0.1, hi=10.0, unit="mm", meaning="the plate's thickness (along the stack)"
    )
    clearance_mm: float = spec(
        0.2,
        lo=0.0,
        hi=2.0,
        unit="mm",
        meaning="room around the plate in its slot across the face and above it in the print (none "
        "through its thickness: printed TPU gives, so the plate is held)",
    )

    @property
    def present(self) -> bool:
        return self.material != NO_INSERT


@dataclass(frozen=True)
class PrintPause:
    """A pause of the print: after the layer whose top is at ``z_mm`` (print height)."""

    after_layer: int
    z_mm: float
    why: str


def insert_violations(g: _Geometry) -> list[Violation]:
    """Broken rules of the insert of ``g`` (a SensorGeometry): the face must leave a plate at
    least as wide and as tall as the magnet's pocket."""
    if not g.has_insert:
        return []
    (x0, y0, _), (x1, y1, _) = g.insert_box_mm
    if y1 - y0 < 2.0 * g.pocket_radius_mm or x1 - x0 < 2.0 * g.pocket_radius_mm:
        return [
            Violation.of_field(
                "insert.thickness_mm",
                g.insert_plate.thickness_mm if g.insert_plate else None,
                f"leaves a plate of {x1 - x0:.3g} x {y1 - y0:.3g} mm, smaller than the magnet's pocket "
                f"({2 * g.pocket_radius_mm:g} mm): a thinner plate, a smaller insert.clearance_mm or "
                "a deeper family.depth_mm",
            )
        ]
    return []
