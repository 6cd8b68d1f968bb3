"""The sensor description: a design or spec file as one :class:`Document` (docs/file-format.md).

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
from mst_cli.io.rules import Rule, default_of
from mst_cli.io.yaml_io import MAX_INPUT_BYTES, YAMLRefused, load_text
from mst_cli.model.assembly import Housing, InsertPlate, Magnet, SensorGeometry
from mst_cli.model.cell import HexCell
from mst_cli.model.components import BOARDS, Board
from mst_cli.model.material import Material
from mst_cli.model.printer import Printer
from mst_cli.sensor.sections import (
    DEFAULT_OBJECTIVE,
    GEOMETRY_KEYS,
    LAYER_RULES,
    MAX_LAYERS,
    REMOVED_KEYS,
    SECTION_TYPES,
    SECTIONS,
    TARGET_KEYS,
    TOP_KEYS,
    CellFamily,
    DesignOptions,
    LayerEntry,
    MagnetometerSection,
    MagnetSection,
    ModelSection,
)


# --------------------------------------------------------------------------- documents
@dataclass(frozen=True)
class Document:
    """A loaded design or spec file: everything except per-layer data is shared."""

    name: str
    layers: tuple[LayerEntry, ...]
    family: CellFamily
    material: Material
    magnet: Magnet
    board: Board
    noise_uT_rms: float
    chip_offset_mm: tuple[float, float]
    magnet_tilt_deg: float
    housing: Housing
    printer: Printer
    mechanics: str
    field_model: str  # "auto" or one of FIELD_MODELS
    design: dict
    source: str = "<memory>"
    accuracy_rel: float | None = None  # model.accuracy_rel: requested accuracy of k and R
    chip_positions_mm: tuple[tuple[float, float], ...] | None = None  # magnetometer.positions_mm
    insert: InsertPlate = InsertPlate()  # the insert section (material none: no plate)
    load_path: str = "part"  # model.load_path: the whole part, or the layers alone (docs/design.md 4.6)

    @property
    def whole_part(self) -> bool:
        """The predictions include the cap, plates and cover (model.load_path: part or section)."""
        return self.load_path in ("part", "section")

    @property
    def section_rung(self) -> bool:
        """The members' closed form is corrected per regime by the whole-part rung (model.load_path: section)."""
        return self.load_path == "section"

    @property
    def chips_mm(self) -> list[tuple[float, float]]:
        """Every chip's (x, y): magnetometer.positions_mm, else the one chip at chip_offset_mm."""
        chips = self.chip_positions_mm or (self.chip_offset_mm,)
        return [(float(x), float(y)) for x, y in chips]

    def section(self, name: str) -> Any:
        """The values of the file section ``name``, as an object with its keys as attributes."""
        if name == "magnetometer":
            return MagnetometerSection(
                board=self.board.key,
                noise_uT_rms=self.noise_uT_rms,
                chip_offset_mm=(self.chip_offset_mm[0], self.chip_offset_mm[1]),
                magnet_tilt_deg=self.magnet_tilt_deg,
                positions_mm=self.chip_positions_mm,
            )
        if name == "model":
            return ModelSection(
                mechanics=self.mechanics,
                field=self.field_model,
                load_path=self.load_path,
                accuracy_rel=self.accuracy_rel,
            )
        if name == "design":
            return DesignOptions(**self.design)
        return getattr(self, name)  # family, material, magnet, housing, insert, printer: as the file has them

    @property
    def is_design(self) -> bool:
        return all(layer.has_geometry for layer in self.layers)

    @property
    def is_spec(self) -> bool:
        return all(layer.has_targets for layer in self.layers)

    def geometry(self, cells: Sequence[HexCell] | None = None) -> SensorGeometry:
        """The sensor geometry of this document (or of ``cells`` with the same constants)."""
        if cells is None:
            self.require_geometry()
            cells = [self.family.cell(*la.drawn) for la in self.layers]
        return SensorGeometry(
            tuple(cells),
            self.magnet,
            self.board,
            self.housing,
            self.chip_offset_mm,
            self.magnet_tilt_deg,
            self.printer,
            self.chip_positions_mm,
            self.insert if self.insert.present else None,
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
    housing = Housing(**_section(raw, "housing"))
    insert = InsertPlate(**_section(raw, "insert"))
    printer = Printer(**_section(raw, "printer"))
    model = ModelSection(**_section(raw, "model"))
    design = _design_options(_section(raw, "design"))

    _check_housing(family, magnet, board, housing, meter, printer, insert)
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
        chip_positions_mm=meter.positions_mm,
        insert=insert,
        load_path=model.load_path,
    )


def _check_housing(
    family: CellFamily,
    magnet: Magnet,
    board: Board,
    housing: Housing,
    meter: MagnetometerSection,
    printer: Printer,
    insert: InsertPlate,
) -> None:
    """The housing rules (printable depth, pocket and slots inside the body, the insert) do not
    depend on the layers' theta, t, h: check them on any cell of the family, before any design
    work; the first broken one is an InputError."""
    probe = SensorGeometry(
        (family.cell(45.0, 1.0, 3.0),),
        magnet,
        board,
        housing,
        meter.chip_offset_mm,
        0.0,
        printer,
        meter.positions_mm,
        insert if insert.present else None,
    )
    for v in probe.housing_violations():
        raise v.input_error()


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
        out[f.name] = (
            [list(v) if isinstance(v, tuple) else v for v in value] if isinstance(value, (tuple, list)) else value
        )
    return out


def document_to_dict(doc: Document, layers: Sequence[LayerEntry] | None = None) -> dict:
    """Serialise a document back to the file format (all sections but ``design``, explicit values;
    mst_cli.design.result.design_dict adds a spec's ``design`` section)."""
    layers = doc.layers if layers is None else layers
    out: dict[str, Any] = {"name": doc.name}
    for name, declared in SECTION_TYPES.items():
        if name != "design":
            out[name] = section_to_dict(declared, doc.section(name))
    out["layers"] = [section_to_dict(LayerEntry, la) for la in layers]
    return out


def load_design_document(path: str | Path) -> tuple[Document, SensorGeometry]:
    """Load a design file and check its cells; InputError on any broken rule."""
    doc = load_document(path)
    return doc, design_geometry(doc)


def design_geometry(doc: Document) -> SensorGeometry:
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
    ``<!-- /fields -->`` regenerated: ``python -m mst_cli.sensor.document docs/file-format.md``."""
    return field_tables.with_tables(text, field_table_markdown)


if __name__ == "__main__":  # rewrite the field tables of the files named (docs/file-format.md)
    field_tables.rewrite(sys.argv[1:], field_table_markdown)
