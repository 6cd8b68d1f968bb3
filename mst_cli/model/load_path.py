"""The part's load path: the compliance of the members that are not layers, in closed form.

Rung L0 (and L1, L2) model the layers between rigid plates. The exported part's cap, the plates
between layers and the housing's cover are TPU too (docs/design.md section 4.6). A centred
press reaches the layers through them, so the magnet's drop relative to the chip is the
layers' compression plus each member's bending:

* **cap** -- the cap (pocket floor, magnet pocket, cap top) bonded to the top layer's top pad:
  a beam of depth b = D across the top layer's two wall heads, loaded by the press's contact
  patch (a centred strip ``patch_mm`` wide, all of the depth). The section is the pad plus the
  cap, less the magnet pocket over its width 2r (the magnet's own stiffness is left out: an
  upper bound on the compliance, by the pocket's share of the section).
* **plates** -- each plate bonded to the pads above and below it: a beam across the lower
  layer's wall heads, loaded by the upper layer's wall feet. When the two layers' walls stand
  at the same x the load goes straight down and the plate does not bend.
* **cover** -- the base's cover bonded to layer 1's bottom pad: a beam across the board slot,
  loaded by layer 1's wall feet. It does not bend when the walls stand on the slot's side walls
  or beyond them on the solid base (the slot is narrower than the wall feet: no overhang, the
  base under it is solid). The side walls carry it over the whole depth but
  at the cable windows, which end just above their sockets (docs/design.md section 10): the
  cover spans a window's 6-7 mm along the depth with wall on both sides, no cantilever.

Each beam is a plane-strain Timoshenko beam (E' = E/(1 - nu^2) in bending, G in shear, shear
factor 5/6) with its supports either simply supported (the default: the wall heads turn with
the slender walls) or clamped (the stiff bound); a symmetric load, so the shear deflection is
the same for both. Pure numpy, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SHEAR_FACTOR = 5.0 / 6.0  # kappa of a rectangular section
# a fingertip pressed on the face: a contact patch about 6 mm wide (the width the issue's
# independent check presses over); the press runs the whole depth (a strip, in plane strain)
FINGERTIP_PATCH_MM = 6.0
SUPPORTS = ("simple", "clamped")


def strip_bending_mm_per_N(span_mm: float, patch_mm: float, EI_Nmm2: float, support: str) -> float:
    """Centre deflection per newton of a beam of ``span_mm`` under a centred uniform strip load
    ``patch_mm`` wide (clipped to the span), bending only.

    The influence of a point load at a <= L/2 on the mid-span deflection is a (3L^2 - 4a^2)/(48 EI)
    (simply supported) or a^2 (3L - 4a)/(48 EI) (clamped at both ends); integrated over the strip
    with q = F/c. The limit c -> 0 is F L^3/(48 EI) and F L^3/(192 EI)."""
    L = span_mm
    c = min(max(patch_mm, 0.0), L)
    a0, a1 = 0.5 * (L - c), 0.5 * L
    if c < 1e-9 * L:
        return L**3 / ((48.0 if support == "simple" else 192.0) * EI_Nmm2)
    if support == "simple":
        prim = lambda a: 1.5 * L**2 * a**2 - a**4  # noqa: E731  (the antiderivative of a (3L^2 - 4a^2))
    else:
        prim = lambda a: L * a**3 - a**4  # noqa: E731  (of a^2 (3L - 4a))
    return 2.0 * (prim(a1) - prim(a0)) / (c * 48.0 * EI_Nmm2)


def strip_shear_mm_per_N(span_mm: float, patch_mm: float, kGA_N: float) -> float:
    """Centre deflection per newton from shear (Timoshenko), any symmetric supports: the shear
    force is F/2 up to the strip and falls linearly to 0 across it, so delta = F (L - c/2)/(4 kGA)."""
    c = min(max(patch_mm, 0.0), span_mm)
    return (span_mm - 0.5 * c) / (4.0 * kGA_N)


def two_load_mm_per_N(span_mm: float, offset_mm: float, EI_Nmm2: float, kGA_N: float, support: str) -> float:
    """Deflection per newton (total force F, F/2 at each load) under two symmetric line loads
    ``offset_mm`` inside each support of a beam of ``span_mm`` (a plate loaded by the walls above
    it, held by the walls below). Bending under each load: P e^2 (3L - 4e)/(6 EI) simply supported
    (four-point bending), less the end moments' lift when clamped (:func:`_clamped_two_load`);
    shear P e/(kGA). A load outside the supports (e < 0) hangs on an overhang |e| long from a
    support held level by symmetry: P |e|^3/(3 EI) + P |e|/(kGA)."""
    P, e, L = 0.5, offset_mm, span_mm
    if abs(e) < 1e-12:
        return 0.0
    if e < 0:  # outside the supports: each load on a cantilever of |e|, the span held level by symmetry
        return P * abs(e) ** 3 / (3.0 * EI_Nmm2) + P * abs(e) / kGA_N
    e = min(e, 0.5 * L)
    bend = P * e**2 * (3 * L - 4 * e) / (6.0 * EI_Nmm2) if support == "simple" else _clamped_two_load(P, e, L, EI_Nmm2)
    return bend + P * e / kGA_N


def _clamped_two_load(P: float, e: float, L: float, EI: float) -> float:
    """Deflection under each of two symmetric loads P at e from the ends of a clamped-clamped beam:
    the simply supported one less the end moments' rotation, M = P e (L - e)/L each end, which
    lift the load point by M e (L - e)/(2 EI)."""
    simple = P * e**2 * (3 * L - 4 * e) / (6.0 * EI)
    M = P * e * (L - e) / L
    return simple - M * e * (L - e) / (2.0 * EI)


def section_EI_kGA(
    depth_mm: float,
    thickness_mm: float,
    E_prime_MPa: float,
    G_MPa: float,
    hole_width_mm: float = 0.0,
    hole_z_mm: tuple[float, float] = (0.0, 0.0),
    insert: Insert | None = None,
) -> tuple[float, float]:
    """(E'I in N mm^2, kappa G A in N) of a rectangle ``depth_mm`` x ``thickness_mm`` less a hole
    ``hole_width_mm`` wide (along the depth) between heights ``hole_z_mm`` above its bottom, and
    with an optional bonded ``insert`` (:class:`Insert`, at its ``z_mm`` above the bottom, over
    the whole depth, replacing the TPU there): the transformed section about its own neutral axis."""
    b, T = depth_mm, thickness_mm
    # strips (z0, z1, width x modulus), parallel axes about the modulus-weighted centroid
    strips = [(0.0, T, b * E_prime_MPa), (hole_z_mm[0], hole_z_mm[1], -hole_width_mm * E_prime_MPa)]
    shear = SHEAR_FACTOR * G_MPa * (b * T - hole_width_mm * max(hole_z_mm[1] - hole_z_mm[0], 0.0))
    if insert is not None:
        z0, z1 = insert.z_mm, insert.z_mm + insert.thickness_mm
        bi = b if insert.depth_mm is None else min(insert.depth_mm, b)  # the plate's own depth
        strips.append((z0, z1, bi * (insert.modulus_MPa - E_prime_MPa)))
        shear += SHEAR_FACTOR * bi * (z1 - z0) * (insert.shear_modulus_MPa - G_MPa)
    EA = sum(w * (z1 - z0) for z0, z1, w in strips)
    zc = sum(w * (z1 - z0) * 0.5 * (z0 + z1) for z0, z1, w in strips) / EA
    EI = sum(w * ((z1 - z0) ** 3 / 12.0 + (z1 - z0) * (0.5 * (z0 + z1) - zc) ** 2) for z0, z1, w in strips)
    return EI, shear


@dataclass(frozen=True)
class Insert:
    """A stiff plate bonded in the cap over the whole face (a load-path option, section 4.6)."""

    name: str
    modulus_MPa: float
    poisson_ratio: float
    thickness_mm: float
    z_mm: float = 0.0  # its underside above the cap beam's bottom (the top pad's underside)
    depth_mm: float | None = None  # along the depth (y); None: the whole depth D

    @property
    def shear_modulus_MPa(self) -> float:
        return self.modulus_MPa / (2.0 * (1.0 + self.poisson_ratio))


def wall_head_x_mm(cell) -> float:
    """Where a layer's walls meet its pad: the mid-point of the pad's outer (p) and inner
    (p - t tan(theta/2)) corners, the beam's support."""
    return 0.5 * (cell.p_mm + cell.p_inner_mm)


@dataclass(frozen=True)
class Members:
    """Compliance of each member that is not a layer, mm/N, for a centred press."""

    cap_mm_per_N: float
    plates_mm_per_N: tuple[float, ...]  # bottom to top, one per plate
    cover_mm_per_N: float
    patch_mm: float
    support: str

    @property
    def total_mm_per_N(self) -> float:
        return self.cap_mm_per_N + sum(self.plates_mm_per_N) + self.cover_mm_per_N

    @classmethod
    def rigid(cls, patch_mm: float = FINGERTIP_PATCH_MM, n_plates: int = 0) -> Members:
        """The members of the layer rungs: no bending (L0/L2 exactly)."""
        return cls(0.0, (0.0,) * n_plates, 0.0, patch_mm, "rigid")


def members(
    geometry, material, patch_mm: float = FINGERTIP_PATCH_MM, support: str = "simple", insert: Insert | None = None
) -> Members:
    """The cap's, the plates' and the cover's compliance of ``geometry`` (a SensorGeometry) in
    ``material`` under a centred press ``patch_mm`` wide (module docstring); ``insert``, a stiff
    plate in the cap (its own modulus, in plane strain as given), by default the geometry's own."""
    insert = getattr(geometry, "insert", None) if insert is None else insert
    if support not in SUPPORTS:
        raise ValueError(f"support must be one of {SUPPORTS}")
    E = material.youngs_modulus_MPa / (1.0 - material.poisson_ratio**2)
    G, D = material.shear_modulus_MPa, geometry.depth_mm
    top = geometry.layers[-1]
    # the cap: top pad + everything above the stack, less the pocket (its heights above the pad's underside)
    T = top.t_mm + geometry.total_height_mm - geometry.z_stack_top_mm
    z_pocket = top.t_mm + geometry.housing.pocket_floor_mm
    EI, kGA = section_EI_kGA(
        D, T, E, G, 2.0 * geometry.pocket_radius_mm, (z_pocket, z_pocket + geometry.pocket_depth_mm), insert
    )
    span = 2.0 * wall_head_x_mm(top)
    cap = strip_bending_mm_per_N(span, patch_mm, EI, support) + strip_shear_mm_per_N(span, patch_mm, kGA)
    plates = []
    for below, above in zip(geometry.layers[:-1], geometry.layers[1:]):
        EI_p, kGA_p = section_EI_kGA(D, below.t_mm + geometry.housing.plate_mm + above.t_mm, E, G)
        s, a = wall_head_x_mm(below), wall_head_x_mm(above)
        plates.append(two_load_mm_per_N(2.0 * s, s - a, EI_p, kGA_p, support))
    first = geometry.layers[0]
    EI_c, kGA_c = section_EI_kGA(D, geometry.housing.cover_mm + first.t_mm, E, G)
    x0, x1 = geometry.board_slots[0].x_mm
    half_slot = 0.5 * (x1 - x0)  # the slot's half width: the cover's span over it
    inside = half_slot - wall_head_x_mm(first)  # how far inside the slot's edge layer 1's walls land
    # walls past the slot's edge stand on the base's solid side walls: the cover does not bend
    cover = two_load_mm_per_N(2.0 * half_slot, inside, EI_c, kGA_c, support) if inside > 0.0 else 0.0
    return Members(cap, tuple(plates), cover, patch_mm, support)


def layer_compliances_mm_per_N(stack) -> np.ndarray:
    """(n_regimes, n_layers): each layer's dd/dF at the middle of each regime (a locked layer on
    its locked branch), from its own law (Stack.layers)."""
    edges = stack.regime_bounds_N
    mids = 0.5 * (edges[:-1] + edges[1:])
    out = np.empty((len(mids), len(stack.layers)))
    for j, law in enumerate(stack.layers):
        step = 1e-6 * max(float(edges[-1]), 1e-9)
        for i, F in enumerate(mids):
            if F >= law.lock_force_N:
                out[i, j] = 1.0 / law.k_locked_N_per_mm
            else:
                d = law.displacement_mm(np.array([max(F - step, 0.0), F + step]))
                out[i, j] = float((d[1] - d[0]) / (F + step - max(F - step, 0.0)))
    return out


def motion_shares(stack, parts: Members) -> list[dict]:
    """Per regime: the share of the magnet's drop per newton from each layer, the cap, the plates
    and the housing's cover (they sum to 1), and the share outside the layers."""
    layers = layer_compliances_mm_per_N(stack)
    edges = stack.regime_bounds_N
    out = []
    for i, row in enumerate(layers):
        total = float(row.sum()) + parts.total_mm_per_N
        shares = {f"layer_{j + 1}": float(c) / total for j, c in enumerate(row)}
        shares |= {
            "cap": parts.cap_mm_per_N / total,
            "plates": sum(parts.plates_mm_per_N) / total,
            "housing": parts.cover_mm_per_N / total,
        }
        out.append(
            {
                "regime": i + 1,
                "force_N": [float(edges[i]), float(edges[i + 1])],
                "compliance_mm_per_N": total,
                "layers_compliance_mm_per_N": float(row.sum()),
                "shares": shares,
                "outside_layers": parts.total_mm_per_N / total,
            }
        )
    return out


def load_path_report(geometry, material, stack, patch_mm: float = FINGERTIP_PATCH_MM) -> dict:
    """report.json's ``load_path``: the members' compliance (simply supported, and the clamped
    bound) and, per regime, each member's share of the magnet's motion (docs/design.md 4.6)."""
    simple = members(geometry, material, patch_mm, "simple")
    clamped = members(geometry, material, patch_mm, "clamped")
    bound = motion_shares(stack, clamped)
    regimes = []
    for row, stiff in zip(motion_shares(stack, simple), bound):
        row["outside_layers_clamped"] = stiff["outside_layers"]
        regimes.append(row)
    return {
        "patch_mm": patch_mm,
        "support": "simple (clamped: the stiff bound)",
        "cap_mm_per_N": simple.cap_mm_per_N,
        "plates_mm_per_N": list(simple.plates_mm_per_N),
        "housing_mm_per_N": simple.cover_mm_per_N,
        "cap_clamped_mm_per_N": clamped.cap_mm_per_N,
        "regimes": regimes,
        "outside_layers_max": max(r["outside_layers"] for r in regimes),
        "patch_dependence": patch_dependence(geometry, material, stack),
        "not_modelled": "the cover's bending along the depth over the cable windows (3D; walls on both sides)",
    }


def dominant_member(row: dict) -> tuple[str, float]:
    """The member outside the layers with the largest share in a regime row of :func:`motion_shares`."""
    name = max(("cap", "plates", "housing"), key=lambda k: row["shares"][k])
    return name, row["shares"][name]


def patch_dependence(geometry, material, stack) -> list[dict]:
    """How the response depends on the press's contact patch: the cap's compliance and the share
    outside the layers in the first and last regimes, for a fingertip's half, itself, twice it
    and the whole face."""
    rows = []
    for patch in (0.5 * FINGERTIP_PATCH_MM, FINGERTIP_PATCH_MM, 2.0 * FINGERTIP_PATCH_MM, geometry.width_mm):
        parts = members(geometry, material, patch)
        shares = motion_shares(stack, parts)
        rows.append(
            {
                "patch_mm": patch,
                "cap_mm_per_N": parts.cap_mm_per_N,
                "compliance_first_regime_mm_per_N": shares[0]["compliance_mm_per_N"],
                "outside_layers_first_regime": shares[0]["outside_layers"],
                "outside_layers_last_regime": shares[-1]["outside_layers"],
            }
        )
    return rows
