"""A rig's load test in ``mst calibrate`` (issue 38): the branches, which rows the elastic fit
uses, and what the calibration reports about the rest.

* the branches (:func:`~mst_cli.calibrate.branches.find_branches`) from the force in time order
  (``time_s``, else row order), the rig's own ``branch`` and ``cycle`` columns checked against it;
* a first cycle that differs from the later ones beyond noise
  (:func:`~mst_cli.calibrate.hysteresis.first_cycle`) is left out of the fit;
* the elastic model is fitted to the LOADING rows: unloading rows read less force at the same
  field (hysteresis) and hold rows creep, neither is the elastic loading curve. A load test whose
  loading rows alone cannot carry the fit (a staircase of holds: too few rows, or less than
  :data:`MIN_LOADING_SPAN` of the force span) keeps its hold rows in the fit, and says so;
* after the fit, per regime of the calibrated model: the largest hysteresis (loading minus
  unloading force at matched |B|, % of the regime's band) and where; the unloading branch
  relative to the loading one (:class:`~mst_cli.calibrate.hysteresis.UnloadingModel`, what
  ``mst read`` uses); creep under each hold (% of the held force per decade of time).

``use_branches=False`` is the calibration that ignores branches (every row as loading): the
"before" of benchmarks/bench_rig.py.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import numpy as np

from mst_cli.calibrate import hysteresis as hy
from mst_cli.calibrate.branches import HOLD, LOADING, UNLOADING, Branches, find_branches
from mst_cli.calibrate.loadtest import Readings, rig_column
from mst_cli.errors import CalibrationFailed, InputError

MIN_LOADING_SPAN = 0.5  # loading rows must span this fraction of the force span, else holds are fitted too


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

    @property
    def full_scale_N(self) -> float:
        """The calibrated model's last lock force (after :func:`describe`; the largest force before)."""
        return float(self.hysteresis[-1].hi_N) if self.hysteresis else float(np.max(self.readings.load_N))

    @property
    def time_s(self) -> np.ndarray:
        t = rig_column(self.readings, "time_s")
        return np.arange(len(self.readings), dtype=float) if t is None else t

    def counts(self) -> dict[str, int]:
        return {k: int(np.sum(self.branches.label == k)) for k in (LOADING, UNLOADING, HOLD)}

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
            "unloading_model": None
            if self.unloading is None
            else {
                "form": "F_unloading = F_loading - F_turn x (1 - x) (a + b x), x = F_loading / F_turn",
                "a": self.unloading.a,
                "b": self.unloading.b,
                "residual_rms_N": self.unloading.residual_rms_N,
                "rows": self.unloading.samples,
            },
            "first_cycle": None
            if fc is None
            else {
                "stiffer_pct": fc.difference_pct,
                "sigma_pct": fc.sigma_pct,
                "differs": fc.differs,
                "left_out_of_fit": bool(fc.differs and self.use_branches),
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
            f"branches: {n[LOADING]} loading, {n[UNLOADING]} unloading, {n[HOLD]} hold rows in "
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
                f"  unloading model a {u.a:.4g}, b {u.b:.4g} (residual {u.residual_rms_N:.3g} N RMS, {u.samples} rows)"
            )
        fc = self.first_cycle
        if fc is not None and fc.differs:
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


def analyse(lt: Readings, min_rows: int, use_branches: bool = True) -> RigAnalysis:
    """The branches and the rows the fit uses (module doc); ``min_rows``: what the fit needs."""
    b = branches_of(lt)
    notes: list[str] = []
    fc = None
    if int(b.cycle.max(initial=1)) > 1:
        try:
            fc = hy.first_cycle(lt.B_abs_T, lt.load_N, b.label, b.cycle)
        except CalibrationFailed:
            fc = None
    if not use_branches:
        return RigAnalysis(lt, b, np.ones(len(lt), bool), False, fc, notes)
    keep = hy.rows_without_first_cycle(b.cycle, fc) if fc is not None else np.ones(len(lt), bool)
    rows = keep & (b.label == LOADING)
    F = lt.load_N
    span = float(np.ptp(F)) if len(F) else 0.0
    if rows.sum() < min_rows or (span > 0 and (np.ptp(F[rows]) if rows.any() else 0.0) < MIN_LOADING_SPAN * span):
        rows = keep & (b.label != UNLOADING)
        notes.append("too few loading rows for the fit alone: hold rows fitted as loading")
    if rows.sum() < min_rows:
        rows = np.ones(len(lt), bool)
        notes.append("too few loading and hold rows for the fit: every row fitted as loading")
    return RigAnalysis(lt, b, rows, True, fc, notes)


def describe(analysis: RigAnalysis, edges_N: np.ndarray, force_of_field_N) -> None:
    """After the fit: hysteresis per regime of the calibrated model (``edges_N``), the unloading
    model and creep under each hold (the reading as force: ``force_of_field_N(|B|)``)."""
    lt, b = analysis.readings, analysis.branches
    mask = analysis.fit_rows | (b.label != LOADING)
    if analysis.first_cycle is not None and analysis.first_cycle.differs:
        mask &= b.cycle != 1
    n_load, n_unload = int(np.sum(mask & (b.label == LOADING))), int(np.sum(mask & (b.label == UNLOADING)))
    if n_load >= 2 and n_unload >= 1:
        analysis.hysteresis = hy.measure_hysteresis(lt.B_abs_T, lt.load_N, b.label, [float(e) for e in edges_N], mask)
        try:
            analysis.unloading = hy.fit_unloading(lt.B_abs_T, lt.load_N, b.label, b.turn_force_N, mask)
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
