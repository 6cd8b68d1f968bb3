"""``export.json``: what the exported body should measure, written by ``mst export`` and read by
``mst check`` and ``mst slice``.

Every number is read from the geometry object (analytic, not measured on the CAD), so
``mst check`` compares the written mesh against the design itself. Units are in the keys.
Dimensions are in the sensor frame (z up the stack) except in the ``print`` section, which
describes the mesh files as they lie on the bed. No CAD or mesh library is imported here.

Writing: :func:`export_manifest` (a JSON-ready dict). Reading: :func:`load_manifest` gives a
:class:`Manifest`, the typed part ``mst check`` uses, validated field by field on load (type,
nesting, finite and sane size): a malformed file is an :class:`~mst_cli.errors.InputError`
naming the field, so a KeyError or TypeError inside a check is a bug, not bad input.
``mst slice`` reads :class:`SliceManifest` (``load_manifest(path, SliceManifest)``): the few keys
it uses, each optional (any hand-made body can be sliced), each of the same kind as in
:class:`Manifest`, so the two commands share every rule.

Bounds that a writer and a reader share live here once: :data:`STL_TOLERANCE_MM` is both what
``mst export --stl-tolerance`` accepts and what ``export.json.stl_tolerance_mm`` may hold.
"""

from __future__ import annotations

import json
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar, overload

import numpy as np

from mst_cli.cad.expected_body import (
    base_volume_mm3,
    body_bbox_mm,
    body_volume_mm3,
    cap_volume_mm3,
    cell_volume_mm3,
    plates_volume_mm3,
    pocket_curved_area_mm2,
    pocket_section_area_mm2,
    pocket_volume_mm3,
    to_print_frame,
    wall_centrelines_xz,
    wall_horizontal_width_mm,
)
from mst_cli.cad.placed_parts import crush_ribs_section, parts_section
from mst_cli.errors import InputError
from mst_cli.io.files import read_input_text
from mst_cli.sensor.document import Document, design_geometry, parse_document
from mst_cli.version import package_version

if TYPE_CHECKING:
    from mst_cli.model.assembly import SensorGeometry
    from mst_cli.model.printer import Printer

MANIFEST_NAME = "export.json"
MANIFEST_FORMAT = 2


def print_section(g: SensorGeometry) -> dict:
    """How the part lies on the bed, where the print pauses, and the designed cavity gaps and
    wall centre lines in the print frame (what ``mst slice`` compares with the G-code)."""
    lo, hi = body_bbox_mm(g)
    corners = to_print_frame(g, [lo, hi])
    lh = g.layer_height_mm
    # measure the cavities a quarter of the depth up, mid-layer (away from pocket and slot)
    z_measure = round((round(0.25 * g.depth_mm / lh) + 0.5) * lh, 9)
    cavity_lines = []
    for i, (cell, zb) in enumerate(zip(g.layers, g.layer_bottoms_mm)):
        # print y = -sensor z: the cavity between the pads, on the axis x = 0
        cavity_lines.append(
            {
                "layer": i + 1,
                "x_mm": 0.0,
                "z_mm": z_measure,
                "y_low_mm": -(zb + cell.h_mm - cell.t_mm),
                "y_high_mm": -(zb + cell.t_mm),
                "gap_mm": cell.cavity_height_mm,
            }
        )
    # every inclined wall cuts every print layer along the same line (print y = -sensor z):
    # the middle of its free stretch, measured over the print layers above the first
    wall_lines = []
    for i, (cell, zb) in enumerate(zip(g.layers, g.layer_bottoms_mm)):
        for name, (xa, za), (xb, zb_) in wall_centrelines_xz(cell):
            wall_lines.append(
                {
                    "layer": i + 1,
                    "wall": name,
                    "t_mm": cell.t_mm,
                    "x0_mm": xa,
                    "y0_mm": -(zb + za),
                    "x1_mm": xb,
                    "y1_mm": -(zb + zb_),
                    "z_low_mm": lh,
                    "z_high_mm": g.depth_mm,
                }
            )
    return {
        "orientation": "lying on the sensor's -y face: print (x, y, z) = (x, -z, y + depth/2)",
        "rotation": [[1, 0, 0], [0, 0, -1], [0, 1, 0]],
        "translation_mm": [0.0, 0.0, 0.5 * g.depth_mm],
        "layer_height_mm": lh,
        "height_mm": g.depth_mm,
        "layers": int(round(g.depth_mm / lh)),
        "bbox_min_mm": corners.min(axis=0).tolist(),
        "bbox_max_mm": corners.max(axis=0).tolist(),
        "pause": {
            "after_layer": g.pause_after_layer,
            "z_mm": g.pause_height_mm,
            "why": "drop the magnet into its pocket",
        },
        # every pause, lowest first (the magnet's is print.pause, kept for older readers)
        "pauses": [{"after_layer": p.after_layer, "z_mm": p.z_mm, "why": p.why} for p in g.pauses],
        "magnet_top_z_mm": g.print_height_mm(g.magnet.radius_mm),
        "cavity_lines": cavity_lines,
        "wall_lines": wall_lines,
    }


def export_manifest(
    name: str,
    geometry: SensorGeometry,
    printer: Printer,
    stl_tolerance_mm: float,
    files: list[str],
    design: dict | None = None,
) -> dict:
    """The expected dimensions of the exported body (see module docstring); ``design`` (the
    design document as its file holds it) lets ``mst slice`` simulate the walls as sliced."""
    g = geometry
    cells = g.layers
    return {
        "format": MANIFEST_FORMAT,
        "mst_version": package_version(),
        "name": name,
        "files": list(files),
        "units": "mm, deg",
        "stl_tolerance_mm": stl_tolerance_mm,
        "print": print_section(g),
        "body": _body_section(g, stl_tolerance_mm),
        "magnet_pocket": _pocket_section(g),
        "parts": parts_section(g),
        **_slots_sections(g),
        "gap0_mm": g.gap0_mm,
        "base_top_z_mm": g.z_base_top_mm,
        "layers": [
            {
                "z_bottom_mm": zb,
                "h_mm": c.h_mm,
                "theta_deg": c.theta_deg,
                "t_mm": c.t_mm,
                "web_depth_mm": c.b_mm,
                "width_mm": c.width_mm,
                "cavity_height_mm": c.cavity_height_mm,
                "wall_horizontal_width_mm": wall_horizontal_width_mm(c),
            }
            for c, zb in zip(cells, g.layer_bottoms_mm)
        ],
        "printer": {
            "nozzle_mm": printer.nozzle_mm,
            "min_wall_mm": printer.min_wall_mm,
            "min_gap_mm": printer.min_gap_mm,
            "layer_height_mm": printer.layer_height_mm,
        },
        "min_features": {
            "wall_mm": min(c.t_mm for c in cells),
            "cavity_gap_mm": min(c.cavity_height_mm for c in cells),
        },
        **({"design": design} if design is not None else {}),
    }


def _body_section(g: SensorGeometry, stl_tolerance_mm: float) -> dict:
    """export.json's body: volume (with the tolerance a mesh of ``stl_tolerance_mm`` allows), its
    parts and the bounding box."""
    bbox_min, bbox_max = body_bbox_mm(g)
    # A mesh with chord deviation <= delta misses at most delta x (curved area) of the pocket;
    # float32 STL coordinates add ~1e-7 relative per vertex.
    volume_tol = stl_tolerance_mm * pocket_curved_area_mm2(g) + 1e-5 * body_volume_mm3(g)
    return {
        "volume_mm3": body_volume_mm3(g),
        "volume_tolerance_mm3": volume_tol,
        "volume_parts_mm3": {
            "base": base_volume_mm3(g),
            "layers": [cell_volume_mm3(c) for c in g.layers],
            "plates": plates_volume_mm3(g),
            "cap": cap_volume_mm3(g),
        },
        "bbox_min_mm": list(bbox_min),
        "bbox_max_mm": list(bbox_max),
        "bodies": 1,
        "internal_voids": 1 + g.has_insert,  # the closed magnet pocket, and the insert's slot
    }


def _pocket_section(g: SensorGeometry) -> dict:
    """export.json's magnet_pocket: its size, roof and a section through its middle."""
    z_pocket_mid = g.z_magnet_bottom_mm + 0.5 * g.pocket_depth_mm
    return {
        "radius_mm": g.pocket_radius_mm,
        "depth_mm": g.pocket_depth_mm,
        "top_y_mm": g.pocket_top_y_mm,
        "roof_apex_y_mm": g.pocket_roof_apex_y_mm,
        "roof_rise_mm": g.pocket_roof_rise_mm,
        "floor_z_mm": g.z_magnet_bottom_mm,
        "section_z_mm": z_pocket_mid,
        "section_area_mm2": pocket_section_area_mm2(g, z_pocket_mid),
        "volume_mm3": pocket_volume_mm3(g),
        "curved_area_mm2": pocket_curved_area_mm2(g),
        "magnet_diameter_mm": g.magnet.diameter_mm,
        "magnet_thickness_mm": g.magnet.thickness_mm,
        "crush_ribs": crush_ribs_section(g),
    }


def _slot_section(g: SensorGeometry, chip: int = 0) -> dict:
    """export.json's board_slot (and each entry of board_slots): where chip ``chip``'s board
    slides in, its cable windows and the chip."""
    slot = g.board_slots[chip]
    x0, x1 = slot.x_mm
    return {
        "board": g.board.key,
        "x0_mm": x0,
        "x1_mm": x1,
        "floor_y_mm": slot.floor_y_mm,
        "open_face": "+y",
        "floor_z_mm": g.z_board_bottom_mm,
        "top_z_mm": g.z_cover_bottom_mm,
        "height_mm": g.slot_height_mm,
        "headroom_mm": g.board.headroom_mm,
        "cable_windows": [
            # top_y_mm: under a 45 deg gable (the side wall over it carries the cover), or the +y face
            {"x_inner_mm": a, "x_outer_mm": b, "floor_y_mm": yf, "z0_mm": z0, "z1_mm": z1}
            | {"top_y_mm": 0.5 * g.depth_mm if top is None else top, "open_through_top_face": top is None}
            for (a, b, yf, z0, z1), top in zip(slot.windows, slot.window_tops_y_mm)
        ],
        "board_thickness_mm": g.board.thickness_mm,
        "chip_height_mm": g.board.chip_height_mm,
        "chip_xy_mm": list(slot.chip_xy_printed_mm),
        "chip_xy_nominal_mm": list(slot.chip_xy_mm),
        "hall_z_mm": g.z_hall_mm,
        "cover_mm": g.housing.cover_mm,
    }


def _slots_sections(g: SensorGeometry) -> dict:
    """``board_slot`` (the first chip's, as a one-chip export has it) and, with more than one
    chip, ``board_slots``: every chip's, in the order of magnetometer.positions_mm."""
    n = len(g.board_slots)
    out: dict[str, dict | list[dict]] = {"board_slot": _slot_section(g)}
    if n > 1:
        out["board_slots"] = [_slot_section(g, i) for i in range(n)]
    return out


# --------------------------------------------------------------------------- reading
# Sizes in export.json: a sensor body is centimetres, so anything beyond a metre is no body mst
# wrote (and 1e37 would overflow the measurements).
MAX_COORD_MM = 1000.0
MAX_MANIFEST_BYTES = 10_000_000
MAX_LIST = 64
MAX_VOLUME = 1e9
# a finer layer, tolerance or nozzle would overflow the layer counts
MIN_SIZE_MM = 1e-3
# the chord tolerance of the mesh: 'mst export --stl-tolerance' and export.json's stl_tolerance_mm
STL_TOLERANCE_MM = (1e-4, 1.0)


def _kind(kind):
    """A field of export.json: ``kind`` is "num" (a finite number within +-MAX_COORD_MM; bool is
    not a number), "pos" (a size from MIN_SIZE_MM to MAX_COORD_MM), "tol" (STL_TOLERANCE_MM),
    "vol" (an area or volume from 0 to MAX_VOLUME), "int", "str", "design" (a design document,
    :func:`_design_document`), (kind, n) a list of exactly n,
    ListOf a list of up to MAX_LIST, or a dataclass below (a mapping). A field with a default
    may be missing (``optional``)."""
    return field(metadata={"kind": kind})


def _optional(kind, default=None):
    """A field that may be missing from the file (then ``default``); given, it is ``kind``."""
    return field(default=default, metadata={"kind": kind})


@dataclass(frozen=True)
class ListOf:
    """A list of up to MAX_LIST mappings of ``kind``, at least ``min_len`` of them."""

    kind: type
    min_len: int = 0


@dataclass(frozen=True)
class Pause:
    after_layer: int = _kind("int")
    z_mm: float = _kind("num")


@dataclass(frozen=True)
class CavityLine:
    """A line of the print frame across one layer's cavity: its designed gap, which ``mst slice``
    measures in the G-code."""

    layer: int = _kind("int")
    x_mm: float = _kind("num")
    z_mm: float = _kind("num")
    y_low_mm: float = _kind("num")
    y_high_mm: float = _kind("num")
    gap_mm: float = _kind("num")


@dataclass(frozen=True)
class WallLine:
    """The centre line of one inclined wall in the print frame (the middle of the stretch where
    it stands free) and the print heights it is measured over: ``mst slice`` measures the
    as-sliced wall across it."""

    layer: int = _kind("int")
    wall: str = _kind("str")
    t_mm: float = _kind("pos")
    x0_mm: float = _kind("num")
    y0_mm: float = _kind("num")
    x1_mm: float = _kind("num")
    y1_mm: float = _kind("num")
    z_low_mm: float = _kind("num")
    z_high_mm: float = _kind("num")


@dataclass(frozen=True)
class PrintFrame:
    """How the mesh lies on the bed: print = rotation @ sensor + translation (row-vector form in
    :func:`mst_cli.cad.measure.to_sensor_frame`)."""

    rotation: tuple[tuple[float, float, float], ...] = _kind((("num", 3), 3))
    translation_mm: tuple[float, float, float] = _kind(("num", 3))
    layer_height_mm: float = _kind("pos")
    height_mm: float = _kind("pos")
    magnet_top_z_mm: float = _kind("num")
    pause: Pause = _kind(Pause)
    cavity_lines: tuple[CavityLine, ...] = _kind(ListOf(CavityLine))
    wall_lines: tuple[WallLine, ...] = _optional(ListOf(WallLine), ())  # exports before issue 21 lack it


@dataclass(frozen=True)
class Body:
    volume_mm3: float = _kind("vol")
    volume_tolerance_mm3: float = _kind("vol")
    bbox_min_mm: tuple[float, float, float] = _kind(("num", 3))
    bbox_max_mm: tuple[float, float, float] = _kind(("num", 3))
    bodies: int = _kind("int")
    internal_voids: int = _kind("int")


@dataclass(frozen=True)
class Layer:
    z_bottom_mm: float = _kind("num")
    h_mm: float = _kind("pos")
    t_mm: float = _kind("pos")
    theta_deg: float = _kind("num")
    web_depth_mm: float = _kind("pos")
    cavity_height_mm: float = _kind("num")
    width_mm: float | None = _optional("pos")  # the face's width W; exports before 0.18 may lack it


@dataclass(frozen=True)
class Pocket:
    section_z_mm: float = _kind("num")
    radius_mm: float = _kind("num")
    section_area_mm2: float = _kind("vol")
    depth_mm: float = _kind("num")
    floor_z_mm: float = _kind("num")
    curved_area_mm2: float = _kind("vol")
    volume_mm3: float = _kind("vol")
    roof_rise_mm: float = _kind("num")


@dataclass(frozen=True)
class CableWindow:
    x_inner_mm: float = _kind("num")
    x_outer_mm: float = _kind("num")
    floor_y_mm: float = _kind("num")


@dataclass(frozen=True)
class Slot:
    board: str = _kind("str")
    chip_xy_mm: tuple[float, float] = _kind(("num", 2))
    floor_z_mm: float = _kind("num")
    top_z_mm: float = _kind("num")
    floor_y_mm: float = _kind("num")
    x0_mm: float = _kind("num")
    x1_mm: float = _kind("num")
    board_thickness_mm: float = _kind("num")
    chip_height_mm: float = _kind("num")
    cable_windows: tuple[CableWindow, ...] = _kind(ListOf(CableWindow))


@dataclass(frozen=True)
class PlacedPart:
    """An entry of ``parts``: a part that is not the TPU body, and (the insert) the slot the body
    leaves for it, sensor frame."""

    name: str = _kind("str")
    sensor_box_min_mm: tuple[float, float, float] = _kind(("num", 3))
    sensor_box_max_mm: tuple[float, float, float] = _kind(("num", 3))
    placed_at_pause: Pause = _kind(Pause)
    sensor_slot_min_mm: tuple[float, float, float] | None = _optional(("num", 3))
    sensor_slot_max_mm: tuple[float, float, float] | None = _optional(("num", 3))
    slot_roof_rise_mm: float | None = _optional("num")


@dataclass(frozen=True)
class PrinterLimits:
    nozzle_mm: float = _kind("pos")
    min_gap_mm: float = _kind("pos")


@dataclass(frozen=True)
class Manifest:
    """What ``mst check`` reads from export.json, typed and validated (:meth:`from_dict`).
    Fields are the file's keys, in the order they are validated."""

    name: str = _kind("str")
    stl_tolerance_mm: float = _kind("tol")
    gap0_mm: float = _kind("num")
    print: PrintFrame = _kind(PrintFrame)
    body: Body = _kind(Body)
    layers: tuple[Layer, ...] = _kind(ListOf(Layer, min_len=1))
    magnet_pocket: Pocket = _kind(Pocket)
    board_slot: Slot = _kind(Slot)
    printer: PrinterLimits = _kind(PrinterLimits)
    board_slots: tuple[Slot, ...] = _optional(ListOf(Slot), ())  # one-chip exports lack it
    parts: tuple[PlacedPart, ...] = _optional(ListOf(PlacedPart), ())  # exports before issue 44 lack it
    design: Document | None = _optional("design")  # exports before issue 21 lack it

    @property
    def slots(self) -> tuple[Slot, ...]:
        """Every chip's board slot: ``board_slots``, else the one ``board_slot``."""
        return self.board_slots or (self.board_slot,)

    @property
    def insert(self) -> PlacedPart | None:
        """The insert plate's entry of ``parts`` (None without one)."""
        return next((p for p in self.parts if p.name == "insert" and p.sensor_slot_min_mm is not None), None)

    @classmethod
    def from_dict(cls, data: Any) -> Manifest:
        """The manifest of a parsed export.json (or of :func:`export_manifest`'s dict): an
        InputError names the first field that is missing, of the wrong type or nesting, out of
        range (``export.json.layers[2].t_mm``), or a rotation that is not one."""
        manifest = _parse(cls, data, "export.json")
        rotation = np.asarray(manifest.print.rotation, dtype=float)
        if not (np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) and np.linalg.det(rotation) > 0):
            raise InputError(
                "export.json.print.rotation",
                data["print"]["rotation"],
                "must be a rotation matrix (orthonormal, determinant +1): rewrite it with 'mst export'",
            )
        return manifest


@dataclass(frozen=True)
class SlicePrint:
    """The keys of ``print`` that ``mst slice`` reads (each optional)."""

    layer_height_mm: float | None = _optional("pos")
    pause: Pause | None = _optional(Pause)
    pauses: tuple[Pause, ...] = _optional(ListOf(Pause), ())  # exports before issue 44 give one pause
    cavity_lines: tuple[CavityLine, ...] = _optional(ListOf(CavityLine), ())
    wall_lines: tuple[WallLine, ...] = _optional(ListOf(WallLine), ())


@dataclass(frozen=True)
class SliceManifest:
    """What ``mst slice`` reads from export.json: the name, the pause asked for, the cavity and
    wall lines and the design document, validated before anything is sliced with
    :class:`Manifest`'s own field kinds (the design with the design-file rules, when it is
    simulated). Every key is optional: a hand-made export of any body slices (a missing pause
    is "not given"), and an export.json written before the walls were measured slices without
    them."""

    name: str | None = _optional("str")
    print: SlicePrint = _optional(SlicePrint, SlicePrint())
    design: Document | None = _optional("design")

    @classmethod
    def from_dict(cls, data: Any) -> SliceManifest:
        return _parse(cls, data, "export.json")


def _is_number(v) -> bool:
    # abs(v) <= limit is False for NaN and infinities, and exact for integers of any size
    return isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) <= MAX_COORD_MM


_SCALAR_OK = {
    "num": _is_number,
    "pos": lambda v: _is_number(v) and v >= MIN_SIZE_MM,
    "tol": lambda v: _is_number(v) and STL_TOLERANCE_MM[0] <= v <= STL_TOLERANCE_MM[1],
    "vol": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v <= MAX_VOLUME,
    "int": lambda v: isinstance(v, int) and not isinstance(v, bool) and abs(v) <= 10**9,
    "str": lambda v: isinstance(v, str),
}
_KIND_TEXT = {
    "num": f"a finite number within +-{MAX_COORD_MM:g}",
    "pos": f"a size from {MIN_SIZE_MM:g} to {MAX_COORD_MM:g}",
    "tol": f"a tolerance from {STL_TOLERANCE_MM[0]:g} to {STL_TOLERANCE_MM[1]:g} mm",
    "vol": f"a number from 0 to {MAX_VOLUME:g}",
    "int": "an integer",
    "str": "a string",
}


def _describe(kind) -> str:
    if isinstance(kind, str):
        return _KIND_TEXT[kind]
    if isinstance(kind, tuple):
        return f"a list of {kind[1]} entries, each {_describe(kind[0])}"
    if isinstance(kind, ListOf):
        return f"a list of up to {MAX_LIST} mappings"
    return "a mapping with " + ", ".join(f.name for f in fields(kind))


def _parse(kind, data, path: str):
    """``data`` as ``kind`` (see :func:`_kind`), checked before it is read: numbers become
    floats, lists tuples, mappings dataclasses. ``path`` names the field in errors."""
    if kind == "design":
        return _design_document(data, path)
    if isinstance(kind, str):
        if _SCALAR_OK[kind](data):
            return data if kind in ("int", "str") else float(data)
    elif isinstance(kind, tuple):
        sub, n = kind
        if isinstance(data, list) and len(data) == n:
            return tuple(_parse(sub, item, f"{path}[{i}]") for i, item in enumerate(data))
    elif isinstance(kind, ListOf):
        if isinstance(data, list) and kind.min_len <= len(data) <= MAX_LIST:
            return tuple(_parse(kind.kind, item, f"{path}[{i}]") for i, item in enumerate(data))
    elif isinstance(data, dict):
        values = {}
        for f in fields(kind):
            if f.name not in data and f.default is not MISSING:
                values[f.name] = f.default
                continue
            if f.name not in data:
                raise InputError(f"{path}.{f.name}", None, "missing: rewrite it with 'mst export'")
            values[f.name] = _parse(f.metadata["kind"], data[f.name], f"{path}.{f.name}")
        return kind(**values)
    shown = data if not isinstance(data, (dict, list)) else type(data).__name__
    raise InputError(path, shown, f"must be {_describe(kind)}: rewrite it with 'mst export'")


def _design_document(data, path: str) -> Document:
    """export.json's ``design``: the design document the body was built from, with the
    design-file rules (every cell printable and working); an InputError names the field inside
    it (``export.json.design.layers[1].t_mm``)."""
    if not isinstance(data, dict):
        raise InputError(
            path,
            type(data).__name__ if isinstance(data, list) else data,
            "must be a mapping (the design document): rewrite it with 'mst export'",
        )
    try:
        doc = parse_document(data, source=path)
        if not doc.is_design:
            raise InputError("layers", None, "must give every layer's theta_deg, t_mm and h_mm (a design)")
        design_geometry(doc)
    except InputError as exc:
        raise InputError(f"{path}.{exc.field}", exc.value, f"{exc.allowed}: rewrite it with 'mst export'") from None
    return doc


_Kind = TypeVar("_Kind", Manifest, SliceManifest)


@overload
def load_manifest(path: Path) -> Manifest: ...
@overload
def load_manifest(path: Path, kind: type[_Kind]) -> _Kind: ...
def load_manifest(path: Path, kind: Any = Manifest) -> Any:
    """export.json, validated field by field (``kind.from_dict``: :class:`Manifest` for ``mst
    check``, :class:`SliceManifest` for ``mst slice``)."""
    text = read_input_text(
        path, MAX_MANIFEST_BYTES, field="export.json", what="JSON file", too_large=": rewrite it with 'mst export'"
    )
    try:
        data = json.loads(text, parse_constant=_refuse_constant)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise InputError("export.json", str(path), f"cannot be read as JSON ({type(exc).__name__})") from None
    except ValueError as exc:  # NaN / Infinity, which JSON does not have
        raise InputError("export.json", str(path), f"cannot be read as JSON ({exc})") from None
    return kind.from_dict(data)


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")
