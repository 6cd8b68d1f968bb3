"""The files of an export that ``mst check`` and ``mst slice`` read: the folder ``mst export``
wrote (export.json next to its meshes) and the STL, read and welded with its coordinates
bounded (no body mst exports is larger than :data:`MAX_STL_BYTES`)."""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mst_cli.cad.manifest import MAX_COORD_MM
from mst_cli.cad.mesh_io import Mesh, binary_stl_triangles, weld
from mst_cli.errors import InputError
from mst_cli.io.files import read_input

MAX_STL_BYTES = 500_000_000


@dataclass(frozen=True)
class ExportFiles:
    """The files of a folder ``mst export`` wrote (a mesh that is not there is None)."""

    folder: Path
    manifest: Path  # export.json
    stl: Path | None
    three_mf: Path | None


def resolve_export(path: str | Path, need_stl: bool = True) -> ExportFiles:
    """The export at ``path``: the folder 'mst export' wrote, or the .stl (or, without
    ``need_stl``, the .3mf) in it. InputError when it does not exist, when its mesh (the STL,
    ``mst check``'s; either, ``mst slice``'s) or export.json is missing."""
    path = Path(path)
    if not path.exists():
        raise InputError("PATH", str(path), "does not exist: give the folder 'mst export' wrote or the .stl in it")
    suffix = path.suffix.lower()
    if path.is_dir():
        folder, stl = path, path / "sensor.stl"
    elif suffix == ".stl" or (suffix == ".3mf" and not need_stl):
        folder, stl = path.parent, path if suffix == ".stl" else path.parent / "sensor.stl"
    else:
        raise InputError("PATH", str(path), "must be a folder written by 'mst export' or an .stl in it")
    three_mf = folder / "sensor.3mf"
    # mst check reads whatever sits at the STL's name (a FIFO or a folder there is refused by
    # kind when it is read); mst slice slices only regular files
    found = ExportFiles(
        folder,
        folder / "export.json",
        stl if (stl.exists() if need_stl else stl.is_file()) else None,
        three_mf if three_mf.is_file() else None,
    )
    if need_stl and found.stl is None:
        raise InputError("PATH", str(stl), "no such STL file (run 'mst export --stl' first)")
    if found.stl is None and found.three_mf is None:
        raise InputError(
            "PATH",
            str(folder),
            "holds neither sensor.3mf nor sensor.stl: run 'mst export DESIGN.yaml --3mf --stl --out DIR' first",
        )
    if not found.manifest.exists():
        raise InputError(
            "PATH", str(found.manifest), "export.json not found next to the mesh: run 'mst export' to write it"
        )
    return found


def load_mesh(path: Path) -> Mesh:
    """Read an STL into a :class:`~mst_cli.cad.mesh_io.Mesh` (vertices welded); InputError when
    it is not a regular file or not a mesh, or when a coordinate is not finite or beyond
    +-MAX_COORD_MM (nothing is measured on such a mesh). A binary STL is read with numpy;
    anything else (an ASCII STL, garbage) goes through trimesh, which says whether it is a
    mesh at all."""
    data = read_input(path, MAX_STL_BYTES, field="PATH", what="STL file", too_large=": no body mst exports")
    corners = binary_stl_triangles(data)
    if corners is not None:
        vertices, faces = corners.reshape(-1, 3), np.arange(3 * len(corners)).reshape(-1, 3)
    else:
        vertices, faces = _load_with_trimesh(path, data)
    bad = ~np.isfinite(vertices).all(axis=1) | (np.abs(np.nan_to_num(vertices, nan=0.0)) > MAX_COORD_MM).any(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError(
            "PATH",
            str(path),
            f"vertex {i} at {vertices[i].tolist()} mm: every coordinate "
            f"must be finite and within +-{MAX_COORD_MM:g} mm",
        )
    return weld(vertices, faces)  # what trimesh.load(process=True) does, on finite coordinates


def _load_with_trimesh(path: Path, data: bytes) -> tuple[np.ndarray, np.ndarray]:
    import trimesh  # deferred: heavy (pulls scipy.spatial), only for files that are not binary STL

    try:
        with np.errstate(all="ignore"):
            mesh = trimesh.load(io.BytesIO(data), file_type="stl", force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds on garbage; all mean "unreadable"
        raise InputError("PATH", str(path), f"cannot be read as an STL mesh ({type(exc).__name__})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError("PATH", str(path), "holds no triangles")
    return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)
