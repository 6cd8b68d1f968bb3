"""A plane frame by the stiffness method: Timoshenko beam elements, rotational springs between two
nodes tied in position, links (springs along x and z between two points, each held rigidly off
a node), held dofs, nodal loads. Each node has three dofs (u along x, w along z,
a turn counter-clockwise from x to z). Pure numpy, no I/O.

Used by :mod:`mst_cli.model.plate_sway` (the stack under a tangential force) and
studies/base_frame.py (the housing's base). The element is the standard two-node Timoshenko beam,
exact for loads at its nodes (Przemieniecki, Theory of Matrix Structural Analysis, 1968, ch. 5:
the shear parameter phi = 12 EI / (kGA L^2)).
"""

from __future__ import annotations

import numpy as np


def element_stiffness(a, b, EA, EI, kGA) -> np.ndarray:
    """(6, 6) the stiffness of a Timoshenko element from node a to node b ((x, z), mm) in global
    (u, w, turn) at both ends; EA, kGA in N, EI in N mm^2 (kGA inf: Euler-Bernoulli)."""
    return element_stiffnesses(np.array([a], float), np.array([b], float), [EA], [EI], [kGA])[0]


def element_stiffnesses(a, b, EA, EI, kGA) -> np.ndarray:
    """(m, 6, 6) :func:`element_stiffness` of m elements from nodes ``a`` (m, 2) to ``b`` (m, 2)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    EA, EI, kGA = (np.asarray(v, dtype=float) for v in (EA, EI, kGA))
    dx, dz = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    L = np.hypot(dx, dz)
    c, s = dx / L, dz / L
    phi = np.where(np.isinf(kGA), 0.0, 12.0 * EI / (np.where(np.isinf(kGA), 1.0, kGA) * L * L))
    k, axial = EI / (L**3 * (1.0 + phi)), EA / L
    m = len(L)
    local = np.zeros((m, 6, 6))
    local[:, 0, 0] = local[:, 3, 3] = axial
    local[:, 0, 3] = local[:, 3, 0] = -axial
    bend = np.array(
        [
            [12.0 + 0 * L, 6.0 * L, -12.0 + 0 * L, 6.0 * L],
            [6.0 * L, (4.0 + phi) * L * L, -6.0 * L, (2.0 - phi) * L * L],
            [-12.0 + 0 * L, -6.0 * L, 12.0 + 0 * L, -6.0 * L],
            [6.0 * L, (2.0 - phi) * L * L, -6.0 * L, (4.0 + phi) * L * L],
        ]
    )  # (4, 4, m)
    idx = np.array([1, 2, 4, 5])
    local[:, idx[:, None], idx[None, :]] = np.moveaxis(bend, -1, 0) * k[:, None, None]
    R = np.zeros((m, 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, s, -s, c, 1.0
    T = np.zeros((m, 6, 6))
    T[:, :3, :3] = T[:, 3:, 3:] = R
    return np.transpose(T, (0, 2, 1)) @ local @ T


class Frame:
    """Nodes, elements (a, b, EA, EI, kGA), springs (a, b, k_turn: the two nodes tied in position
    by ``tie`` N/mm, their turns through k_turn N mm/rad), links (:meth:`link`) and held dofs,
    assembled on solve."""

    def __init__(self, tie_N_per_mm: float) -> None:
        self.tie_N_per_mm = tie_N_per_mm
        self.nodes: list[tuple[float, float]] = []
        self.elements: list[tuple[int, int, float, float, float]] = []
        self.springs: list[tuple[int, int, float]] = []
        self.links: list[tuple] = []  # (a, b, k_x, k_z, offset of a (x, z), offset of b (x, z))
        self.held: list[int] = []

    def node(self, x_mm: float, z_mm: float) -> int:
        self.nodes.append((float(x_mm), float(z_mm)))
        return len(self.nodes) - 1

    def beam(self, a: int, b: int, EA: float, EI: float, kGA: float) -> None:
        self.elements.append((a, b, EA, EI, kGA))

    def spring(self, a: int, b: int, k_turn_Nmm_per_rad: float) -> None:
        self.springs.append((a, b, k_turn_Nmm_per_rad))

    def link(
        self, a: int, b: int, k_x_N_per_mm: float, k_z_N_per_mm: float,
        offset_a_mm: tuple[float, float] = (0.0, 0.0), offset_b_mm: tuple[float, float] = (0.0, 0.0),
    ) -> None:  # fmt: skip
        """Springs along x and z between a point held rigidly at ``offset_a_mm`` (x, z) from node
        a and one at ``offset_b_mm`` from node b (a rigid body's point: exact, no stiff element)."""
        self.links.append((a, b, k_x_N_per_mm, k_z_N_per_mm, *offset_a_mm, *offset_b_mm))

    def hold(self, node: int, dofs: tuple[int, ...] = (0, 1, 2)) -> None:
        self.held += [3 * node + d for d in dofs]

    def stiffness(self) -> np.ndarray:
        """The assembled stiffness (3 x nodes, 3 x nodes), every element and spring at once."""
        n = 3 * len(self.nodes)
        K = np.zeros((n, n))
        if self.elements:
            ab = np.array([(a, b) for a, b, *_ in self.elements])
            props = np.array([p for *_, p0, p1, p2 in self.elements for p in (p0, p1, p2)]).reshape(-1, 3)
            xz = np.asarray(self.nodes)
            k_e = element_stiffnesses(xz[ab[:, 0]], xz[ab[:, 1]], props[:, 0], props[:, 1], props[:, 2])
            dofs = (3 * ab[:, :, None] + np.arange(3)).reshape(-1, 6)
            np.add.at(K, (dofs[:, :, None], dofs[:, None, :]), k_e)
        if self.springs:
            ab = np.array([(a, b) for a, b, _ in self.springs])
            k = np.array([[self.tie_N_per_mm, self.tie_N_per_mm, kt] for *_, kt in self.springs])  # (m, 3)
            i, j = 3 * ab[:, :1] + np.arange(3), 3 * ab[:, 1:] + np.arange(3)
            np.add.at(K, (i, i), k)
            np.add.at(K, (j, j), k)
            np.add.at(K, (i, j), -k)
            np.add.at(K, (j, i), -k)
        if self.links:
            _add_links(K, np.array(self.links, dtype=float))
        return K

    def solve(self, loads: dict[int, float]) -> np.ndarray:
        """(3 x nodes,) the displacements under ``loads`` (a global dof, 3 node + d: N or N mm)."""
        return self.solve_cases([loads])[0]

    def solve_cases(self, cases: list[dict[int, float]]) -> np.ndarray:
        """(len(cases), 3 x nodes) the displacements under each load case (as :meth:`solve`'s),
        the stiffness assembled and factorised once."""
        K = self.stiffness()
        n = K.shape[0]
        f = np.zeros((n, len(cases)))
        for c, loads in enumerate(cases):
            for dof, value in loads.items():
                f[dof, c] += value
        free = np.setdiff1d(np.arange(n), self.held)
        u = np.zeros((n, len(cases)))
        u[free] = np.linalg.solve(K[np.ix_(free, free)], f[free])
        return u.T


def _add_links(K: np.ndarray, links: np.ndarray) -> None:
    """Add :meth:`Frame.link`'s springs (rows a, b, k_x, k_z, offsets) to ``K`` in place. A point
    (dx, dz) off a node moves (u - turn dz, w + turn dx); the springs act on the two points'
    relative motion, so the element is B^T diag(k_x, k_z) B with B = [-T_a, T_b]."""
    m = len(links)
    a, b = links[:, 0].astype(int), links[:, 1].astype(int)
    B = np.zeros((m, 2, 6))
    for col, sign, (ox, oz) in ((0, -1.0, (4, 5)), (3, 1.0, (6, 7))):
        B[:, 0, col], B[:, 1, col + 1] = sign, sign
        B[:, 0, col + 2], B[:, 1, col + 2] = -sign * links[:, oz], sign * links[:, ox]
    k_e = np.einsum("mri,mr,mrj->mij", B, links[:, 2:4], B)
    dofs = np.concatenate([3 * a[:, None] + np.arange(3), 3 * b[:, None] + np.arange(3)], axis=1)
    np.add.at(K, (dofs[:, :, None], dofs[:, None, :]), k_e)
