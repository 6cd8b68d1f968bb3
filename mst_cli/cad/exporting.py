"""What ``mst export`` writes for one design: the print-orientation meshes (STL, 3MF with the
magnet pause), the STEP assembly and export.json, atomically (all or none).

The mesh kernel (manifold3d) is imported only when a mesh is asked for and the CAD kernel
(build123d, seconds to import) only for STEP.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.cad import mesh_io
from mst_cli.cad.expected_body import body_volume_mm3
from mst_cli.cad.manifest import MANIFEST_NAME, STL_TOLERANCE_MM, export_manifest
from mst_cli.cad.mesh_body import insert_mesh, print_mesh
from mst_cli.cad.shapes import check_fits
from mst_cli.errors import InputError
from mst_cli.io.outputs import staged
from mst_cli.model.assembly import SensorGeometry
from mst_cli.sensor.document import Document, document_to_dict

if TYPE_CHECKING:
    from mst_cli.design.result import DesignResult

DEFAULT_STL_TOLERANCE_MM = 0.01


def check_stl_tolerance(stl_tolerance_mm: float) -> None:
    """InputError unless the chord tolerance is one export.json may hold."""
    lo, hi = STL_TOLERANCE_MM
    if not lo <= stl_tolerance_mm <= hi:
        raise InputError("--stl-tolerance", stl_tolerance_mm, f"must be a number from {lo:g} to {hi:g} mm")


def write_export(
    doc: Document,
    geometry: SensorGeometry,
    out: Path,
    *,
    stl: bool = True,
    step: bool = False,
    three_mf: bool = False,
    stl_tolerance_mm: float = DEFAULT_STL_TOLERANCE_MM,
    design_yaml: dict | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[str]:
    """Write the asked formats, ``design_yaml`` as design.yaml when given (the design a spec
    became) and export.json into ``out``; the names written (export.json last)."""
    say = progress or (lambda message: None)
    check_stl_tolerance(stl_tolerance_mm)
    check_fits(geometry)
    names = (["sensor.stl"] if stl else []) + (["sensor.step"] if step else []) + (["sensor.3mf"] if three_mf else [])
    with staged(out) as st:
        if stl or three_mf:
            vertices, triangles = print_mesh(geometry, stl_tolerance_mm)
            say(
                f"meshed the body (base, layers, plates, cap; pocket and slot cut): "
                f"{len(triangles)} triangles at {stl_tolerance_mm:g} mm"
            )
            if stl:
                st.write_bytes("sensor.stl", mesh_io.stl_bytes(vertices, triangles))
                say("wrote sensor.stl")
            if three_mf:
                st.write_bytes(
                    "sensor.3mf",
                    mesh_io.three_mf_bytes(
                        vertices,
                        triangles,
                        doc.name,
                        pause_after_z_mm=[(p.z_mm, p.why) for p in geometry.pauses],
                        layer_height_mm=geometry.layer_height_mm,
                    ),
                )
                say("wrote sensor.3mf")
        if geometry.has_insert and (stl or three_mf):  # the plate for a user who prints it, flat
            st.write_bytes("insert.stl", mesh_io.stl_bytes(*insert_mesh(geometry)))
            names.append("insert.stl")
            say("wrote insert.stl (the plate to print flat and drop in at its pause)")
        if step:
            from mst_cli.cad.assembly import build_sensor  # deferred: build123d takes seconds, only --step needs it

            say("building the CAD body: base, layers, plates, cap (one fuse)")
            cad = build_sensor(geometry)
            st.write_bytes("sensor.step", mesh_io.step_bytes(cad.assembly(doc.name)))
            say("wrote sensor.step (body, magnet, board" + (", insert)" if geometry.has_insert else ")"))
        if design_yaml is not None:
            # the design the body was built from, loadable by mst simulate / mst export
            st.write_yaml("design.yaml", design_yaml)
            names.append("design.yaml")
        st.write_json(
            MANIFEST_NAME,
            export_manifest(doc.name, geometry, doc.printer, stl_tolerance_mm, names, design=document_to_dict(doc)),
        )
    return names + [MANIFEST_NAME]


class ExportedFiles(list[Path]):
    """:func:`mst_cli.api.export`'s answer: the files written (a list, export.json last), the
    sensor they hold and, for a spec, the design it became."""

    def __init__(self, paths: list[Path], geometry: SensorGeometry, designed: DesignResult | None = None):
        super().__init__(paths)
        self.geometry = geometry
        self.designed = designed

    def tilt_note(self) -> str | None:
        """A note when the design carries a magnet tilt (an assembly error the body does not build)."""
        tilt = self.geometry.magnet_tilt_deg
        if not tilt:
            return None
        return (
            f"note: magnet_tilt_deg = {tilt:g} is an assembly error "
            "in the forward model; the pocket is built on the axis"
        )

    def summary(self, three_mf: bool) -> str:
        """The body's size, how it prints, where the magnet pause is and the files written."""
        g = self.geometry
        out = self[0].parent if self else Path(".")
        return "\n".join(
            [
                f"body volume {body_volume_mm3(g):.1f} mm3, sensor height {g.total_height_mm:.2f} mm; "
                f"prints on its side, {g.depth_mm:g} mm high in "
                f"{int(round(g.depth_mm / g.layer_height_mm))} layers of {g.layer_height_mm:g} mm",
                "; ".join(f"pause after layer {p.after_layer} (z = {p.z_mm:.2f} mm) to {p.why}" for p in g.pauses)
                + (" (the 3MF carries the pauses)" if three_mf else ""),
                f"wrote {out}/{', '.join(p.name for p in self)}",
            ]
        )
