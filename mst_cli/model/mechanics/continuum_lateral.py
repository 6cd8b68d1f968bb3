"""L2 under a lateral (tangential) load: the stiffness across the width (x) and along the depth (y).

The layer between its plates, the bottom plate held, the top plate moved by (u_x, u_y, -d). The
two chevrons are independent (the plates are rigid and the bonded pad between them is unstressed
a few t from the walls; :mod:`~mst_cli.model.mechanics.continuum_tilt` uses the same split), and
each chevron (a lower and an upper wall, mirror images about the mid-plane z = h/2) is what this
module's problems are cut from.

Across the width (x), plane strain
----------------------------------
Mirror the chevron about z = h/2 (M: (x, z) -> (x, h - z), a vector (v_x, v_z) -> (v_x, -v_z)). A
top-plate translation (u_x, 0) with the bottom held is, after a rigid shift by u_x / 2, the plates
at (-+u_x / 2, 0): a load odd under M. Compression (0, -d) is even under M. Linear elasticity, and
the linearisation about any M-symmetric state (the compressed chevron: L2's quarter problem solved
on the lock path), split into an even and an odd part, and the lateral response is the odd one:
u_x odd and u_z even about the mid-plane, so on z = h/2 u_x = u_x(top) / 2 and the normal traction
vanishes (u_z free). So the lateral tangent stiffness at any compression d is a solve on L2's own
quarter profile (:class:`~mst_cli.model.mechanics.continuum.ContactProblem`, same mesh, P2,
Neo-Hookean tangent at the converged compressed state, initial stress included):

* bonded face z = 0: du = 0; the pad's cut x_cut > 0: du_x = 0 (the pad moves with its plate); a
  cut at x = 0 (pads shorter than PAD_LENGTH_IN_T t): du_z = 0, du_x free (the other chevron is
  this one's x-mirror under the same lateral load, the x-antisymmetry of u_x even, u_z odd);
* tip face z = h/2: du_x = 1/2 per mm of top-plate travel, du_z free; its reaction R (N per mm of
  depth) is the chevron's lateral force per mm of travel, and the layer's k_x = 2 b R (two
  chevrons, a web b = D deep, as the normal F = 2 b f).

A finite u_x is not odd-only (the even and odd parts couple at second order), so a nonlinear
lateral solve on this half (:func:`lateral_force_N`) is exact only to first order in u_x: it is
the small-load limit's check (linear in u_x, odd in its sign), not a large-shear law.

Contact under lateral load: what is assumed
-------------------------------------------
The state is the centred problem's: its active contacts (the inner wall faces zipping from the
cavity's tip, the outer wall face on its plate, the pads after the lock) stay active under the
small lateral perturbation (a tangent: the contact set does not change with an infinitesimal
u_x). A contact pair across the mirror plane moves together in z under the odd perturbation, so
its normal pressure does not change; what matters is its tangential behaviour, and both limits are
computed (``stuck``):

* frictionless (``stuck=False``, the default; L2's own contact law): the pair slides freely, so an
  inner contact adds nothing and an outer-face contact only holds du_z = 0 on its plate: a lower
  bound;
* stuck (``stuck=True``): an inner contact point moves with the mirror plane (du_x = 1/2, its
  odd partner at 1 - du_x), an outer-face point stays on its plate (du = 0): an upper bound.

Before the pads meet the two differ only by the zipped inner wall faces and the outer faces lying
on the plate (a few per cent); after the lock the stuck pads make the locked layer a solid block
in shear, many times stiffer. Printed TPU on TPU has a friction coefficient well above one, and the
pads are pressed together by the whole load past the lock, so the stuck bound is what a locked
layer does under a small lateral load; before the lock (the design range) frictionless is L2's law
and the default.

Along the depth (y): antiplane shear
------------------------------------
A top-plate translation u_y of a web of infinite depth is antiplane shear, u = (0, u_y(x, z), 0):
G laplace(u_y) = 0, odd about the mid-plane (u_y = u_y(top) / 2 on z = h/2), the bonded faces held,
the other faces traction-free. The compressible Neo-Hookean tangent about any plane-strain state
(F_yy = 1, F_{xy} = F_{zy} = 0) has A_{yJyL} = mu delta_JL and no coupling with the in-plane
perturbation, so this scalar problem on the reference quarter is the depth tangent at every
compression; only the contacts change it, stuck (an inner point at u_y / 2, an outer point held)
or frictionless (nothing). A web of finite depth D loses stiffness at its free faces y = +-D/2
(the antiplane stresses sigma_xy there must vanish): :mod:`~mst_cli.model.mechanics.lateral`
corrects for it, fitted to a 3D check (tools/lateral_check.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.linalg import spsolve

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.continuum import (
    PRODUCTION_MESH,
    ContactProblem,
    ContinuumError,
    MeshOptions,
    follow_to_lock,
    linear_k,
    linear_stiffness_N_per_mm,
)

PATH_MESH = MeshOptions(
    levels=0
)  # the compression path's own mesh (as L2's law: the production mesh without refinement)
PATH_STEPS = 24  # load steps from rest to the lock on the compression path (halved where Newton fails)


def _x_dof_of_z_dof(prob: ContactProblem) -> np.ndarray:
    """For every z dof of the vector P2 basis, the x dof at the same node (-1 elsewhere)."""
    b = prob.basis
    out = np.full(b.N, -1, dtype=np.int64)
    out[b.nodal_dofs[1]] = b.nodal_dofs[0]
    out[b.facet_dofs[1]] = b.facet_dofs[0]
    return out


def _tip_and_support(prob: ContactProblem) -> tuple[np.ndarray, np.ndarray]:
    """(the tip face's x dofs, the dofs held at zero under a lateral perturbation: the bonded
    face, and the pad's cut: its x dofs when the cut is away from the axis, else its z dofs)."""
    xy = prob.basis.doflocs
    tol = 1e-9 * max(prob.cell.width_mm, prob.cell.h_mm)
    on_tip = np.abs(xy[1] - prob.h2) < tol
    tip_x = np.flatnonzero(on_tip & prob.is_x & ~prob.on_bottom)
    cut = prob.on_cut & ~prob.on_bottom
    cut_held = cut & prob.is_x if prob.x_cut > 0.0 else cut & ~prob.is_x
    return tip_x, np.flatnonzero(prob.on_bottom | cut_held)


def _contact_dofs(prob: ContactProblem, active: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """(the active inner contacts' z dofs, the active outer contacts' z dofs)."""
    if active is None:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    idx = np.flatnonzero(active)
    inner = idx[idx < prob.n_inner]
    outer = idx[idx >= prob.n_inner]
    return prob.contact_dofs[inner], prob.contact_dofs[outer]


def _reaction_at_half(K: csr_matrix, held_zero: np.ndarray, held_half: np.ndarray) -> float:
    """Solve K du = 0 with du = 0 on ``held_zero``, 1/2 on ``held_half``, free elsewhere, and
    return the reaction summed over ``held_half`` (per unit of the whole travel)."""
    N = K.shape[0]
    du = np.zeros(N)
    du[held_half] = 0.5
    free = np.setdiff1d(np.arange(N), np.union1d(held_zero, held_half))
    du[free] = spsolve(K[free][:, free].tocsc(), -(K @ du)[free])
    if not np.all(np.isfinite(du)):
        raise ContinuumError("singular lateral tangent")
    return float((K @ du)[held_half].sum())


def lateral_tangent_x_N_per_mm(
    prob: ContactProblem, u: np.ndarray | None = None, active: np.ndarray | None = None, stuck: bool = False
) -> float:
    """k_x = dF_x / du_x (N/mm, whole layer) of the quarter problem ``prob`` at the state (u,
    active) of its centred compression (rest when None), contacts frictionless or ``stuck``
    (module docstring)."""
    u = np.zeros(prob.basis.N) if u is None else u
    _, K = prob.assemble(u)
    tip_x, held = _tip_and_support(prob)
    inner_z, outer_z = _contact_dofs(prob, active)
    x_of = _x_dof_of_z_dof(prob)
    half = tip_x
    zero = np.union1d(held, outer_z)
    if stuck:
        half = np.union1d(half, x_of[inner_z])
        zero = np.union1d(zero, x_of[outer_z])
    return _reaction_at_half(K, zero, np.setdiff1d(half, zero)) * prob.depth_factor


def lateral_tangent_y_N_per_mm(
    prob: ContactProblem, material: Material, active: np.ndarray | None = None, stuck: bool = False
) -> float:
    """k_y = dF_y / du_y (N/mm) of an infinitely deep web (antiplane shear, module docstring) on
    ``prob``'s quarter mesh, with its centred state's ``active`` contacts frictionless or
    ``stuck``; per mm of depth times the web's depth b."""
    from skfem import Basis, BilinearForm, ElementTriP2  # deferred: scikit-fem loads only when a mesh is built
    from skfem.helpers import dot, grad

    scalar = Basis(prob.mesh, ElementTriP2(), intorder=4)
    G = material.shear_modulus_MPa

    @BilinearForm
    def shear(u, v, w):
        return G * dot(grad(u), grad(v))

    K = shear.assemble(scalar).tocsr()
    of_z = np.full(prob.basis.N, -1, dtype=np.int64)  # the vector basis's z dof -> the scalar dof at its node
    of_z[prob.basis.nodal_dofs[1]] = scalar.nodal_dofs[0]
    of_z[prob.basis.facet_dofs[1]] = scalar.facet_dofs[0]
    tip_x, held = _tip_and_support(prob)
    x_of = _x_dof_of_z_dof(prob)
    z_of_x = np.full(prob.basis.N, -1, dtype=np.int64)
    z_of_x[x_of[x_of >= 0]] = np.flatnonzero(x_of >= 0)
    tip = of_z[z_of_x[tip_x]]
    bonded = np.flatnonzero(prob.on_bottom & ~prob.is_x)
    cut = np.flatnonzero(prob.on_cut & ~prob.is_x) if prob.x_cut > 0.0 else np.zeros(0, np.int64)
    zero = of_z[np.union1d(bonded, cut)]
    half = tip
    if stuck:
        inner_z, outer_z = _contact_dofs(prob, active)
        half = np.union1d(half, of_z[inner_z])
        zero = np.union1d(zero, of_z[outer_z])
    return _reaction_at_half(K, zero, np.setdiff1d(half, zero)) * prob.depth_factor


def lateral_stiffness_x_N_per_mm(cell: HexCell, material: Material, options: MeshOptions = PRODUCTION_MESH) -> float:
    """Small-load k_x (N/mm) of one layer on L2's production mesh (one linear solve)."""
    return lateral_tangent_x_N_per_mm(ContactProblem(cell, material, options))


def lateral_stiffness_y_N_per_mm(cell: HexCell, material: Material, options: MeshOptions = PRODUCTION_MESH) -> float:
    """Small-load k_y (N/mm) of one layer as an infinitely deep web (antiplane shear), L2's mesh;
    :func:`~mst_cli.model.mechanics.lateral.depth_end_factor` corrects it for the free faces."""
    return lateral_tangent_y_N_per_mm(ContactProblem(cell, material, options), material)


def lateral_force_N(
    cell: HexCell, material: Material, u_x_mm: float, options: MeshOptions = PRODUCTION_MESH, rtol: float = 1e-10
) -> float:
    """F_x (N, whole layer) of the nonlinear (Neo-Hookean) quarter at d = 0 with its mirror plane
    moved by u_x / 2 (free in z): exact to first order in u_x only (module docstring), the
    small-load limit's check. Raises ContinuumError when Newton does not converge."""
    prob = ContactProblem(cell, material, options)
    tip_x, held = _tip_and_support(prob)
    pinned = np.union1d(held, tip_x)
    free = np.setdiff1d(np.arange(prob.basis.N), pinned)
    u = np.zeros(prob.basis.N)
    r, K = prob.assemble(u)
    u[tip_x] = 0.5 * u_x_mm  # the first pass imposes the travel: the rest tangent's response to it
    u[free] = spsolve(K[free][:, free].tocsc(), -(K @ u)[free])
    r, K = prob.assemble(u)
    scale = None
    for _ in range(30):
        reaction = abs(r[tip_x].sum())
        scale = reaction if scale is None else max(scale, reaction)
        if np.linalg.norm(r[free]) <= rtol * max(scale, 1e-300):
            return float(r[tip_x].sum()) * prob.depth_factor
        u[free] -= spsolve(K[free][:, free].tocsc(), r[free])
        r, K = prob.assemble(u)
    raise ContinuumError("lateral Newton did not converge")


@dataclass(frozen=True)
class LateralPath:
    """Lateral tangent stiffnesses along the centred compression path, through the lock.

    ``d_mm`` the compressions; ``k_z`` the normal tangent dF/dd; ``k_x_free`` / ``k_x_stuck`` and
    ``k_y_free`` / ``k_y_stuck`` the lateral tangents with frictionless / stuck contacts (N/mm,
    the whole layer, infinitely deep for y); every column computed on the path mesh and scaled
    by its own direction's production-mesh small-load value over the path mesh's (``mesh_scale``
    is k_x's); ``d_lock_mm`` L2's lock on the path mesh.
    """

    d_mm: np.ndarray
    k_z_N_per_mm: np.ndarray
    k_x_free_N_per_mm: np.ndarray
    k_x_stuck_N_per_mm: np.ndarray
    k_y_free_N_per_mm: np.ndarray
    k_y_stuck_N_per_mm: np.ndarray
    d_lock_mm: float
    mesh_scale: float


def _compressed_states(prob: ContactProblem, d_targets: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(u, active, k_z) of the centred problem at each of the increasing ``d_targets``, stepping
    from rest with the path's tangent as predictor (steps halved where Newton fails)."""
    u, active, d = np.zeros(prob.basis.N), np.zeros(prob.contact_dofs.size, bool), 0.0
    step = max(float(d_targets.max()), 1e-9) / PATH_STEPS
    out = []
    for target in d_targets:
        while d < target - 1e-12:
            d_next = min(d + step, float(target))
            v, _ = prob.rate(u, active, d)
            try:
                u_new, _, active_new = prob.solve_step(u + (d_next - d) * v, d_next, active, pads=True)
            except FloatingPointError:
                if step < 1e-4 * float(d_targets.max()):
                    raise ContinuumError(f"compression path stalls at d = {d:.4g} mm") from None
                step *= 0.5
                continue
            u, active, d = u_new, active_new, d_next
        out.append((u.copy(), active.copy(), prob.rate(u, active, d)[1]))
    return out


def lateral_path(
    cell: HexCell, material: Material, fractions: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 0.95, 1.05)
) -> LateralPath:
    """The lateral tangents at ``fractions`` of L2's lock stroke (past 1: locked), both contact
    limits. One lock search and one compression path on the path mesh, one small-load solve on
    the production mesh for the scale."""
    prob = ContactProblem(cell, material, PATH_MESH)
    k_z0_path = linear_k(prob)
    path, _ = follow_to_lock(prob, k_z0_path)
    d_lock = float(path.d_mm[-1])
    d = np.array(fractions, float) * d_lock
    states = _compressed_states(prob, d)
    scale = {  # each direction's production-mesh small-load value over the path mesh's
        "z": linear_stiffness_N_per_mm(cell, material) / k_z0_path,
        "x": lateral_stiffness_x_N_per_mm(cell, material) / lateral_tangent_x_N_per_mm(prob),
        "y": lateral_stiffness_y_N_per_mm(cell, material) / lateral_tangent_y_N_per_mm(prob, material),
    }
    cols: dict[str, list[float]] = {k: [] for k in ("z", "xf", "xs", "yf", "ys")}
    for u, active, k_z in states:
        cols["z"].append(scale["z"] * k_z)
        cols["xf"].append(scale["x"] * lateral_tangent_x_N_per_mm(prob, u, active))
        cols["xs"].append(scale["x"] * lateral_tangent_x_N_per_mm(prob, u, active, stuck=True))
        cols["yf"].append(scale["y"] * lateral_tangent_y_N_per_mm(prob, material, active))
        cols["ys"].append(scale["y"] * lateral_tangent_y_N_per_mm(prob, material, active, stuck=True))
    arr = {k: np.array(v) for k, v in cols.items()}
    return LateralPath(d, arr["z"], arr["xf"], arr["xs"], arr["yf"], arr["ys"], d_lock, float(scale["x"]))


__all__ = [
    "PATH_MESH",
    "LateralPath",
    "lateral_force_N",
    "lateral_path",
    "lateral_stiffness_x_N_per_mm",
    "lateral_stiffness_y_N_per_mm",
    "lateral_tangent_x_N_per_mm",
    "lateral_tangent_y_N_per_mm",
]
