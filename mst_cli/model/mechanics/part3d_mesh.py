"""Tetrahedra of a closed triangulated body, for the 3D check of the part as exported
(docs/design.md section 4.8).

TetGen (through ``tetgenpy``, an optional dependency: this module and the 3D check that imports
it need it, nothing else does) fills the body's surface with quality tetrahedra (radius-edge
ratio and dihedral bounds, a largest volume). The exported
body has closed internal voids (the magnet's pocket, the insert's slot): TetGen fills them too,
and a seed point inside each tags its tetrahedra, so the caller keeps, drops or gives them their
own material. Every kept tetrahedron is positively oriented; the volume of each region is the
enclosed volume of its surface (a test checks it against export.json's own figures).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import tetgenpy  # optional (pip install tetgenpy): only the 3D check imports this module

BODY = 0  # the region of the tetrahedra outside every seeded void
# TetGen's -q bounds: a tetrahedron's circumradius / shortest edge, and its smallest dihedral
# angle by radius-edge ratio (the finer the ratio, the more tetrahedra the thin walls take)
MIN_DIHEDRAL_DEG = {3.0: 5.0, 2.0: 10.0, 1.5: 15.0}


@dataclass(frozen=True)
class TetMesh:
    """Tetrahedra ``tets`` (m, 4) over ``points_mm`` (n, 3), each in ``region`` (m,): BODY, or
    k >= 1 for the k-th seed's void."""

    points_mm: np.ndarray
    tets: np.ndarray
    region: np.ndarray

    def volumes_mm3(self) -> np.ndarray:
        """Each tetrahedron's volume (> 0: positively oriented)."""
        p = self.points_mm[self.tets]
        return np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6.0

    def centroids_mm(self) -> np.ndarray:
        return self.points_mm[self.tets].mean(axis=1)

    def kept(self, mask: np.ndarray) -> TetMesh:
        """The tetrahedra where ``mask`` holds, their points renumbered (unused points dropped)."""
        tets = self.tets[mask]
        used = np.unique(tets)
        renumber = np.full(len(self.points_mm), -1)
        renumber[used] = np.arange(used.size)
        return TetMesh(self.points_mm[used], renumber[tets], self.region[mask])


def tetrahedralize(
    vertices_mm: np.ndarray,
    faces: np.ndarray,
    seeds_mm: Sequence[Sequence[float]],
    max_volume_mm3: float,
    radius_edge_ratio: float = 2.0,
) -> TetMesh:
    """Quality tetrahedra of the closed surface (``vertices_mm`` (n, 3), ``faces`` (m, 3)), no
    larger than ``max_volume_mm3``, their radius-edge ratio at most ``radius_edge_ratio`` (a key
    of :data:`MIN_DIHEDRAL_DEG`); the void holding ``seeds_mm[k]`` is region k + 1."""
    if not max_volume_mm3 > 0.0:
        raise ValueError(f"max_volume_mm3 must be > 0, not {max_volume_mm3!r}")
    if radius_edge_ratio not in MIN_DIHEDRAL_DEG:
        raise ValueError(f"radius_edge_ratio must be one of {sorted(MIN_DIHEDRAL_DEG)}, not {radius_edge_ratio!r}")
    tio = tetgenpy.TetgenIO()
    # one region attribute per seed (k + 1), no volume bound of its own (-1: the global one)
    regions = np.array([[*s, k + 1, -1.0] for k, s in enumerate(seeds_mm)], dtype=float).reshape(-1, 5)
    tio.setup_plc(np.asarray(vertices_mm, dtype=float), np.asarray(faces).tolist(), regions=regions)
    # p: a piecewise linear complex; q: quality; A: region attributes; a: largest volume; Q: quiet
    switches = f"pq{radius_edge_ratio:g}/{MIN_DIHEDRAL_DEG[radius_edge_ratio]:g}Aa{max_volume_mm3:g}Q"
    try:
        out = tetgenpy.tetrahedralize(switches, tio)
    except RuntimeError as exc:  # TetGen gives no reason through the wrapper
        raise RuntimeError(
            f"TetGen failed on the surface with switches {switches!r}: try another radius-edge bound"
        ) from exc
    points = np.asarray(out.points(), dtype=float)
    tets = np.asarray(out.tetrahedra(), dtype=np.int64)
    attrs = np.asarray(out.tetrahedronattributes(), dtype=float).reshape(len(tets), -1)
    # TetGen numbers the unseeded region after the seeded ones: every attribute outside 1..k is the body
    region = np.rint(attrs[:, 0]).astype(np.int64) if attrs.size else np.zeros(len(tets), dtype=np.int64)
    region[(region < 1) | (region > len(seeds_mm))] = BODY
    mesh = TetMesh(points, tets, region)
    flipped = mesh.volumes_mm3() < 0.0
    if flipped.any():
        tets = tets.copy()
        tets[flipped] = tets[flipped][:, [0, 2, 1, 3]]
        mesh = TetMesh(points, tets, region)
    return mesh.kept(np.ones(len(tets), dtype=bool))
