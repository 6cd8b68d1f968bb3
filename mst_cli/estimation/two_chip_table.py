"""A fast reader of all five unknowns (Fz, Fx, Fy, x, y) from two chips or more (issue 39): the
general-load model (:mod:`mst_cli.model.general_load`) with its layers' states tabulated, and a
Levenberg-Marquardt fit of every reading at once.

Where the exact reader (:mod:`mst_cli.estimation.shear_reading`) spends its time is the tilt
rung's equilibrium, one scalar Newton solve per layer per load. A layer answers only to the
normal force and where it sees it pressed, (F, ox, oy) (the shear's moment moves that point by
lever_j (Fx, Fy) / Fz), so each layer's state (d, phi_y, phi_x) is tabulated once over
(F, |ox|, |oy|) nodes, the offsets past the face by lever_j x the largest shear ratio supported
(the cell is mirror symmetric in x and y: d is even in both offsets, phi_y odd in ox, phi_x odd
in oy, so a quadrant of nodes holds it all). Read trilinearly the tables are a guess, not the
answer: past the lock the pads' pressed patch bends the states between the offsets' nodes, and
on the bundled sensor (mohammadi2021-forward, spring, chips (0, 0) and (10, 6) mm, 200 random
loads over the tables' range) the trilinear field is a median 4 uT off (max 49 uT) at the default
nodes (2 mm, 33 forces) and still 1.2 uT (max 13 uT) at 1 mm and 65 forces, more than the chip
noise. From that guess a few steps of the same Newton, vectorised
(:mod:`mst_cli.model.mechanics.tilt_batch`), give the exact states: the field then within 1e-9 T
of the exact one (benchmarks/bench_two_chip.py). The fit on the tables, a guess too, reads the
magnet's field from its (rho, z) table (:mod:`mst_cli.model.cylinder_table`, built once per reader
over where the chips are seen from the magnet at a census of the loads the fit may try; within
1e-8 T of magpylib's); on the exact states the fields are the forward model's own
(:func:`~mst_cli.model.general_load.fields_of`: the slides, the magnet's pose, its exact cylinder
field at every chip). Both fits' Jacobians are chained analytically: the states' derivative (the
tables' gradient in their cells, or the states' own tangent at equilibrium, by the implicit
function theorem: no solve per unknown), the slides', the pose's and the field table's gradient;
no model call per unknown.

The fit is the exact reader's, the estimators' one solver
(:func:`~mst_cli.estimation.least_squares.levenberg_marquardt`): Levenberg-damped Gauss-Newton on
the chi^2 of the readings weighted by the chip noise, every step clipped to the model's domain (Fz in (0, the
tables' top force], |Fx|, |Fy| <= ratio_max Fz, the press on the face). Every reading is fitted
from five starts (the centred press whose |B| at the first chip is the reading's, and that
force pressed a quarter of the face out toward each corner) on the tables alone; each reading's
distinct fits (further apart than twice their combined 1-sigma) go on to the exact states. The
best chi^2 is the estimate. Flags: ``no_fit`` past the exact reader's chi^2 limit
(:data:`~mst_cli.estimation.shear_reading.CHI2_FLAG`), ``ambiguous`` when two fits within it lie
further apart than twice their combined Cramer-Rao 1-sigma in any unknown, else ``ok``. Each
estimate's 1-sigma is the Cramer-Rao bound at the fit.

Pure: no I/O.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.estimation.layer_tables import LayerTable, layer_tables
from mst_cli.estimation.least_squares import levenberg_marquardt
from mst_cli.estimation.shear_reading import CHI2_FLAG, ShearReader
from mst_cli.model.cylinder_table import CylinderFieldTable, rotation_and_left_jacobian
from mst_cli.model.general_load import LoadedStack, fields_of, load_ratios, magnet_pose_of
from mst_cli.model.load_bound import UNKNOWNS, crb_sigma
from mst_cli.model.mechanics.tilt import member_compliance
from mst_cli.model.mechanics.tilt_batch import newton_many, residual_many
from mst_cli.model.stack_pose import chip_from_magnet_mm, magnet_pose, magnet_rotvec_rad

RATIO_MAX = 0.5  # |Fx| / Fz and |Fy| / Fz the table supports
FORCE_TOP = 1.5  # the table's top force, x the stack's last lock (the exact reader's span)
N_FORCE = 33  # force nodes, 0 to the top force (the layer laws' knots added)
STEP_MM = 2.0  # offsets' spacing
MAX_ITER = 60
STEP_TOL = 1e-3  # a fit ends once a step is this share of the bound's sigma in every unknown ...
TABLE_STEP_TOL = 3e-2  # ... on the tables' states (the exact states' fit goes on from there)
START_FRACTION = 0.25  # the four off-centre starts: this share of the face's width and depth out
NEWTON_STEPS = 12  # the tilt rung's Newton steps from the tables' states (most loads need 2 to 6, a few 10)
# Of 100 random presses on tests/test_two_chip_table.py's sensor, the fit on the exact states ends
# within 3 steps for 92, within 12 for 98 and within 20 for all (a flat valley past the lock).
EXACT_ITER = 40  # at most this many fit steps on the exact states, from the tables' fit
MAX_FITS = 3  # distinct fits per reading carried to the exact states
CENSUS_NODES = 7  # loads a side of the census the field table's domain is found from (7^5)
FIELD_MARGIN_MM = 1.0  # the field table's domain past the census
FIELD_STEP_MM = 0.1  # the field table's nodes' spacing
MERGE_SIGMA = 1.0  # a start's fit this close to a better one's (in its step's scale) ends there
FLAGS = ("ok", "ambiguous", "no_fit")


def table_top_N(stack: LoadedStack) -> float:
    """The tables' top force: FORCE_TOP x the stack's last lock."""
    return FORCE_TOP * max(t.lock_force_N for t in stack.tilt)


@dataclass
class TwoChipModel:
    """The general-load model of one stack at its chips, its tilts tabulated: fields of many
    loads at once."""

    stack: LoadedStack
    chips_mm: list[tuple[float, float]]
    tables: list[LayerTable]
    ratio_max: float

    @classmethod
    def build(
        cls,
        stack: LoadedStack,
        chips_mm: Sequence[tuple[float, float]],
        ratio_max: float = RATIO_MAX,
        force_max_N: float | None = None,
        n_force: int = N_FORCE,
        step_mm: float = STEP_MM,
    ) -> TwoChipModel:
        """The tables up to ``force_max_N`` (FORCE_TOP x the last lock unless given)."""
        top = table_top_N(stack) if force_max_N is None else force_max_N
        tables = layer_tables(stack, top, ratio_max, n_force, step_mm)
        return cls(stack, [(float(c[0]), float(c[1])) for c in chips_mm], tables, ratio_max)

    @property
    def force_max_N(self) -> float:
        return float(self.tables[0].force_N[-1])

    def states(self, theta: np.ndarray, newton_steps: int = 0, near: np.ndarray | None = None) -> np.ndarray:
        """(m, n, 3) every layer's (d, phi_y, phi_x) at the loads ``theta`` (m, 5): the tables'
        and, with ``newton_steps``, that many Newton steps of the tilt rung's equilibrium from
        there, or from the states ``near`` (m, n, 3) (a close load's: the Jacobian's steps)."""
        F, rx, ry = load_ratios(theta)
        out = np.empty((len(F), len(self.tables), 3))
        for j, (table, law, lever) in enumerate(zip(self.tables, self.stack.tilt, self.stack.lever_mm)):
            off = np.column_stack([theta[:, 3] + lever * rx, theta[:, 4] + lever * ry])
            s = table.at(F, off[:, 0], off[:, 1]) if near is None else near[:, j]
            out[:, j] = newton_many(law, F, off, s, newton_steps) if newton_steps else s
        return out

    def fields_T(self, theta: np.ndarray, newton_steps: int = 0) -> np.ndarray:
        """(m, 3 k) the chips' fields in T at the loads ``theta`` (m, 5) = (Fz, Fx, Fy, x, y)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        return self.fields_of(theta, self.states(theta, newton_steps))

    def state_tangent(self, theta: np.ndarray, states: np.ndarray) -> np.ndarray:
        """(m, 5, n, 3) d(states)/d(theta) at equilibrium ``states`` of the loads ``theta``: each
        layer's tangent K solved against the load's derivative (the implicit function theorem;
        the layer carries (F, F ox, F oy) = (Fz, Fz x + lever Fx, Fz y + lever Fy))."""
        m = len(theta)
        out = np.zeros((m, 5, len(self.tables), 3))
        F, rx, ry = load_ratios(theta)
        for j, (law, lever) in enumerate(zip(self.stack.tilt, self.stack.lever_mm)):
            target = np.column_stack([F, F * (theta[:, 3] + lever * rx), F * (theta[:, 4] + lever * ry)])
            _, K = residual_many(law, states[:, j], target)  # K in the layer's own state
            dload = np.zeros((m, 3, 5))
            dload[:, 0, 0] = 1.0
            dload[:, 1, 0], dload[:, 1, 1], dload[:, 1, 3] = theta[:, 3], lever, theta[:, 0]
            dload[:, 2, 0], dload[:, 2, 2], dload[:, 2, 4] = theta[:, 4], lever, theta[:, 0]
            ok = np.abs(np.linalg.det(K)) > 1e-300
            own = np.zeros((m, 3, 5))
            own[ok] = np.linalg.solve(K[ok], dload[ok])
            # the member in series (the cover) adds its compliance to the layer's, load by load
            member = member_compliance(law, F)[:, :, None] * dload
            out[:, :, j, :] = np.where(ok[:, None, None], own + member, 0.0).transpose(0, 2, 1)
        return out

    def jacobian_T(self, theta: np.ndarray, at: np.ndarray, states: np.ndarray) -> np.ndarray:
        """(m, 3 k, 5) dB/dtheta at equilibrium ``states``: the states' tangent chained through
        the pose to the field table's gradient (:meth:`chain_T`; the exact field's within its
        table's error, no call of the exact field). ``at``: the :data:`Jacobian` signature's, unused."""
        return self.chain_T(theta, states, self.state_tangent(theta, states).transpose(0, 2, 3, 1))

    def fields_of(self, theta: np.ndarray, states: np.ndarray, exact: bool = True) -> np.ndarray:
        """(m, 3 k) the chips' fields at the loads ``theta`` with the layers' ``states``: the
        forward model's (:func:`~mst_cli.model.general_load.fields_of`, the exact cylinder field),
        or (``exact`` False) the field from its (rho, z) table (:attr:`field_table`)."""
        if exact:
            return fields_of(self.stack, theta, states, self.chips_mm)
        B = self.field_table.field_T(*self._seen(*self.pose(theta, states)), gradient=False)[0]  # (3, k m)
        return B.reshape(3, len(self.chips_mm), len(theta)).transpose(2, 1, 0).reshape(len(theta), -1)

    def pose(self, theta: np.ndarray, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the magnet centre's displacement (m, 3) mm, its rotation vector (m, 3)) at the loads
        ``theta`` with the layers' ``states``."""
        return magnet_pose_of(self.stack, theta, states)

    def _seen(self, shift: np.ndarray, rotvec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q (3, k m) every chip from the magnet's centre, chip by chip; the magnet's turn (3, k m)),
        components first: every chip in one call of the field table."""
        g = self.stack.geometry
        q = np.concatenate([chip_from_magnet_mm(g, shift, c) for c in self.chips_mm])
        return q.T, np.tile(magnet_rotvec_rad(g, rotvec), (len(self.chips_mm), 1)).T

    @functools.cached_property
    def field_table(self) -> CylinderFieldTable:
        """The magnet's field tabulated over where the chips are seen from it at every load the
        fit may try: a census of the domain (:data:`CENSUS_NODES` a side) on the tables' states,
        widened by FIELD_MARGIN_MM."""
        g = self.stack.geometry
        t = np.linspace(-1.0, 1.0, CENSUS_NODES)
        F, rx, ry, x, y = np.meshgrid(np.linspace(0.0, self.force_max_N, CENSUS_NODES), t, t, t, t, indexing="ij")
        theta = np.column_stack(
            [
                F.ravel(),
                (rx * F).ravel() * self.ratio_max,
                (ry * F).ravel() * self.ratio_max,
                0.5 * g.width_mm * x.ravel(),
                0.5 * g.depth_mm * y.ravel(),
            ]
        )
        shift, rotvec = self.pose(theta, self.states(theta))
        q, rot = self._seen(shift, rotvec)
        own = np.einsum("jim,jm->im", rotation_and_left_jacobian(rot)[0], q)  # R^T q: in the magnet's frame
        rho_max = float(np.hypot(own[0], own[1]).max()) + FIELD_MARGIN_MM
        z_top = min(float(own[2].max()) + FIELD_MARGIN_MM, -0.5 * g.magnet.thickness_mm - FIELD_MARGIN_MM)
        # short of the magnet's face (its edge is singular); a chip nearer is read from the end cells
        z_range = (min(float(own[2].min()) - FIELD_MARGIN_MM, z_top - FIELD_MARGIN_MM), z_top)
        mag = g.magnet
        return CylinderFieldTable.build(
            mag.diameter_mm, mag.thickness_mm, mag.remanence_T, rho_max, z_range, FIELD_STEP_MM
        )

    def table_jacobian_T(self, theta: np.ndarray, at: np.ndarray, states: np.ndarray) -> np.ndarray:
        """(m, 3 k, 5) dB/dtheta of the tables' model (:meth:`fields_of` not ``exact``, the
        states the tables'), exact: the tables' gradient in their cells chained (:meth:`chain_T`).
        ``at``, ``states``: the :data:`Jacobian` signature's, unused (read afresh with the gradient)."""
        return self.table_fields_and_jacobian_T(theta)[1]

    def table_fields_and_jacobian_T(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((m, 3 k) the tables' model's fields, (m, 3 k, 5) their Jacobian) in one pass: the
        tables, the pose and the field table read once (the fit needs both at every load it tries
        but a refused one; reading them twice cost a third of its time)."""
        return self._chain(theta, *self._table_state_gradient(theta))

    def chain_T(self, theta: np.ndarray, states: np.ndarray, dstates: np.ndarray) -> np.ndarray:
        """(m, 3 k, 5) dB/dtheta of the field table's field at the loads ``theta`` with the
        layers' ``states`` (m, n, 3) moving by ``dstates`` (m, n, 3, 5) = d(states)/dtheta: the
        slides', the pose's (linear) and the field table's derivatives chained."""
        return self._chain(theta, states, dstates)[1]

    def _chain(self, theta: np.ndarray, states: np.ndarray, dstates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((m, 3 k) the field table's fields, (m, 3 k, 5) :meth:`chain_T`'s Jacobian)."""
        m, n = dstates.shape[:2]
        per_unknown = dstates.transpose(0, 3, 1, 2).reshape(5 * m, n, 3)  # row 5 i + k: d(states_i)/dtheta_k
        if self.stack.counter_turn is not None:  # the members' counter-turn: phi_y = Fx U(Fz) / Fz, on the tilts
            per_unknown = per_unknown.copy()
            per_unknown[..., 1] += self.stack.counter_turn.tilt_gradient_rad(theta).reshape(5 * m, n)
        # the pose is linear in the states and the slides, without a constant: their derivatives' pose is its derivative
        dshift, drot = magnet_pose(
            self.stack.geometry, per_unknown[..., 0], per_unknown[..., 1:], self._slide_gradient(theta)
        )
        dshift, drot = dshift.reshape(m, 5, 3).transpose(0, 2, 1), drot.reshape(m, 5, 3).transpose(0, 2, 1)
        if self.stack.members_pose is not None:  # section mode: the members' pose moves with the load itself
            extra_shift, extra_rot = self.stack.members_pose.pose_gradient(theta)
            dshift, drot = dshift + extra_shift, drot + extra_rot
        B, dB_dq, dB_drot = self.field_table.field_T(*self._seen(*self.pose(theta, states)))
        assert dB_dq is not None and dB_drot is not None
        k = len(self.chips_mm)
        # (m, k, 3, 3) @ (m, 1, 3, 5): batched matmul, several times einsum's speed on these shapes
        dB_dq = dB_dq.reshape(3, 3, k, m).transpose(3, 2, 0, 1)
        dB_drot = dB_drot.reshape(3, 3, k, m).transpose(3, 2, 0, 1)
        J = dB_drot @ drot[:, None] - dB_dq @ dshift[:, None]
        return B.reshape(3, k, m).transpose(2, 1, 0).reshape(m, -1), J.reshape(m, 3 * k, 5)

    def _table_state_gradient(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((m, n, 3) every layer's tables' state, (m, n, 3, 5) its derivative in theta: the
        tables' gradient in (F, ox, oy) times the layer's load's in theta (ox = x + lever Fx / Fz,
        oy likewise))."""
        F, rx, ry = load_ratios(theta)
        safe = np.where(F > 0.0, F, 1.0)
        m = len(theta)
        states = np.empty((m, len(self.tables), 3))
        out = np.empty((m, len(self.tables), 3, 5))
        for j, (table, lever) in enumerate(zip(self.tables, self.stack.lever_mm)):
            states[:, j], grad = table.read(F, theta[:, 3] + lever * rx, theta[:, 4] + lever * ry)
            assert grad is not None
            dload = np.zeros((m, 3, 5))
            dload[:, 0, 0] = 1.0
            dload[:, 1, 0], dload[:, 1, 1], dload[:, 1, 3] = -lever * rx / safe, lever / safe, 1.0
            dload[:, 2, 0], dload[:, 2, 2], dload[:, 2, 4] = -lever * ry / safe, lever / safe, 1.0
            out[:, j] = grad @ dload
        return states, out

    def _slide_gradient(self, theta: np.ndarray) -> np.ndarray:
        """(5 m, n, 2) d(every layer's slide)/dtheta, row 5 i + k the load i's in theta_k: each
        slide is Fx c_x(Fz) (Fy c_y(Fz)), c's slope by a forward difference (piecewise smooth in Fz)."""
        F, m = theta[:, 0], len(theta)
        h = np.maximum(1e-6 * np.abs(F), 1e-9)
        out = np.zeros((m, 5, len(self.stack.lateral), 2))
        for j, law in enumerate(self.stack.lateral):
            c = np.array(law.compliance_mm_per_N(np.concatenate([F, F + h])))  # (2, 2 m): at F, at F + h
            slope = (c[:, m:] - c[:, :m]) / h
            out[:, 0, j] = theta[:, 1:3] * slope.T
            out[:, 1, j, 0], out[:, 2, j, 1] = c[0, :m], c[1, :m]
        return out.reshape(5 * m, -1, 2)


@dataclass
class TwoChipEstimates:
    """Per reading: the five unknowns at the best fit whatever its flag (a caller blanks what it
    does not trust), their Cramer-Rao 1-sigma there (inf where the chips cannot tell one apart),
    the fit's chi^2 and flag (:data:`FLAGS`), and how many distinct fits went on to the exact
    states."""

    force_N: np.ndarray
    shear_x_N: np.ndarray
    shear_y_N: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    sigma_force_N: np.ndarray
    sigma_shear_x_N: np.ndarray
    sigma_shear_y_N: np.ndarray
    sigma_x_mm: np.ndarray
    sigma_y_mm: np.ndarray
    chi2: np.ndarray
    flag: np.ndarray
    fits: np.ndarray

    @classmethod
    def of(
        cls, theta: np.ndarray, sigma: np.ndarray, chi2: np.ndarray, flag: np.ndarray, fits: np.ndarray
    ) -> TwoChipEstimates:
        """From the estimates (n, 5) and their 1-sigma (n, 5) in the order of UNKNOWNS."""
        columns = {name: theta[:, i] for i, name in enumerate(UNKNOWNS)}
        columns.update({"sigma_" + name: sigma[:, i] for i, name in enumerate(UNKNOWNS)})
        return cls(**columns, chi2=chi2, flag=flag, fits=fits)

    @property
    def theta(self) -> np.ndarray:
        """(n, 5) the estimates in the order of :data:`~mst_cli.model.load_bound.UNKNOWNS`."""
        return np.column_stack([getattr(self, name) for name in UNKNOWNS])

    @property
    def sigma(self) -> np.ndarray:
        """(n, 5) their 1-sigma, in the same order."""
        return np.column_stack([getattr(self, "sigma_" + name) for name in UNKNOWNS])


# loads (m, 5) and the layers' states of close loads (m, n, 3) or None -> (fields, states)
Model = Callable[[np.ndarray, np.ndarray | None], tuple[np.ndarray, np.ndarray]]
Jacobian = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]  # (theta, fields, states) -> (m, 3 k, 5)


def fit_many(
    fields: Model,
    B_T: np.ndarray,
    theta: np.ndarray,
    noise_T: float,
    clip: Callable[[np.ndarray], np.ndarray],
    max_iter: int,
    step_tol: float = STEP_TOL,
    *,
    jacobian: Jacobian,
    siblings: int = 1,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every row of ``theta`` (m, 5) fitted to its reading ``B_T`` (m, 3 k) by the estimators' one
    solver (:func:`~mst_cli.estimation.least_squares.levenberg_marquardt`, its default damping):
    (theta, chi^2, the Jacobian (m, 3 k, 5) there). ``jacobian`` (theta, fields,
    states) -> (m, 3 k, 5): the model's own, analytic (:meth:`TwoChipModel.jacobian_T`,
    :meth:`TwoChipModel.table_jacobian_T`).
    ``siblings``: rows in runs of that many starts of one reading, a row ending once within
    MERGE_SIGMA steps' scale of a sibling of lower chi^2 (the same minimum: :func:`_distinct`'s)."""
    fit = levenberg_marquardt(
        fields, jacobian, B_T, theta, noise_T, clip, max_iter, step_tol, siblings=siblings, merge_sigma=MERGE_SIGMA
    )
    return fit.theta, fit.chi2, fit.jacobian


class TwoChipReader:
    """The fast estimator of all five unknowns from two chips or more: the tabulated model
    (:class:`TwoChipModel`), fitted from every start on the tables alone, then each reading's
    distinct fits (at most MAX_FITS) made exact (the tables' states put through ``newton_steps``
    of the tilt rung's Newton) by a few more steps on the exact states. ``model``: tables built
    already (then ``stack`` and ``ratio_max`` are its); the tables depend on the stack and the
    shear ratio only, so readers of other chip layouts may share them,
    ``TwoChipModel(stack, chips_mm, other.model.tables, other.model.ratio_max)``."""

    def __init__(
        self,
        stack: LoadedStack,
        chips_mm: Sequence[tuple[float, float]],
        noise_T: float,
        ratio_max: float = RATIO_MAX,
        model: TwoChipModel | None = None,
        newton_steps: int = NEWTON_STEPS,
    ):
        if len(chips_mm) < 2:
            raise ValueError("two chips or more estimate all five unknowns")
        self.model = model if model is not None else TwoChipModel.build(stack, chips_mm, ratio_max)
        self.noise_T = float(noise_T)
        self.newton_steps = newton_steps
        dof = 3 * len(self.model.chips_mm) - 5
        self.chi2_limit = CHI2_FLAG.get(dof, 3.0 * dof + 10.0)  # the exact reader's
        F = np.linspace(0.0, self.model.force_max_N, 257)
        centred = np.column_stack([F, np.zeros((len(F), 4))])
        _ = self.model.field_table  # built now, not in a reading's time
        self._start_F = F
        self._start_B = np.linalg.norm(self.exact(centred)[0][:, :3], axis=1)  # |B| at the first chip

    def table(self, theta: np.ndarray, near: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(the chips' fields (m, 3 k), their Jacobian (m, 3 k, 5)) on the tables' states, the
        field the field table's: the Jacobian rides as the :data:`Model`'s warm start, so the fit
        reads it back (:func:`_carried_jacobian`) instead of reading the tables again (``near``,
        the signature's, unused: the tables need no start)."""
        return self.model.table_fields_and_jacobian_T(theta)

    def exact(self, theta: np.ndarray, near: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(the chips' fields (m, 3 k), the layers' states) on the exact states, the Newton
        started from the tables' or from ``near``."""
        states = self.model.states(theta, self.newton_steps, near)
        return self.model.fields_of(theta, states), states

    def clip(self, theta: np.ndarray) -> np.ndarray:
        """Loads kept inside the model's domain: Fz in (0, the tables' top], the shear inside
        |Fx|, |Fy| <= ratio_max Fz, the press on the face."""
        g = self.model.stack.geometry
        t = theta.copy()
        t[:, 0] = np.clip(t[:, 0], 1e-3, self.model.force_max_N)
        lim = self.model.ratio_max * t[:, 0]
        t[:, 1], t[:, 2] = np.clip(t[:, 1], -lim, lim), np.clip(t[:, 2], -lim, lim)
        t[:, 3] = np.clip(t[:, 3], -0.5 * g.width_mm, 0.5 * g.width_mm)
        t[:, 4] = np.clip(t[:, 4], -0.5 * g.depth_mm, 0.5 * g.depth_mm)
        return t

    def starts(self, B: np.ndarray) -> np.ndarray:
        """(n, 5 starts, 5): the centred press whose |B| at the first chip is the reading's, and
        that force pressed START_FRACTION of the face out toward each corner."""
        g = self.model.stack.geometry
        F0 = np.maximum(np.interp(np.linalg.norm(B[:, :3], axis=1), self._start_B, self._start_F), 1e-2)
        spots = [(0.0, 0.0)] + [(sx * g.width_mm, sy * g.depth_mm) for sx in (-1, 1) for sy in (-1, 1)]
        out = np.zeros((len(B), len(spots), 5))
        out[:, :, 0] = F0[:, None]
        out[:, 1:, 3:] = START_FRACTION * np.array(spots[1:])[None, :, :]
        return out

    def estimate(self, B_T: np.ndarray, every_start: bool = True) -> TwoChipEstimates:
        """The estimates from readings ``B_T`` (n, k, 3) or (n, 3 k) in T. ``every_start`` False:
        the centred start alone, the other four only where its fit is ``no_fit`` (the exact
        reader's way: about twice as fast, but a second fit within the noise, ``ambiguous``, is
        looked for only there)."""
        B = np.asarray(B_T, dtype=float).reshape(len(B_T), -1)
        starts = self.starts(B)
        if every_start:
            return self._estimate_from(B, starts)
        out = self._estimate_from(B, starts[:, :1])
        again = np.flatnonzero(out.flag == "no_fit")
        if len(again):
            more = self._estimate_from(B[again], starts[again])
            for name in (f.name for f in dataclasses.fields(TwoChipEstimates)):
                getattr(out, name)[again] = getattr(more, name)
        return out

    def _estimate_from(self, B: np.ndarray, starts: np.ndarray) -> TwoChipEstimates:
        """The readings ``B`` (n, 3 k) fitted from ``starts`` (n, S, 5): every start on the tables,
        each reading's distinct fits on the exact states, the verdict."""
        n, S = starts.shape[:2]
        theta, chi2, J = fit_many(
            self.table,
            np.repeat(B, S, axis=0),
            starts.reshape(n * S, 5),
            self.noise_T,
            self.clip,
            MAX_ITER,
            TABLE_STEP_TOL,
            jacobian=_carried_jacobian,
            siblings=S,
        )
        keep = _distinct(theta.reshape(n, S, 5), chi2.reshape(n, S), crb_sigma(J, self.noise_T).reshape(n, S, 5))
        owner, slot = np.nonzero(keep)
        cand = theta.reshape(n, S, 5)[owner, slot]
        cand, c_chi2, c_J = fit_many(
            self.exact, B[owner], cand, self.noise_T, self.clip, EXACT_ITER, jacobian=self.model.jacobian_T
        )
        return self._verdict(n, owner, cand, c_chi2, crb_sigma(c_J, self.noise_T))

    def _verdict(
        self, n: int, owner: np.ndarray, theta: np.ndarray, chi2: np.ndarray, sigma: np.ndarray
    ) -> TwoChipEstimates:
        """Each reading's best fit by chi^2 and its flag from all its fits (``owner``: whose)."""
        order = np.lexsort((chi2, owner))  # by reading, then by chi^2
        owner, theta, chi2, sigma = owner[order], theta[order], chi2[order], sigma[order]
        first = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
        best = np.full(n, -1)
        best[owner[first]] = first
        fits = np.bincount(owner, minlength=n)
        ok = chi2 <= self.chi2_limit
        far = np.abs(theta - theta[best[owner]]) > 2.0 * np.sqrt(sigma**2 + sigma[best[owner]] ** 2)
        rival = ok & np.any(far, axis=1) & ok[best[owner]]
        ambiguous = np.bincount(owner, weights=rival, minlength=n) > 0
        t, s, c = theta[best], sigma[best], chi2[best]
        flag = np.where(c <= self.chi2_limit, np.where(ambiguous, "ambiguous", "ok"), "no_fit").astype(object)
        return TwoChipEstimates.of(t, s, c, flag, fits)

    def polish(self, B_T: np.ndarray, estimates: TwoChipEstimates) -> TwoChipEstimates:
        """The estimates put through the exact reader's fit (:class:`ShearReader`) from the fast
        estimate (0.1 to 0.5 s a reading): the exact model's least squares.
        An ``ambiguous`` flag stays (the polish refines the best fit only)."""
        B = np.asarray(B_T, dtype=float).reshape(len(B_T), -1)
        exact = ShearReader(self.model.stack, self.model.chips_mm)
        theta, sigma, chi2 = exact.fit(B, self.noise_T, self.clip(estimates.theta))
        flag = np.where(chi2 <= self.chi2_limit, np.where(estimates.flag == "ambiguous", "ambiguous", "ok"), "no_fit")
        return TwoChipEstimates.of(theta, sigma, chi2, flag.astype(object), estimates.fits)


def _carried_jacobian(theta: np.ndarray, fields: np.ndarray, jacobian: np.ndarray) -> np.ndarray:
    """The :data:`Jacobian` of a model that returned its Jacobian as its warm start
    (:meth:`TwoChipReader.table`)."""
    return jacobian


def _distinct(theta: np.ndarray, chi2: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """(n, S) which of every reading's S fits to keep: the best, and each further one (by chi^2)
    further than twice the combined 1-sigma from every fit kept before it, at most MAX_FITS."""
    n, S = chi2.shape
    order = np.argsort(chi2, axis=1)
    t = np.take_along_axis(theta, order[:, :, None], axis=1)
    s = np.take_along_axis(np.where(np.isfinite(sigma), sigma, 0.0), order[:, :, None], axis=1)
    kept = np.zeros((n, S), dtype=bool)
    kept[:, 0] = True
    for a in range(1, S):
        close = np.zeros(n, dtype=bool)
        for b in range(a):
            same = np.all(np.abs(t[:, a] - t[:, b]) <= 2.0 * np.sqrt(s[:, a] ** 2 + s[:, b] ** 2), axis=1)
            close |= kept[:, b] & same
        kept[:, a] = ~close & (kept.sum(axis=1) < MAX_FITS)
    out = np.zeros((n, S), dtype=bool)
    np.put_along_axis(out, order, kept, axis=1)
    return out
