"""The file format shared by design files and spec files (docs/file-format.md).

A *design* gives theta, t, h for every layer; a *spec* gives target sensitivities and ranges
instead (a file may give both). Both share every other section. Units are in the key names.
Files are read with :mod:`mst_cli.io.yaml_io` (a ``yaml.SafeLoader`` without anchors, aliases or
duplicate keys, size-capped). Every numeric key is bounded above and below. Every problem
raises :class:`InputError` naming the field, the value and what is allowed; the CLI turns that
into one line and exit code 2.

Each key is declared once, as a typed dataclass field made with :func:`spec` (unit, bounds or
choices, null, meaning, default): the model's own dataclasses (``HexCell``, ``Magnet``,
``Housing``, ``Printer``, ``SensorGeometry``) where the model keeps the value, the section
classes below otherwise. The validation rules (:data:`SECTIONS`, :data:`LAYER_RULES`), the
defaults, :func:`document_to_dict` and the tables of docs/file-format.md
(:func:`field_table_markdown`) are all read from those declarations.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import yaml

from mst_cli.errors import InputError
from mst_cli.io import field_tables
from mst_cli.io.files import read_input_text
from mst_cli.io.rules import Rule, adopt, default_of
from mst_cli.io.yaml_io import MAX_INPUT_BYTES, YAMLRefused, load_text
from mst_cli.model import geometry as geo
from mst_cli.model.chip import DEFAULT_NOISE_uT
from mst_cli.model.components import BOARDS, DEFAULT_BOARD, grade_remanence_T
from mst_cli.model.field import FIELD_MODELS
from mst_cli.model.fields import SEED_RANGE, spec
from mst_cli.model.material import Material
from mst_cli.model.mechanics.correction import VERIFIED_BOX

# the terms of design.objective (mst_cli.design.problem reads the same tuple)
OBJECTIVE_TERMS = ("height", "force_resolution", "print_robustness")
DEFAULT_OBJECTIVE = dict.fromkeys(OBJECTIVE_TERMS, 1.0)

# 12 printable cells still lock bottom to top below the chip's saturation and the design loop
# meets 12-layer targets (benchmarks/bench_layers.py); each layer adds at least 2 mm of height
# (a 1.2 mm cell and a 0.8 mm plate) and moves the magnet away from the chip, so beyond 12 the
# part is over 33 mm tall and its worst force resolution coarser than 0.4 N with the default magnet.
MAX_LAYERS = 12
MECHANICS_MODELS = ("spring", "frame", "continuum")


# --------------------------------------------------------------------------- the sections
# Sections whose keys are not fields of a model dataclass (or not all of them, or not in the
# file's order) declare them here; housing and printer are geo.Housing and geo.Printer as they are.
@dataclass(frozen=True)
class CellFamily:
    """Family constants shared by every layer; builds a :class:`HexCell` from (theta, t, h)."""

    type: str = spec("hex", choices=("hex",), meaning="cell family (only `hex` for now)")
    width_mm: float = adopt(geo.HexCell, "width_mm")
    depth_mm: float = adopt(geo.HexCell, "depth_mm")
    contact_allowance_mm: float = adopt(geo.HexCell, "contact_allowance_mm")

    def cell(self, theta_deg: float, t_mm: float, h_mm: float) -> geo.HexCell:
        return geo.HexCell(
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


_GRADE = default_of(geo.Magnet.__dataclass_fields__["grade"])


@dataclass(frozen=True)
class MagnetSection:
    """The ``magnet`` section: an axially magnetised NdFeB disc (:class:`geo.Magnet`)."""

    diameter_mm: float = adopt(geo.Magnet, "diameter_mm")
    thickness_mm: float = adopt(geo.Magnet, "thickness_mm")
    grade: str = adopt(geo.Magnet, "grade")
    remanence_T: float | None = spec(
        None,
        lo=0.01,
        hi=2.0,
        unit="T",
        nullable=True,
        meaning=f"Br; null means the grade's mid value ({_GRADE}: {grade_remanence_T(_GRADE):.2f} T)",
    )

    def magnet(self) -> geo.Magnet:
        return geo.Magnet(
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
    chip_offset_mm: tuple[float, float] = adopt(geo.SensorGeometry, "chip_offset_mm")
    magnet_tilt_deg: float = adopt(geo.SensorGeometry, "magnet_tilt_deg")


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
    "housing": geo.Housing,
    "printer": geo.Printer,
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


# --------------------------------------------------------------------------- documents
@dataclass(frozen=True)
class Document:
    """A loaded design or spec file: everything except per-layer data is shared."""

    name: str
    layers: tuple[LayerEntry, ...]
    family: CellFamily
    material: Material
    magnet: geo.Magnet
    board: geo.Board
    noise_uT_rms: float
    chip_offset_mm: tuple[float, float]
    magnet_tilt_deg: float
    housing: geo.Housing
    printer: geo.Printer
    mechanics: str
    field_model: str  # "auto" or one of FIELD_MODELS
    design: dict
    source: str = "<memory>"
    accuracy_rel: float | None = None  # model.accuracy_rel: requested accuracy of k and R

    def section(self, name: str) -> Any:
        """The values of the file section ``name``, as an object with its keys as attributes."""
        if name == "magnetometer":
            return MagnetometerSection(
                board=self.board.key,
                noise_uT_rms=self.noise_uT_rms,
                chip_offset_mm=(self.chip_offset_mm[0], self.chip_offset_mm[1]),
                magnet_tilt_deg=self.magnet_tilt_deg,
            )
        if name == "model":
            return ModelSection(mechanics=self.mechanics, field=self.field_model, accuracy_rel=self.accuracy_rel)
        if name == "design":
            return DesignOptions(**self.design)
        return getattr(self, name)  # family, material, magnet, housing, printer: kept as the file has them

    @property
    def is_design(self) -> bool:
        return all(layer.has_geometry for layer in self.layers)

    @property
    def is_spec(self) -> bool:
        return all(layer.has_targets for layer in self.layers)

    def geometry(self, cells: Sequence[geo.HexCell] | None = None) -> geo.SensorGeometry:
        """The sensor geometry of this document (or of ``cells`` with the same constants)."""
        if cells is None:
            self.require_geometry()
            cells = [self.family.cell(*la.drawn) for la in self.layers]
        return geo.SensorGeometry(
            tuple(cells), self.magnet, self.board, self.housing, self.chip_offset_mm, self.magnet_tilt_deg, self.printer
        )

    def require_geometry(self) -> None:
        for i, layer in enumerate(self.layers):
            for key in GEOMETRY_KEYS:
                if getattr(layer, key) is None:
                    raise InputError(
                        f"layers[{i}].{key}",
                        None,
                        "a design needs theta_deg, t_mm and h_mm for every layer "
                        "(this looks like a spec: run 'mst design' on it)",
                    )

    def require_targets(self) -> None:
        for i, layer in enumerate(self.layers):
            for key in TARGET_KEYS:
                if getattr(layer, key) is None:
                    raise InputError(
                        f"layers[{i}].{key}",
                        None,
                        "a spec needs target_sensitivity_per_N and target_range_N for every layer",
                    )

    def with_layers(self, layers: Iterable[LayerEntry]) -> Document:
        return replace(self, layers=tuple(layers))


def _section(raw: dict, name: str) -> dict:
    """Validate one section; returns only the keys given (defaults are the dataclasses')."""
    data = raw.get(name, {})
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise InputError(name, data, "must be a mapping of keys to values")
    rules = SECTIONS[name]
    out = {}
    for key, value in data.items():
        if f"{name}.{key}" in REMOVED_KEYS:
            raise InputError(f"{name}.{key}", value, REMOVED_KEYS[f"{name}.{key}"])
        if key not in rules:
            raise InputError(f"{name}.{key}", value, "unknown key; allowed: " + ", ".join(rules))
        out[key] = rules[key].check(f"{name}.{key}", value)
    return out


def _design_options(given: dict) -> dict:
    """The ``design`` section as the dict a :class:`Document` keeps: defaults for the keys not
    given, the objective's weights merged into the default ones (a file may weigh some terms
    only) and every [low, high] pair checked once the whole section is read."""
    options = DesignOptions(**given)
    design = {f.name: getattr(options, f.name) for f in fields(DesignOptions)}
    design["objective"] = {**DEFAULT_OBJECTIVE, **design["objective"]}
    for key, rule in SECTIONS["design"].items():
        if rule.kind == "bounds":
            design[key] = rule.ordered(f"design.{key}", design[key])
    return design


def parse_document(raw: Any, source: str = "<memory>") -> Document:
    """Validate a parsed YAML mapping and build a :class:`Document`."""
    if not isinstance(raw, dict):
        raise InputError(
            "(file)",
            type(raw).__name__ if raw is not None else None,
            "must be a YAML mapping with at least a 'layers' list",
        )
    for key in raw:
        if key not in TOP_KEYS:
            raise InputError(str(key), raw[key], "unknown top-level key; allowed: " + ", ".join(TOP_KEYS))
    name = _file_name(raw.get("name", Path(source).stem if source != "<memory>" else "sensor"))

    # the sections in file order, each from its declaration: keys not given take its defaults
    family = CellFamily(**_section(raw, "family"))
    material = Material(**_section(raw, "material"))
    magnet = MagnetSection(**_section(raw, "magnet")).magnet()
    meter = MagnetometerSection(**_section(raw, "magnetometer"))
    board = BOARDS[meter.board]
    housing = geo.Housing(**_section(raw, "housing"))
    printer = geo.Printer(**_section(raw, "printer"))
    model = ModelSection(**_section(raw, "model"))
    design = _design_options(_section(raw, "design"))

    # The housing rules (printable depth, pocket and slot inside the body) do not depend on the
    # layers' theta, t, h: check them on any cell of the family, before any design work.
    probe = geo.SensorGeometry(
        (family.cell(45.0, 1.0, 3.0),), magnet, board, housing, meter.chip_offset_mm, 0.0, printer
    )
    for v in probe.housing_violations():
        raise v.input_error()

    return Document(
        name=name,
        layers=_layers(raw.get("layers")),
        family=family,
        material=material,
        magnet=magnet,
        board=board,
        noise_uT_rms=meter.noise_uT_rms,
        chip_offset_mm=meter.chip_offset_mm,
        magnet_tilt_deg=meter.magnet_tilt_deg,
        housing=housing,
        printer=printer,
        mechanics=model.mechanics,
        field_model=model.field,
        design=design,
        source=source,
        accuracy_rel=model.accuracy_rel,
    )


def _file_name(value: Any) -> str:
    """The document's ``name``: a string that is safe as a file name (output folders use it)."""
    name = Rule("str").check("name", value)
    if (
        not name
        or any(c in name for c in "/\\")
        or name.startswith(".")
        or any(ord(c) < 32 or ord(c) == 127 for c in name)
    ):
        raise InputError(
            "name",
            name,
            "must be a non-empty file-name-safe string (no '/', '\\', "
            "control characters or NUL; not starting with '.')",
        )
    return name


def _layers(layers_raw: Any) -> tuple[LayerEntry, ...]:
    """The ``layers`` list: 1 to MAX_LAYERS entries, each a design's or a spec's (or both)."""
    if not isinstance(layers_raw, list) or not 1 <= len(layers_raw) <= MAX_LAYERS:
        raise InputError(
            "layers",
            layers_raw if not isinstance(layers_raw, list) else f"{len(layers_raw)} layers",
            f"must be a list of 1 to {MAX_LAYERS} layers (bottom to top): each adds at least 2 mm "
            "of height and moves the magnet away from the chip",
        )
    return tuple(_layer(f"layers[{i}]", entry) for i, entry in enumerate(layers_raw))


def _layer(path: str, entry: Any) -> LayerEntry:
    """One entry of ``layers``: theta_deg, t_mm, h_mm and/or the targets, each checked."""
    if not isinstance(entry, dict):
        raise InputError(
            path,
            entry,
            "must be a mapping with theta_deg, t_mm, h_mm and/or target_sensitivity_per_N, target_range_N",
        )
    values = {}
    for key, value in entry.items():
        if key not in LAYER_RULES:
            raise InputError(f"{path}.{key}", value, "unknown key; allowed: " + ", ".join(LAYER_RULES))
        values[key] = LAYER_RULES[key].check(f"{path}.{key}", value)
    layer = LayerEntry(**values)
    if not (layer.has_geometry or layer.has_targets):
        missing = [k for k in GEOMETRY_KEYS + TARGET_KEYS if getattr(layer, k) is None]
        raise InputError(
            f"{path}.{missing[0]}",
            None,
            "each layer needs theta_deg, t_mm, h_mm (a design) or target_sensitivity_per_N, target_range_N (a spec)",
        )
    return layer


def load_document(path: str | Path) -> Document:
    """Read and validate a design or spec file."""
    path = Path(path)
    # a regular file only (a FIFO would block), at most MAX_INPUT_BYTES + 1 bytes read
    text = read_input_text(path, MAX_INPUT_BYTES, what="YAML file", too_large=": a design file is a few KB")
    try:
        raw = load_text(text)
    except YAMLRefused as exc:
        raise InputError(
            exc.path, exc.value, (f"line {exc.line}: " if exc.line is not None else "") + exc.reason
        ) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise InputError("(file)", str(path), f"is not valid YAML{where}") from None
    return parse_document(raw, source=str(path))


def section_to_dict(declared: type, values: Any) -> dict:
    """The keys ``declared`` (a section or layer dataclass) declares, read from ``values`` (any
    object with those attributes), as a file writes them: pairs as lists; a key declared
    ``omit_default`` is left out while it holds its default."""
    out = {}
    for f in fields(declared):
        value = getattr(values, f.name)
        if f.metadata["omit_default"] and value == default_of(f):
            continue
        out[f.name] = list(value) if isinstance(value, (tuple, list)) else value
    return out


def document_to_dict(doc: Document, layers: Sequence[LayerEntry] | None = None) -> dict:
    """Serialise a document back to the file format (all sections but ``design``, explicit values;
    mst_cli.design.document.design_dict adds a spec's ``design`` section)."""
    layers = doc.layers if layers is None else layers
    out: dict[str, Any] = {"name": doc.name}
    for name, declared in SECTION_TYPES.items():
        if name != "design":
            out[name] = section_to_dict(declared, doc.section(name))
    out["layers"] = [section_to_dict(LayerEntry, la) for la in layers]
    return out


def load_design_document(path: str | Path) -> tuple[Document, geo.SensorGeometry]:
    """Load a design file and check its cells; InputError on any broken rule."""
    doc = load_document(path)
    return doc, design_geometry(doc)


def design_geometry(doc: Document) -> geo.SensorGeometry:
    """The sensor of a design document whose cells are all valid; InputError on any broken rule."""
    geometry = doc.geometry()
    for v in geometry.violations(doc.printer):
        raise v.input_error("invalid cell")
    return geometry


# --------------------------------------------------------------------------- docs/file-format.md
FIELD_TABLE = field_tables.FIELD_TABLE


def field_table_markdown(section: str) -> str:
    """The table of one section (or ``layers``) in docs/file-format.md, from the declarations."""
    declared, prefix = (LayerEntry, "layers[i]") if section == "layers" else (SECTION_TYPES[section], section)
    return field_tables.table_markdown(declared, prefix)


def with_field_tables(text: str) -> str:
    """``text`` (docs/file-format.md) with every table between ``<!-- fields:SECTION -->`` and
    ``<!-- /fields -->`` regenerated: ``python -m mst_cli.io.schema docs/file-format.md``."""
    return field_tables.with_tables(text, field_table_markdown)


if __name__ == "__main__":  # rewrite the field tables of the files named (docs/file-format.md)
    field_tables.rewrite(sys.argv[1:], field_table_markdown)
