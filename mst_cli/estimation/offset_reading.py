"""Where a reading was pressed, from all three field axes (``mst read --estimate-offset``).

A press at (x0, y0) tilts the stack and moves the magnet sideways (:mod:`mst_cli.model.offcentre`),
so one reading (Bx, By, Bz) holds three numbers for three unknowns: the force and the two
offsets. :class:`OffsetEstimator` finds them by damped Gauss-Newton on the model's field, each
reading started from the centred model's force at the previous reading's offset (a stream of
presses moves little between samples) and at the centre. The chip's field noise sigma gives
their covariance, sigma^2 (J^T J)^-1. A reading keeps the centred model's force, flagged, when
the data cannot tell the press: its offset's 1-sigma exceeds a bound (*not identifiable*: under
a light press the stack hardly tilts, so Bx and By say nothing), the two starts end on different
roots (*ambiguous*: late in the stack the field folds over, so distant presses give the same
reading), or neither fits the reading (*no fit*).

The field is the general load's forward model (:func:`~mst_cli.model.general_load.fields_T`'s
parts, no shear, warm-started from the last call). The solve is not the shear readers'
Levenberg-Marquardt (:mod:`~mst_cli.estimation.least_squares` says why): three equations in three unknowns have
an exact root, which must lie in the box of the force range and the face, so it is a projected
Gauss-Newton (a coordinate at the box held, steps halved until the misfit falls), the algorithm
the one-chip tables' direct inverse runs cell by cell on the trilinear field
(:mod:`~mst_cli.estimation.inverse_table`, as the C header does) on the exact model instead.

This is the rung's own inverse: it corrects what the tilt rung predicts, and is as good as
that rung (docs/design.md section 4.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.general_load import fields_of, layer_states, normal_stack
from mst_cli.model.load_bound import crb_sigma
from mst_cli.model.material import Material
from mst_cli.model.member_pose import MemberPose
from mst_cli.model.stack_pose import tilt_laws

DEFAULT_MAX_SIGMA_MM = 1.0  # an offset less certain than this is not identifiable
GAUSS_NEWTON_ITERATIONS = 30
STEP_FORCE_REL = 1e-5  # finite-difference steps: of the largest force ...
STEP_OFFSET_MM = 1e-3  # ... and in mm
MAX_HALVINGS = 6  # a Gauss-Newton step is halved at most this often before the solve stops
FIT_SIGMAS = 3.0  # a solve that ends further off the reading than this many noise sigmas found no root
CENTRE_ITERATIONS = 10  # the second start's Gauss-Newton steps, at most
SAME_START_MM = 0.5  # a previous press nearer the centre than this: one start (the centre) is enough


@dataclass(frozen=True)
class OffsetEstimate:
    """One reading's solve: force N, offset mm, their 1-sigma, and its flag (ok, not_identifiable,
    ambiguous, no_fit); NaN values where the flag says the solve is not to be used. The next
    reading of a stream starts from ``next_start_mm`` (None: from where this one started)."""

    force_N: float
    x_mm: float
    y_mm: float
    sigma_force_N: float
    sigma_x_mm: float
    sigma_y_mm: float
    flag: str
    next_start_mm: tuple[float, float] | None = None

    @classmethod
    def without(cls, flag: str, next_start_mm: tuple[float, float] | None = None) -> OffsetEstimate:
        nan = math.nan
        return cls(nan, nan, nan, nan, nan, nan, flag, next_start_mm)


@dataclass
class OffsetReadings:
    """Per reading: the corrected force, the offset and their 1-sigma (NaN where not estimated)."""

    force_N: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    sigma_x_mm: np.ndarray
    sigma_y_mm: np.ndarray
    sigma_force_N: np.ndarray
    flag: np.ndarray  # OffsetEstimate's flag, or "" (the reading itself is flagged)

    @classmethod
    def concat(cls, parts: list[OffsetReadings]) -> OffsetReadings:
        """The readings of ``parts`` one after the other (a stream's samples)."""
        names = ("force_N", "x_mm", "y_mm", "sigma_x_mm", "sigma_y_mm", "sigma_force_N", "flag")
        return cls(*(np.concatenate([getattr(p, n) for p in parts]) for n in names))

    @property
    def force_sigma_N(self) -> np.ndarray:
        return self.sigma_force_N

    def scaled(self, modulus_scale: np.ndarray) -> OffsetReadings:
        """The estimates of a sensor whose modulus is ``modulus_scale`` (n,) times the
        calibration's: every layer law is linear in E, so forces scale by it, offsets not
        (:mod:`~mst_cli.calibration.temperature`)."""
        m = np.asarray(modulus_scale, dtype=float)
        return replace(self, force_N=self.force_N * m, sigma_force_N=self.sigma_force_N * m)

    def append_columns(self, forces_csv_text: str, centred_force_N: np.ndarray) -> str:
        """forces.csv with the offset's columns (:func:`offset_columns`)."""
        return offset_columns(forces_csv_text, self, centred_force_N)

    def terminal(self, i: int) -> str:
        """What a live line adds for reading ``i`` (its flag where not ok)."""
        if self.flag[i] != "ok":
            return f"  {self.flag[i]}" if self.flag[i] else ""
        return (
            f"  at ({self.x_mm[i]:.2f}, {self.y_mm[i]:.2f}) mm +- ({self.sigma_x_mm[i]:.2f}, {self.sigma_y_mm[i]:.2f})"
        )

    def summary(self) -> str:
        ok = self.flag == "ok"
        kept = ", ".join(
            f"{int(np.sum(self.flag == f))} {f.replace('_', ' ')}"
            for f in ("not_identifiable", "ambiguous", "no_fit")
            if f == "not_identifiable" or np.any(self.flag == f)
        )
        if not ok.any():
            return f"offset: identifiable on no reading ({kept}: the centred force kept)"
        x, y = self.x_mm[ok], self.y_mm[ok]
        return (
            f"offset: estimated on {int(ok.sum())} readings (median 1-sigma "
            f"{np.median(self.sigma_x_mm[ok]):.2g} mm in x, {np.median(self.sigma_y_mm[ok]):.2g} mm in y; "
            f"x {x.min():.3g}..{x.max():.3g} mm, y {y.min():.3g}..{y.max():.3g} mm); "
            f"{kept} (the centred force kept)"
        )


class OffsetEstimator:
    """(force, x0, y0) of readings, from the tilt rung of one sensor model."""

    def __init__(
        self,
        geometry: SensorGeometry,
        material: Material,
        mechanics: str,
        field_sigma_T: float,
        force_max_N: float,
        max_sigma_mm: float = DEFAULT_MAX_SIGMA_MM,
        lever_factor: float = 1.0,
        whole_part: bool = True,
        members: MemberPose | None = None,  # model.load_path: section: what the whole-part rung adds
    ):
        self.geometry = geometry
        laws = tilt_laws(geometry, material, mechanics, lever_factor, whole_part)
        self.stack = normal_stack(geometry, laws, mechanics, members)
        self.sigma_T = float(field_sigma_T)
        self.force_max_N = float(force_max_N)
        self.max_sigma_mm = float(max_sigma_mm)
        self.half_face_mm = np.array([0.5 * geometry.width_mm, 0.5 * geometry.depth_mm])
        self._start: np.ndarray | None = None  # the layers' last (d, phi_y, phi_x)

    def field_T(self, p: np.ndarray) -> np.ndarray:
        """The forward model's field (3,) (:func:`~mst_cli.model.general_load.fields_T`) at p =
        (force N, x0 mm, y0 mm); each layer's solve starts from the last call's answer (the
        estimate moves by small steps)."""
        F = max(float(p[0]), 0.0)
        theta = np.array([[F, 0.0, 0.0, float(p[1]), float(p[2])]])
        states = layer_states(self.stack, theta, None if self._start is None else self._start[None])
        if F > 0.0:
            self._start = states[0]
        return fields_of(self.stack, theta, states)[0]

    def _jacobian(self, p: np.ndarray, B0: np.ndarray) -> np.ndarray:
        steps = np.array([STEP_FORCE_REL * self.force_max_N, STEP_OFFSET_MM, STEP_OFFSET_MM])
        cols = []
        for k in range(3):
            q = p.copy()
            q[k] += steps[k]
            cols.append((self.field_T(q) - B0) / steps[k])
        return np.stack(cols, axis=1)

    def _sigmas(self, J: np.ndarray) -> np.ndarray:
        """1-sigma of (force, x0, y0) from the chip's noise and the Jacobian J there
        (:func:`~mst_cli.model.load_bound.crb_sigma`)."""
        return crb_sigma(J, self.sigma_T)

    def _box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) bounds of (force N, x0 mm, y0 mm): no force to the range's end, the face."""
        return (
            np.array([0.0, -self.half_face_mm[0], -self.half_face_mm[1]]),
            np.array([self.force_max_N, self.half_face_mm[0], self.half_face_mm[1]]),
        )

    def on_box_edge(self, p: np.ndarray) -> bool:
        """Whether (force, x0, y0) ``p`` sits on a bound of the solve's box (the range's end, the
        face's edge; zero force aside): where a solve stops when the root lies past it."""
        lo, hi = self._box()
        return bool(p[0] >= hi[0] or np.any(p[1:] <= lo[1:]) or np.any(p[1:] >= hi[1:]))

    def _solve_from(self, B_T: np.ndarray, p0: np.ndarray, iterations: int = GAUSS_NEWTON_ITERATIONS) -> _Solve:
        """Damped, projected Gauss-Newton from ``p0`` inside the face and the force range.

        A coordinate at its bound whose step points out of the box is held there; each step is
        cut to the box, then halved (up to MAX_HALVINGS times) until it lowers the misfit. A
        plain step clipped to the box overshoots where the field flattens late in the stack and
        pins the force at the range's end, far from the root."""
        lo, hi = self._box()
        p = np.clip(p0, lo, hi)
        B0 = self.field_T(p)
        misfit = float(np.linalg.norm(B_T - B0))
        for _ in range(iterations):
            J = self._jacobian(p, B0)
            dp = _box_direction(J, B_T - B0, p, lo, hi)
            # converged when the step would move the model's field by a thousandth of the noise
            if float(np.linalg.norm(J @ dp)) <= 1e-3 * self.sigma_T:
                p = np.clip(p + dp, lo, hi)
                return _Solve(p, float(np.linalg.norm(B_T - self.field_T(p))), J, True)
            dp *= _fraction_inside(p, dp, lo, hi)
            for halving in range(MAX_HALVINGS + 1):
                p_new = np.clip(p + 0.5**halving * dp, lo, hi)
                B_new = self.field_T(p_new)
                misfit_new = float(np.linalg.norm(B_T - B_new))
                if misfit_new < misfit:
                    break
            else:
                return _Solve(p, misfit, J, False)  # no step lowers the misfit: stuck, no root near
            p, B0, misfit = p_new, B_new, misfit_new
        return _Solve(p, misfit, J, False)

    def estimate(self, B_T: np.ndarray, force_guess_N: float, offset_guess_mm=(0.0, 0.0)) -> OffsetEstimate:
        """One reading (T), solved from the previous press (``offset_guess_mm``) and from the centre.

        Three field axes and three unknowns: a root fits the reading exactly, whatever the noise,
        so a solve that ends more than FIT_SIGMAS noise sigmas off found no root (flag
        ``no_fit``). Late in the stack the field can fold over, and two roots further apart than
        their 2-sigma fit the same reading (flag ``ambiguous``): the data cannot tell the press,
        so neither root's force is trusted. A single root whose offset is less certain than the
        bound is ``not_identifiable``. Only ``ok`` carries the solved force."""
        solves = [self._solve_from(B_T, np.array([force_guess_N, *offset_guess_mm], dtype=float))]
        if math.hypot(*offset_guess_mm) > SAME_START_MM:  # the centre, at the force found (or guessed)
            force_N = solves[0].p[0] if solves[0].converged else force_guess_N
            solves.append(self._solve_from(B_T, np.array([force_N, 0.0, 0.0]), CENTRE_ITERATIONS))
        roots = [(s.p, self._sigmas(s.J)) for s in solves if s.converged and s.misfit_T <= FIT_SIGMAS * self.sigma_T]
        if not roots:
            return OffsetEstimate.without("no_fit")
        (p, sig), others = roots[0], roots[1:]
        for q, sig_q in others:
            if np.any(np.abs(p - q) > 2.0 * np.hypot(sig, sig_q)):  # the stream's next start: its own root
                return OffsetEstimate.without("ambiguous", (float(p[1]), float(p[2])))
        ok = bool(np.all(np.isfinite(sig)) and max(sig[1], sig[2]) <= self.max_sigma_mm)
        F, x, y = (float(v) for v in p)
        sF, sx, sy = (float(v) for v in sig)
        return OffsetEstimate(F, x, y, sF, sx, sy, *(("ok", (x, y)) if ok else ("not_identifiable", None)))

    def estimate_all(self, B_T: np.ndarray, force_axial_N: np.ndarray) -> OffsetReadings:
        """Every reading with a finite centred force (the others stay flagged as they are); a
        reading not ``ok`` keeps its centred force."""
        estimates, guess = [], (0.0, 0.0)
        for B, F in zip(B_T, force_axial_N):
            e = self.estimate(B, float(F), guess) if np.isfinite(F) else OffsetEstimate.without("")
            guess = e.next_start_mm or guess
            estimates.append(e)

        flag = np.array([e.flag for e in estimates], dtype=object)
        ok = flag == "ok"

        def column(name: str) -> np.ndarray:  # the solve's values where it is to be used, else NaN
            return np.where(ok, np.array([getattr(e, name) for e in estimates], dtype=float), np.nan)

        return OffsetReadings(
            np.where(ok, column("force_N"), force_axial_N),
            column("x_mm"),
            column("y_mm"),
            column("sigma_x_mm"),
            column("sigma_y_mm"),
            column("sigma_force_N"),
            flag,
        )


class _Solve(NamedTuple):
    """Where one Gauss-Newton solve ended: the point, its field's misfit (T), the Jacobian there
    (at the last step's start when it converged, a thousandth of the noise away) and whether it
    converged (a root, when the misfit is within the noise)."""

    p: np.ndarray
    misfit_T: float
    J: np.ndarray
    converged: bool


def _box_direction(J: np.ndarray, r: np.ndarray, p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The least-squares step of J dp = r with every coordinate held that sits on a bound its
    step would cross."""
    dp = np.linalg.lstsq(J, r, rcond=None)[0]
    held = ((p <= lo) & (dp < 0.0)) | ((p >= hi) & (dp > 0.0))
    if held.any():
        dp = np.zeros_like(p)
        if not held.all():
            dp[~held] = np.linalg.lstsq(J[:, ~held], r, rcond=None)[0]
    return dp


def _fraction_inside(p: np.ndarray, dp: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """The largest share (at most 1) of the step dp from p that stays inside [lo, hi]."""
    room = np.where(dp > 0.0, hi - p, np.where(dp < 0.0, lo - p, np.inf))
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(dp != 0.0, room / dp, np.inf)
    return float(min(1.0, share.min()))


OFFSET_COLUMNS = ("force_centred_N", "x_mm", "y_mm", "force_N_sigma", "x_mm_sigma", "y_mm_sigma", "offset_flag")


def offset_columns(forces_csv_text: str, est: OffsetReadings, centred_force_N: np.ndarray) -> str:
    """forces.csv with the offset's columns appended: the centred model's force, x and y (mm),
    the 1-sigma of the force, x and y (the Cramer-Rao bound at the estimate, from the chip's
    noise), and offset_flag (ok; not_identifiable, ambiguous or no_fit, whose force is the
    centred one; empty for a reading flagged itself)."""
    lines = forces_csv_text.splitlines()
    out = [lines[0] + "," + ",".join(OFFSET_COLUMNS)]
    for i, line in enumerate(lines[1:]):
        vals = [
            centred_force_N[i],
            est.x_mm[i],
            est.y_mm[i],
            est.sigma_force_N[i],
            est.sigma_x_mm[i],
            est.sigma_y_mm[i],
        ]
        cells = ["" if not np.isfinite(v) else f"{v:.6g}" for v in vals]
        out.append(line + "," + ",".join(cells) + "," + str(est.flag[i]))
    return "\n".join(out) + "\n"
