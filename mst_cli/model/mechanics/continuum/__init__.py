"""Rung L2 ``continuum``: nonlinear plane-strain finite elements of the real hex profile.

The reference model of the ladder (docs/design.md section 4). The layer's profile (x across the
width, z up; one continuous web through the depth D along y) is meshed from the
:class:`~mst_cli.model.cell.HexCell` polygons, with quadratic triangles (P2: linear
triangles lock in bending at nu = 0.45), and loaded by displacement control with a compressible
Neo-Hookean material through closure, up to the lock.

Symmetry and boundary conditions (a quarter of the profile: x >= 0, z <= h/2)
---------------------------------------------------------------------------
The profile is mirror-symmetric about x = 0 and, for equal and opposite plate motions, about
the mid-plane z = h/2; a rigid translation does not change the stresses, so bottom plate fixed
and top plate lowered by d is the symmetric problem shifted by d/2. The quarter model is the
bottom pad's right part plus the lower right wall:

* bottom face z = 0 (bonded to the rigid plate below): u = 0;
* pad cut at x = x_cut (x = 0 is the mirror plane; far from the wall the bonded pad is
  unstressed, so the pad is truncated a few t from the wall root): u_x = 0;
* wall tip face z = h/2 (the mirror plane, moving down by d/2 with the chevron's tip):
  u_z = -d/2, free to slide in x (no shear traction on a mirror plane).

The tip reaction f (N per mm of depth) is the force carried by one chevron whose compression is
d. The web's two chevrons act in parallel over its width b = D:  F = 2 b f.

Plane strain (the web is D = 20 mm wide, its walls 0.4-3 mm thick: away from the faces
y = +-D/2 nothing can stretch along y), lambda_3 = 1: the compressible Neo-Hookean energy
W = mu/2 (I_1 - 3) - mu ln J + lambda/2 (ln J)^2 (e.g. Bonet & Wood, "Nonlinear Continuum
Mechanics for Finite Element Analysis", 2nd ed., section 6.4.3) of the in-plane F, with the
3D Lame constants of the material's small-strain E and nu. Its small-strain limit is
plane-strain linear elasticity (uniaxial modulus E' = E / (1 - nu^2); tests/test_continuum.py
checks the tangent, a patch test and a Timoshenko cantilever).

Contact (:meth:`ContactProblem._contact_sets`): frictionless, by an active set inside Newton, of the
inner pad and wall faces against the moving mirror plane z = h/2 - d/2 and of the wall's outer
face against the plate z = 0. The pads touch at the contact allowance (the roughness of two
printed faces); faces that close at an angle, from the cavity's tip vertex and the outer wall
root, touch at zero gap. The lock (:func:`follow_to_lock`) is the first compression at which
the tangent stiffness reaches LOCK_STIFFNESS_FACTOR x k: a wall pinched between the plate and
its mirror, or the pads meeting (docs/design.md section 4). With rigid pads that is at most
d = h - 2t - allowance; the pads are elastic, so they meet up to a few per cent later.

The package, one module per concept:

* :mod:`.mesh`: the quarter profile's mesh, the root fillet, corner refinement (:class:`MeshOptions`);
* :mod:`.assembly`: the Neo-Hookean kinematics, the vectorised assembler, the plate as a penalty;
* :mod:`.algebra`: a tangent's free block and its banded solve, the contact active set;
* :mod:`.problem`: the contact problem (:class:`ContactProblem`);
* :mod:`.lock_path`: following the path to the lock (:func:`follow_to_lock`), the linear k;
* :mod:`.solve`: one layer's law (:func:`solve_continuum`, :func:`continuum_layer`).

Production calls ``solve_continuum(cell, material)`` and ``continuum_layer(cell, material)``.
Studies vary the kernel through one hook, :class:`StudyOptions` (``solve_continuum(cell,
material, StudyOptions(...))``: the mesh, the path's own mesh, the plate as a penalty, the
steps, the lock's factor), or build a :class:`ContactProblem` on :class:`MeshOptions` and follow
it with :func:`follow_to_lock`.

This package loads only when L2 is asked for (``mechanics`` defers it), so scipy is imported at
its modules' tops; scikit-fem, the slowest import, loads only when a mesh is built.
"""

from mst_cli.model.mechanics.continuum.assembly import smallest_stretch, smallest_stretches
from mst_cli.model.mechanics.continuum.lock_path import (
    D_MAX_OVER_NOMINAL,
    LOCK_STIFFNESS_FACTOR,
    ContinuumError,
    ContinuumResult,
    continuum_result,
    follow_to_lock,
    linear_k,
    linear_stiffness_N_per_mm,
)
from mst_cli.model.mechanics.continuum.mesh import (
    CORNERS,
    DEFAULT_LEVELS,
    DEFAULT_N_LENGTH,
    DEFAULT_N_THICK,
    PAD_LENGTH_IN_T,
    PRODUCTION_MESH,
    REFINE_RADIUS_IN_T,
    MeshOptions,
    RootFillet,
    quarter_profile_mesh,
    refined_quarter_mesh,
    root_fillet,
)
from mst_cli.model.mechanics.continuum.problem import ContactProblem
from mst_cli.model.mechanics.continuum.solve import PRODUCTION, StudyOptions, continuum_layer, solve_continuum

__all__ = [
    "CORNERS",
    "DEFAULT_LEVELS",
    "DEFAULT_N_LENGTH",
    "DEFAULT_N_THICK",
    "D_MAX_OVER_NOMINAL",
    "LOCK_STIFFNESS_FACTOR",
    "PAD_LENGTH_IN_T",
    "PRODUCTION",
    "PRODUCTION_MESH",
    "REFINE_RADIUS_IN_T",
    "ContactProblem",
    "ContinuumError",
    "ContinuumResult",
    "MeshOptions",
    "RootFillet",
    "StudyOptions",
    "continuum_layer",
    "continuum_result",
    "follow_to_lock",
    "linear_k",
    "linear_stiffness_N_per_mm",
    "quarter_profile_mesh",
    "refined_quarter_mesh",
    "root_fillet",
    "smallest_stretch",
    "smallest_stretches",
    "solve_continuum",
]
