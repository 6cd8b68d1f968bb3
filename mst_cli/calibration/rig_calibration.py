"""A rig's load test in ``mst calibrate`` (issue 38): the branches, which rows the elastic fit
uses, and what the calibration reports about the rest.

* the branches (:func:`~mst_cli.calibration.branches.find_branches`) from the force in time order
  (``time_s``, else row order), the rig's own ``branch`` and ``cycle`` columns checked against it;
* a first cycle that differs from the later ones at its temperature (``T_C``) beyond noise
  (:func:`~mst_cli.calibration.hysteresis.first_cycle`) is left out of the fit;
* the elastic model is fitted to the LOADING rows: unloading rows read less force at the same
  field (hysteresis) and hold rows creep, neither is the elastic loading curve. A load test whose
  loading rows alone cannot carry the fit (a staircase of holds: too few rows, or less than
  :data:`MIN_LOADING_SPAN` of the force span) keeps its hold rows in the fit, and says so;
* after the fit, per regime of the calibrated model: the largest hysteresis (loading minus
  unloading force at matched |B|, % of the regime's band) and where; the unloading branch
  relative to the loading one (:class:`~mst_cli.calibration.hysteresis.UnloadingModel`, what
  ``mst read`` uses); creep under each hold (% of the held force per decade of time).

``use_branches=False`` is the calibration that ignores branches (every row as loading): the
"before" of benchmarks/bench_rig.py.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import numpy as np

from mst_cli.calibration import hysteresis as hy
from mst_cli.calibration.branches import HOLD, LOADING, UNLOADING, Branches, find_branches
from mst_cli.calibration.loadtest import Readings, rig_column
from mst_cli.calibration.softening import Softening, fit_softening
from mst_cli.calibration.time_alignment import Alignment
from mst_cli.calibration.zero_drift import ZeroLaw, fit_zero, remove_zero, rest_runs
from mst_cli.errors import CalibrationFailed, InputError

MIN_LOADING_SPAN = 0.5  # loading rows must span this fraction of the force span, else holds are fitted too
SAME_TEMPERATURE_K = 0.5  # presses within this of press 1's T_C are compared with it (0.4 % of TPU modulus)
REST_FORCE_REL = 0.05  # a hold below this fraction of the largest force is a rest: no creep, the zero's rows


@dataclass
class RigAnalysis:
    """The branches of a load test and what the calibration says about them."""

    readings: Readings  # every centred row
    branches: Branches
    fit_rows: np.ndarray  # bool: the rows the elastic fit uses
    use_branches: bool
    first_cycle: hy.FirstCycle | None
    notes: list[str] = field(default_factory=list)
    hysteresis: list[hy.RegimeHysteresis] = field(default_factory=list)
    unloading: hy.UnloadingModel | None = None
    creep: list[tuple[tuple[int, int], hy.Creep]] = field(default_factory=list)
    rest: np.ndarray | None = None  # bool: rows at rest (force clipped or near 0 between presses)
    alignment: Alignment | None = None
    zero: ZeroLaw | None = None
    softening: Softening | None = None

    @property
    def full_scale_N(self) -> float:
        """The calibrated model's last lock force (after :func:`describe`; the largest force before)."""
        return float(self.hysteresis[-1].hi_N) if self.hysteresis else float(np.max(self.readings.load_N))

    @property
    def time_s(self) -> np.ndarray:
        t = rig_column(self.readings, "time_s")
        return np.arange(len(self.readings), dtype=float) if t is None else t

    def counts(self) -> dict[str, int]:
        rest = self.rest if self.rest is not None else np.zeros(len(self.readings), bool)
        out = {k: int(np.sum((self.branches.label == k) & ~rest)) for k in (LOADING, UNLOADING, HOLD)}
        return {**out, "rest": int(rest.sum())} if rest.any() else out

    def rig_records(self) -> dict:
        """calibration.json's time_alignment, zero and softening (None where not measured)."""
        return {
            "time_alignment": None if self.alignment is None else self.alignment.record(),
            "zero": None if self.zero is None else self.zero.record(),
            "softening": None if self.softening is None else self.softening.record(),
        }

    def rig_lines(self) -> list[str]:
        """The summary's lines on the lag, the zero and the softening (one each, when measured)."""
        return [x.line() for x in (self.alignment, self.zero, self.softening) if x is not None]

    def record(self) -> dict:
        """calibration.json's ``hysteresis`` section (units in the keys)."""
        b = self.branches
        fc = self.first_cycle
        return {
            "branches_used": self.use_branches,
            "rows": self.counts(),
            "rows_in_fit": int(self.fit_rows.sum()),
            "fitted_branch": "loading" if self.use_branches else "all rows as loading",
            "cycles": int(b.cycle.max()) if len(b.cycle) else 0,
            "turning_forces_N": [float(self.readings.load_N[i]) for i in b.turn_rows],
            "dead_band_N": b.dead_band_N,
            "by_regime": [
                {
                    "regime": i + 1,
                    "force_from_N": r.lo_N,
                    "force_to_N": r.hi_N,
                    "max_pct_of_full_scale": 100 * r.max_N / self.full_scale_N,
                    "max_pct_of_band": r.max_pct,
                    "max_N": r.max_N,
                    "at_loading_force_N": r.at_force_N,
                    "unloading_rows": r.samples,
                }
                for i, r in enumerate(self.hysteresis)
            ],
            "unloading_model": None if self.unloading is None else self.unloading.record(self.full_scale_N),
            "first_cycle": None
            if fc is None
            else {
                "stiffer_pct": fc.difference_pct,
                "sigma_pct": fc.sigma_pct,
                "differs": fc.differs,
                "left_out_of_fit": bool(self.use_branches and fc.differs and self.softening is None),
            },
            "creep": [
                {
                    "rows": [int(a), int(z)],
                    "held_force_N": c.held_force_N,
                    "pct_per_decade": c.pct_per_decade,
                    "sigma_pct": c.sigma_pct,
                }
                for (a, z), c in self.creep
            ],
            "notes": list(self.notes),
        }

    def summary_lines(self) -> list[str]:
        """The lines ``mst calibrate`` prints about the branches."""
        n = self.counts()
        lines = [
            f"branches: {n[LOADING]} loading, {n[UNLOADING]} unloading, {n[HOLD]} hold"
            + (f", {n['rest']} rest (force at 0: the zero's rows, no hold)" if "rest" in n else "")
            + " rows in "
            f"{int(self.branches.cycle.max()) if len(self.readings) else 0} cycle(s); fitted to "
            + (f"{int(self.fit_rows.sum())} loading rows" if self.use_branches else "every row as loading")
        ]
        for i, r in enumerate(self.hysteresis):
            if r.samples:
                lines.append(
                    f"  hysteresis regime {i + 1} ({r.lo_N:.3g}-{r.hi_N:.4g} N): "
                    f"{100 * r.max_N / self.full_scale_N:.2f} % of full scale ({r.max_pct:.2f} % of the band) "
                    f"at {r.at_force_N:.3g} N"
                )
        if self.unloading is not None:
            u = self.unloading
            lines.append(
                f"  unloading model h/F_turn = {' '.join(f'{c:+.4f}x^{j}' for j, c in enumerate(u.coefficients))}"
                + (f", {u.after_hold:+.4f}x^4 after a hold" if u.after_hold else "")
                + f"; unexplained {u.residual_rms_N:.3g} N RMS ({100 * u.residual_rms_N / self.full_scale_N:.2f} % "
                f"of full scale, {u.samples} rows)"
            )
        fc = self.first_cycle
        if fc is not None and fc.differs and self.softening is None:
            lines.append(
                f"  first cycle {fc.difference_pct:+.1f} % stiff (+- {fc.sigma_pct:.2g} %): "
                + ("left out of the fit" if self.use_branches else "kept (branches ignored)")
            )
        for _, c in self.creep:
            lines.append(
                f"  creep under the hold at {c.held_force_N:.3g} N: {c.pct_per_decade:.2f} +- {c.sigma_pct:.2g} % "
                "of the held force per decade"
            )
        return lines + [f"  note: {note}" for note in self.notes]


def branches_of(lt: Readings) -> Branches:
    """The branches of a load test's rows; a rig column at odds with the force raises an
    InputError naming the file's line."""
    hint = _branch_hint(lt)
    try:
        b = find_branches(lt.load_N, rig_column(lt, "time_s"), branch=hint, cycle=_cycle_hint(lt))
    except InputError as exc:
        m = re.fullmatch(r"(\w+)\[(\d+)\]", str(exc.field))
        if m is None:
            raise
        raise InputError(f"{lt.source} line {lt.lines[int(m.group(2))]} {m.group(1)}", exc.value, exc.allowed) from None
    return b if hint is not None else _holds_at_turns(b)


def _holds_at_turns(b: Branches) -> Branches:
    """Only a hold at a turning point (the rig stops at a peak or a valley and the sensor creeps)
    stays a hold; a run of close forces on a ramp (a staircase of weights, sparse samples of a
    slow ramp) is the branch it lies on."""
    turns = set(int(r) for r in b.turn_rows)
    label = b.label.copy()
    kept = []
    for a, z in b.holds:
        if a - 1 in turns:
            kept.append((a, z))
        else:
            label[a:z] = label[a - 1] if a > 0 and label[a - 1] != HOLD else LOADING
    return replace(b, label=label, holds=tuple(kept))


def _branch_hint(lt: Readings) -> list[str] | None:
    b = rig_column(lt, "branch")
    return None if b is None else [str(v) for v in b]


def _cycle_hint(lt: Readings) -> list[int] | None:
    c = rig_column(lt, "cycle")
    return None if c is None else [int(v) for v in c]


def _rests(lt: Readings, b: Branches) -> tuple[Branches, np.ndarray]:
    """(the branches without holds near zero force, the rows at rest): a hold below
    REST_FORCE_REL of the largest force (a load cell clipped at 0 between presses) is no hold (no
    creep); its rows and every run of rows within the dead band of 0 lasting MIN_REST_S (with
    time_s) are the zero's."""
    F = lt.load_N
    top = float(np.max(F)) if len(F) else 0.0
    rest = np.zeros(len(F), bool)
    t = rig_column(lt, "time_s")
    for a, z in rest_runs(t, F <= b.dead_band_N) if t is not None else ():
        rest[a:z] = True
    label, kept = b.label.copy(), []
    for a, z in b.holds:
        if float(np.mean(F[a:z])) <= REST_FORCE_REL * top:
            rest[a:z] = True
            label[a:z] = label[a - 1] if a > 0 and label[a - 1] != HOLD else LOADING
        else:
            kept.append((a, z))
    return replace(b, label=label, holds=tuple(kept)), rest


def _zero(lt: Readings, b: Branches, notes: list[str]) -> tuple[Readings, ZeroLaw | None]:
    """The rows with the zero's baseline removed, and its law (module zero_drift)."""
    t = rig_column(lt, "time_s")
    if t is None:
        notes.append("no time_s: the zero's drift and recovery are not tracked")
        return lt, None
    law = fit_zero(t, lt.B_abs_T, lt.load_N, b.dead_band_N)
    if law is None:
        return lt, None
    return remove_zero(lt, law, t, b.dead_band_N), law


def _at_another_temperature(lt: Readings, cycle: np.ndarray, notes: list[str]) -> np.ndarray:
    """Rows of presses logged more than :data:`SAME_TEMPERATURE_K` from press 1's temperature
    (``T_C``): a warmer press is softer and its magnet weaker, which a comparison with press 1
    would read as press 1's softening (-0.8 %/K of TPU modulus: 10 K reads as a press 1 several %
    stiffer); such presses are left out of the first-press and softening comparisons (noted)."""
    T = rig_column(lt, "T_C")
    if T is None or not np.any(cycle == 1):
        return np.zeros(len(lt), bool)
    T1 = float(np.median(T[cycle == 1]))
    press_T = {int(k): float(np.median(T[cycle == k])) for k in np.unique(cycle)}
    other = [k for k, t in press_T.items() if abs(t - T1) > SAME_TEMPERATURE_K]
    if other:
        notes.append(
            f"press(es) {', '.join(map(str, other))} logged at another T_C than press 1 ({T1:g} degC): "
            "not compared with it for softening (temperature would read as softening)"
        )
    return np.isin(cycle, other)


def analyse(lt: Readings, min_rows: int, use_branches: bool = True, alignment: Alignment | None = None) -> RigAnalysis:
    """The branches and the rows the fit uses (module doc); ``min_rows``: what the fit needs.
    The zero's law is removed from the rows first (:mod:`~mst_cli.calibration.zero_drift`); with
    three presses or more, the softening law decides which presses are fitted
    (:mod:`~mst_cli.calibration.softening`), else a first cycle that differs is left out."""
    b, rest = _rests(lt, branches_of(lt))
    notes: list[str] = []
    lt, zero = _zero(lt, b, notes) if use_branches else (lt, None)
    fc, soft = None, None
    if int(b.cycle.max(initial=1)) > 1:
        label = np.where(_at_another_temperature(lt, b.cycle, notes), "", b.label)
        try:
            fc = hy.first_cycle(lt.B_abs_T, lt.load_N, label, b.cycle)
        except CalibrationFailed:
            fc = None
        soft = fit_softening(lt.B_abs_T, lt.load_N, np.where(rest, "", label), b.cycle) if use_branches else None
    if not use_branches:
        return RigAnalysis(lt, b, np.ones(len(lt), bool), False, fc, notes, rest=rest, alignment=alignment)
    if soft is not None:
        keep = b.cycle >= soft.first_settled
    else:
        keep = hy.rows_without_first_cycle(b.cycle, fc) if fc is not None else np.ones(len(lt), bool)
    rows = keep & (b.label == LOADING) & ~rest
    F = lt.load_N
    span = float(np.ptp(F)) if len(F) else 0.0
    if rows.sum() < min_rows or (span > 0 and (np.ptp(F[rows]) if rows.any() else 0.0) < MIN_LOADING_SPAN * span):
        rows = keep & (b.label != UNLOADING)
        notes.append("too few loading rows for the fit alone: hold rows fitted as loading")
    if rows.sum() < min_rows:
        rows = np.ones(len(lt), bool)
        notes.append("too few loading and hold rows for the fit: every row fitted as loading")
    return RigAnalysis(lt, b, rows, True, fc, notes, rest=rest, alignment=alignment, zero=zero, softening=soft)


def describe(analysis: RigAnalysis, edges_N: np.ndarray, force_of_field_N) -> None:
    """After the fit: hysteresis per regime of the calibrated model (``edges_N``), the unloading
    model and creep under each hold (the reading as force: ``force_of_field_N(|B|)``)."""
    lt, b = analysis.readings, analysis.branches
    mask = analysis.fit_rows | (b.label != LOADING)
    if analysis.rest is not None:
        mask &= ~analysis.rest
    if analysis.softening is not None:
        mask &= b.cycle >= analysis.softening.first_settled
    elif analysis.first_cycle is not None and analysis.first_cycle.differs:
        mask &= b.cycle != 1
    n_load, n_unload = int(np.sum(mask & (b.label == LOADING))), int(np.sum(mask & (b.label == UNLOADING)))
    if n_load >= 2 and n_unload >= 1:
        analysis.hysteresis = hy.measure_hysteresis(lt.B_abs_T, lt.load_N, b.label, [float(e) for e in edges_N], mask)
        try:
            after_hold = hy.rows_after_holds(b.label, b.holds)
            analysis.unloading = hy.fit_unloading(lt.B_abs_T, lt.load_N, b.label, b.turn_force_N, mask, after_hold)
        except CalibrationFailed as exc:
            analysis.notes.append(f"no unloading model: {exc}")
    t = analysis.time_s
    reading_N = force_of_field_N(lt.B_abs_T)
    for hold in b.holds:
        a, z = hold
        if a == 0:
            continue
        held_N = float(np.mean(lt.load_N[a:z]))
        if not held_N > b.dead_band_N:  # a hold at no load: creep as a share of ~0 N is no number
            continue
        try:
            c = hy.creep(t, reading_N, hold, held_force_N=held_N)
        except CalibrationFailed:
            continue
        analysis.creep.append((hold, c))
