"""Reading off-centre presses with all three field axes (issue 24): how far `mst read
--estimate-offset` corrects the force, against what the centred reading gets wrong.

Synthetic readings of the bundled sensor (configs/mohammadi2021-forward.yaml): presses at
--offsets random points within 80 % of the top face (seeded), at forces spread over every
regime, the field from the tilt rung on the *continuum* (L2) layer laws (--truth spring: on
the reader's own, which leaves the noise alone), plus the chip's noise (2 uT rms per axis,
seeded). They are read with the design file's own rung (spring, L0), as `mst read` would read
them: the centred inverse map, then the offset estimate. So the numbers hold the chip's noise
and L0's error against L2, not the tilt rung's own error against a full 3D sensor
(docs/design.md section 4.2 says how far that rung is checked).

Printed per press and overall: the centred reading's force error, the corrected one's on the
readings whose offset is identifiable (1-sigma under 1 mm), how many are, and how often the
true offset lies within 2 sigma of the estimate.

Run:  .venv/bin/python studies/offset_reading.py [--offsets 5 --seed 3 --per-regime 4]   # ~1 min
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.offset_reading import OffsetEstimator
from mst_cli.model.general_load import pose_field_T
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.document import load_design_document

DESIGN = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
NOISE_T = 2e-6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--offsets", type=int, default=5)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--per-regime", type=int, default=4, help="forces per regime")
    ap.add_argument(
        "--truth", choices=("continuum", "spring"), default="continuum", help="the layer laws of the synthetic sensor"
    )
    args = ap.parse_args()
    doc, _ = load_design_document(DESIGN)
    geo, mat = doc.geometry(), doc.material
    imap, resp = inverse_map(doc, "spring")
    truth = tilt_laws(geo, mat, args.truth)
    est = OffsetEstimator(geo, mat, "spring", imap.field_resolution_T, float(imap.force_N[-1]))
    rng = np.random.default_rng(args.seed)
    edges = np.concatenate([[0.0], resp.lock_forces_N])
    fr = (np.arange(args.per_regime) + 0.5) / args.per_regime
    F = np.concatenate([lo + fr * (hi - lo) for lo, hi in zip(edges[:-1], edges[1:])])
    half = 0.4 * np.array([geo.width_mm, geo.depth_mm])
    t0 = time.perf_counter()
    rows = []
    print("| press (x, y) mm | centred: median / max error | corrected: median / max | identifiable | within 2 sigma |")
    print("|---|---|---|---|---|")
    for _ in range(args.offsets):
        off = tuple(float(v) for v in rng.uniform(-half, half))
        B = pose_field_T(geo, truth, F, off) + rng.normal(0.0, NOISE_T, (len(F), 3))
        Fc, _, flag = imap.force(np.linalg.norm(B, axis=1), np.zeros(len(F), bool))
        r = est.estimate_all(B, np.where(flag == "ok", Fc, np.nan))
        ok = r.flag == "ok"
        e_c = np.abs(Fc / F - 1.0)
        e_o = np.abs(r.force_N[ok] / F[ok] - 1.0)
        inside = (np.abs(r.x_mm[ok] - off[0]) <= 2 * r.sigma_x_mm[ok]) & (
            np.abs(r.y_mm[ok] - off[1]) <= 2 * r.sigma_y_mm[ok]
        )
        rows.append((e_c, e_o, ok, inside))
        print(
            f"| ({off[0]:.1f}, {off[1]:.1f}) | {100 * np.nanmedian(e_c):.1f} / {100 * np.nanmax(e_c):.1f} % "
            f"| {100 * np.median(e_o):.1f} / {100 * np.max(e_o):.1f} % | {ok.sum()} of {len(F)} "
            f"| {inside.sum()} of {ok.sum()} |"
        )
    e_c = np.concatenate([r[0] for r in rows])
    e_o = np.concatenate([r[1] for r in rows])
    n_ok = sum(int(r[2].sum()) for r in rows)
    n_in = sum(int(r[3].sum()) for r in rows)
    print(
        f"all {len(e_c)} readings: centred median {100 * np.nanmedian(e_c):.1f} %, max {100 * np.nanmax(e_c):.1f} %; "
        f"corrected ({n_ok} identifiable) median {100 * np.median(e_o):.1f} %, max {100 * np.max(e_o):.1f} %; "
        f"true offset within 2 sigma on {n_in} of {n_ok}; {time.perf_counter() - t0:.0f} s"
    )


if __name__ == "__main__":
    main()
