"""Reading PrusaSlicer G-code and judging what it would print: pure kernels, no CLI, no slicer.

* :func:`parse_gcode` turns G-code text into layers of extrusion segments
  ``(x0, y0, x1, y1, width_mm)`` with their feature type (``;TYPE:``), the filament each one
  pushes, the path each belongs to, the pause commands and the footer (print time, filament).
* :mod:`mst_cli.cad.layer_measure` measures the layers it reads: free spans, the gaps along a
  line, the material across a wall.

Conventions: the G-code frame (mm, bed coordinates); layers are numbered from 1 and carry the
height of their top (``;Z:``). A pause found at the start of layer k is reported as "after
layer k - 1 whose top is at z".
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

DEFAULT_PAUSE_GCODE = "M601"
FILAMENT_DIAMETER_MM = 1.75

# Feature types that are not part of the part (never need support, never give support).
NOT_PART = ("Skirt/Brim", "Wipe tower", "Custom")
SUPPORT_TYPES = ("Support material", "Support material interface")


@dataclass
class Layer:
    """One printed layer: its index from 1, the height of its top and its extrusions."""

    index: int
    z_mm: float
    height_mm: float
    segments: np.ndarray  # (n, 5): x0, y0, x1, y1, width_mm
    types: np.ndarray  # (n,) feature type strings
    e_mm: np.ndarray  # (n,) filament length pushed by each segment
    paths: np.ndarray  # (n,) path id: consecutive segments with no travel between

    @property
    def z_bottom_mm(self) -> float:
        return self.z_mm - self.height_mm

    def of_part(self) -> np.ndarray:
        """Boolean mask of the segments that belong to the part (no skirt, wipe tower, custom)."""
        return ~np.isin(self.types, NOT_PART)


@dataclass
class Pause:
    """A pause command: the line it is on, the command, and where it falls."""

    line: int  # 1-based line number in the G-code
    command: str
    after_layer: int  # layers wholly printed before the pause (0: before layer 1)
    z_mm: float  # top of that layer (0.0 for the bed)
    mid_layer: bool  # True when part of the layer being printed precedes it


@dataclass
class GCode:
    layers: list[Layer]
    pauses: list[Pause]
    print_time_s: float | None = None
    filament_mm: float | None = None
    filament_cm3: float | None = None
    filament_g: float | None = None
    config: dict[str, str] = field(default_factory=dict)

    def layer_at(self, z_mm: float) -> Layer | None:
        """The layer that prints height z_mm: z_bottom < z <= z_top (to 1e-6 mm)."""
        for layer in self.layers:
            if layer.z_bottom_mm + 1e-6 < z_mm <= layer.z_mm + 1e-6:
                return layer
        return None

    def type_volume_mm3(self, types: Iterable[str]) -> float:
        """Volume of filament pushed by extrusions of the given feature types, mm3."""
        diameter = _float_or(self.config.get("filament_diameter", "").split(",")[0], FILAMENT_DIAMETER_MM)
        area = math.pi * diameter**2 / 4
        return float(sum(lay.e_mm[np.isin(lay.types, list(types))].sum() for lay in self.layers) * area)


def _float_or(text: str, default):
    try:
        return float(text)
    except (TypeError, ValueError):
        return default


# Commands that may be part of a pause_print_gcode macro but are no pause by themselves.
_NOT_PAUSE = {
    "G0",
    "G1",
    "G2",
    "G3",
    "G4",
    "G90",
    "G91",
    "G92",
    "M82",
    "M83",
    "M117",
    "M400",
    "M104",
    "M109",
    "M140",
    "M190",
    "M106",
    "M107",
}

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_TIME_PART = re.compile(r"(\d+)\s*([dhms])")


def parse_duration_s(text: str) -> float | None:
    """'1h 14m 15s' (PrusaSlicer's format, also with d) -> seconds."""
    parts = _TIME_PART.findall(text)
    if not parts:
        return None
    scale = {"d": 86400, "h": 3600, "m": 60, "s": 1}
    return float(sum(int(n) * scale[u] for n, u in parts))


def pause_commands(config: dict[str, str], extra: Iterable[str] = ()) -> set[str]:
    """The commands (first word, upper case) that pause the print under this config."""
    commands = {DEFAULT_PAUSE_GCODE}
    text = config.get("pause_print_gcode")
    if text is not None:
        commands = set()
        for line in text.replace("\\n", "\n").splitlines():
            word = line.split(";", 1)[0].strip().split()
            if word:
                commands.add(word[0].upper())
    commands.update(c.upper() for c in extra)
    return commands


def _footer_config(lines: list[str]) -> dict[str, str]:
    """The ``; key = value`` settings PrusaSlicer writes at the end of the G-code."""
    config: dict[str, str] = {}
    start = 0
    for i in range(len(lines) - 1, -1, -1):
        if lines[i].startswith("; prusaslicer_config = begin"):
            start = i + 1
            break
    else:
        # older files: the settings follow the last 'estimated printing time' line
        for i in range(len(lines) - 1, -1, -1):
            if lines[i].startswith("; estimated printing time"):
                start = i + 1
                break
        else:
            return config
    for line in lines[start:]:
        if line.startswith("; ") and " = " in line:
            key, value = line[2:].split(" = ", 1)
            if key == "prusaslicer_config":
                continue
            config[key.strip()] = value
    return config


def parse_gcode(text: str, pause_gcode: str | None = None) -> GCode:
    """Layers, extrusion segments, pauses and footer of PrusaSlicer G-code.

    Understands G0/G1 with X Y Z E F, G90/G91 (positions; also E unless M82/M83 follow),
    M82/M83 (absolute/relative E), G92 (set positions, usually E0), and PrusaSlicer's comments
    ``;LAYER_CHANGE``, ``;Z:``, ``;HEIGHT:``, ``;TYPE:``, ``;WIDTH:``, ``;PAUSE_PRINT``.
    A move extrudes when E increases and X/Y change. Extrusions before the first
    ``;LAYER_CHANGE`` (start G-code) are ignored. ``pause_gcode``: the pause_print_gcode
    to look for [default: the file's own setting, else M601].
    """
    lines = text.splitlines()
    config = _footer_config(lines)
    config_for_pause = {"pause_print_gcode": pause_gcode} if pause_gcode is not None else config
    reader = _GCodeReader(pause_commands(config_for_pause) - _NOT_PAUSE)
    for lineno, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line[0] == ";":
            reader.comment(lineno, line[1:])
            continue
        code = line.split(";", 1)[0].strip()
        if code:
            reader.command(lineno, code)
    layers = _layers(reader.layers_raw)
    for pause in reader.pauses:
        pause.z_mm = layers[pause.after_layer - 1].z_mm if pause.after_layer >= 1 else 0.0
    footer = reader.footer
    return GCode(layers, reader.pauses, footer.time_s, footer.fil_mm, footer.fil_cm3, footer.fil_g, config)


@dataclass
class _RawLayer:
    """A layer as read: its ``;Z:`` and ``;HEIGHT:`` (None until given) and its extrusions."""

    z: float | None = None
    h: float | None = None
    seg: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    type: list[str] = field(default_factory=list)
    e: list[float] = field(default_factory=list)
    path: list[int] = field(default_factory=list)


@dataclass
class _Footer:
    """The print time and filament PrusaSlicer states in its closing comments."""

    time_s: float | None = None
    fil_mm: float | None = None
    fil_cm3: float | None = None
    fil_g: float | None = None

    def read(self, c: str) -> None:
        """Take the value of one comment (``c``: the text after ';') if it states one."""
        if c.startswith(" estimated printing time (normal mode)"):
            self.time_s = parse_duration_s(c.split("=", 1)[1])
        elif c.startswith(" filament used [mm]"):
            self.fil_mm = _float_or(c.split("=", 1)[1].split(",")[0], None)
        elif c.startswith(" filament used [cm3]"):
            self.fil_cm3 = _float_or(c.split("=", 1)[1].split(",")[0], None)
        elif c.startswith(" total filament used [g]"):
            self.fil_g = _float_or(c.split("=", 1)[1], None)
        elif c.startswith(" filament used [g]") and self.fil_g is None:
            self.fil_g = _float_or(c.split("=", 1)[1].split(",")[0], None)


def _words(code: str, head: str) -> dict[str, float]:
    """The letter -> number words of a G-code command after its head (``X1.5 E.2`` -> X, E)."""
    return {k.upper(): float(v) for k, v in _WORD.findall(code[len(head) :])}


class _GCodeReader:
    """The state of the print head line by line: position, E, modes, the layer being printed."""

    def __init__(self, pause_words: set[str]):
        self.pause_words = pause_words
        self.x = self.y = self.z = 0.0
        self.e = 0.0
        self.abs_xyz = True
        self.abs_e = True
        self.width = 0.45
        self.ftype = ""
        self.path = 0
        self.last_was_extrusion = False
        self.layers_raw: list[_RawLayer] = []
        self.cur: _RawLayer | None = None
        self.pauses: list[Pause] = []
        self.footer = _Footer()

    def _pause_here(self, lineno: int, command: str) -> Pause:
        started = self.cur is not None and bool(self.cur.seg)
        done = len(self.layers_raw) - 1 if self.cur is not None else 0
        return Pause(lineno, command, done, 0.0, started)

    def comment(self, lineno: int, c: str) -> None:
        """One comment line (``c``: the text after ';')."""
        cur = self.cur
        if c.startswith("LAYER_CHANGE"):
            self.cur = _RawLayer()
            self.layers_raw.append(self.cur)
            self.last_was_extrusion = False
            self.path += 1
        elif c.startswith("Z:") and cur is not None and cur.z is None:
            cur.z = _float_or(c[2:], None)
        elif c.startswith("HEIGHT:") and cur is not None and cur.h is None:
            cur.h = _float_or(c[7:], None)
        elif c.startswith("TYPE:"):
            self.ftype = c[5:].strip()
        elif c.startswith("WIDTH:"):
            self.width = _float_or(c[6:], self.width)
        elif c.startswith("PAUSE_PRINT"):
            self.pauses.append(self._pause_here(lineno, ";PAUSE_PRINT"))
        else:
            self.footer.read(c)

    def command(self, lineno: int, code: str) -> None:
        """One G-code command (comment stripped)."""
        head = code.split(None, 1)[0].upper()
        if head in ("G1", "G0"):
            self._move(_words(code, head))
        elif head in ("G90", "G91"):
            self.abs_xyz = self.abs_e = head == "G90"
        elif head in ("M82", "M83"):
            self.abs_e = head == "M82"
        elif head == "G92":
            words = _words(code, head)
            self.e = words.get("E", self.e if words else 0.0)
            self.x = words.get("X", self.x)
            self.y = words.get("Y", self.y)
            self.z = words.get("Z", self.z)
        if head in self.pause_words:
            recent = self.pauses[-1] if self.pauses else None
            if recent is not None and recent.command == ";PAUSE_PRINT" and lineno - recent.line <= 10:
                recent.command = head  # the command PrusaSlicer wrote for it
            else:
                self.pauses.append(self._pause_here(lineno, head))
            self.last_was_extrusion = False

    def _axis(self, words: dict[str, float], key: str, now: float) -> float:
        if key not in words:
            return now
        return words[key] if self.abs_xyz else now + words[key]

    def _move(self, words: dict[str, float]) -> None:
        """G0/G1: the new position; an extrusion segment when E increases and X/Y change."""
        x, y = self.x, self.y
        nx, ny, nz = self._axis(words, "X", x), self._axis(words, "Y", y), self._axis(words, "Z", self.z)
        de = 0.0
        if "E" in words:
            de = words["E"] - self.e if self.abs_e else words["E"]
            self.e = words["E"] if self.abs_e else self.e + words["E"]
        moved_xy = nx != x or ny != y
        cur = self.cur
        if moved_xy and de > 0 and cur is not None:
            if not self.last_was_extrusion:
                self.path += 1
            cur.seg.append((x, y, nx, ny, self.width))
            cur.type.append(self.ftype)
            cur.e.append(de)
            cur.path.append(self.path)
            self.last_was_extrusion = True
        elif moved_xy:
            self.last_was_extrusion = False
        self.x, self.y, self.z = nx, ny, nz


def _layers(layers_raw: list[_RawLayer]) -> list[Layer]:
    """The layers read, numbered from 1, a missing ``;Z:``/``;HEIGHT:`` taken from the other."""
    layers: list[Layer] = []
    prev_z = 0.0
    for i, raw in enumerate(layers_raw, start=1):
        zt = raw.z if raw.z is not None else prev_z + (raw.h or 0.0)
        h = raw.h if raw.h is not None else zt - prev_z
        seg = np.array(raw.seg, dtype=float).reshape(-1, 5)
        layers.append(
            Layer(
                i,
                float(zt),
                float(h),
                seg,
                np.array(raw.type, dtype=object),
                np.array(raw.e, dtype=float),
                np.array(raw.path, dtype=np.int64),
            )
        )
        prev_z = zt
    return layers
