"""The plate between unlike layers, its overhang with one pad: tried, not built (issue 44,
docs/design.md 4.7, "The closed form over the design box").

``load_path.plates_mm_per_N`` bends the plate between two layers whose walls stand at different
x as a span between the nearer pair of walls and a cantilever out to the other pair, both with
the section of the plate and both layers' pads. Past the nearer pair only the outer layer's pad
is bonded to the plate (the inner one ends at its own walls), as ``model.past_lock`` already
takes for a plate over a locked layer. The trial bends the overhang with the plate and that pad
alone (studies/data/plate_overhang.patch is the same change to the model, for ``git apply``).

Prints, per design, the rung's plates in regime 1 (every layer open: plates in TPU, the rest
rigid, less every member rigid) against the closed form now and with the trial, um/N, and the
part's figure per regime (the closed form's linear model against the rung as printed). In the
regimes marked "(lands)" the closed form's cover is on the board (the linear rung has no
contact: not like for like). The sampled designs come from a CSV of studies/member_regimes.py
(rebuilt from its seed), the bundled ones are measured here (2 rung solves a regime).

    PYTHONPATH=. .venv/bin/python studies/plate_overhang.py --csv member_regimes.csv --designs 40 --seed 1
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import tempfile
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.beams import section_EI_kGA
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.stack import Stack
from studies import member_regimes as mr

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ("mohammadi2021", "fingertip", "mohammadi2021-forward", "mohammadi2021-compact")


def plates_one_pad_overhang(scene, t_below_mm, t_above_mm, head_below_mm, head_above_mm, sway_below, sway_above):
    """``load_path.plates_mm_per_N`` with the overhang's section the plate and the outer pad."""
    s, P = scene, 0.5
    tb, ta, hb, ha = (np.asarray(a, dtype=float) for a in (t_below_mm, t_above_mm, head_below_mm, head_above_mm))
    EI_in, _ = section_EI_kGA(s.depth_mm, tb + s.plate_mm + ta, s.E_prime_MPa, s.G_MPa)
    EI_out, kGA_out = section_EI_kGA(s.depth_mm, np.where(hb > ha, tb, ta) + s.plate_mm, s.E_prime_MPa, s.G_MPa)
    near, e = np.minimum(hb, ha), np.abs(hb - ha)
    rho = 1.0 / (1.0 + (sway_below + sway_above) * near / EI_in)
    return P * (rho * e * e * near / EI_in + e**3 / 3.0 / EI_out) + P * e / kGA_out


@contextlib.contextmanager
def trial_plates():
    """load_path's plates replaced by the trial's while inside (the forward model's path only;
    the design loop's seed tables import their own name: the patch file changes both)."""
    kept = lp.plates_mm_per_N
    lp.plates_mm_per_N = plates_one_pad_overhang
    try:
        yield
    finally:
        lp.plates_mm_per_N = kept


def closed_figures(g, m) -> tuple[float, list[float], list[bool]]:
    """(the plates in regime 1 with their joints, um/N; the part per regime as the closed form's
    linear model gives it, um/N; per regime whether its cover lands on the board before the
    regime ends, a contact the linear rung does not have)."""
    stack = Stack(layer_laws(g.layers, m, "spring"))
    parts = lp.members(g, m)
    plates = 1e3 * (sum(parts.plates_mm_per_N) + sum(parts.joints_mm_per_N))
    shares = lp.motion_shares(stack, parts)
    lands = [lp.cover_landing_N(parts) < r["force_N"][1] for r in shares]
    return plates, [1e3 * r["small_load_compliance_mm_per_N"] for r in shares], lands


def rung_figures(g, m) -> tuple[float, list[float]]:
    """(the rung's plates in regime 1, the rung as printed per regime), um/N."""
    stack = Stack(layer_laws(g.layers, m, "spring"))
    rigid = wp.press(g, m, wp.PartOptions(member_factor=wp.RIGID_FACTOR)).drop_mm_per_N
    plates = wp.press(g, m, wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=("base", "cap"))).drop_mm_per_N
    printed = [wp.press(g, m, wp.PartOptions(locked=locked)).drop_mm_per_N for locked in wp.regime_locked(stack)]
    return 1e3 * (plates - rigid), [1e3 * p for p in printed]


def row(name: str, g, m, rung_plates: float, printed: list[float]) -> str:
    now_plates, now_part, lands = closed_figures(g, m)
    with trial_plates():
        trial_plates_, trial_part, _ = closed_figures(g, m)
    parts = " / ".join(
        f"{n / p - 1:+.1%} → {t / p - 1:+.1%}" + (" (lands)" if landed else "")
        for n, t, p, landed in zip(now_part, trial_part, printed, lands)
    )
    return (
        f"| {name} | {rung_plates:.1f} | {now_plates:.1f} ({now_plates / rung_plates:.2f}) | "
        f"{trial_plates_:.1f} ({trial_plates_ / rung_plates:.2f}) | {parts} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", type=Path, help="a CSV of studies/member_regimes.py (its sampled designs)")
    ap.add_argument("--designs", type=int, default=0, help="how many designs that CSV's run sampled")
    ap.add_argument("--seed", type=int, default=1, help="and its seed")
    ap.add_argument("--no-bundled", action="store_true", help="leave out the bundled designs (their rung solves)")
    args = ap.parse_args()
    print("| design | rung's plates, regime 1 | closed form now | trial | part per regime, now → trial |")
    print("|---|---|---|---|---|")
    if not args.no_bundled:
        for name in BUNDLED:
            doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
            print(row(name, doc.geometry(), doc.material, *rung_figures(doc.geometry(), doc.material)), flush=True)
    if args.csv is None:
        return
    with args.csv.open() as f:
        rows = list(csv.DictReader(f))
    with tempfile.TemporaryDirectory() as tmp:
        for path in mr.sampled_designs(Path(tmp), args.designs, args.seed):
            mine = [r for r in rows if r["name"] == path.stem]
            if not mine:
                continue
            doc, _ = mst.designed(path)
            printed = [float(r["printed"]) for r in mine]
            print(row(path.stem, doc.geometry(), doc.material, float(mine[0]["rung_plate"]), printed), flush=True)


if __name__ == "__main__":
    main()
