"""Where a tilted plate presses a flat contact patch: moments of a clipped rectangle.

The pads of a closed layer are a rectangle [-a, a] x [-b, b] (x across the width, y along the
depth). Pressed by rigid plates that close by c + alpha x + beta y beyond their gap, they carry a
pressure kappa (c + alpha x + beta y) where that is positive: a linear field on the part of the
rectangle on one side of a line. Its force and moments are the polygon's area moments (up to
second order) times (c, alpha, beta), exactly, and so is their derivative in (c, alpha, beta):
the pressure vanishes on the moving edge, so the edge's motion adds nothing.

Pure numpy, no I/O.
"""

from __future__ import annotations

import numpy as np


def clip_rectangle(half_x: float, half_y: float, c: float, alpha: float, beta: float) -> np.ndarray:
    """Vertices (k, 2), counter-clockwise, of {c + alpha x + beta y >= 0} inside the rectangle
    [-half_x, half_x] x [-half_y, half_y] (empty (0, 2) when nothing of it is pressed)."""
    box = [(-half_x, -half_y), (half_x, -half_y), (half_x, half_y), (-half_x, half_y)]
    out = []
    for i, p in enumerate(box):
        q = box[(i + 1) % 4]
        fp = c + alpha * p[0] + beta * p[1]
        fq = c + alpha * q[0] + beta * q[1]
        if fp >= 0.0:
            out.append(p)
        if (fp >= 0.0) != (fq >= 0.0):
            s = fp / (fp - fq)
            out.append((p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])))
    return np.asarray(out, dtype=float).reshape(-1, 2)


def polygon_moments(vertices: np.ndarray) -> tuple[float, float, float, float, float, float]:
    """(A, Sx, Sy, Sxx, Sxy, Syy) = the integrals of 1, x, y, x^2, xy, y^2 over a simple polygon
    with counter-clockwise vertices (Green's theorem, edge by edge)."""
    if len(vertices) < 3:
        return (0.0,) * 6
    x0, y0 = vertices[:, 0], vertices[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    cross = x0 * y1 - x1 * y0
    A = cross.sum() / 2.0
    Sx = ((x0 + x1) * cross).sum() / 6.0
    Sy = ((y0 + y1) * cross).sum() / 6.0
    Sxx = ((x0 * x0 + x0 * x1 + x1 * x1) * cross).sum() / 12.0
    Syy = ((y0 * y0 + y0 * y1 + y1 * y1) * cross).sum() / 12.0
    Sxy = ((x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * cross).sum() / 24.0
    return float(A), float(Sx), float(Sy), float(Sxx), float(Sxy), float(Syy)


def pressed_patch(half_x: float, half_y: float, c: float, alpha: float, beta: float) -> tuple[np.ndarray, np.ndarray]:
    """(F, M about y, M about x) / kappa of the pressure c + alpha x + beta y where positive, and
    its 3 x 3 derivative in (c, alpha, beta) (symmetric: the second moments of the pressed part)."""
    A, Sx, Sy, Sxx, Sxy, Syy = polygon_moments(clip_rectangle(half_x, half_y, c, alpha, beta))
    J = np.array([[A, Sx, Sy], [Sx, Sxx, Sxy], [Sy, Sxy, Syy]])
    return J @ np.array([c, alpha, beta]), J
