"""The top layer's walls' thrust on the cap and the plate under it, past the lock of the layer
below (issue 44, docs/design.md 4.7, "The cap and the plate together, past two locks").

mst's closed form sums each member alone: the cap bending between the top layer's wall heads
(model.load_path), the plate over a locked layer hanging from its block (model.past_lock). The
whole-part rung finds them giving more together than alone once the layer under the top one is
locked. A wall's ends meet the cap at its underside (the cap's mid-plane cap_above/2 above it) and
the plate on its top (its mid-plane p/2 below); the hexagon's walls thrust along both, the thrust
bends them off their mid-planes, and how much thrust there is depends on how freely each wall end
turns: a soft cap and a soft plate feed each other. studies/cap_plate_thrust.py solves that plane
frame of half the top layer's cell (model.plane_frame) and finds its interaction at 0.65 of the
rung's over the design box (0.10 with the offsets removed, its control).

:func:`chain_drop_mm_per_N` is that frame by the flexibility method, vectorised over stacks: each
member's 3 x 3 flexibility (its six entries, elementwise) carried to the cap's centre and summed,
the centre then held by the symmetry plane. The top layer alone fixes the walls' and the cap's
part (:func:`top_chain`, on :func:`chain_members`, which the study's frame takes too); the block
under it enters last (:func:`drop_on_block`), and a member made k times stiffer divides its part by
k, so the four rigid cases cost one chain. :func:`thrust_extra_mm_per_N` is the interaction the
closed form lacks, the drop with both members as printed, less with the cap rigid, less with the
plate rigid, plus with both rigid. It is a centred press's term: under a moment or a tangential
force the walls' thrusts differ side to side, so it carries no member's lever (model.part_laws).
Pure numpy, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.model.beams import section_EI_kGA
from mst_cli.model.cell import wall_centreline_length_mm
from mst_cli.model.past_lock import LOCKED_FITTED
from mst_cli.model.plate_joint import root_spring_Nmm_per_rad

# (cap, plate) stiffness factors of the four chains whose signed sum is the interaction
RIGID_CASES = ((1.0, 1.0), (np.inf, 1.0), (1.0, np.inf), (np.inf, np.inf))
RIGID_SIGNS = (1.0, -1.0, -1.0, 1.0)


def beam_flexibility(a_xz: tuple, b_xz: tuple, EA, EI, kGA) -> tuple:
    """A Timoshenko beam's flexibility at its end b, a held, in global (u, w, turn), as its six
    entries (uu, uw, ut, ww, wt, tt) of arrays: the local [[L/EA, 0, 0], [0, L^3/(3 EI) + L/kGA,
    L^2/(2 EI)], [0, L^2/(2 EI), L/EI]] turned from the beam's axis (a to b) to x (EA, kGA inf: no
    stretch, no shear). Entries, not (..., 3, 3) stacks: the design's start evaluates this over
    thousands of cells, where small stacked matrix products cost ten times the arithmetic."""
    dx, dz = b_xz[0] - a_xz[0], b_xz[1] - a_xz[1]
    L = np.hypot(dx, dz)
    c, s = dx / L, dz / L
    axial, bend = L / EA, L**3 / (3.0 * EI) + L / kGA
    couple, turn = L * L / (2.0 * EI), L / EI
    uu, ww = axial * c * c + bend * s * s, axial * s * s + bend * c * c
    return (uu, (axial - bend) * c * s, -s * couple, ww, c * couple, turn)


def carried(f: tuple, b_xz: tuple, tip_xz: tuple) -> tuple:
    """The flexibility ``f`` (six entries) at point b seen at the tip, B^T f B, where B carries a
    tip load (Fx, Fz, M) to b: the same forces and the moment M + (x_tip - x_b) Fz - (z_tip - z_b)
    Fx (turns counter-clockwise from x to z); with a = (-(z_tip - z_b), x_tip - x_b, 0), entry ij
    gains f_i,turn a_j + a_i f_turn,j + f_turn,turn a_i a_j."""
    a0, a1 = b_xz[1] - tip_xz[1], tip_xz[0] - b_xz[0]
    uu, uw, ut, ww, wt, tt = f
    return (
        uu + 2.0 * ut * a0 + tt * a0 * a0,
        uw + ut * a1 + wt * a0 + tt * a0 * a1,
        ut + tt * a0,
        ww + 2.0 * wt * a1 + tt * a1 * a1,
        wt + tt * a1,
        tt,
    )


@dataclass(frozen=True)
class TopChain:
    """The part of the frame's chain that the top layer alone fixes, arrays (...): the walls', the
    cap's (its root spring and its half span) and the plate root's at the walls' feet flexibilities
    carried to the cap's centre (six entries each, :func:`carried`'s), and what the plate's hang
    from the block needs. The block (the closed layer's wall heads) enters in :func:`drop_on_block`,
    so a design start that tries every cell under one top layer builds this once."""

    walls: tuple
    cap: tuple
    foot: tuple  # the plate's root at the walls' feet (turns with the plate's stiffness)
    x_head_mm: np.ndarray
    z_plate_mm: np.ndarray  # the plate's mid-plane: the walls' feet less the plate's offset
    tip_z_mm: np.ndarray
    EI_plate: np.ndarray
    kGA_plate: np.ndarray
    block_root_Nmm_per_rad: np.ndarray  # the plate's root in the block (model.past_lock)


def rotational_spring(k, b_xz: tuple, tip_xz: tuple) -> tuple:
    """A rotational spring ``k`` (N mm/rad) at b seen at the tip: :func:`carried` of f = 1/k in turn
    alone, its six entries."""
    a0, a1, tt = b_xz[1] - tip_xz[1], tip_xz[0] - b_xz[0], 1.0 / k
    return (tt * a0 * a0, tt * a0 * a1, tt * a0, tt * a1 * a1, tt * a1, tt)


def _summed(*parts: tuple) -> tuple:
    return tuple(sum(entries) for entries in zip(*parts))


@dataclass(frozen=True)
class ChainMembers:
    """The members of the top layer's half-cell frame, arrays (...): each wall's centre line (L,
    mm, from its foot at z_foot to its head at z_head, the plate's top at z = 0) and section (EA,
    EI, kGA: N, N mm^2, N), its ends' root spring (N mm/rad, model.plate_joint), the cap's and the
    plate's sections (EI, kGA), the plate and the pad over it d thick, its root in the block under
    it (N mm/rad, model.past_lock), and the cap's and the plate's mid-planes' offsets from the
    walls' ends (mm; 0 in the study's control)."""

    L_mm: np.ndarray
    wall: tuple
    root_Nmm_per_rad: np.ndarray
    cap: tuple
    plate: tuple
    d_mm: np.ndarray
    block_root_Nmm_per_rad: np.ndarray
    z_foot_mm: np.ndarray
    z_head_mm: np.ndarray
    e_cap_mm: float
    e_plate_mm: float


def chain_members(scene, theta_rad, t_mm, h_mm, offsets: bool = True) -> ChainMembers:
    """:class:`ChainMembers` of top layers given as arrays (theta in rad; t, h, mm) in ``scene``
    (a model.load_path.MemberScene): the frame the chain here and the study's stiffness-method
    frame (studies/cap_plate_thrust.py) both solve."""
    s = scene
    theta, t, h = (np.asarray(v, dtype=float) for v in (theta_rad, t_mm, h_mm))
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    ED = E * D
    L = wall_centreline_length_mm(theta, t, h)
    z_pocket = t + s.pocket_floor_mm
    cap = section_EI_kGA(
        D, t + s.cap_above_stack_mm, E, G, s.pocket_width_mm, (z_pocket, z_pocket + s.pocket_depth_mm),
        s.insert, t + s.insert_above_pad_mm,
    )  # fmt: skip
    d = s.plate_mm + t  # the plate and the pad over it
    e_cap, e_plate = (0.5 * s.cap_above_stack_mm, 0.5 * s.plate_mm) if offsets else (0.0, 0.0)
    return ChainMembers(
        L, (ED * t, ED * t**3 / 12.0, 5.0 / 6.0 * G * D * t), root_spring_Nmm_per_rad(theta, t, L, D, E), cap,
        section_EI_kGA(D, d, E, G), d, LOCKED_FITTED[1] * ED * d * d, 0.5 * t, h - 0.5 * t, e_cap, e_plate,
    )  # fmt: skip


def top_chain(scene, theta_rad, t_mm, h_mm, head_mm, offsets: bool = True) -> TopChain:
    """:class:`TopChain` of top layers given as arrays (...) (theta in rad; t, h and their wall
    heads' x, mm) in ``scene`` (a model.load_path.MemberScene); ``offsets``: False puts the walls'
    ends on the members' mid-planes (the study's control)."""
    m = chain_members(scene, theta_rad, t_mm, h_mm, offsets)
    theta, h = np.asarray(theta_rad, dtype=float), np.asarray(h_mm, dtype=float)
    x_head = np.asarray(head_mm, dtype=float)
    L, root, (EI_c, kGA_c), (EI_p, kGA_p) = m.L_mm, m.root_Nmm_per_rad, m.cap, m.plate
    z_foot, z_head, e_cap, e_plate, wall = m.z_foot_mm, m.z_head_mm, m.e_cap_mm, m.e_plate_mm, m.wall
    # points as (x, z), mm
    tip = (0.0, z_head + e_cap)
    foot, vertex, head = (x_head, z_foot), (x_head + L * np.cos(theta), 0.5 * h), (x_head, z_head)
    walls = _summed(
        carried(beam_flexibility(foot, vertex, *wall), vertex, tip),
        carried(beam_flexibility(vertex, head, *wall), head, tip),
    )
    cap = _summed(
        rotational_spring(root, head, tip), beam_flexibility((x_head, z_head + e_cap), tip, np.inf, EI_c, kGA_c)
    )
    return TopChain(
        walls, cap, rotational_spring(root, foot, tip), x_head, z_foot - e_plate, tip[1], EI_p, kGA_p,
        m.block_root_Nmm_per_rad,
    )  # fmt: skip


def drop_on_block(chain: TopChain, head_below_mm, cap_factor=1.0, plate_factor=1.0) -> np.ndarray:
    """The cap centre's drop, mm/N, of the chain's top layers on the closed layer below, whose wall
    heads stand at ``head_below_mm``: under 1/2 N down on the half cell, the centre held from
    moving along x and from turning. ``cap_factor``, ``plate_factor``: those members' (and their
    roots') stiffness times that (inf: rigid; arrays broadcast with the stacks)."""
    x_head, z_plate, tip = chain.x_head_mm, chain.z_plate_mm, (0.0, chain.tip_z_mm)
    x_block = np.asarray(head_below_mm, dtype=float)
    hangs = x_head > x_block  # the feet beyond the block's edge: the plate hangs from it
    c = np.where(hangs, x_head - x_block, 1.0)  # a dummy length where the feet stand on the block
    plate_end = (x_head, z_plate)
    plate = beam_flexibility((x_head - c, z_plate), plate_end, np.inf, chain.EI_plate, chain.kGA_plate)
    plate_side = _summed(
        rotational_spring(chain.block_root_Nmm_per_rad, (np.minimum(x_block, x_head), z_plate), tip),
        carried(tuple(np.where(hangs, f, 0.0) for f in plate), plate_end, tip),
        chain.foot,
    )
    # a member's flexibility is inversely proportional to its stiffness: the factors divide it
    cap_f, plate_f = (1.0 / np.asarray(f, dtype=float) for f in (cap_factor, plate_factor))
    uu, uw, ut, ww, wt, tt = (w + p * plate_f + k * cap_f for w, p, k in zip(chain.walls, plate_side, chain.cap))
    # the centre held along x and in turn under Fz: [[uu, ut], [ut, tt]] (Fx, M) = -Fz (uw, wt)
    Fz = -0.5
    det = uu * tt - ut * ut
    Fx = -Fz * (uw * tt - ut * wt) / det
    M = -Fz * (uu * wt - ut * uw) / det
    return -(uw * Fx + ww * Fz + wt * M)


def chain_drop_mm_per_N(
    scene, theta_rad, t_mm, h_mm, head_mm, head_below_mm, cap_factor=1.0, plate_factor=1.0, offsets: bool = True
) -> np.ndarray:  # fmt: skip
    """The cap centre's drop, mm/N, of top layers given as arrays (...) (theta in rad; t, h, their
    wall heads' x and the heads' x of the closed layer below, mm) in ``scene`` (a
    model.load_path.MemberScene): the frame's chain from the block to the cap's centre (module
    docstring), :func:`top_chain` on :func:`drop_on_block`, whose arguments these are."""
    chain = top_chain(scene, theta_rad, t_mm, h_mm, head_mm, offsets)
    return drop_on_block(chain, head_below_mm, cap_factor, plate_factor)


def thrust_on_block(chain: TopChain, head_below_mm) -> np.ndarray:
    """(...) what the cap and the plate under the chain's top layers give together beyond each
    alone, mm/N, on the closed layer whose wall heads stand at ``head_below_mm``: its four rigid
    cases in one call, signed as the module docstring says."""
    shape = np.broadcast_shapes(np.shape(chain.x_head_mm), np.shape(head_below_mm))
    cases = np.array(RIGID_CASES).reshape((4, 2) + (1,) * len(shape))
    drops = drop_on_block(chain, head_below_mm, cases[:, 0], cases[:, 1])
    return np.tensordot(np.array(RIGID_SIGNS), drops, axes=1)


def thrust_extra_mm_per_N(scene, theta_rad, t_mm, h_mm, head_mm, head_below_mm) -> np.ndarray:
    """(...) :func:`thrust_on_block` of top layers given as arrays (:func:`chain_drop_mm_per_N`'s)."""
    return thrust_on_block(top_chain(scene, theta_rad, t_mm, h_mm, head_mm), head_below_mm)


def scene_thrust_mm_per_N(scene, theta_rad, t_mm, h_mm, head_mm) -> np.ndarray:
    """(..., n - 1) the walls' thrust per plate of stacks given as arrays (..., n) (theta in rad;
    t, h, their wall heads' x, mm): on the plate under the top layer, which moves while the layer
    below it is locked and the top one open (model.past_lock's rule); 0 on the others and on a
    one-layer stack."""
    t = np.asarray(t_mm, dtype=float)
    n = t.shape[-1]
    out = np.zeros(t.shape[:-1] + (max(n - 1, 0),))
    if n >= 2:
        theta, h, head = (np.asarray(a, dtype=float) for a in (theta_rad, h_mm, head_mm))
        out[..., -1] = thrust_extra_mm_per_N(
            scene, theta[..., -1], t[..., -1], h[..., -1], head[..., -1], head[..., -2]
        )
    return out
