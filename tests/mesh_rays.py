"""Ray casts on a triangle mesh in numpy (Moller-Trumbore), for tests that measure an exported
body with nothing of mst's own (manifold3d) ray casts."""

import numpy as np


def triangle_hits(tri: np.ndarray, origin, direction) -> np.ndarray:
    """Distances along a ray (unit ``direction``) from ``origin`` of its crossings with the
    triangles ``tri`` (m, 3, 3), sorted, repeats (a ray through a shared edge) merged."""
    o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    t = o - tri[:, 0]
    u = np.einsum("ij,ij->i", t, p) * inv
    q = np.cross(t, e1)
    v = (q @ d) * inv
    s = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (s > 0)
    return np.unique(np.round(s[hit], 6))
