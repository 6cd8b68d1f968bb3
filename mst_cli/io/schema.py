"""The file format shared by design files and spec files (docs/file-format.md).

A *design* gives theta, t, h for every layer; a *spec* gives target sensitivities and ranges
instead (a file may give both). Both share every other section. Units are in the key names.
Files are read with :mod:`mst_cli.io.yaml_io` (a ``yaml.SafeLoader`` without anchors, aliases or
duplicate keys, size-capped). Every numeric key is bounded above and below. Every problem
raises :class:`InputError` naming the field, the value and what is allowed; the CLI turns that
into one line and exit code 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import yaml

from mst_cli.errors import InputError
from mst_cli.model import geometry as geo
from mst_cli.model.chip import DEFAULT_NOISE_uT
from mst_cli.model.components import BOARDS, DEFAULT_BOARD, MAGNET_GRADES_T, grade_remanence_T
from mst_cli.model.field import FIELD_MODELS
from mst_cli.model.material import Material
from mst_cli.model.mechanics.correction import VERIFIED_BOX

# the terms of design.objective (mst_cli.design.problem reads the same tuple)
OBJECTIVE_TERMS = ("height", "force_resolution", "print_robustness")
DEFAULT_OBJECTIVE = {"height": 1.0, "force_resolution": 1.0, "print_robustness": 1.0}

MAX_LAYERS = 6
MECHANICS_MODELS = ("spring", "frame", "continuum")


# --------------------------------------------------------------------------- field rules
@dataclass(frozen=True)
class Rule:
    """What one key accepts: a kind and optional bounds (open or closed) or choices."""

    kind: str                       # "float", "int", "str", "bool", "pair", "weights"
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    nullable: bool = False
    unit: str = ""

    def describe(self) -> str:
        if self.kind == "weights":
            return (f"must be a mapping of weights >= 0 (at least one > 0) with keys from "
                    f"{', '.join(self.choices)}")
        if self.choices:
            return "one of " + ", ".join(map(str, self.choices))
        kind = {"float": "a number", "int": "an integer", "str": "a string", "bool": "true or false",
                "pair": "a list of two numbers"}[self.kind]
        parts = []
        if self.lo is not None:
            parts.append(f"{'>' if self.lo_open else '>='} {self.lo:g}")
        if self.hi is not None:
            parts.append(f"{'<' if self.hi_open else '<='} {self.hi:g}")
        unit = f" {self.unit}" if self.unit else ""
        null = " (or null)" if self.nullable else ""
        return f"must be {kind}{' ' + ' and '.join(parts) if parts else ''}{unit}{null}"

    def check(self, path: str, value: Any):
        if value is None:
            if self.nullable:
                return None
            raise InputError(path, value, self.describe())
        if self.kind == "weights":
            if not isinstance(value, dict) or not value:
                raise InputError(path, value, self.describe())
            out = {}
            for key, w in value.items():
                if key not in self.choices:
                    raise InputError(f"{path}.{key}", w, "unknown term; allowed: " + ", ".join(self.choices))
                out[key] = Rule("float", lo=0.0, hi=1e3).check(f"{path}.{key}", w)
            if not any(out.values()):
                raise InputError(path, value, self.describe())
            return out
        if self.kind == "pair":
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                raise InputError(path, value, self.describe())
            return tuple(self._number(f"{path}[{i}]", v) for i, v in enumerate(value))
        if self.kind == "str":
            if not isinstance(value, str):
                raise InputError(path, value, self.describe())
            if self.choices and value not in self.choices:
                raise InputError(path, value, self.describe())
            return value
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise InputError(path, value, self.describe())
            return value
        if self.kind == "int":
            if isinstance(value, bool) or not isinstance(value, int):
                raise InputError(path, value, self.describe())
            return int(self._bounded(path, value))
        return self._number(path, value)

    def _number(self, path, value):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(path, value, self.describe())
        return float(self._bounded(path, value))

    def _bounded(self, path, value):
        if self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo):
            raise InputError(path, value, self.describe())
        if self.hi is not None and (value >= self.hi if self.hi_open else value > self.hi):
            raise InputError(path, value, self.describe())
        return value


def positive(unit="mm", hi=None, nullable=False):
    return Rule("float", lo=0.0, lo_open=True, hi=hi, unit=unit, nullable=nullable)


def nonneg(unit="mm", hi=None):
    return Rule("float", lo=0.0, hi=hi, unit=unit)


def span(lo, hi, unit="mm", nullable=False, hi_open=False):
    """A closed physical range: every numeric input is bounded below and above before any
    arithmetic, so no value such as 1e-308 or 1e300 reaches a division or a field model."""
    return Rule("float", lo=lo, hi=hi, unit=unit, nullable=nullable, hi_open=hi_open)


# Housing: clearances may be zero, walls and floors at least 0.01 mm. Printer: per-key ranges.
HOUSING_CLEARANCES = ("board_clearance_mm", "chip_clearance_mm", "pocket_clearance_mm")
PRINTER_RANGES_MM = {"nozzle_mm": (0.05, 5.0), "layer_height_mm": (0.01, 2.0)}


SECTIONS: dict[str, dict[str, Rule]] = {
    "family": {
        "type": Rule("str", choices=("hex",)),
        "width_mm": span(1.0, 500),
        "depth_mm": span(1.0, 500),
        "contact_allowance_mm": nonneg(hi=10),
    },
    "material": {
        "name": Rule("str"),
        "youngs_modulus_MPa": span(1e-3, 1e5, "MPa"),
        "poisson_ratio": Rule("float", lo=0.0, hi=0.5, hi_open=True),
    },
    "magnet": {
        "diameter_mm": span(0.1, 100),
        "thickness_mm": span(0.1, 100),
        "grade": Rule("str", choices=tuple(MAGNET_GRADES_T)),
        "remanence_T": span(0.01, 2.0, "T", nullable=True),
    },
    "magnetometer": {
        "model": Rule("str", choices=("MLX90393",)),
        "board": Rule("str", choices=tuple(BOARDS)),
        "noise_uT_rms": Rule("float", lo=0.0, hi=1000, unit="uT"),
        "chip_offset_mm": Rule("pair", lo=-100.0, hi=100.0, unit="mm"),
        "magnet_tilt_deg": Rule("float", lo=-45, hi=45, unit="deg"),
    },
    "housing": {f.name: nonneg(hi=100) if f.name in HOUSING_CLEARANCES else span(0.01, 100)
                for f in fields(geo.Housing)},
    "printer": {f.name: span(*PRINTER_RANGES_MM.get(f.name, (0.01, 10.0))) for f in fields(geo.Printer)},
    "model": {
        "mechanics": Rule("str", choices=MECHANICS_MODELS),
        "field": Rule("str", choices=("auto",) + FIELD_MODELS),
        # relative accuracy of layer stiffness and lock force against the continuum reference: the
        # tool picks the cheapest mechanics rung whose measured median errors meet it (mst_cli.model.ladder)
        "accuracy_rel": span(1e-4, 1.0, "", nullable=True, hi_open=True),
    },
    "design": {
        "tolerance_rel": span(1e-4, 0.5, ""),
        "theta_deg_bounds": Rule("pair", unit="deg"),
        "t_mm_bounds": Rule("pair", unit="mm"),
        "h_mm_bounds": Rule("pair", unit="mm"),
        "max_height_mm": span(1.0, 1000, nullable=True),
        "lock_margin_rel": Rule("float", lo=0.0, hi=1.0),
        "saturation_margin_rel": Rule("float", lo=0.0, hi=0.9),
        "seed": Rule("int", lo=0, hi=2**32 - 1),
        "max_evaluations": Rule("int", lo=10, hi=10_000_000),
        # weights of the preference among designs that meet the targets (mst_cli.design.problem)
        "objective": Rule("weights", choices=OBJECTIVE_TERMS),
    },
}

# Keys of earlier versions that no longer mean anything, with why (a file that sets one is
# refused with that reason rather than silently built differently).
REMOVED_KEYS: dict[str, str] = {
    "family.struts_per_chevron": "removed in mst 0.2: the cell is one continuous web through the "
                                 "whole depth (the part prints on its side); delete the key",
    "family.strut_width_mm": "removed in mst 0.2: the web runs the whole depth_mm; delete the key "
                             "and set depth_mm",
    "housing.pocket_chamfer_mm": "removed in mst 0.2: the pocket is open upwards in the print until "
                                 "the magnet pause; delete the key",
    "housing.cable_exit_width_mm": "removed in mst 0.2: cables leave through the slot's open end "
                                   "and the connector windows; delete the key",
}

LAYER_RULES: dict[str, Rule] = {
    "theta_deg": span(0.1, 90.0, "deg", hi_open=True),
    "t_mm": span(0.01, 100),
    "h_mm": span(0.01, 100),
    "target_sensitivity_per_N": span(1e-6, 1e3, "1/N"),
    "target_range_N": span(1e-3, 1e4, "N"),
    "weight": span(1e-3, 1e3, ""),
}
GEOMETRY_KEYS = ("theta_deg", "t_mm", "h_mm")
TARGET_KEYS = ("target_sensitivity_per_N", "target_range_N")
TOP_KEYS = ("name", "layers") + tuple(SECTIONS)

# Default bounds of the design variables: the printable box (t >= one 0.4 mm line; the part
# prints on its side, so the walls are lines in the bed plane at any theta), which is also the
# box every mechanics rung is fitted and measured on (mechanics.correction.VERIFIED_BOX).
DEFAULT_DESIGN = {
    "tolerance_rel": 0.02,
    "theta_deg_bounds": VERIFIED_BOX["theta_deg"],
    "t_mm_bounds": VERIFIED_BOX["t_mm"],
    "h_mm_bounds": VERIFIED_BOX["h_mm"],
    "max_height_mm": None,
    "lock_margin_rel": 0.1,
    "saturation_margin_rel": 0.1,
    "seed": 0,
    "max_evaluations": 20000,
    "objective": DEFAULT_OBJECTIVE,
}


# --------------------------------------------------------------------------- documents
@dataclass(frozen=True)
class CellFamily:
    """Family constants shared by every layer; builds a :class:`HexCell` from (theta, t, h)."""

    width_mm: float = 30.0
    depth_mm: float = 20.0
    contact_allowance_mm: float = 0.1

    def cell(self, theta_deg: float, t_mm: float, h_mm: float) -> geo.HexCell:
        return geo.HexCell(float(theta_deg), float(t_mm), float(h_mm), self.width_mm, self.depth_mm,
                           self.contact_allowance_mm)


@dataclass(frozen=True)
class LayerEntry:
    theta_deg: float | None = None
    t_mm: float | None = None
    h_mm: float | None = None
    target_sensitivity_per_N: float | None = None
    target_range_N: float | None = None
    weight: float = 1.0

    @property
    def has_geometry(self) -> bool:
        return None not in (self.theta_deg, self.t_mm, self.h_mm)

    @property
    def has_targets(self) -> bool:
        return None not in (self.target_sensitivity_per_N, self.target_range_N)


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
    field_model: str            # "auto" or one of FIELD_MODELS
    design: dict
    source: str = "<memory>"
    accuracy_rel: float | None = None   # model.accuracy_rel: requested accuracy of k and R

    @property
    def is_design(self) -> bool:
        return all(layer.has_geometry for layer in self.layers)

    @property
    def is_spec(self) -> bool:
        return all(layer.has_targets for layer in self.layers)

    def geometry(self, cells=None) -> geo.SensorGeometry:
        """The sensor geometry of this document (or of ``cells`` with the same constants)."""
        if cells is None:
            self.require_geometry()
            cells = [self.family.cell(la.theta_deg, la.t_mm, la.h_mm) for la in self.layers]
        return geo.SensorGeometry(tuple(cells), self.magnet, self.board, self.housing,
                                  self.chip_offset_mm, self.magnet_tilt_deg, self.printer)

    def require_geometry(self):
        for i, layer in enumerate(self.layers):
            for key in GEOMETRY_KEYS:
                if getattr(layer, key) is None:
                    raise InputError(f"layers[{i}].{key}", None,
                                     "a design needs theta_deg, t_mm and h_mm for every layer "
                                     "(this looks like a spec: run 'mst design' on it)")

    def require_targets(self):
        for i, layer in enumerate(self.layers):
            for key in TARGET_KEYS:
                if getattr(layer, key) is None:
                    raise InputError(f"layers[{i}].{key}", None,
                                     "a spec needs target_sensitivity_per_N and target_range_N "
                                     "for every layer")

    def with_layers(self, layers) -> Document:
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


def _pair_bounds(path: str, pair, lo: float, hi: float, hi_open=False) -> tuple[float, float]:
    a, b = pair
    if not (lo <= a < b and (b < hi if hi_open else b <= hi)):
        raise InputError(path, list(pair), f"must be [low, high] with {lo:g} <= low < high "
                                           f"{'<' if hi_open else '<='} {hi:g}")
    return (a, b)


def parse_document(raw: Any, source: str = "<memory>") -> Document:
    """Validate a parsed YAML mapping and build a :class:`Document`."""
    if not isinstance(raw, dict):
        raise InputError("(file)", type(raw).__name__ if raw is not None else None,
                         "must be a YAML mapping with at least a 'layers' list")
    for key in raw:
        if key not in TOP_KEYS:
            raise InputError(str(key), raw[key], "unknown top-level key; allowed: " + ", ".join(TOP_KEYS))
    name = raw.get("name", Path(source).stem if source != "<memory>" else "sensor")
    name = Rule("str").check("name", name)
    if (not name or any(c in name for c in "/\\") or name.startswith(".")
            or any(ord(c) < 32 or ord(c) == 127 for c in name)):
        raise InputError("name", name, "must be a non-empty file-name-safe string (no '/', '\\', "
                                       "control characters or NUL; not starting with '.')")

    fam = _section(raw, "family")
    fam.pop("type", None)
    family = CellFamily(**fam)

    material = Material(**_section(raw, "material"))

    mag = _section(raw, "magnet")
    grade = mag.get("grade", "N42")
    remanence = mag.get("remanence_T") or grade_remanence_T(grade)
    magnet = geo.Magnet(mag.get("diameter_mm", 6.0), mag.get("thickness_mm", 2.0), remanence, grade)

    mm = _section(raw, "magnetometer")
    board = BOARDS[mm.get("board", DEFAULT_BOARD)]
    housing = geo.Housing(**_section(raw, "housing"))
    printer = geo.Printer(**_section(raw, "printer"))
    model = _section(raw, "model")

    design = dict(DEFAULT_DESIGN)
    design.update(_section(raw, "design"))
    design["objective"] = {**DEFAULT_OBJECTIVE, **design["objective"]}
    design["theta_deg_bounds"] = _pair_bounds("design.theta_deg_bounds", design["theta_deg_bounds"],
                                              1.0, 89.0)
    design["t_mm_bounds"] = _pair_bounds("design.t_mm_bounds", design["t_mm_bounds"], 0.01, 100.0)
    design["h_mm_bounds"] = _pair_bounds("design.h_mm_bounds", design["h_mm_bounds"], 0.01, 100.0)

    # The housing rules (printable depth, pocket and slot inside the body) do not depend on the
    # layers' theta, t, h: check them on any cell of the family, before any design work.
    probe = geo.SensorGeometry((family.cell(45.0, 1.0, 3.0),), magnet, board, housing,
                               mm.get("chip_offset_mm", (0.0, 0.0)), 0.0, printer)
    for field_name, value, allowed in probe.housing_violations():
        raise InputError(field_name, value, allowed)

    layers_raw = raw.get("layers")
    if not isinstance(layers_raw, list) or not 1 <= len(layers_raw) <= MAX_LAYERS:
        raise InputError("layers", layers_raw if not isinstance(layers_raw, list) else f"{len(layers_raw)} layers",
                         f"must be a list of 1 to {MAX_LAYERS} layers (bottom to top)")
    layers = []
    for i, entry in enumerate(layers_raw):
        path = f"layers[{i}]"
        if not isinstance(entry, dict):
            raise InputError(path, entry, "must be a mapping with theta_deg, t_mm, h_mm "
                                          "and/or target_sensitivity_per_N, target_range_N")
        values = {}
        for key, value in entry.items():
            if key not in LAYER_RULES:
                raise InputError(f"{path}.{key}", value, "unknown key; allowed: " + ", ".join(LAYER_RULES))
            values[key] = LAYER_RULES[key].check(f"{path}.{key}", value)
        layer = LayerEntry(**values)
        if not (layer.has_geometry or layer.has_targets):
            missing = [k for k in GEOMETRY_KEYS + TARGET_KEYS if getattr(layer, k) is None]
            raise InputError(f"{path}.{missing[0]}", None,
                             "each layer needs theta_deg, t_mm, h_mm (a design) or "
                             "target_sensitivity_per_N, target_range_N (a spec)")
        layers.append(layer)

    return Document(
        name=name, layers=tuple(layers), family=family, material=material, magnet=magnet,
        board=board, noise_uT_rms=mm.get("noise_uT_rms", DEFAULT_NOISE_uT),
        chip_offset_mm=mm.get("chip_offset_mm", (0.0, 0.0)),
        magnet_tilt_deg=mm.get("magnet_tilt_deg", 0.0), housing=housing, printer=printer,
        mechanics=model.get("mechanics", "spring"), field_model=model.get("field", "auto"),
        design=design, source=source, accuracy_rel=model.get("accuracy_rel"))


def load_document(path: str | Path) -> Document:
    """Read and validate a design or spec file."""
    from mst_cli.io.yaml_io import MAX_INPUT_BYTES, FileTooLarge, YAMLRefused, load_text, read_text_capped

    path = Path(path)
    try:
        text = read_text_capped(path)       # at most MAX_INPUT_BYTES + 1 bytes are read
    except FileNotFoundError:
        raise InputError("(file)", str(path), "file not found") from None
    except FileTooLarge:
        raise InputError("(file)", str(path), f"is larger than {MAX_INPUT_BYTES} bytes: a design "
                                              "file is a few KB") from None
    except UnicodeDecodeError as exc:
        raise InputError("(file)", str(path), f"cannot be read as text ({type(exc).__name__})") from None
    except (OSError, ValueError) as exc:    # ValueError: a NUL in the path
        reason = getattr(exc, "strerror", None) or str(exc)
        raise InputError("(file)", str(path), f"cannot be read ({reason})") from None
    try:
        raw = load_text(text)
    except YAMLRefused as exc:
        raise InputError(exc.path, exc.value, (f"line {exc.line}: " if exc.line is not None else "")
                         + exc.reason) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise InputError("(file)", str(path), f"is not valid YAML{where}") from None
    return parse_document(raw, source=str(path))


def document_to_dict(doc: Document, layers=None) -> dict:
    """Serialise a document back to the file format (all sections, explicit values)."""
    layers = doc.layers if layers is None else layers
    out_layers = []
    for la in layers:
        entry = {k: getattr(la, k) for k in GEOMETRY_KEYS + TARGET_KEYS if getattr(la, k) is not None}
        if la.weight != 1.0:
            entry["weight"] = la.weight
        out_layers.append(entry)
    fam = doc.family
    return {
        "name": doc.name,
        "family": {"type": "hex", "width_mm": fam.width_mm, "depth_mm": fam.depth_mm,
                   "contact_allowance_mm": fam.contact_allowance_mm},
        "material": {"name": doc.material.name, "youngs_modulus_MPa": doc.material.youngs_modulus_MPa,
                     "poisson_ratio": doc.material.poisson_ratio},
        "magnet": {"diameter_mm": doc.magnet.diameter_mm, "thickness_mm": doc.magnet.thickness_mm,
                   "grade": doc.magnet.grade, "remanence_T": doc.magnet.remanence_T},
        "magnetometer": {"model": "MLX90393", "board": doc.board.key, "noise_uT_rms": doc.noise_uT_rms,
                         "chip_offset_mm": list(doc.chip_offset_mm), "magnet_tilt_deg": doc.magnet_tilt_deg},
        "housing": {f.name: getattr(doc.housing, f.name) for f in fields(geo.Housing)},
        "printer": {f.name: getattr(doc.printer, f.name) for f in fields(geo.Printer)},
        "model": {"mechanics": doc.mechanics, "field": doc.field_model,
                  **({"accuracy_rel": doc.accuracy_rel} if doc.accuracy_rel is not None else {})},
        "layers": out_layers,
    }


def load_design_document(path):
    """Load a design file and check its cells; InputError on any broken rule."""
    doc = load_document(path)
    geometry = doc.geometry()
    for i, v in geometry.violations(doc.printer):
        raise InputError(f"layers[{i}]", {"theta_deg": geometry.layers[i].theta_deg,
                                          "t_mm": geometry.layers[i].t_mm,
                                          "h_mm": geometry.layers[i].h_mm},
                         f"invalid cell ({v.rule}): {v.message}")
    return doc, geometry
