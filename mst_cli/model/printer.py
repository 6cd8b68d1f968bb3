"""What the printer can make, and how it misses: :class:`Printer` (the file's ``printer`` section)."""

from __future__ import annotations

from dataclasses import dataclass

from mst_cli.model.file_keys import spec


@dataclass(frozen=True)
class Printer:
    """What the printer can make, and how it misses. Defaults: 0.4 mm nozzle, 0.2 mm layers.

    min_wall_mm: one extrusion line of TPU (= nozzle) is the thinnest reliable wall.
    min_gap_mm: the narrowest slot that stays open when printed (= nozzle).
    wall_offset_mm, modulus_factor, gap_offset_mm: the systematic difference between the part
    as drawn and as printed (what ``mst calibrate`` fits on an earlier print); geometry and
    export stay nominal, the forward model of a document applies them
    (:func:`mst_cli.sensor.as_printed.as_printed`). wall_tolerance_mm: the scatter left after that.
    """

    nozzle_mm: float = spec(0.4, lo=0.05, hi=5.0, unit="mm", meaning="nozzle diameter")
    layer_height_mm: float = spec(0.2, lo=0.01, hi=2.0, unit="mm", meaning="print layer height")
    min_wall_mm: float = spec(0.4, lo=0.01, hi=10.0, unit="mm", meaning="thinnest printable wall (one line)")
    min_gap_mm: float = spec(0.4, lo=0.01, hi=10.0, unit="mm", meaning="narrowest printable gap")
    # how this printer and filament miss the drawing (docs/design.md section 10): the design is
    # made for the part as printed, the export draws the nominal part
    wall_offset_mm: float = spec(
        0.0,
        lo=-0.3,
        hi=0.4,
        unit="mm",
        meaning="systematic wall error: every wall prints this much thicker than drawn "
        "(`mst calibrate`'s wall_offset_mm). `mst design` draws the walls so that "
        "the walls as printed meet the targets; `export` draws the drawn walls",
    )
    wall_tolerance_mm: float = spec(
        0.05,
        lo=0.001,
        hi=0.5,
        unit="mm",
        meaning="± scatter of the printed walls around drawn + offset (one print to "
        "the next): `mst design` reports the worst and RMS change of every "
        "S_i and R_i over it",
    )
    modulus_factor: float = spec(
        1.0,
        lo=0.2,
        hi=5.0,
        meaning="printed modulus / `material.youngs_modulus_MPa` (`mst calibrate`'s modulus_factor)",
    )
    gap_offset_mm: float = spec(
        0.0,
        lo=-3.0,
        hi=5.0,
        unit="mm",
        meaning="magnet–chip gap as built minus as drawn (`mst calibrate`'s gap_offset_mm: "
        "cover, pocket floor, board seating); the model adds it, `export` does not",
    )
