"""Why the lag estimate reads high on the real rig's log (studies/rig_log.py; tests/test_rig_log.py
documents the bias): the rig's effects one at a time over the lag alone, then all but one, each
on six noise seeds, through ``time_alignment.estimate_lag`` (no calibration: seconds a row).

    PYTHONPATH=. .venv/bin/python studies/lag_bias.py   (about 1 min)
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from rig_log import RigLog, all_off, rig_log

from mst_cli.calibration.time_alignment import estimate_lag

SEEDS = range(1, 7)
EFFECTS = {  # each effect at the real rig's size (RigLog's defaults)
    k: getattr(RigLog(), k)
    for k in (
        "hold_cycles", "turn_gap_s", "force_noise_N", "force_present", "clip_force", "noise_uT", "drift_uT_per_s",
        "zero_off_pct", "first_zero_off_pct", "zero_recovery_pct_per_decade", "loop_pct", "open_after_hold_pct",
        "softening_pct", "creep_pct_per_decade",
    )
}  # fmt: skip


def row(rig: RigLog, label: str) -> str:
    lags = []
    for seed in SEEDS:
        rows, _ = rig_log(replace(rig, seed=seed))
        B = 1e-6 * np.linalg.norm(np.stack([rows[c] for c in ("Bx_uT", "By_uT", "Bz_uT")], -1), axis=1)
        lags.append(1e3 * estimate_lag(rows["time_s"], B, rows["force_N"])[0])
    bias = np.mean(lags) - 1e3 * rig.lag_s
    return f"| {label} | {bias:+.1f} | {np.std(lags):.1f} | " + " ".join(f"{x:.0f}" for x in lags) + " |"


def main() -> None:
    print(f"the lag's estimate, ms, true {1e3 * RigLog().lag_s:.0f} ms, seeds {SEEDS.start}-{SEEDS.stop - 1}")
    print("| rig | bias | sd | per seed |")
    print("|---|---|---|---|")
    print(row(RigLog(), "all on"), flush=True)
    print(row(all_off(lag_s=RigLog().lag_s), "the lag alone"), flush=True)
    for name, value in EFFECTS.items():
        print(row(all_off(lag_s=RigLog().lag_s, **{name: value}), f"the lag + {name}"), flush=True)
    for name in EFFECTS:
        rest = {k: v for k, v in EFFECTS.items() if k != name}
        print(row(all_off(lag_s=RigLog().lag_s, **rest), f"all but {name}"), flush=True)


if __name__ == "__main__":
    main()
