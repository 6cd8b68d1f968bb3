"""The plate over a locked layer: what it gives beyond its closed form while the layer above it
is still open (issue 44, docs/design.md 4.7).

mst stops a plate's bending when the layer under it locks (model.load_path: it closes that
layer's cavity). The whole-part rung takes a locked layer as closed, its cavity filled, as the
issue's independent model does, and finds the plate over it still giving several times the
upper layer's root joint (model.plate_joint) alone: 6.6 to 75 um/N on stacks whose joint there
is 4 to 30 (studies/locked_plates.py). Two things the closed form leaves out:

* **the upper walls' root turns unbalanced.** Between two open layers the plate sits on the
  lower walls' heads, whose root moment meets the upper walls' (the cell's mirror symmetry);
  over a filled layer nothing meets it, and the root turns further: the joint times (1 + a);
* **the feet above can overhang the block.** The filled layer's top ends at its wall heads;
  where the feet above stand further out (c = head above - head below > 0) the plate and the
  upper pad (p + t thick) hang as a cantilever c long from the block, its root turning against a
  spring k E'D (p + t)^2 (the form of an end built into a body of the same modulus):
  P c^3/(3 E'I) + P c/kGA + P c^2/(k E'D (p + t)^2), P = 1/2.

* **the foot presses into the block's edge.** Where B's feet stand on the block near its edge,
  or hang from it, the corner of the block under them gives way: g P/(E'D) e^(-s/t), s how far
  inside the edge the foot's centre line stands (0 where it hangs beyond), decaying over the
  foot's own width t (a strip's indentation of a body of its own modulus is of the order of
  1/(E'D), its logarithm left in g; under a quarter-plane, at the edge, it is largest). Thin
  feet well inside give nothing; B's 1.4 mm feet on the forward design, 0.25 mm inside layer
  2's heads, give most of what its plate 2 showed beyond the first two terms.

a and k are fitted, not derived: on the rung's plate over the locked lower layer of 25 stacks
A, B, A (each of 13, 20, 28, 40 and 57 degrees below and above, t 0.4, h 1.8 mm, 1.6 mm plates;
studies/locked_plates.py --fit, its data in studies/data/locked_plates.csv), they leave it
within 18 % (8 % rms), against the joint alone's 95 % (53 % rms). g is fitted with a and k held,
on those 25 and the 50 with B's walls 0.7 mm over 0.8 and 1.6 mm plates
(studies/data/locked_plates_thick.csv; docs/design.md 4.7, "The feet's press into the locked
block: built").
The filled block here is one layer on the rigid cover; a deeper block is softer (the bundled
designs, not in the fit, are its check). Pure numpy, no I/O.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mst_cli.model.beams import as_value, section_EI_kGA
from mst_cli.model.plate_joint import joint_scene, root_joint_mm_per_N

# studies/locked_plates.py --fit studies/data/locked_plates.csv (docs/design.md 4.7): the upper
# root's turn past the joint (a) and the overhang's root spring (k); the foot's press into the
# block's edge (g), fitted with a and k held (--fit-press, the thick walls' rows too)
LOCKED_FITTED = (0.446, 0.101, 0.836)
P_N = 0.5  # each side's share of a newton through the cell


def locked_plates_mm_per_N(
    theta_rad, t_mm, h_mm, head_mm, plate_mm: float, depth_mm: float, E_prime_MPa: float, G_MPa: float,
    constants: tuple[float, ...] = LOCKED_FITTED, joints_mm_per_N=None,
) -> Any:  # fmt: skip
    """(..., n - 1) what plate j gives, mm/N, while the layer under it is locked and the one
    above it open, beyond the upper layer's root joint on it (module docstring), of stacks given
    as arrays (..., n) of theta (rad), t, h and the wall heads' x (mm), bottom to top;
    ``joints_mm_per_N`` (..., n): every layer's root joint on one plate, when the caller has it."""
    theta, t, h, head = (np.asarray(v, dtype=float) for v in (theta_rad, t_mm, h_mm, head_mm))
    joint = None if joints_mm_per_N is None else np.asarray(joints_mm_per_N)[..., 1:]
    upper = upper_layer_terms(
        theta[..., 1:], t[..., 1:], h[..., 1:], plate_mm, depth_mm, E_prime_MPa, G_MPa, constants, joint
    )
    return plate_overhang_mm_per_N(head[..., 1:] - head[..., :-1], upper)


def upper_layer_terms(
    theta_rad, t_mm, h_mm, plate_mm: float, depth_mm: float, E_prime_MPa: float, G_MPa: float,
    constants: tuple[float, ...] = LOCKED_FITTED, joint_mm_per_N=None,
) -> tuple:  # fmt: skip
    """(a x the root joint, the overhang's E'I and kGA, its root spring, the foot's press at the
    block's edge g P/(E'D), the foot's width t) of the plate under layers of cells given as arrays
    (theta in rad, t, h in mm): what :func:`locked_plates_mm_per_N` takes from the open layer
    above the plate alone (the design's start reuses them over its table of cells, whatever layer
    is locked under it); ``joint_mm_per_N``: the cells' root joint (model.plate_joint), when the
    caller has it."""
    a, k, g = constants
    t = np.asarray(t_mm, dtype=float)
    upper = (
        root_joint_mm_per_N(theta_rad, t, h_mm, plate_mm, depth_mm, E_prime_MPa)
        if joint_mm_per_N is None
        else joint_mm_per_N
    )
    ED, thick = E_prime_MPa * depth_mm, plate_mm + t
    EI, kGA = section_EI_kGA(depth_mm, thick, E_prime_MPa, G_MPa)
    return a * np.asarray(upper), EI, kGA, k * ED * thick**2, edge_press_mm_per_N(g, plate_mm, depth_mm, E_prime_MPa), t


def edge_press_mm_per_N(g: float, plate_mm: float, depth_mm: float, E_prime_MPa: float) -> float:
    """The feet's press at the block's edge, g P/(E'D), mm/N (module docstring; ``plate_mm``
    unused, in model.plate_joint.joint_scene's order)."""
    return g * P_N / (E_prime_MPa * depth_mm)


def plate_overhang_mm_per_N(c_mm, upper_terms: tuple) -> Any:
    """:func:`locked_plates_mm_per_N` of feet standing ``c_mm`` beyond the locked layer's wall
    heads (negative: inside them), the layer above given by its :func:`upper_layer_terms`."""
    joint, EI, kGA, root, _, _ = upper_terms
    c = np.maximum(c_mm, 0.0)
    bends = P_N * (c**3 / (3.0 * EI) + c / kGA + c * c / root)
    return as_value(joint + bends + foot_press_mm_per_N(c_mm, *upper_terms[4:]))


def foot_press_mm_per_N(c_mm, press_mm_per_N, foot_mm) -> Any:
    """The part of :func:`plate_overhang_mm_per_N` that is the feet's press into the block's edge
    (module docstring), feet ``foot_mm`` wide standing ``c_mm`` beyond it, ``press_mm_per_N`` its
    g P/(E'D): a centred press's term, which under a moment or a pull acts as the layer's own
    axial give, not as the plate's bending (model.part_laws.unit_members)."""
    inside = np.maximum(-np.asarray(c_mm, dtype=float), 0.0)
    return as_value(press_mm_per_N * np.exp(-inside / foot_mm))


def over_two_locked_mm_per_N(
    t_mm, h_mm, head_mm, plate_mm: float, depth_mm: float, E_prime_MPa: float, G_MPa: float, upper_terms: tuple,
    k: float = LOCKED_FITTED[1],
) -> Any:  # fmt: skip
    """What plate j gives, mm/N, while layers j - 1 and j are both locked and j + 1 open (module
    docstring), of three consecutive layers given as arrays (..., 3) of t, h and the wall heads' x
    (mm): where block j stands out beyond block j - 1 (its heads further out), plate j - 1, block j
    and plate j hang together from block j - 1 out to layer j + 1's feet, a cantilever d = 2 p +
    h_j + t_(j+1) deep built into block j - 1 (the root spring k E'D d^2 of a plate over one
    block; its turn under P (deep + thin) less P thin, which block j's own root takes, so the
    figure is continuous where block j's edge meets block j - 1's); beyond block j plate j hangs on
    as over one block (:func:`plate_overhang_mm_per_N`, ``upper_terms`` of layer j + 1). Where
    block j stands inside block j - 1, the plate over one block alone."""
    t, h, head = (np.asarray(v, dtype=float) for v in (t_mm, h_mm, head_mm))
    low, mid, feet = head[..., 0], head[..., 1], head[..., 2]
    thin = np.maximum(feet - mid, 0.0)
    deep = np.where(mid > low, np.maximum(np.minimum(feet, mid) - low, 0.0), 0.0)
    d = 2.0 * plate_mm + h[..., 1] + t[..., 2]
    EI, kGA = section_EI_kGA(depth_mm, d, E_prime_MPa, G_MPa)
    P, lever = 0.5, deep + thin
    hangs = P * ((deep**3 / 3.0 + deep * deep * thin + deep * thin * thin) / EI + deep / kGA)
    # block j - 1's root turns under the composite's moment P (deep + thin), less what block j's own
    # root (in plate_overhang_mm_per_N) takes: nothing more as block j's edge nears block j - 1's
    root = P * (lever * lever - thin * thin) / (k * E_prime_MPa * depth_mm * d * d)
    return as_value(plate_overhang_mm_per_N(feet - mid, upper_terms) + hangs + root)


def scene_locked_plates_mm_per_N(scene, theta_rad, t_mm, h_mm, head_mm, joints_mm_per_N=None) -> tuple:
    """(:func:`locked_plates_mm_per_N`, each plate's while the layer under that one is locked too,
    :func:`over_two_locked_mm_per_N`, the bottom plate's the same; the part of both that is the
    feet's press, :func:`foot_press_mm_per_N`) of the part a model.load_path.MemberScene
    describes, arrays (..., n - 1)."""
    G, fitted, plates = scene.G_MPa, LOCKED_FITTED, joint_scene(scene)
    one = np.asarray(locked_plates_mm_per_N(theta_rad, t_mm, h_mm, head_mm, *plates, G, fitted, joints_mm_per_N))
    t, h, head = (np.asarray(v, dtype=float) for v in (t_mm, h_mm, head_mm))
    press = foot_press_mm_per_N(head[..., 1:] - head[..., :-1], edge_press_mm_per_N(fitted[2], *plates), t[..., 1:])
    two = [one[..., :1]]
    for j in range(1, t.shape[-1] - 1):
        joint = None if joints_mm_per_N is None else np.asarray(joints_mm_per_N)[..., j + 1]
        cell = (np.asarray(theta_rad)[..., j + 1], t[..., j + 1], h[..., j + 1])
        upper = upper_layer_terms(*cell, *plates, G, fitted, joint)
        span = slice(j - 1, j + 2)
        over_two = over_two_locked_mm_per_N(t[..., span], h[..., span], head[..., span], *plates, G, upper)
        two.append(np.asarray(over_two)[..., None])
    return one, np.concatenate(two, axis=-1), np.asarray(press, dtype=float)


def by_regime(locked_plates_mm_per_N, lock_N, over_two_locked_mm_per_N=None) -> np.ndarray:
    """(..., n + 1) what the plates over locked layers add per regime of the part, past the last
    lock too (model.stack.regime_extra_displacement_mm): regime r (from 0, in the order of
    ``lock_N`` (..., n), each layer's lock force) has its r first layers locked, and plate j
    gives its share (``locked_plates_mm_per_N`` (..., n - 1)) while layer j is locked and layer
    j + 1 open, ``over_two_locked_mm_per_N`` (the same shape; None: the same) while layer j - 1
    is locked too."""
    X, R = np.asarray(locked_plates_mm_per_N, dtype=float), np.asarray(lock_N, dtype=float)
    X2 = X if over_two_locked_mm_per_N is None else np.asarray(over_two_locked_mm_per_N, dtype=float)
    rank = np.argsort(np.argsort(R, axis=-1, kind="stable"), axis=-1, kind="stable")  # each layer's place
    locked = rank[..., None, :] < np.arange(R.shape[-1] + 1)[:, None]  # (..., regimes, layers)
    acts = locked[..., :-1] & ~locked[..., 1:]
    below = np.concatenate([np.zeros_like(locked[..., :1]), locked[..., :-2]], axis=-1)  # layer j - 1 locked
    return np.where(acts, np.where(below, X2[..., None, :], X[..., None, :]), 0.0).sum(axis=-1)
