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
member's 3 x 3 flexibility carried to the cap's centre and summed, the centre then held by the
symmetry plane. :func:`thrust_extra_mm_per_N` is the interaction the closed form lacks, the drop
with both members as printed, less with the cap rigid, less with the plate rigid, plus with both
rigid. It is a centred press's term: under a moment or a tangential force the walls' thrusts
differ side to side, so it carries no member's lever (model.part_laws). Pure numpy, no I/O.
"""

from __future__ import annotations

import numpy as np

from mst_cli.model.beams import section_EI_kGA
from mst_cli.model.cell import wall_centreline_length_mm
from mst_cli.model.past_lock import LOCKED_FITTED
from mst_cli.model.plate_joint import root_spring_Nmm_per_rad

# (cap, plate) stiffness factors of the four chains whose signed sum is the interaction
RIGID_CASES = ((1.0, 1.0), (np.inf, 1.0), (1.0, np.inf), (np.inf, np.inf))
RIGID_SIGNS = (1.0, -1.0, -1.0, 1.0)


def beam_flexibility(a_xz, b_xz, EA, EI, kGA) -> np.ndarray:
    """(..., 3, 3) a Timoshenko beam's flexibility at its end b, a held, in global (u, w, turn):
    the local [[L/EA, 0, 0], [0, L^3/(3 EI) + L/kGA, L^2/(2 EI)], [0, L^2/(2 EI), L/EI]] turned
    from the beam's axis (a to b) to x (EA, kGA inf: no stretch, no shear)."""
    d = np.asarray(b_xz, dtype=float) - np.asarray(a_xz, dtype=float)
    L = np.hypot(d[..., 0], d[..., 1])
    c, s = d[..., 0] / L, d[..., 1] / L
    L, EA, EI, kGA, c, s = np.broadcast_arrays(L, EA, EI, kGA, c, s)
    local = np.zeros(L.shape + (3, 3))
    local[..., 0, 0] = L / EA
    local[..., 1, 1] = L**3 / (3.0 * EI) + L / kGA
    local[..., 1, 2] = local[..., 2, 1] = L * L / (2.0 * EI)
    local[..., 2, 2] = L / EI
    R = np.zeros(L.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, s, -s, c, 1.0
    return np.swapaxes(R, -1, -2) @ local @ R


def load_transfer(b_xz, tip_xz) -> np.ndarray:
    """(..., 3, 3) the load at point b of a load (Fx, Fz, M) at the tip: the same forces and the
    moment M + (x_tip - x_b) Fz - (z_tip - z_b) Fx (turns counter-clockwise from x to z)."""
    r = np.asarray(tip_xz, dtype=float) - np.asarray(b_xz, dtype=float)
    B = np.zeros(r.shape[:-1] + (3, 3))
    B[..., 0, 0] = B[..., 1, 1] = B[..., 2, 2] = 1.0
    B[..., 2, 0], B[..., 2, 1] = -r[..., 1], r[..., 0]
    return B


def chain_drop_mm_per_N(
    scene, theta_rad, t_mm, h_mm, head_mm, head_below_mm, cap_factor=1.0, plate_factor=1.0, offsets: bool = True
) -> np.ndarray:  # fmt: skip
    """The cap centre's drop, mm/N, of top layers given as arrays (...) (theta in rad; t, h, their
    wall heads' x and the heads' x of the closed layer below, mm) in ``scene`` (a
    model.load_path.MemberScene): the frame's chain from the block to the cap's centre (module
    docstring) under 1/2 N down on the half cell, the centre held from moving along x and from
    turning. ``cap_factor``, ``plate_factor``: those members' (and their roots') stiffness times
    that (inf: rigid; arrays broadcast with the stacks); ``offsets``: False puts the walls' ends on
    the members' mid-planes (the study's control)."""
    s = scene
    theta, t, h = (np.asarray(v, dtype=float) for v in (theta_rad, t_mm, h_mm))
    x_head, x_block = np.asarray(head_mm, dtype=float), np.asarray(head_below_mm, dtype=float)
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    ED = E * D
    L = wall_centreline_length_mm(theta, t, h)
    root = root_spring_Nmm_per_rad(theta, t, L, D, E)
    z_pocket = t + s.pocket_floor_mm
    EI_c, kGA_c = section_EI_kGA(
        D, t + s.cap_above_stack_mm, E, G, s.pocket_width_mm, (z_pocket, z_pocket + s.pocket_depth_mm),
        s.insert, t + s.insert_above_pad_mm,
    )  # fmt: skip
    d = s.plate_mm + t  # the plate and the pad over it
    EI_p, kGA_p = section_EI_kGA(D, d, E, G)
    z_foot, z_head = 0.5 * t, h - 0.5 * t  # the wall's centre line: foot, head (the plate's top at z = 0)
    e_cap, e_plate = (0.5 * s.cap_above_stack_mm, 0.5 * s.plate_mm) if offsets else (0.0, 0.0)
    xz = lambda x, z: np.stack(np.broadcast_arrays(x, z), axis=-1)  # noqa: E731
    tip = xz(0.0 * x_head, z_head + e_cap)
    foot, vertex, head = xz(x_head, z_foot), xz(x_head + L * np.cos(theta), 0.5 * h), xz(x_head, z_head)
    plate_end, edge = xz(x_head, z_foot - e_plate), xz(np.minimum(x_block, x_head), z_foot - e_plate)
    cap_f, plate_f = np.asarray(cap_factor, dtype=float), np.asarray(plate_factor, dtype=float)

    def turn_only(k) -> np.ndarray:
        f = np.zeros(np.shape(k) + (3, 3))
        f[..., 2, 2] = 1.0 / k
        return f

    wall = (ED * t, ED * t**3 / 12.0, 5.0 / 6.0 * G * D * t)
    hangs = x_head > x_block  # the feet beyond the block's edge: the plate hangs from it
    c = np.where(hangs, x_head - x_block, 1.0)  # a dummy length where the feet stand on the block
    plate = beam_flexibility(xz(x_head - c, z_foot - e_plate), plate_end, np.inf, EI_p * plate_f, kGA_p * plate_f)
    members = (
        (edge, turn_only(LOCKED_FITTED[1] * ED * d * d * plate_f)),  # the plate's root in the block (past_lock)
        (plate_end, np.where(hangs[..., None, None], plate, 0.0)),
        (foot, turn_only(root * plate_f)),
        (vertex, beam_flexibility(foot, vertex, *wall)),
        (head, beam_flexibility(vertex, head, *wall)),
        (head, turn_only(root * cap_f)),
        (tip, beam_flexibility(xz(x_head, z_head + e_cap), tip, np.inf, EI_c * cap_f, kGA_c * cap_f)),
    )
    F = sum(np.swapaxes(load_transfer(b, tip), -1, -2) @ f @ load_transfer(b, tip) for b, f in members)
    Fz = -0.5
    held = F[..., [0, 2], :][..., :, [0, 2]]
    Fx, M = np.moveaxis(np.linalg.solve(held, -Fz * F[..., [0, 2], 1][..., None])[..., 0], -1, 0)
    return -(F[..., 1, 0] * Fx + F[..., 1, 1] * Fz + F[..., 1, 2] * M)


def thrust_extra_mm_per_N(scene, theta_rad, t_mm, h_mm, head_mm, head_below_mm) -> np.ndarray:
    """(...) what the cap and the plate under the top layer give together beyond each alone, mm/N,
    of top layers given as arrays (:func:`chain_drop_mm_per_N`'s): its four rigid cases in one
    call, signed as the module docstring says."""
    shape = np.broadcast_shapes(*(np.shape(v) for v in (theta_rad, t_mm, h_mm, head_mm, head_below_mm)))
    cases = np.array(RIGID_CASES).reshape((4, 2) + (1,) * len(shape))
    drops = chain_drop_mm_per_N(scene, theta_rad, t_mm, h_mm, head_mm, head_below_mm, cases[:, 0], cases[:, 1])
    return np.tensordot(np.array(RIGID_SIGNS), drops, axes=1)


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
