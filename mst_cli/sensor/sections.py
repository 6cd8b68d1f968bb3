"""The sections of a sensor description, each key declared once (docs/file-format.md).

Each key is a typed dataclass field made with :func:`~mst_cli.model.file_keys.spec` (unit, bounds
or choices, null, meaning, default): the model's own dataclasses (``HexCell``, ``Magnet``,
``Housing``, ``Printer``, ``SensorGeometry``) where the model keeps the value, the section
classes below otherwise. The validation rules (:data:`SECTIONS`, :data:`LAYER_RULES`) and the
defaults are read from those declarations; :mod:`mst_cli.sensor.document` assembles them into
one :class:`~mst_cli.sensor.document.Document`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from mst_cli.errors import InputError
from mst_cli.io.rules import Rule, adopt, default_of
from mst_cli.model.assembly import Housing, InsertPlate, Magnet, SensorGeometry
from mst_cli.model.cell import HexCell
from mst_cli.model.chip import DEFAULT_NOISE_uT
from mst_cli.model.components import BOARDS, DEFAULT_BOARD, grade_remanence_T
from mst_cli.model.file_keys import SEED_RANGE, spec
from mst_cli.model.magnet_field import FIELD_MODELS
from mst_cli.model.material import Material
from mst_cli.model.mechanics.correction import VERIFIED_BOX
from mst_cli.model.printer import Printer

# the terms of design.objective (mst_cli.design.problem reads the same tuple)
OBJECTIVE_TERMS = ("height", "force_resolution", "print_robustness")
DEFAULT_OBJECTIVE = dict.fromkeys(OBJECTIVE_TERMS, 1.0)

MIN_CHIP_SPACING_MM = 3.0  # an MLX90393's QFN package is 3 mm square


def check_chip_positions(positions, chip_offset_mm) -> None:
    """InputError unless the chips start at chip_offset_mm and no two overlap."""
    if positions is None:
        return
    if tuple(positions[0]) != tuple(chip_offset_mm):
        raise InputError(
            "magnetometer.positions_mm[0]",
            list(positions[0]),
            f"must be the chip at magnetometer.chip_offset_mm {list(chip_offset_mm)}",
        )
    for i, a in enumerate(positions):
        for j, b in enumerate(positions[:i]):
            if math.dist(a, b) < MIN_CHIP_SPACING_MM:
                raise InputError(
                    f"magnetometer.positions_mm[{i}]", list(a), f"must be >= {MIN_CHIP_SPACING_MM:g} mm from chip {j}"
                )


# 12 printable cells still lock bottom to top below the chip's saturation and the design loop
# meets 12-layer targets (benchmarks/bench_layers.py); each layer adds at least 2 mm of height
# (a 1.2 mm cell and a 0.8 mm plate) and moves the magnet away from the chip, so beyond 12 the
# part is over 33 mm tall and its worst force resolution coarser than 0.4 N with the default magnet.
MAX_LAYERS = 12
MECHANICS_MODELS = ("spring", "frame", "continuum")
LOAD_PATHS = ("part", "section", "layers")  # model.load_path: closed form, closed form + whole-part rung, layers alone


# --------------------------------------------------------------------------- the sections
# Sections whose keys are not fields of a model dataclass (or not all of them, or not in the
# file's order) declare them here; housing and printer are Housing and Printer as they are.
@dataclass(frozen=True)
class CellFamily:
    """Family constants shared by every layer; builds a :class:`HexCell` from (theta, t, h)."""

    type: str = spec("hex", choices=("hex",), meaning="cell family (only `hex` for now)")
    width_mm: float = adopt(HexCell, "width_mm")
    depth_mm: float = adopt(HexCell, "depth_mm")
    contact_allowance_mm: float = adopt(HexCell, "contact_allowance_mm")

    def cell(self, theta_deg: float, t_mm: float, h_mm: float) -> HexCell:
        return HexCell(
            float(theta_deg), float(t_mm), float(h_mm), self.width_mm, self.depth_mm, self.contact_allowance_mm
        )


@dataclass(frozen=True)
class MaterialSection:
    """The ``material`` section: :class:`Material`'s fields with its defaults, bounded here."""

    name: str = adopt(Material, "name", meaning="name of the printed material")
    youngs_modulus_MPa: float = adopt(
        Material,
        "youngs_modulus_MPa",
        lo=1e-3,
        hi=1e5,
        unit="MPa",
        meaning="small-strain Young's modulus (NinjaTek NinjaFlex 85A data sheet)",
    )
    poisson_ratio: float = adopt(Material, "poisson_ratio", lo=0.0, hi=0.5, hi_open=True, meaning="Poisson's ratio ν")


_GRADE = default_of(Magnet.__dataclass_fields__["grade"])


@dataclass(frozen=True)
class MagnetSection:
    """The ``magnet`` section: an axially magnetised NdFeB disc (:class:`Magnet`)."""

    diameter_mm: float = adopt(Magnet, "diameter_mm")
    thickness_mm: float = adopt(Magnet, "thickness_mm")
    grade: str = adopt(Magnet, "grade")
    remanence_T: float | None = spec(
        None,
        lo=0.01,
        hi=2.0,
        unit="T",
        nullable=True,
        meaning=f"Br; null means the grade's mid value ({_GRADE}: {grade_remanence_T(_GRADE):.2f} T)",
    )

    def magnet(self) -> Magnet:
        return Magnet(
            self.diameter_mm, self.thickness_mm, self.remanence_T or grade_remanence_T(self.grade), self.grade
        )


@dataclass(frozen=True)
class MagnetometerSection:
    """The ``magnetometer`` section: the chip, its board and where it sits."""

    model: str = spec("MLX90393", choices=("MLX90393",), meaning="the magnetometer chip")
    board: str = spec(
        DEFAULT_BOARD,
        choices=tuple(BOARDS),
        meaning="carrier board (docs/design.md §8): its tallest part sets the housing's headroom",
    )
    noise_uT_rms: float = spec(
        DEFAULT_NOISE_uT,
        lo=0.0,
        hi=1000.0,
        unit="uT",
        meaning="RMS field noise; the force resolution uses the larger of this and one LSB",
    )
    chip_offset_mm: tuple[float, float] = adopt(SensorGeometry, "chip_offset_mm")
    magnet_tilt_deg: float = adopt(SensorGeometry, "magnet_tilt_deg")
    positions_mm: tuple[tuple[float, float], ...] | None = spec(
        None,
        kind="pairs",
        lo=-100.0,
        hi=100.0,
        unit="mm",
        nullable=True,
        omit_default=True,
        meaning="every chip's centre (x, y) relative to the magnet axis when more than one MLX90393 "
        "reads the magnet, the first at chip_offset_mm, centres at least "
        f"{MIN_CHIP_SPACING_MM:g} mm apart (null: one chip, at chip_offset_mm); two chips tell shear "
        "from position (docs/design.md 4.5). The housing cuts a board slot for each, side by side along x, "
        "each on its own floor, each with a side wall inside the face: a layout that needs a wider body than "
        "`family.width_mm` is refused by design and export, a chip off the face by every command (docs/printing.md)",
    )

    def __post_init__(self):
        check_chip_positions(self.positions_mm, self.chip_offset_mm)


@dataclass(frozen=True)
class ModelSection:
    """The ``model`` section: which models answer."""

    mechanics: str = spec(
        "spring",
        choices=MECHANICS_MODELS,
        meaning="mechanics of a layer: `spring` (L0), `frame` (L1), `continuum` (L2)",
    )
    field: str = spec(
        "auto",
        choices=("auto",) + FIELD_MODELS,
        meaning="magnet field model; `auto` is the cheapest exact one: `axial` on the axis, "
        "`cylinder` off it (`dipole` only when asked)",
    )
    load_path: str = spec(
        "part",
        choices=LOAD_PATHS,
        omit_default=True,
        meaning="what carries the press in `mst simulate`'s and `mst design`'s predictions: `part`, the layers "
        "with the cap, plates and cover in series in closed form (the cap closing the top layer's cavity as it "
        "bends); `section`, the same with each regime's compliance outside the layers measured by the whole-part "
        "rung (the exported part's section in plane strain, 2 finite-element solves a regime, about 10-30 s; "
        "`mst design` corrects its closed form by it until the two agree, `mst calibrate` and `mst read` take it "
        "too; the boards must fit the face, as `mst export` needs: docs/design.md 4.7); or `layers`, the "
        "layers alone between rigid plates (the ladder's own verification; docs/design.md 4.6)",
    )
    # relative accuracy of layer stiffness and lock force against the continuum reference: the
    # tool picks the cheapest mechanics rung whose measured median errors meet it (mst_cli.model.ladder)
    accuracy_rel: float | None = spec(
        None,
        lo=1e-4,
        hi=1.0,
        hi_open=True,
        nullable=True,
        omit_default=True,
        meaning="requested relative accuracy of the layer stiffness and of the lock force against the "
        "`continuum` reference (e.g. 0.05 for 5 %): `mst simulate` uses the cheapest mechanics rung "
        "whose measured median errors (`mst bench`) in both meet it, `mst design` refines with that rung "
        "(`spring`: no refinement), and both print which rung was picked. An explicit `--mechanics` / "
        "`--refine` flag wins; `mechanics` is then ignored",
    )


@dataclass(frozen=True)
class DesignOptions:
    """The ``design`` section: options of ``mst design`` (a :class:`Document` keeps them as a dict).

    The default bounds of the design variables are the printable box (t >= one 0.4 mm line; the
    part prints on its side, so the walls are lines in the bed plane at any theta), which is also
    the box every mechanics rung is fitted and measured on (mechanics.correction.VERIFIED_BOX).
    """

    tolerance_rel: float = spec(0.02, lo=1e-4, hi=0.5, meaning="relative tolerance on every S_i and R_i")
    theta_deg_bounds: tuple[float, float] = spec(
        VERIFIED_BOX["theta_deg"],
        kind="bounds",
        lo=1.0,
        hi=89.0,
        unit="deg",
        meaning="bounds of θ (default: the box the mechanics are fitted and verified on; the part prints on "
        "its side, so θ sets no overhang)",
    )
    t_mm_bounds: tuple[float, float] = spec(
        VERIFIED_BOX["t_mm"],
        kind="bounds",
        lo=0.01,
        hi=100.0,
        unit="mm",
        meaning="bounds of t (the default starts at one nozzle line)",
    )
    h_mm_bounds: tuple[float, float] = spec(
        VERIFIED_BOX["h_mm"], kind="bounds", lo=0.01, hi=100.0, unit="mm", meaning="bounds of h"
    )
    max_height_mm: float | None = spec(
        None, lo=1.0, hi=1000.0, unit="mm", nullable=True, meaning="optional limit on the printed sensor's total height"
    )
    lock_margin_rel: float = spec(0.1, lo=0.0, hi=1.0, meaning="R_(i+1) ≥ (1 + margin) R_i")
    saturation_margin_rel: float = spec(0.1, lo=0.0, hi=0.9, meaning="chip field ≤ (1 − margin) × 50 mT")
    seed: int = spec(0, lo=SEED_RANGE[0], hi=SEED_RANGE[1], meaning="random seed of the multi-start")
    max_evaluations: int = spec(20000, lo=10, hi=10_000_000, meaning="cap on forward evaluations")
    # weights of the preference among designs that meet the targets (mst_cli.design.problem)
    objective: dict[str, float] = spec(
        default_factory=lambda: dict(DEFAULT_OBJECTIVE),
        kind="weights",
        choices=OBJECTIVE_TERMS,
        lo=0.0,
        hi=1e3,
        meaning="weights of the preference among the designs that meet every target (any subset of the keys; "
        "the others keep their default): `height` prices ln(total part height), `force_resolution` "
        "ln(worst noise-limited force resolution σ_B / (B0 min S_i)), `print_robustness` the RMS relative "
        "change of every S_i and R_i with every wall printed ± `printer.wall_tolerance_mm`. "
        "`mst design --pareto N` maps the whole trade",
    )
    max_print_deviation_rel: float | None = spec(
        None,
        lo=1e-3,
        hi=0.95,
        nullable=True,
        meaning="optional limit on the worst relative change of any S_i or R_i when every wall is printed "
        "± `printer.wall_tolerance_mm`: a constraint, not a weight. When no design meets it, `mst design` "
        "exits 1 and names the lowest part height at which one does (or says that none does)",
    )
    offcentre_region_mm: tuple[float, float] | None = spec(
        None,
        kind="pair",
        lo=0.0,
        hi=100.0,
        unit="mm",
        nullable=True,
        meaning="optional half extents (x, y) of the part of the top face a touch may land on: `mst design` then "
        "reports, per regime, the worst error of a force read as axial over that region (the tilt rung, "
        "docs/design.md section 4.2; about 10 s). A reported figure, not a constraint",
    )


@dataclass(frozen=True)
class LayerEntry:
    """One entry of ``layers``: the geometry (a design), the targets (a spec) or both."""

    theta_deg: float | None = spec(
        None, lo=0.1, hi=90.0, hi_open=True, unit="deg", omit_default=True, meaning="strut wall angle from horizontal"
    )
    t_mm: float | None = spec(
        None, lo=0.01, hi=100.0, unit="mm", omit_default=True, meaning="wall (and pad) thickness t"
    )
    h_mm: float | None = spec(None, lo=0.01, hi=100.0, unit="mm", omit_default=True, meaning="layer height h (outer)")
    target_sensitivity_per_N: float | None = spec(
        None,
        lo=1e-6,
        hi=1e3,
        unit="1/N",
        omit_default=True,
        meaning="spec: secant sensitivity S_i of regime i, (ΔB/B0 over the band) / band width",
    )
    target_range_N: float | None = spec(
        None,
        lo=1e-3,
        hi=1e4,
        unit="N",
        omit_default=True,
        meaning="spec: force R_i at which regime i ends (cumulative: regimes are 0–R_1, R_1–R_2, …)",
    )
    weight: float = spec(
        1.0, lo=1e-3, hi=1e3, omit_default=True, meaning="spec: weight of this layer's targets in the objective"
    )

    @property
    def drawn(self) -> tuple[float, float, float]:
        """(theta_deg, t_mm, h_mm) of a design's layer (one that :attr:`has_geometry`)."""
        assert self.theta_deg is not None and self.t_mm is not None and self.h_mm is not None, "not a design's layer"
        return self.theta_deg, self.t_mm, self.h_mm

    @property
    def has_geometry(self) -> bool:
        return None not in (self.theta_deg, self.t_mm, self.h_mm)

    @property
    def has_targets(self) -> bool:
        return None not in (self.target_sensitivity_per_N, self.target_range_N)


# Every section of the file, in file order, and the dataclass that declares its keys.
SECTION_TYPES: dict[str, type] = {
    "family": CellFamily,
    "material": MaterialSection,
    "magnet": MagnetSection,
    "magnetometer": MagnetometerSection,
    "housing": Housing,
    "insert": InsertPlate,
    "printer": Printer,
    "model": ModelSection,
    "design": DesignOptions,
}
SECTIONS: dict[str, dict[str, Rule]] = {
    name: {f.name: Rule.of(f) for f in fields(cls)} for name, cls in SECTION_TYPES.items()
}
LAYER_RULES: dict[str, Rule] = {f.name: Rule.of(f) for f in fields(LayerEntry)}
DEFAULT_DESIGN = {f.name: default_of(f) for f in fields(DesignOptions)}

# Keys of earlier versions that no longer mean anything, with why (a file that sets one is
# refused with that reason rather than silently built differently).
REMOVED_KEYS: dict[str, str] = {
    "family.struts_per_chevron": "removed in mst 0.2: the cell is one continuous web through the "
    "whole depth (the part prints on its side); delete the key",
    "family.strut_width_mm": "removed in mst 0.2: the web runs the whole depth_mm; delete the key and set depth_mm",
    "housing.pocket_chamfer_mm": "removed in mst 0.2: the pocket is open upwards in the print until "
    "the magnet pause; delete the key",
    "housing.cable_exit_width_mm": "removed in mst 0.2: cables leave through the slot's open end "
    "and the connector windows; delete the key",
}

GEOMETRY_KEYS = ("theta_deg", "t_mm", "h_mm")
TARGET_KEYS = ("target_sensitivity_per_N", "target_range_N")
TOP_KEYS = ("name", "layers") + tuple(SECTIONS)
