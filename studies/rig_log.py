"""A rig log as real as a public sensor's runs (issue 47): the synthetic rig of
studies/rig_loadtest.py (the same printed sensor and forward curve), sampled in time the way a
robot indenter, a load cell and a logger write it. The sizes are those measured on eFlesh's
normal-force runs (MLX90393-class chips, 10 indentations a run, a force sensor); each effect has
its own field (0 turns it off) and a stated truth:

* timing: rows every ``dt_s`` (50 Hz: a 0.1 s pause is five rows); each press rests
  ``rest_s`` at no load, loads linearly in time to its turning force in ``ramp_s``, may hold it
  (``hold_cycles``, ``hold_s``, at ``hold_fraction`` of the full scale), unloads in
  ``ramp_s``; a gap of ``turn_gap_s`` (no rows at all) falls at every turn to unloading;
* the force stream lags the field by ``lag_s``: a row's force is the true force ``lag_s``
  earlier; the load cell adds ``force_noise_N`` and clips at 0 N (an unloaded cell reads 0,
  never below); only a fraction ``force_present`` of the rows carry a force (random rows), the
  others are NaN here (the writer puts -1 or an empty cell);
* the chip: ``noise_uT`` RMS per axis (x, y, z), the LSB of the chip setting; ``drift_uT_per_s``
  on z; ``zero_shift_uT`` on z for the whole run (the zero moved between runs);
* the zero after each unloading: the field stays below the rested zero by ``zero_off_pct`` of
  the |B| span (0 to full scale), ``first_zero_off_pct`` after the run's first press, 2 s after
  the force reached 0, recovering ``zero_recovery_pct_per_decade`` a decade of time (never
  beyond the rested zero);
* the loop: on unloading the rig reads F = F_load - F_turn h(x), x = F_load / F_turn, with h a
  monotone cubic (PCHIP) through ``loop_pct`` at x = 0, 0.25, 0.5, 0.75, 1 (% of F_turn:
  -3 near no load, -0.4..+2 mid-range, 0 at the turn), plus ``open_after_hold_pct`` exp(-(1 - x)
  / 0.3) after a hold (a loop still open at the turn);
* softening: press k is stiffer by A(x) k^-q (force at a deflection x (1 + A k^-q), x the settled
  sensor's force at that deflection / the full scale), A through
  ``softening_pct`` at x = 0.1, 0.5, 0.9 (log A quadratic in x), q = ``softening_decay``; the
  settled sensor (k -> infinity) is the printed truth;
* creep under a hold: the deflection of F_turn (1 + c log10(max(t - t_peak, 0.1 s) / 1 s)),
  c = ``creep_pct_per_decade`` / 100.

The truth of each row (the force at its field's time, the branch, the press, rest rows) comes
with it. Run:  .venv/bin/python studies/rig_log.py
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from rig_loadtest import Curve, forward_curve
from scipy.interpolate import PchipInterpolator

from mst_cli.model import chip as mlx

LOOP_X = (0.0, 0.25, 0.5, 0.75, 1.0)
SOFTENING_X = (0.1, 0.5, 0.9)


@dataclass(frozen=True)
class RigLog:
    cycles: int = 10
    first_cycle: int = 1  # the press number of the first press (a stream continuing a run: 11)
    turn_fraction: tuple[float, ...] = ()  # per press, of the full scale; default 1.0
    dt_s: float = 0.02
    rest_s: float = 3.0
    ramp_s: float = 4.0
    hold_cycles: tuple[int, ...] = (4, 8)
    hold_fraction: float = 0.8  # a press with a hold turns at this fraction of the full scale (the
    # calibrated map ends at the last lock: creep above it would read as the full scale)
    hold_s: float = 5.0
    turn_gap_s: float = 1.1
    lag_s: float = 0.2
    force_noise_N: float = 0.01
    force_present: float = 0.5
    clip_force: bool = True
    noise_uT: tuple[float, float, float] = (3.0, 3.0, 4.5)
    drift_uT_per_s: float = 0.25  # 15 uT a minute
    zero_shift_uT: float = 0.0
    zero_off_pct: float = 1.6
    first_zero_off_pct: float = 3.2
    zero_recovery_pct_per_decade: float = 1.5
    loop_pct: tuple[float, ...] = (-3.0, -0.4, 2.0, 1.5, 0.0)
    open_after_hold_pct: float = 2.5
    softening_pct: tuple[float, float, float] = (68.0, 20.0, 8.0)
    softening_decay: float = 1.5
    creep_pct_per_decade: float = 1.0
    seed: int = 0


def all_off(**kept) -> RigLog:
    """A rig log with every effect off (the timing kept), then ``kept`` turned on."""
    off = dict(
        hold_cycles=(), turn_gap_s=0.0, lag_s=0.0, force_noise_N=0.0, force_present=1.0, clip_force=False,
        noise_uT=(0.0, 0.0, 0.0), drift_uT_per_s=0.0, zero_off_pct=0.0, first_zero_off_pct=0.0,
        zero_recovery_pct_per_decade=0.0, loop_pct=(0.0,) * 5, open_after_hold_pct=0.0,
        softening_pct=(0.0, 0.0, 0.0), creep_pct_per_decade=0.0,
    )  # fmt: skip
    return RigLog(**{**off, **kept})


def loop_h(rig: RigLog, x, after_hold) -> np.ndarray:
    """h(x) (a fraction of F_turn) of the truth loop; ``after_hold``: bool per row."""
    x = np.clip(np.asarray(x, float), 0.0, 1.0)
    h = PchipInterpolator(LOOP_X, np.asarray(rig.loop_pct) / 100)(x)
    return h + np.where(after_hold, 0.01 * rig.open_after_hold_pct * np.exp(-(1 - x) / 0.3), 0.0)


def softening_A(rig: RigLog, x) -> np.ndarray:
    """A(x): the extra stiffness of press 1 over the settled sensor at load fraction x (log A
    quadratic through the three measured points, x held within 0..1)."""
    pct = np.asarray(rig.softening_pct, float)
    if not np.any(pct > 0):
        return np.zeros_like(np.asarray(x, float))
    coef = np.polyfit(SOFTENING_X, np.log(0.01 * pct), 2)
    return np.exp(np.polyval(coef, np.clip(np.asarray(x, float), 0.0, 1.0)))


def stiffness(rig: RigLog, x, press) -> np.ndarray:
    """1 + A(x) k^-q: the force at a deflection over the settled sensor's, press k."""
    return 1.0 + softening_A(rig, x) * np.asarray(press, float) ** -rig.softening_decay


def _schedule(rig: RigLog, F_fs: float) -> list[tuple[str, float, float, float, float, int]]:
    """(kind, t0, t1, F0, F1, press) segments: rest, loading, hold, unloading, a final rest."""
    fractions = rig.turn_fraction or (1.0,) * rig.cycles
    seg, t = [], 0.0
    for i in range(rig.cycles):
        k = rig.first_cycle + i
        F_turn = (rig.hold_fraction if k in rig.hold_cycles and not rig.turn_fraction else fractions[i]) * F_fs
        seg.append(("rest", t, t + rig.rest_s, 0.0, 0.0, k))
        seg.append(("loading", t + rig.rest_s, t + rig.rest_s + rig.ramp_s, 0.0, F_turn, k))
        t += rig.rest_s + rig.ramp_s
        if k in rig.hold_cycles:
            seg.append(("hold", t, t + rig.hold_s, F_turn, F_turn, k))
            t += rig.hold_s
        seg.append(("unloading", t, t + rig.ramp_s, F_turn, 0.0, k))
        t += rig.ramp_s
    seg.append(("rest", t, t + rig.rest_s, 0.0, 0.0, rig.first_cycle + rig.cycles - 1))
    return seg


@dataclass
class LogTruth:
    rig: RigLog
    curve: Curve
    force_N: np.ndarray  # the true force at each row's time (the field's)
    branch: np.ndarray  # rest / loading / hold / unloading
    press: np.ndarray
    span_uT: float  # |B| from no load to full scale


def _rows(rig: RigLog, F_fs: float):
    """Per time step: (t, true force, loading-equivalent force, branch, press, turning force,
    after a hold, seconds since the last unloading ended or NaN, seconds into a hold or NaN)."""
    seg = _schedule(rig, F_fs)
    t = np.arange(0.0, seg[-1][2], rig.dt_s)
    n = len(t)
    F, kind, press = np.zeros(n), np.empty(n, dtype=object), np.zeros(n, int)
    F_turn, after_hold, since_up, into_hold = np.zeros(n), np.zeros(n, bool), np.full(n, np.nan), np.full(n, np.nan)
    last_up, held = math.nan, False
    for name, t0, t1, F0, F1, k in seg:
        at = (t >= t0) & (t < t1)
        F[at] = F0 + (F1 - F0) * (t[at] - t0) / (t1 - t0)
        kind[at], press[at] = name, k
        since_up[at] = t[at] - last_up
        if name == "loading":
            held = False
        if name == "hold":
            into_hold[at], held = t[at] - t0, True
        if name in ("hold", "unloading"):
            F_turn[at] = F0
            after_hold[at] = held and name == "unloading"
        if name == "unloading":
            last_up = t1
    return t, F, kind, press, F_turn, after_hold, since_up, into_hold, seg


def rig_log(rig: RigLog, curve: Curve | None = None) -> tuple[dict[str, np.ndarray], LogTruth]:
    """The rows (force_N, NaN where the logger wrote none; Bx_uT, By_uT, Bz_uT; time_s) and the truth."""
    curve = curve or forward_curve()
    F_fs = curve.full_scale_N
    t, F, kind, press, F_turn, after_hold, since_up, into_hold, seg = _rows(rig, F_fs)
    F_load = F.copy()  # the loading branch's force at each row's deflection
    un = kind == "unloading"
    x = np.clip(F[un] / F_turn[un], 0, 1)
    for _ in range(30):  # F = F_load - F_turn h(F_load / F_turn): fixed point
        x = np.clip((F[un] + F_turn[un] * loop_h(rig, x, after_hold[un])) / F_turn[un], -0.2, 1.2)
    F_load[un] = np.clip(x, 0.0, None) * F_turn[un]
    hold = kind == "hold"
    c = 0.01 * rig.creep_pct_per_decade
    F_load[hold] = F[hold] * (1 + c * np.log10(np.maximum(into_hold[hold], 0.1)))
    Fe = F_load.copy()
    for _ in range(20):  # the settled sensor's force at the deflection: F_load = Fe (1 + A(Fe / F_fs) k^-q)
        Fe = F_load / stiffness(rig, Fe / F_fs, press)
    B = curve.field_T(Fe)
    span_T = float(curve.field_abs_T(F_fs) - curve.field_abs_T(0.0))
    first_up = next(s[2] for s in seg if s[0] == "unloading")
    A = np.where(t - since_up <= first_up + 1e-9, rig.first_zero_off_pct, rig.zero_off_pct) * 0.01 * span_T
    R = 0.01 * rig.zero_recovery_pct_per_decade * span_T
    off = np.where(np.isfinite(since_up), -(A - R * np.log10(np.maximum(since_up, 0.1) / 2.0)), 0.0)
    B[:, 2] += np.clip(off, -(A + 2 * R), 0.0) + 1e-6 * (rig.drift_uT_per_s * t + rig.zero_shift_uT)
    rng = np.random.default_rng(rig.seed)
    B += 1e-6 * np.asarray(rig.noise_uT) * rng.standard_normal(B.shape)
    lsb = np.array([curve.xy_uT_per_lsb, curve.xy_uT_per_lsb, curve.z_uT_per_lsb])
    B_uT = np.stack([mlx.quantise_lsb(B[:, i], lsb[i]) * lsb[i] for i in range(3)], -1)
    logged = np.interp(t - rig.lag_s, t, F, left=0.0) + rig.force_noise_N * rng.standard_normal(len(t))
    if rig.clip_force:
        logged = np.maximum(logged, 0.0)
    logged[rng.random(len(t)) >= rig.force_present] = np.nan
    keep = np.ones(len(t), bool)
    for name, t0, _t1, *_ in seg:
        if name == "unloading" and rig.turn_gap_s > 0:
            keep &= np.abs(t - t0) > 0.5 * rig.turn_gap_s
    rows = {"force_N": logged, "Bx_uT": B_uT[:, 0], "By_uT": B_uT[:, 1], "Bz_uT": B_uT[:, 2], "time_s": t}
    rows = {k: np.round(v[keep], 6) for k, v in rows.items()}
    truth = LogTruth(rig, curve, F[keep], kind[keep], press[keep], span_T * 1e6)
    return rows, truth


def write_log(path, rows: dict, missing: str = "-1") -> None:
    """The rows as a logger writes them: ``missing`` where a row has no force."""
    cols = ("time_s", "force_N", "Bx_uT", "By_uT", "Bz_uT")
    lines = [",".join(cols)]
    for i in range(len(rows["time_s"])):
        cells = [missing if c == "force_N" and not np.isfinite(rows[c][i]) else f"{rows[c][i]:.6g}" for c in cols]
        lines.append(",".join(cells))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main() -> None:
    rows, truth = rig_log(RigLog())
    n = len(rows["time_s"])
    print(f"{n} rows over {rows['time_s'][-1]:.1f} s, force on {np.isfinite(rows['force_N']).mean():.0%} of them")
    print(f"|B| span {truth.span_uT:.0f} uT; full scale {truth.curve.full_scale_N:.2f} N")
    for k in (1, 2, 10):
        print(
            f"press {k}: extra stiffness at 10/50/90 % FS",
            np.round(100 * (stiffness(truth.rig, SOFTENING_X, k) - 1), 1),
        )


if __name__ == "__main__":
    main()
