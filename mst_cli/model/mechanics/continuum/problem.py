"""The contact problem of the quarter profile: boundary conditions, contact surfaces, Newton with
an active set, and the layer force with its equilibrium check (:class:`ContactProblem`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.mechanics.continuum.algebra import ActiveSet, FreeBlock
from mst_cli.model.mechanics.continuum.assembly import Assembler, PlatePenalty, assembler_of, lame_3d, set_assembler
from mst_cli.model.mechanics.continuum.mesh import (
    PRODUCTION_MESH,
    MeshOptions,
    RootFillet,
    refined_quarter_mesh,
    root_fillet,
)

if TYPE_CHECKING:
    from mst_cli.model.cell import HexCell
    from mst_cli.model.material import Material


class ContactProblem:
    """One quarter profile under displacement control, with frictionless contact (module docstring
    of :mod:`mst_cli.model.mechanics.continuum`): its mesh and P2 basis, the held and free dofs,
    the contact surfaces and their obstacles, Newton with an active set at a compression d
    (:meth:`solve_step`), the path's tangent (:meth:`rate`) and the layer force (:meth:`force`).

    ``options``: how the profile is meshed (:class:`MeshOptions`; the defaults are the production
    mesh with its corner refinement, the path runs on ``levels = 0``). ``plate_penalty_per_mm``:
    the outer face's contact with the plate as a penalty (:class:`PlatePenalty`), a study knob.
    :func:`~mst_cli.model.mechanics.continuum.follow_to_lock` follows its path; studies, the 3D
    check (tools/continuum_3d.py) and the tilted problem (continuum_tilt) build or subclass it.
    """

    # the contact surfaces, set by _contact_sets: dof, side (+1 inner, -1 outer), the obstacle's
    # offset at d = 0 and its rate in d; the first n_inner are the inner faces
    contact_dofs: np.ndarray
    contact_sign: np.ndarray
    obstacle_u0: np.ndarray
    obstacle_rate: np.ndarray
    n_inner: int

    plate: PlatePenalty | None = None  # the plate's contact as a penalty, when asked for
    fillet: RootFillet | None = None  # the outer root's printed fillet (quarter_profile_mesh), if any

    def __init__(
        self,
        cell: HexCell,
        material: Material,
        options: MeshOptions = PRODUCTION_MESH,
        plate_penalty_per_mm: float | None = None,
    ):
        from skfem import Basis, ElementTriP2, ElementVector  # deferred: scikit-fem, as in refined_quarter_mesh

        self.cell = cell
        self.fillet = root_fillet(cell, options.root_fillet_mm) if options.root_fillet_mm > 0 else None
        self.mesh, x_cut = refined_quarter_mesh(cell, options)
        self.basis = Basis(self.mesh, ElementVector(ElementTriP2()), intorder=4)
        self.mu, self.lam = lame_3d(material.youngs_modulus_MPa, material.poisson_ratio)
        b = self.basis
        h2 = 0.5 * cell.h_mm
        tol = 1e-9 * max(cell.width_mm, cell.h_mm)
        xy = b.doflocs  # (2, ndofs): location of every dof
        is_x = np.zeros(b.N, bool)
        is_x[b.nodal_dofs[0]] = True
        is_x[b.facet_dofs[0]] = True
        on_bottom = np.abs(xy[1]) < tol
        on_cut = np.abs(xy[0] - x_cut) < tol
        on_tip = np.abs(xy[1] - h2) < tol
        # the masks the tilted problem (continuum_tilt) reuses: x dofs, bonded face, the pad's cut
        self.is_x, self.on_bottom, self.on_cut = is_x, on_bottom, on_cut
        self.fixed_zero = np.flatnonzero(on_bottom | (on_cut & is_x))
        self.tip_z = np.flatnonzero(on_tip & ~is_x & ~on_bottom)
        self.support_z = np.flatnonzero((on_bottom | on_cut) & ~is_x)
        self.dirichlet = np.union1d(self.fixed_zero, self.tip_z)
        self.free = np.setdiff1d(np.arange(b.N), self.dirichlet)
        self._blocks: dict[bytes, FreeBlock] = {}  # free_block's cache, per pinned set
        self.x_cut = x_cut
        self._contact_sets(cell, xy, is_x, tol, on_bottom, on_tip)
        self.h2 = h2
        self.depth_factor = 2.0 * cell.b_mm  # F = 2 b f: two chevrons of a web b wide
        self.plate = None if plate_penalty_per_mm is None else self._plate_as_penalty(plate_penalty_per_mm)

    def _plate_as_penalty(self, per_mm):
        """Take the outer face's contact out of the active set and into a penalty (PlatePenalty)."""
        n = self.n_inner
        dofs, obstacle = self.contact_dofs[n:], self.obstacle_u0[n:]
        self.contact_dofs, self.contact_sign = self.contact_dofs[:n], self.contact_sign[:n]
        self.obstacle_u0, self.obstacle_rate = self.obstacle_u0[:n], self.obstacle_rate[:n]
        # each point's share of the face's length: half the distance between its neighbours
        xy = self.basis.doflocs[:, dofs]
        along = np.hypot(xy[0] - xy[0].min(), xy[1] - xy[1].min())
        order = np.argsort(along)
        sorted_share = np.gradient(along[order])
        sorted_share[[0, -1]] *= 0.5
        share = np.empty(dofs.size)
        share[order] = sorted_share
        plate = PlatePenalty(Assembler(self.basis), dofs, obstacle, per_mm * self.mu * share)
        set_assembler(self.basis, plate)
        return plate

    def _contact_sets(self, cell, xy, is_x, tol, on_bottom, on_tip):
        """The z-dofs of every surface that can close, each with its side and offset.

        * inner faces (the inner pad face z = t and the inner wall face) against their mirror
          images across the moving mid-plane: z + u_z <= h/2 - d/2 - g_c/2 (sign +1);
        * the outer wall face against the plate below it, z = 0: z + u_z >= g_c (sign -1); with
          a root fillet, the face from T2 up and the fillet's arc (:meth:`_fillet_arc_dofs`).

        g_c is the clear gap at which two printed faces touch: the contact allowance (the
        roughness and elephant's foot of two printed faces, section 4 of docs/design.md), but
        never more than the gap at rest, so that no point starts inside its obstacle (next
        to the cavity's tip vertex and the outer root corner the faces meet at an angle and
        the gap at rest falls to zero): g_c = min(allowance, gap at rest). The obstacle is a
        continuous function of position, so no mesh node decides where contact may start.
        """
        t, h2, a = cell.t_mm, 0.5 * cell.h_mm, cell.contact_allowance_mm
        inner = cell.inner_profile_xz()
        (ax, az), (cx, cz) = inner[0], inner[1]
        outer = cell.outer_profile_xz()
        (px, pz), (bx, bz) = outer[0], outer[1]

        def on_segment(x0, z0, x1, z1):
            ux = np.array([x1 - x0, z1 - z0]) / math.hypot(x1 - x0, z1 - z0)
            rel = xy - np.array([[x0], [z0]])
            along = ux[0] * rel[0] + ux[1] * rel[1]
            across = -ux[1] * rel[0] + ux[0] * rel[1]
            return (np.abs(across) < tol) & (along >= -tol) & (along <= math.hypot(x1 - x0, z1 - z0) + tol)

        z_dof = ~is_x & ~on_tip & ~on_bottom
        on_pad_face = (np.abs(xy[1] - t) < tol) & (xy[0] <= ax + tol)
        self.pad_z = np.flatnonzero(on_pad_face & z_dof)
        wall_in = np.flatnonzero(on_segment(ax, az, cx, cz) & ~on_pad_face & z_dof)
        if self.fillet is not None:  # the face from T2 up, then the fillet's arc
            T2 = self.fillet.T2
            wall_out = np.flatnonzero(on_segment(T2[0], T2[1], bx, bz) & z_dof)
            arc = self._fillet_arc_dofs(self.fillet, xy, tol)
            wall_out = np.concatenate([wall_out, np.setdiff1d(arc, wall_out)])
        else:
            wall_out = np.flatnonzero(on_segment(px, pz, bx, bz) & z_dof)
        self.inner_z = np.concatenate([self.pad_z, wall_in])
        z = xy[1]
        rest_in = 2.0 * (h2 - z[self.inner_z])  # gap to the mirror image at rest
        rest_out = z[wall_out]  # gap to the plate at rest
        # clear gap at touch: the allowance between the pads (parallel faces), none where faces
        # close at an angle (zipping from a vertex)
        touch_in = np.where(np.arange(self.inner_z.size) < self.pad_z.size, a, 0.0)
        self.contact_dofs = np.concatenate([self.inner_z, wall_out])
        self.contact_sign = np.concatenate([np.ones(self.inner_z.size), -np.ones(wall_out.size)])
        self.n_inner = self.inner_z.size
        # obstacle position in u_z at d = 0, and its rate with d (the mirror plane moves by -d/2)
        self.obstacle_u0 = np.concatenate([0.5 * (rest_in - touch_in), -rest_out])
        self.obstacle_rate = np.concatenate([np.full(self.inner_z.size, -0.5), np.zeros(wall_out.size)])

    def _fillet_arc_dofs(self, f: RootFillet, xy, tol) -> np.ndarray:
        """The z-dofs on the root fillet ``f``'s arc: on the mesh's boundary, inside the triangle
        A T1 T2 and off the plate (the fillet's face edge A-T2 is inside the solid)."""
        b, mesh = self.basis, self.mesh
        facets = mesh.boundary_facets()
        dofs = np.unique(np.concatenate([b.nodal_dofs[1][mesh.facets[:, facets]].ravel(), b.facet_dofs[1][facets]]))
        rel = xy[:, dofs] - f.A[:, None]
        u = (f.T2 - f.A) / f.tangent_mm
        along_face = u[0] * rel[0] + u[1] * rel[1]  # the triangle: z > 0, below the face, before T1 T2
        below_face = u[0] * rel[1] - u[1] * rel[0]
        n = np.array([math.cos(0.5 * f.theta_rad), math.sin(0.5 * f.theta_rad)])  # the bisector
        inside = (rel[1] > tol) & (below_face < tol) & (n[0] * rel[0] + n[1] * rel[1] <= float(n @ (f.T1 - f.A)) + tol)
        return dofs[inside & (along_face > -tol)]

    # residual and tangent -------------------------------------------------------
    def assemble(self, u, need_K=True) -> tuple:
        """Residual r (N,) and, with ``need_K``, the tangent K (CSR) at the displacement u.

        Works on any object with ``basis``, ``mu`` and ``lam`` (the tests reuse it on their own
        meshes); raises FloatingPointError when an element inverts (J <= 0).
        """
        asm = assembler_of(self.basis)
        r, state = asm.residual(u, self.mu, self.lam)
        return r, (asm.tangent(state, self.mu, self.lam) if need_K else None)

    def obstacle(self, d) -> np.ndarray:
        """Where each contact dof's u_z meets its obstacle at compression d (mm)."""
        return self.obstacle_u0 + self.obstacle_rate * d

    def rate(self, u, active, d) -> tuple[np.ndarray, float]:
        """(du/dd (N,), dF/dd in N/mm) of the converged state (u, active) at compression d: one
        linear solve with the state's tangent, the tip and the active inner contacts moving with
        the mirror plane, the active outer contacts held on the plate. dF/dd is the lock's test,
        du/dd the path's tangent (the next step's predictor)."""

        asm = assembler_of(self.basis)
        if active is None:
            active = np.zeros(self.contact_dofs.size, bool)
        _, kin = asm.residual(u, self.mu, self.lam)
        K = asm.tangent(kin, self.mu, self.lam)
        contact = self.contact_dofs[active]
        block = self.free_block(np.sort(contact))
        free = block.free
        v = self.pinned_rate()
        v[contact] = self.obstacle_rate[active]
        v[free] = block.solve(K, -(K @ v)[free])
        f = K @ v
        inner = active.copy()
        inner[self.n_inner :] = False
        return v, float(-(f[self.tip_z].sum() + f[self.contact_dofs[inner]].sum()) * self.depth_factor)

    def pinned_rate(self) -> np.ndarray:
        """du/dd on the held dofs: the tip face moves by -1/2 per mm of compression, the bonded
        face stays (a tilted problem moves it too: mst_cli.model.mechanics.continuum_tilt)."""
        v = np.zeros(self.basis.N)
        v[self.tip_z] = -0.5
        return v

    def free_block(self, pinned_extra=()) -> FreeBlock:
        """The free dofs with ``pinned_extra`` also pinned, and how to cut their block out of a
        tangent (:class:`FreeBlock`). Cached per pinned set: the pattern is fixed, so after the
        first time a block costs one gather."""
        key = np.asarray(pinned_extra, dtype=np.int64).tobytes()
        block = self._blocks.get(key)
        if block is None:
            block = self._blocks[key] = FreeBlock(assembler_of(self.basis), np.setdiff1d(self.free, pinned_extra))
        return block

    def solve_step(self, u, d, active=None, max_iter=60, rtol=1e-8, pads=False) -> tuple[np.ndarray, int, np.ndarray]:
        """Newton at compression d from the state u, with frictionless contact of every face
        that can close (:meth:`_contact_sets`) as an active set updated inside the iterations
        (penetrating points are pinned to their obstacle, points whose contact force would
        pull are released; converged when the residual is small and the set no longer
        changes). ``pads``: whether the inner pads may touch (past the lock).

        Returns (u, iterations, active set); iterations counts the residual checks after the
        first pass (which imposes the new d), as :func:`~mst_cli.model.mechanics.path.follow_to_event` expects.
        """
        u, it, active, _ = self._newton(u, d, active, max_iter, rtol, pads)
        return u, it, active

    def _newton(self, u, d, active=None, max_iter=60, rtol=1e-8, pads=False):
        """:meth:`solve_step`, also returning the residual at the solution (for :meth:`force`)."""

        asm = assembler_of(self.basis)
        dofs, sign = self.contact_dofs, self.contact_sign
        eligible = np.ones(dofs.size, bool)
        if not pads:
            eligible[: self.pad_z.size] = False
        active = np.zeros(dofs.size, bool) if active is None else active & eligible
        u = u.copy()
        obstacle = self.obstacle(d)
        tol = 1e-9 * self.cell.h_mm
        scale = None
        contact_set = ActiveSet(eligible, tol)
        r, kin = asm.residual(u, self.mu, self.lam)
        for it in range(1, max_iter + 1):
            contact = dofs[active]
            pinned = np.concatenate([self.tip_z, contact])
            target = np.concatenate([np.full(self.tip_z.size, -0.5 * d), obstacle[active]])
            block = self.free_block(np.sort(contact))
            free = block.free
            reaction = abs(r[pinned].sum())
            scale = max(reaction, 1e-12 * self.mu * self.cell.t_mm) if scale is None else max(scale, reaction)
            jump = target - u[pinned]
            if it > 1 and np.linalg.norm(r[free]) <= rtol * scale and not np.any(np.abs(jump) > tol):
                updated = contact_set.update(active, sign * (u[dofs] - obstacle), sign * r[dofs])
                if updated is None:
                    return u, it - 1, active, r
                active = updated
                continue
            # the tangent only where a correction is solved (not at the converged point)
            K = asm.tangent(kin, self.mu, self.lam)
            jump_all = np.zeros(self.basis.N)
            jump_all[pinned] = jump
            rhs = -r[free] - (K @ jump_all)[free]
            du = block.solve(K, rhs)
            if not np.all(np.isfinite(du)):
                raise FloatingPointError("singular tangent")
            u_try = u.copy()
            u_try[pinned] = target
            # backtrack when the full update would invert an element (J <= 0); the residual of
            # the accepted update is the next iteration's
            for alpha in (1.0, 0.5, 0.25, 0.125, 0.0625):
                u_try[free] = u[free] + alpha * du
                try:
                    r, kin = asm.residual(u_try, self.mu, self.lam)
                    break
                except FloatingPointError:
                    continue
            else:
                raise FloatingPointError("every damped Newton update inverts an element")
            u = u_try
            if it > 1:  # let the set follow the iterate (semi-smooth Newton)
                active = active | (eligible & (sign * (u[dofs] - obstacle) > tol))
        raise FloatingPointError("Newton did not converge")

    def force(self, u, active, r=None) -> tuple[float, float]:
        """Layer force F (N) = what crosses the mirror plane (tip face + inner contact), and the
        relative imbalance against the support reactions (bonded face, pad cut, and the outer
        face's contact with the plate: an equilibrium check). ``r``: the residual at u."""
        if r is None:
            r, _ = self.assemble(u, need_K=False)
        inner = active.copy()
        inner[self.n_inner :] = False
        outer = active.copy()
        outer[: self.n_inner] = False
        f_mirror = -(r[self.tip_z].sum() + r[self.contact_dofs[inner]].sum())
        support = np.setdiff1d(self.support_z, self.contact_dofs[active])
        f_support = r[support].sum() + r[self.contact_dofs[outer]].sum()
        if self.plate is not None:  # the plate's push on the outer face, a penalty
            f_support += float(np.sum(self.plate.kappa * self.plate.overlap_mm(u)))
        balance = abs(f_mirror - f_support) / max(abs(f_mirror), 1e-300)
        return f_mirror * self.depth_factor, balance
