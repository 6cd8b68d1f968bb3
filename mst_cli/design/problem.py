"""The inverse-design problem: variables, targets, constraints and the preference, vectorised.

Every function here takes arrays of candidate designs (any leading shape) and evaluates them
with the same kernels the forward model uses (``spring_arrays``, ``unloaded_gap_mm``,
``regime_kernel``, ``cell_margins_mm``), so thousands of candidates cost one numpy call.

Variables
    Per layer theta (deg), t (mm), h (mm), optimised as u in [0, 1]^(3n), layer-major
    (theta_1, t_1, h_1, theta_2, ...). theta maps linearly onto its bounds; t and h map
    logarithmically, because the wall stiffness goes like (t/L)^3: equal steps in u are then
    equal *relative* changes of k, which keeps one initial step right for every layer.

Match objective (phase 1)
    sum_i w_i [ ln(S_i / S*_i)^2 + ln(R_i / R*_i)^2 ],  R_i the lock force of layer i (file
    order, bottom to top) and S_i the secant sensitivity of regime i. The log makes a 2 % miss
    of a 0.03 1/N target weigh as much as a 2 % miss of a 0.26 1/N one.

Constraints (g <= 0 is satisfied; every g is scaled to order one)
    * cell rules of :func:`~mst_cli.model.cell.cell_margins_mm` for every layer, in nozzles;
    * wall slenderness t/L at most the largest t/L L0's corrections were fitted on
      (:func:`~mst_cli.model.mechanics.correction.fitted_t_over_L_max`);
    * lock order with margin: R_(i+1) >= (1 + lock_margin_rel) R_i, so regime i ends when layer
      i locks and the layers lock bottom to top in file order;
    * chip below saturation: |B| at the last lock (at gap 0 when the magnet would reach the chip
      before it) <= (1 - saturation_margin_rel) x 50 mT, and
      never above what the MLX90393's coarsest setting reads with the headroom
      :func:`~mst_cli.model.chip.choose_setting` keeps;
    * optional total height: SensorGeometry.total_height_mm <= design.max_height_mm;
    * optional print deviation (``design.max_print_deviation_rel``): every S_i and R_i changes by
      at most that fraction when every wall is printed +- printer.wall_tolerance_mm (one smooth
      constraint per output and sign, so the worst case is a constraint, not only a weight).

The part as printed (docs/design.md section 10)
    The variables are the walls as drawn; the physics sees the walls as printed, t +
    printer.wall_offset_mm, with the modulus times printer.modulus_factor and the gap plus
    printer.gap_offset_mm (what ``mst calibrate`` fitted on an earlier print), built into the
    housing as ``mst simulate`` builds it (the cover's air first: where the cover lands). The cell rules
    judge the drawing (what the slicer gets); the t/L range of L0's fit judges the printed wall.

Preference among the designs that meet the targets (phase 2, ``design.objective``)
    Three variables per layer and two targets leave one spare degree of freedom per layer.
    The tool spends it on a weighted sum of three terms, each a log so that a weight prices a
    *relative* change the same anywhere (:data:`OBJECTIVE_TERMS`):

    * ``height``: ln(total part height / mm) -- a fingertip has to be small;
    * ``force_resolution``: ln(worst force resolution / N), the noise-limited
      sigma_B / (B0 min_i S_i): with the S_i pinned by the targets this rewards a strong B0,
      i.e. a magnet close to the chip. The chip's quantisation is left out here because it
      is a step function of the chosen setting (and below the default 2 uT noise for every
      setting that holds <= 50 mT); the report gives the exact figure;
    * ``print_robustness``: how much S_i and R_i move when *every* wall is printed
      printer.wall_tolerance_mm (default 0.05 mm) thicker or thinner than expected (extrusion
      width drifts with the filament and the flow calibration, the same way for every wall of
      one print): the RMS over the 2n outputs and both signs of ln(out(t +- tol) / out(t));
      reported per layer, beside the worst relative change of any output (the verification,
      :func:`mst_cli.design.verify.verify_design`, measures both on the forward model).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, cast

import numpy as np

from mst_cli.model import chip as mlx
from mst_cli.model.assembly import unloaded_gap_mm
from mst_cli.model.cell import CELL_RULES, LENGTH_FLOOR_MM, cell_margins_mm, wall_centreline_length_mm
from mst_cli.model.load_path import layer_caps_mm_per_N, member_scene, moving_share
from mst_cli.model.magnet_field import axial_Bz_T, choose_field_model
from mst_cli.model.material import Material
from mst_cli.model.mechanics import correction
from mst_cli.model.mechanics.depth import web_modulus_MPa
from mst_cli.model.mechanics.spring import spring_arrays
from mst_cli.model.past_lock import by_regime
from mst_cli.model.response import capped_lock_forces_N, field_magnitude_T, regime_kernel
from mst_cli.model.stack import contact_force_N, run_on
from mst_cli.sensor.as_printed import housing_as_printed
from mst_cli.sensor.sections import DEFAULT_OBJECTIVE, OBJECTIVE_TERMS

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from mst_cli.model.arrays import Floats
    from mst_cli.sensor.document import Document

# headroom choose_setting keeps between the largest field and a setting's range (one source)
CHIP_HEADROOM = inspect.signature(mlx.choose_setting).parameters["margin"].default
TINY = 1e-300  # floor of anything a log is taken of (a collapsed output, not a crash)
VIOLATION_PENALTY = 10.0  # merit per unit of constraint violation (g is scaled to order one)
DEDUPE_MIN_CELLS = 64  # below this many cells, sorting out repeats costs more than it saves
ROUNDING_SAFETY = 1e-3  # constraint slack (nozzles / log units) so that the rounded
# design written to design.yaml still satisfies every rule


@dataclass
class Evaluation:
    """Everything the optimiser needs about a batch of candidates (leading shape ``...``)."""

    theta_deg: np.ndarray  # (..., n)
    t_mm: np.ndarray  # (..., n)
    h_mm: np.ndarray  # (..., n)
    R_N: np.ndarray  # (..., n) lock force of each layer, file order
    S_per_N: np.ndarray  # (..., n) secant sensitivity of regime i (sorted locks)
    B_full_T: np.ndarray  # (...)   |B| at the last lock
    B0_T: np.ndarray  # (...)   |B| unloaded
    gap0_mm: np.ndarray  # (...)
    total_height_mm: np.ndarray  # (...)
    cell_margins_mm: np.ndarray  # (..., n, len(CELL_RULES))
    log_err: np.ndarray  # (..., 2n) ln(S/S*) for every regime, then ln(R/R*)
    constraints: np.ndarray  # (..., m) g <= 0 satisfied
    objective: np.ndarray  # (...)  weighted sum of squared log errors

    @property
    def feasible(self) -> np.ndarray:
        return np.all(self.constraints <= 0.0, axis=-1)

    @property
    def violation(self) -> np.ndarray:
        """Sum of positive constraint values (0 for a feasible candidate)."""
        return np.sum(np.maximum(self.constraints, 0.0), axis=-1)

    def merit(self, slack: float = 0.0) -> np.ndarray:
        """Match objective plus VIOLATION_PENALTY x the violation of the constraints tightened by
        ``slack``: how screening and the starts rank candidates that may break a rule."""
        violation = np.sum(np.maximum(self.constraints + slack, 0.0), axis=-1)
        return np.where(np.isfinite(self.objective), self.objective, 1e30) + VIOLATION_PENALTY * violation

    @property
    def rel_err(self) -> np.ndarray:
        """Relative errors out/target - 1, same layout as ``log_err``."""
        return np.expm1(self.log_err)

    @property
    def safe_constraints(self) -> np.ndarray:
        """The constraints tightened by ROUNDING_SAFETY: what the search holds <= 0."""
        return self.constraints + ROUNDING_SAFETY

    @property
    def max_err(self) -> np.ndarray:
        """Worst |relative error| of each candidate."""
        return np.max(np.abs(self.rel_err), axis=-1)


def robustness_of_shifts(d: np.ndarray, first: int = 0) -> np.ndarray:
    """RMS over both signs and all outputs of :meth:`DesignProblem.print_shift_log`'s (2, ..., 2n);
    ``first``: the axis of the signs (1: a stack of such arrays along a leading axis).
    np.mean's own arithmetic (a sum, then a division by the count) without its wrapper's cost."""
    return np.sqrt(np.add.reduce(d**2, axis=(first, -1)) / (d.shape[first] * d.shape[-1]))


class DesignProblem:
    """The targets, bounds and constants of one spec document, with vectorised evaluation.

    Parameters
    ----------
    doc : mst_cli.sensor.document.Document
        A spec: every layer has ``target_sensitivity_per_N`` and ``target_range_N``.
    """

    def __init__(self, doc: Document):
        doc.require_targets()
        self.doc = doc
        self.n = len(doc.layers)
        d = doc.design
        self.tolerance_rel = float(d["tolerance_rel"])
        self.lock_margin_rel = float(d["lock_margin_rel"])
        self.saturation_margin_rel = float(d["saturation_margin_rel"])
        self.max_height_mm = d.get("max_height_mm")
        self.lo = np.array([d["theta_deg_bounds"][0], d["t_mm_bounds"][0], d["h_mm_bounds"][0]])
        self.hi = np.array([d["theta_deg_bounds"][1], d["t_mm_bounds"][1], d["h_mm_bounds"][1]])
        self.S_target = np.array([la.target_sensitivity_per_N for la in doc.layers], dtype=float)
        self.R_target = np.array([la.target_range_N for la in doc.layers], dtype=float)
        self.weights = np.array([la.weight for la in doc.layers], dtype=float)
        self.family = doc.family
        self.printer = doc.printer
        # the part as printed: walls + offset, modulus x factor, gap + offset (module docstring)
        self.wall_offset_mm = float(doc.printer.wall_offset_mm)
        self.wall_tolerance_mm = float(doc.printer.wall_tolerance_mm)
        self.E_MPa = doc.material.youngs_modulus_MPa * doc.printer.modulus_factor
        self.max_print_deviation_rel = d.get("max_print_deviation_rel")
        self.nu = doc.material.poisson_ratio
        self.noise_T = 1e-6 * doc.noise_uT_rms
        objective = {**DEFAULT_OBJECTIVE, **(d.get("objective") or {})}  # documents built in code
        self.objective_weights = np.array([objective[k] for k in OBJECTIVE_TERMS], dtype=float)

        # a probe geometry (any cells) gives the field scene and the fixed height offsets
        probe_cells = [doc.family.cell(45.0, 1.0, 3.0) for _ in range(self.n)]
        probe = doc.geometry(probe_cells)
        self.probe = probe
        # the housing as built (printer.gap_offset_mm in its clearance, else its floor and
        # cover), as mst simulate builds it: the gap, the cover's air and the slot walls
        printed_probe = replace(doc, housing=housing_as_printed(doc)).geometry(probe_cells)
        self.printed_housing = printed_probe.housing
        requested = None if doc.field_model == "auto" else doc.field_model
        self.field_model = choose_field_model(probe.chip_offset_mm, probe.magnet_tilt_deg, requested)
        self.height_offset_mm = probe.total_height_mm - sum(c.h_mm for c in probe_cells)
        # the whole part: the cap, plates and cover in series with the layers, in the printed
        # TPU, under a fingertip's press (docs/design.md 4.6); the cells come per candidate
        self.whole_part = doc.whole_part  # model.load_path: part (else the layers alone)
        printed_tpu = Material(doc.material.name, self.E_MPa, self.nu)
        self.members = member_scene(printed_probe, printed_tpu)
        # section rounds (design.document): the rung's correction held (mm/N a regime); the box |u - centre| <= radius
        self.regime_extra_mm_per_N: np.ndarray | None = None
        self.trust_region: tuple[np.ndarray, float] | None = None
        self.B_limit_T = min(1.0 - self.saturation_margin_rel, 1.0 / CHIP_HEADROOM) * mlx.SATURATION_T
        # L0's fitted corrections hold for walls up to this t/L; stubbier walls are extrapolation
        # (the design loop otherwise drifts there: it is where k and R grow fastest)
        self.t_over_L_max = correction.fitted_t_over_L_max()
        self._spec_constraints = (
            self.n * len(CELL_RULES)
            + self.n
            + (self.n - 1)
            + 1
            + (1 if self.max_height_mm is not None else 0)
            + (8 * self.n if self.max_print_deviation_rel is not None else 0)
        )

    @property
    def n_constraints(self) -> int:
        return self._spec_constraints + (self.dim if self.trust_region is not None else 0)

    # ----------------------------------------------------------------- variables
    @property
    def dim(self) -> int:
        return 3 * self.n

    def to_physical(self, u: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(theta_deg, t_mm, h_mm), each (..., n), from normalised u (..., 3n)."""
        return self.cell_to_physical(np.asarray(u, dtype=float).reshape(np.shape(u)[:-1] + (self.n, 3)))

    def cell_to_physical(self, u_cell: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(theta_deg, t_mm, h_mm), each (...), of single cells from normalised (..., 3)."""
        u = np.asarray(u_cell, dtype=float)
        theta = self.lo[0] + u[..., 0] * (self.hi[0] - self.lo[0])
        t = self.lo[1] * (self.hi[1] / self.lo[1]) ** u[..., 1]
        h = self.lo[2] * (self.hi[2] / self.lo[2]) ** u[..., 2]
        return theta, t, h

    def to_unit(self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike) -> np.ndarray:
        """Inverse of :meth:`to_physical` (not clipped)."""
        u0 = (np.asarray(theta_deg, float) - self.lo[0]) / (self.hi[0] - self.lo[0])
        u1 = np.log(np.asarray(t_mm, float) / self.lo[1]) / math.log(self.hi[1] / self.lo[1])
        u2 = np.log(np.asarray(h_mm, float) / self.lo[2]) / math.log(self.hi[2] / self.lo[2])
        u = np.stack([u0, u1, u2], axis=-1)
        return u.reshape(u.shape[:-2] + (3 * self.n,))

    # ----------------------------------------------------------------- physics
    def field_T(self, gap_mm: ArrayLike) -> np.ndarray:
        """|B| (T) at the chip for an array of gaps: the forward model's field, same model."""
        if self.field_model == "axial":
            m = self.probe.magnet
            return axial_Bz_T(gap_mm, m.radius_mm, m.thickness_mm, m.remanence_T)
        gap = np.asarray(gap_mm, dtype=float)  # magpylib takes a flat list of observers
        return field_magnitude_T(gap.ravel(), self.probe, self.field_model).reshape(gap.shape)

    def gap0_mm(self, sum_h_mm: Floats) -> Floats:
        """Unloaded magnet-to-chip gap, as built, of stacks whose layer heights add up to ``sum_h_mm``."""
        return unloaded_gap_mm(sum_h_mm, self.n, self.printed_housing, self.probe.board)

    def layer_constraints(self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike) -> np.ndarray:
        """The rules each layer meets on its own, (..., len(CELL_RULES) + 1), g <= 0 satisfied:
        the cell rules in nozzles (drawn walls), then the printed wall's t/L over the largest t/L
        L0 is fitted on, minus 1."""
        margins, t_over_L_g = self._layer_rules(theta_deg, t_mm, h_mm)
        return np.concatenate([-margins / self.printer.nozzle_mm, t_over_L_g[..., None]], axis=-1)

    def _layer_rules(self, theta_deg, t_mm, h_mm):
        """(cell margins in mm (..., len(CELL_RULES)), t/L constraint (...)) of cells."""
        fam, pr = self.family, self.printer
        theta = np.radians(theta_deg)
        margins = cell_margins_mm(
            theta, t_mm, h_mm, fam.width_mm, fam.contact_allowance_mm, pr.min_wall_mm, pr.min_gap_mm, pr.nozzle_mm
        )
        t_printed = np.maximum(np.asarray(t_mm) + self.wall_offset_mm, LENGTH_FLOOR_MM)
        t_over_L = t_printed / wall_centreline_length_mm(theta, t_printed, h_mm)
        return margins, t_over_L / self.t_over_L_max - 1.0

    def layer_laws(
        self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """L0 laws (k, d_lock, R, k_locked) of every cell as printed (``t_mm`` drawn, the law's
        wall t + printer.wall_offset_mm, its modulus times printer.modulus_factor), each distinct
        cell computed once.

        The batches the solver sends repeat cells: a finite-difference gradient moves one
        variable per neighbour, so its 2 x 3n + 1 stacks of n cells hold only n + 6n distinct
        cells (84 of 876 at 12 layers), and the print-robustness term sends each of them at
        three wall thicknesses. Sorting the cells (a lexsort, far cheaper than the kernel) and
        computing the distinct ones makes a gradient's spring-law cost linear in the layer count
        instead of quadratic. The kernel gives a cell the same bits in any batch
        (tests/test_spring.py), so this changes no number.
        """
        shape, (theta, t, h), inverse = self._distinct_cells(theta_deg, t_mm, h_mm)
        laws = self._cell_laws(theta, t, h)
        if inverse is not None:
            laws = tuple(a[inverse] for a in laws)
        k, d_lock, R, k_locked = (a.reshape(shape) for a in laws)
        return k, d_lock, R, k_locked

    def shifted_layer_laws(
        self, theta_deg: np.ndarray, t_mm: np.ndarray, h_mm: np.ndarray, dt_mm: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`layer_laws` of the cells with walls t, t + dt and t - dt (each floored at
        LENGTH_FLOOR_MM), stacked on a new first axis of 3: the distinct drawn cells are
        found once (in a third of the cells) and every one computed at the three thicknesses.
        A cell's law has the same bits in any batch, so these are layer_laws' numbers."""
        shape, (theta, t, h), inverse = self._distinct_cells(theta_deg, t_mm, h_mm)
        floor = LENGTH_FLOOR_MM
        t3 = np.concatenate([t, np.maximum(t + dt_mm, floor), np.maximum(t - dt_mm, floor)])
        laws = self._cell_laws(np.concatenate([theta] * 3), t3, np.concatenate([h] * 3))
        distinct = np.arange(len(t)) if inverse is None else inverse
        index = np.arange(3)[:, None] * len(t) + distinct  # (3, cells)
        k, d_lock, R, k_locked = (a[index].reshape((3,) + shape) for a in laws)
        return k, d_lock, R, k_locked

    def _distinct_cells(self, theta_deg, t_mm, h_mm) -> tuple[tuple, tuple, np.ndarray | None]:
        """(the cells' shape, their distinct (theta, t, h) as contiguous columns, the index of
        every cell among them, or None when they were not sorted out: fewer than DEDUPE_MIN_CELLS)."""
        columns = np.broadcast_arrays(theta_deg, t_mm, h_mm)
        if columns[0].size < DEDUPE_MIN_CELLS:  # the same columns, without the stacking
            return columns[0].shape, tuple(np.ravel(a) for a in columns), None
        flat = np.stack(columns, axis=-1).reshape(-1, 3)
        order = np.lexsort(flat.T[::-1])
        ordered = flat[order]
        first = np.concatenate([[True], np.any(ordered[1:] != ordered[:-1], axis=1)])
        inverse = np.empty(len(flat), dtype=np.intp)
        inverse[order] = np.cumsum(first) - 1
        theta, t, h = np.ascontiguousarray(ordered[first].T)  # contiguous columns: numpy's vector loops
        return columns[0].shape, (theta, t, h), inverse

    def _cell_laws(self, theta: np.ndarray, t: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, ...]:
        """(k, d_lock, R, k_locked) of cells given as 1-d columns, the walls as drawn."""
        fam = self.family
        if self.wall_offset_mm:
            t = np.maximum(t + self.wall_offset_mm, LENGTH_FLOOR_MM)
        theta_rad = np.radians(theta)
        E = web_modulus_MPa(theta_rad, t, h, fam.depth_mm, self.E_MPa, self.nu)  # as mechanics.layer_laws
        return spring_arrays(theta_rad, t, h, fam.depth_mm, fam.width_mm, fam.contact_allowance_mm, E, self.nu)

    def responses(
        self, theta_deg: np.ndarray, t_mm: np.ndarray, h_mm: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(R_N per layer, S_per_N per regime, B_full_T, gap0_mm, B0_T) of candidate stacks."""
        members = self.part_members(theta_deg, t_mm, h_mm) if self.whole_part else None
        return self._responses_of(self.layer_laws(theta_deg, t_mm, h_mm), h_mm, members)

    def member_parts(self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike, edges_N: ArrayLike) -> tuple:
        """(cap (...), plates (..., n - 1), cover (..., bands)) compliance in mm/N of candidate
        stacks (with the joints of the layer under each, model.plate_joint), walls as printed, the
        cover's over each force band between ``edges_N`` (..., bands + 1): its slot walls, and its
        bending over the slot until it lands on the board (the band's mean, as a secant sees it)."""
        caps, cover, (over_slot, air_mm, over_locked, delta), _ = self.part_members(theta_deg, t_mm, h_mm)
        cap, plates, edges = caps[..., -1], caps[..., :-1], np.asarray(edges_N, dtype=float)
        R1 = edges[..., 1:2]  # layer 1 locks first, at the first band's end (the targets rise)
        past = edges[..., :-1] >= R1
        lands_N = contact_force_N(R1[..., 0], over_slot, over_locked, air_mm)
        bending = np.where(past, over_locked[..., None], over_slot[..., None]) * moving_share(lands_N, edges)
        walls = np.where(past, (cover + delta - over_locked)[..., None], (cover - over_slot)[..., None])
        return cap, plates, walls + bending

    def printed_t_mm(self, t_mm: ArrayLike) -> np.ndarray:
        """Walls as printed (drawn + printer.wall_offset_mm, floored): what the members rest on."""
        t = np.asarray(t_mm, dtype=float)
        return np.maximum(t + self.wall_offset_mm, LENGTH_FLOOR_MM) if self.wall_offset_mm else t

    def part_members(self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike) -> tuple:
        """(each layer's cap (..., n): the plate above it or the cap, and its joints (model.plate_joint);
        the cover; (its bending over the slot, the air under it, that bending once layer 1 is
        locked, the cover's change then): model.stack's contact; the plates over locked layers
        (..., n - 1), model.past_lock) of candidate stacks."""
        t = self.printed_t_mm(t_mm)
        caps, over, walls, locked, (over_l, walls_l) = layer_caps_mm_per_N(self.members, np.radians(theta_deg), t, h_mm)
        return caps, over + walls, (over, self.members.cover_air_mm, over_l, over_l + walls_l - over - walls), locked

    def _responses_of(
        self, laws: tuple, h_mm: np.ndarray, members: tuple | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`responses` of stacks whose layer laws (and members, :meth:`part_members`) are known:
        R is each layer's lock force, where the plate or cap above it closes its cavity."""
        k, d_lock, R, k_locked = laws
        cap, rest, contact, locked = (None, 0.0, None, None) if members is None else members
        gap0 = cast(np.ndarray, self.gap0_mm(h_mm.sum(axis=-1)))  # candidates' sums: an array
        Rc = capped_lock_forces_N(k, d_lock, R, cap)
        held = self.regime_extra_mm_per_N  # the rung's correction, of the problem's stacks (not one cell's)
        section = run_on(held) if held is not None and len(held) == Rc.shape[-1] else 0.0
        extra = None if members is None else by_regime(locked[0], Rc, locked[1]) + section
        _, S, gap, B = regime_kernel(k, d_lock, k_locked, gap0, self.field_T, R, rest, cap, contact, extra, Rc)
        # the chip's largest field on the way is at the smallest gap: a stack whose members let
        # the magnet reach the chip (gap <= 0 at the last lock) saturates it on the way there
        B_full = np.where(gap[..., -1] > 0.0, B[..., -1], self.field_T(np.zeros_like(gap[..., -1])))
        return Rc, S, B_full, gap0, B[..., 0]

    def evaluate_physical(self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike) -> Evaluation:
        return self._evaluate_physical(theta_deg, t_mm, h_mm, False)[0]

    def evaluate_with_shifts(self, u: np.ndarray) -> tuple[Evaluation, np.ndarray]:
        """(:meth:`evaluate`, :meth:`print_shift_log` of the same candidates), the nominal and
        the two print-shifted stacks through the kernels in one call: each candidate's numbers
        are, to the bit, those of the two calls (the kernels give a stack the same bits in any
        batch)."""
        ev, shifts = self._evaluate_physical(*self.to_physical(u), True)
        assert shifts is not None  # asked for
        return ev, shifts

    def _evaluate_physical(self, theta_deg, t_mm, h_mm, with_shifts: bool) -> tuple[Evaluation, np.ndarray | None]:
        theta_deg, t_mm, h_mm = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (theta_deg, t_mm, h_mm)))
        pr = self.printer
        shifts = None
        if with_shifts:  # nominal, thicker, thinner walls (print_shift_log's steps)
            laws = self.shifted_layer_laws(theta_deg, t_mm, h_mm, self.wall_tolerance_mm)
            H = np.broadcast_to(h_mm, (3,) + h_mm.shape)
            dt = self.wall_tolerance_mm  # the members see the shifted walls too
            T3 = np.stack([t_mm, np.maximum(t_mm + dt, LENGTH_FLOOR_MM), np.maximum(t_mm - dt, LENGTH_FLOOR_MM)])
            members = self.part_members(theta_deg, T3, H) if self.whole_part else None
            R3, S3, B_full3, gap03, B03 = self._responses_of(laws, H, members)
            R, S, B_full, gap0, B0 = R3[0], S3[0], B_full3[0], gap03[0], B03[0]
            logs = np.log(np.maximum(np.concatenate([S3, R3], axis=-1), TINY))  # nominal, thicker, thinner
            shifts = logs[1:] - logs[:1]
        else:
            R, S, B_full, gap0, B0 = self.responses(theta_deg, t_mm, h_mm)
        margins, t_over_L_g = self._layer_rules(theta_deg, t_mm, h_mm)
        height = self.height_offset_mm + h_mm.sum(axis=-1)

        logR = np.log(np.maximum(R, TINY))
        g = [(-margins / pr.nozzle_mm).reshape(margins.shape[:-2] + (-1,)), t_over_L_g]
        if self.n > 1:
            g.append(math.log1p(self.lock_margin_rel) - (logR[..., 1:] - logR[..., :-1]))  # np.diff's, unwrapped
        g.append(np.log(np.maximum(B_full, TINY) / self.B_limit_T)[..., None])
        if self.max_height_mm is not None:
            g.append(((height - self.max_height_mm) / pr.nozzle_mm)[..., None])
        if self.max_print_deviation_rel is not None:
            g.append(self.print_deviation_constraints(theta_deg, t_mm, h_mm, S, R, shifts))
        if self.trust_region is not None:  # <= 0 inside the box around the best design measured
            g.append(np.abs(self.to_unit(theta_deg, t_mm, h_mm) - self.trust_region[0]) / self.trust_region[1] - 1.0)
        constraints = np.concatenate(g, axis=-1)

        log_err = np.concatenate([np.log(np.maximum(S, TINY) / self.S_target), logR - np.log(self.R_target)], axis=-1)
        w = np.concatenate([self.weights, self.weights])
        objective = np.sum(w * log_err**2, axis=-1)
        return Evaluation(
            theta_deg, t_mm, h_mm, R, S, B_full, B0, gap0, height, margins, log_err, constraints, objective
        ), shifts

    def evaluate(self, u: np.ndarray) -> Evaluation:
        return self.evaluate_physical(*self.to_physical(u))

    # ----------------------------------------------------------------- preference
    def print_deviation_constraints(
        self,
        theta_deg: np.ndarray,
        t_mm: np.ndarray,
        h_mm: np.ndarray,
        S: np.ndarray,
        R: np.ndarray,
        shifts: np.ndarray | None = None,
    ) -> np.ndarray:
        """(..., 8n) g <= 0 when every output's change at t +- tolerance lies within
        +- design.max_print_deviation_rel: ln(1 - m) <= ln(out'/out) <= ln(1 + m), per sign and output.
        ``shifts``: the candidates' :meth:`print_shift_log`, when the caller has it."""
        m = self.max_print_deviation_rel
        assert m is not None  # only a spec with design.max_print_deviation_rel has these rows
        d = self.print_shift_log(theta_deg, t_mm, h_mm, nominal=(S, R)) if shifts is None else shifts  # (2, ..., 2n)
        g = np.concatenate([d - math.log1p(m), math.log1p(-m) - d], axis=-1)  # (2, ..., 4n)
        return np.moveaxis(g, 0, -2).reshape(g.shape[1:-1] + (-1,))

    def print_shift_log(
        self,
        theta_deg: ArrayLike,
        t_mm: ArrayLike,
        h_mm: ArrayLike,
        dt_mm: float | None = None,
        nominal: tuple | None = None,
    ) -> np.ndarray:
        """ln(out(t + s dt) / out(t)) for s = +1, -1: shape (2, ..., 2n), S then R; ``dt_mm``
        defaults to printer.wall_tolerance_mm.

        The stacks (nominal, thicker, thinner) go through the kernels in one call; ``nominal``
        = (S_per_N, R_N) of the unshifted stacks, when the caller has them, spares the first.
        """
        theta_deg, t_mm, h_mm = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (theta_deg, t_mm, h_mm)))
        dt_mm = self.wall_tolerance_mm if dt_mm is None else dt_mm
        steps = [0.0, dt_mm, -dt_mm] if nominal is None else [dt_mm, -dt_mm]
        shifts = np.array(steps).reshape((len(steps),) + (1,) * t_mm.ndim)
        T = np.broadcast_to(theta_deg, (len(steps),) + theta_deg.shape)
        H = np.broadcast_to(h_mm, (len(steps),) + h_mm.shape)
        R, S, _, _, _ = self.responses(T, np.maximum(t_mm + shifts, LENGTH_FLOOR_MM), H)
        out = np.log(np.maximum(np.concatenate([S, R], axis=-1), TINY))
        if nominal is None:
            return out[1:] - out[:1]
        base = np.log(np.maximum(np.concatenate([nominal[0], nominal[1]], axis=-1), TINY))
        return out - base[None]

    def print_robustness(
        self, theta_deg: ArrayLike, t_mm: ArrayLike, h_mm: ArrayLike, nominal: tuple | None = None
    ) -> np.ndarray:
        """Print robustness: RMS of :meth:`print_shift_log` over both signs and all 2n outputs."""
        return robustness_of_shifts(self.print_shift_log(theta_deg, t_mm, h_mm, nominal=nominal))

    def worst_force_resolution_N(self, ev: Evaluation) -> np.ndarray:
        """Noise-limited force resolution of the least sensitive regime, sigma_B / (B0 min S)."""
        return self.noise_T / np.maximum(ev.B0_T * np.min(ev.S_per_N, axis=-1), TINY)

    def objective_terms(self, ev: Evaluation, robustness: ArrayLike | None = None) -> np.ndarray:
        """The preference terms (..., len(OBJECTIVE_TERMS)) of evaluated candidates: ln height,
        ln worst force resolution, print robustness (computed unless given)."""
        if robustness is None:
            robustness = self.print_robustness(ev.theta_deg, ev.t_mm, ev.h_mm, nominal=(ev.S_per_N, ev.R_N))
        return np.stack(
            [
                np.log(ev.total_height_mm),
                np.log(self.worst_force_resolution_N(ev)),
                np.asarray(robustness, dtype=float),
            ],
            axis=-1,
        )

    def preference(
        self, ev: Evaluation, weights: ArrayLike | None = None, terms: np.ndarray | None = None
    ) -> np.ndarray:
        """Weighted sum of :meth:`objective_terms` (lower is better): what phase 2 minimises;
        ``terms``: those of ``ev``, when the caller has them (:meth:`evaluate_terms`)."""
        return self.weighted_terms(self.objective_terms(ev) if terms is None else terms, weights)

    def weighted_terms(self, terms: np.ndarray, weights: ArrayLike | None = None) -> np.ndarray:
        """The weighted sum of given :meth:`objective_terms` (``weights`` default design.objective)."""
        w = self.objective_weights if weights is None else np.asarray(weights, dtype=float)
        return terms @ w

    def evaluate_terms(self, u: np.ndarray) -> tuple[Evaluation, np.ndarray]:
        """(:meth:`evaluate`, :meth:`objective_terms`) of candidates, the print-shifted stacks of
        the robustness term in the same kernel call (:meth:`evaluate_with_shifts`)."""
        ev, shifts = self.evaluate_with_shifts(u)
        return ev, self.objective_terms(ev, robustness_of_shifts(shifts))

    # ----------------------------------------------------------------- reporting helpers
    def constraint_names(self) -> list[str]:
        """A readable name for every entry of ``Evaluation.constraints``."""
        names = [f"layer {i + 1} {rule}" for i in range(self.n) for rule in CELL_RULES]
        names += [
            f"layer {i + 1} wall t/L <= {self.t_over_L_max:.2f} (the range L0 is fitted on)" for i in range(self.n)
        ]
        names += [
            f"lock order: layer {i + 2} must lock >= {1 + self.lock_margin_rel:g} x layer {i + 1}"
            for i in range(self.n - 1)
        ]
        names.append(f"chip saturation: field at full load <= {self.B_limit_T * 1e3:.1f} mT")
        if self.max_height_mm is not None:
            names.append(f"total height <= {self.max_height_mm:g} mm")
        if self.max_print_deviation_rel is not None:
            m = self.max_print_deviation_rel
            outs = self.output_names()
            names += [
                f"print deviation: {o} at t {sign} {self.wall_tolerance_mm:g} mm {side} "
                f"{'+' if side == '<=' else '-'}{100 * m:g} %"
                for sign in "+-"
                for side in ("<=", ">=")
                for o in outs
            ]
        if self.trust_region is not None:
            names += [f"layer {i + 1} {v} within the trust region" for i in range(self.n) for v in ("theta", "t", "h")]
        return names

    def output_names(self) -> list[str]:
        return [f"S_{i + 1}" for i in range(self.n)] + [f"R_{i + 1}" for i in range(self.n)]

    @property
    def targets(self) -> np.ndarray:
        return np.concatenate([self.S_target, self.R_target])

    # ----------------------------------------------------------------- random valid designs
    def sample_feasible(
        self, rng: np.random.Generator, count: int, slack: float = 0.05, batch: int = 4096, max_batches: int = 200
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``count`` random designs that satisfy every constraint with ``slack`` to spare.

        Layers of each random candidate are re-ordered by lock force (so that they lock bottom
        to top) before the constraints are checked. Used to make random *reachable* specs for
        the round-trip test and the benchmark. Returns (theta_deg, t_mm, h_mm), each (count, n).
        """
        found = []
        total = 0
        for _ in range(max_batches):
            theta, t, h = self.to_physical(rng.random((batch, self.dim)))
            R, _, _, _, _ = self.responses(theta, t, h)
            order = np.argsort(R, axis=-1)
            theta, t, h = (np.take_along_axis(a, order, axis=-1) for a in (theta, t, h))
            ok = np.all(self.evaluate_physical(theta, t, h).constraints <= -slack, axis=-1)
            if ok.any():
                found.append(np.stack([theta[ok], t[ok], h[ok]]))
                total += int(ok.sum())
            if total >= count:
                break
        if total < count:
            raise RuntimeError(f"only {total} of {count} random designs satisfy the constraints")
        a = np.concatenate(found, axis=1)[:, :count]
        return a[0], a[1], a[2]
