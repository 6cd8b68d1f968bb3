"""Byte-identical 3MF and STEP files: the two writers no library makes deterministic.

The same mesh (or assembly) always gives the same bytes, whatever the process or the clock:
the 3MF is written by hand with fixed zip dates and a fixed member order, and the STEP that
build123d/OCCT writes gets a fixed header time stamp and renumbered assembly-usage ids.
STL writing, welding and tessellation live in :mod:`mst_cli.cad.mesh_io` (trimesh, build123d).
"""

from __future__ import annotations

import io
import itertools
import re
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from build123d import Compound

# Fixed STEP header time stamp and 3MF zip member date: output depends only on the input.
STEP_TIMESTAMP = "2000-01-01T00:00:00"
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def _xml_number(x: float) -> str:
    return f"{x:.6f}".rstrip("0").rstrip(".") if x else "0"


def _xml_escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


# PrusaSlicer's per-height custom G-code inside a 3MF project (PrusaSlicer 2.2+, read by the
# GUI and by its command line): Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml, one <code>
# per event. ``type`` is CustomGCode::Type (ColorChange 0, PausePrint 1, ToolChange 2,
# Template 3, Custom 4); ``gcode`` is the command written for PrusaSlicer <= 2.2, which has no
# ``type``. An event at print_z is emitted at the start of the layer whose top is the first one
# at or above print_z, after the move to that layer and before its first extrusion.
PRUSA_CUSTOM_GCODE_MEMBER = "Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml"
PRUSA_PAUSE_PRINT_TYPE = 1


Pauses = float | Sequence[tuple[float, str]]  # one pause's height, or (height, message) each


def _pause_list(pauses: Pauses, message: str) -> list[tuple[float, str]]:
    return [(float(pauses), message)] if isinstance(pauses, (int, float)) else [(float(z), m) for z, m in pauses]


def prusa_pause_xml(pause_after_z_mm: Pauses, layer_height_mm: float, message: str = "") -> str:
    """The custom G-code member asking for a pause after the layer whose top is
    ``pause_after_z_mm`` (or after each of a list of (height, message)): each event sits at the
    top of the next layer (as the GUI stores it)."""
    codes = "".join(
        f'<code print_z="{_xml_number(round(z + layer_height_mm, 6))}" type="{PRUSA_PAUSE_PRINT_TYPE}" '
        f'extruder="1" color="" extra="{_xml_escape(text)}" gcode="M601"/>\n'
        for z, text in sorted(_pause_list(pause_after_z_mm, message))
    )
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n<custom_gcodes_per_print_z>\n'
        f"{codes}"
        '<mode value="SingleExtruder"/>\n</custom_gcodes_per_print_z>\n'
    )


def three_mf_bytes(
    vertices: np.ndarray,
    triangles: np.ndarray,
    name: str,
    pause_after_z_mm: Pauses | None = None,
    layer_height_mm: float = 0.2,
    pause_message: str = "insert the magnet",
) -> bytes:
    """A 3MF package (3MF Core Specification 1.x) holding one mesh object, unit mm.

    With ``pause_after_z_mm`` (a height, or a list of (height, message)), the package also
    carries PrusaSlicer's per-height custom G-code with a "pause print" after each layer whose
    top is at that height (layers of ``layer_height_mm``): PrusaSlicer's GUI shows the pauses on
    its layer slider and its command line writes the profile's pause_print_gcode
    (``;PAUSE_PRINT``, ``M117 <message>``, then e.g. M601) between that layer's last move and the
    next layer's first.
    """
    content_types = _CONTENT_TYPES
    if pause_after_z_mm is not None:  # every part of the package needs a content type
        content_types = content_types.replace(
            "</Types>", '<Default Extension="xml" ContentType="application/xml"/></Types>'
        )
    members = [
        ("[Content_Types].xml", content_types),
        ("_rels/.rels", _RELS),
        ("3D/3dmodel.model", _model_xml(vertices, triangles, name)),
    ]
    if pause_after_z_mm is not None:
        members.append((PRUSA_CUSTOM_GCODE_MEMBER, prusa_pause_xml(pause_after_z_mm, layer_height_mm, pause_message)))
    return _zip_bytes(members)


_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" '
    'ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
    '<Default Extension="model" '
    'ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
    "</Types>\n"
)
_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>'
    "</Relationships>\n"
)


def _model_xml(vertices: np.ndarray, triangles: np.ndarray, name: str) -> str:
    """The 3MF model part: one mesh object (vertices (n, 3) mm, triangles (m, 3) indices)."""
    vert_xml = "".join(
        f'<vertex x="{_xml_number(x)}" y="{_xml_number(y)}" z="{_xml_number(z)}"/>' for x, y, z in vertices
    )
    tri_xml = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in triangles)
    safe = _xml_escape(name)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<model unit="millimeter" xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">\n'
        f'<metadata name="Title">{safe}</metadata>\n'
        "<resources>\n"
        f'<object id="1" type="model" name="{safe}"><mesh><vertices>{vert_xml}</vertices>'
        f"<triangles>{tri_xml}</triangles></mesh></object>\n"
        '</resources>\n<build><item objectid="1"/></build>\n</model>\n'
    )


def _zip_bytes(members: list[tuple[str, str]]) -> bytes:
    """A deflated zip of ``members`` (name, text) with fixed dates and modes: the same bytes every run."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for member, text in members:
            info = zipfile.ZipInfo(member, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, text)
    return buf.getvalue()


# One NEXT_ASSEMBLY_USAGE_OCCURRENCE record, possibly wrapped over several lines.
_NAUO = re.compile(rb"#\d+ = NEXT_ASSEMBLY_USAGE_OCCURRENCE\('\d+'.*?\);\n", re.DOTALL)
_NAUO_ID = re.compile(rb"NEXT_ASSEMBLY_USAGE_OCCURRENCE\('\d+'")


def _wrap_record(record: bytes, width: int = 80) -> bytes:
    """Break a STEP record after commas so that lines stay within ``width`` columns."""
    lines, line = [], b""
    for piece in re.split(rb"(?<=,)", record):
        if line and len(line) + len(piece) > width:
            lines.append(line)
            line = b"  "
        line += piece
    return b"\n".join(lines + [line]) + b"\n"


def _renumber_nauo(data: bytes) -> bytes:
    counter = itertools.count(1)

    def one(match):
        record = b"".join(part.strip() for part in match.group(0).splitlines())
        record = _NAUO_ID.sub(b"NEXT_ASSEMBLY_USAGE_OCCURRENCE('%d'" % next(counter), record)
        return _wrap_record(record)

    return _NAUO.sub(one, data)


def write_step(assembly: Compound, path: Path) -> None:
    """Write :func:`step_bytes` of the assembly to ``path``."""
    Path(path).write_bytes(step_bytes(assembly))


def step_bytes(assembly: Compound) -> bytes:
    """STEP AP214 file of the named assembly, deterministic.

    The header gets a fixed time stamp, and the ids of the assembly-usage records -- which
    OCCT draws from a process-wide counter -- are renumbered 1, 2, ... in file order (they
    only need to be unique within the file); those records are re-wrapped at 80 columns.
    OCCT writes into memory and Python writes the file, so a full disk is an OSError naming
    the path and the errno reason, as for every other writer (OCCT's own file writer only
    says "Failed to write STEP file").
    """
    from build123d import export_step  # deferred: build123d takes seconds to import, only --step needs it

    buf = io.BytesIO()
    export_step(assembly, buf, timestamp=STEP_TIMESTAMP)  # RuntimeError if OCCT fails
    return _renumber_nauo(buf.getvalue())
