"""Each member's drop on the whole-part rung, regime by regime, over sampled designs: the data a
closed form of the members past the locks needs (issue 44, docs/design.md 4.7). Writes a CSV,
changes nothing.

    PYTHONPATH=. .venv/bin/python studies/member_regimes.py --designs 30 --out member_regimes.csv
    PYTHONPATH=. .venv/bin/python studies/member_regimes.py --configs configs/*.yaml --out bundled.csv
    PYTHONPATH=. .venv/bin/python studies/member_regimes.py --summary member_regimes.csv

A sampled design is the forward config with three layers drawn uniformly from the box below (the
walls' angle and thickness, and the cavity h - 2t), its cover and plates drawn from the thicknesses below. Per
regime (the layers locked before it closed, as on the rung), seven solves: every member rigid;
then one member class as printed, the others rigid: the base (the cover and the slot's walls and
floor), the cover alone (the base below the slot's roof rigid), the slot's walls alone (the
cover rigid), the plates, the cap; then the part as printed. Each member's extra drop over the
rigid solve sits beside the closed form's member as the forward model moves it in that regime
(``load_path.member_band_compliances``), um/N; "rest" is what the members give together beyond
the sum of the three classes' extras. About 2 min a design on one core.

``--summary``: per regime, each member's rung / closed-form ratio over the CSV's designs (median,
spread) and the base's split: what the cover and the slot's walls give alone and together.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import tempfile
from pathlib import Path

import numpy as np
import yaml

import mst_cli as mst
from mst_cli.errors import InputError
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
THETA_DEG = ((10.0, 40.0), (15.0, 60.0), (20.0, 75.0))  # bottom to top
T_MM, CAVITY_MM = (0.4, 1.0), (0.45, 1.6)  # the cavity h - 2t: the printable gap 0.4 mm and up
COVER_MM, PLATE_MM = (0.8, 1.5, 2.2, 3.0), (0.8, 1.2, 1.6, 2.0)
# the rung's solves per regime: (column, the member classes held rigid, the base's part held rigid)
SOLVES = (
    ("base", ("plate", "cap"), ""),
    ("cover", ("plate", "cap"), "slot_walls"),
    ("slot_walls", ("plate", "cap"), "cover"),
    ("plate", ("base", "cap"), ""),
    ("cap", ("base", "plate"), ""),
)
FIELDS = ["name", "regime", "locked", "theta_deg", "t_mm", "h_mm", "cover_mm", "plate_mm", "rigid", "printed"]
FIELDS += [f"rung_{k}" for k, _, _ in SOLVES] + ["rest", "closed_base", "closed_plate", "closed_cap"]
FIELDS += ["closed_part", "regime_from_N", "regime_to_N", "cover_lands_N"]


def sampled_designs(folder: Path, n: int, seed: int) -> list[Path]:
    """``n`` configs: the forward design with layers, cover and plates drawn from the box."""
    rng = np.random.default_rng(seed)
    base = yaml.safe_load(FORWARD.read_text())
    paths = []
    for i in range(n):
        layers = []
        for j in range(3):
            t = round(float(rng.uniform(*T_MM)), 3)
            theta, cavity = float(rng.uniform(*THETA_DEG[j])), float(rng.uniform(*CAVITY_MM))
            layers.append({"theta_deg": round(theta, 2), "t_mm": t, "h_mm": round(2.0 * t + cavity, 3)})
        housing = {**base.get("housing", {}), "cover_mm": float(rng.choice(COVER_MM))}
        housing["plate_mm"] = float(rng.choice(PLATE_MM))
        doc = {**base, "name": f"sample-{seed}-{i}", "layers": layers, "housing": housing}
        path = folder / f"{doc['name']}.yaml"
        path.write_text(yaml.safe_dump(doc))
        paths.append(path)
    return paths


def closed_rows(g, m, stack) -> list[dict]:
    """Per regime of the part ``g`` in ``m`` (``stack``: its layers alone): the closed form's
    members as the forward model moves them there, the part as its linear model gives it (the
    rung's kind of figure), the regime's forces and where the cover lands on the board (a
    contact the linear rung does not have), um/N and N."""
    parts = lp.members(g, m)
    moving = lp.member_band_compliances(stack, parts)[2]
    rows = []
    for r, share in enumerate(lp.motion_shares(stack, parts)):
        row = {
            f"closed_{k}": 1e3 * float(moving[v][r])
            for k, v in (("base", "housing"), ("plate", "plates"), ("cap", "cap"))
        }
        row["closed_part"] = 1e3 * share["small_load_compliance_mm_per_N"]
        row["regime_from_N"], row["regime_to_N"] = (float(f) for f in share["force_N"])
        rows.append(row | {"cover_lands_N": lp.cover_landing_N(parts, lp.first_lock_N(stack.layers, parts))})
    return rows


def design_rows(path: Path) -> list[dict]:
    """Per regime of the design at ``path``: the rung's solves (module docstring) and the closed
    form's figures (:func:`closed_rows`), um/N."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    stack = Stack(layer_laws(g.layers, m, "spring"))
    closed = closed_rows(g, m, stack)
    cells = {k: " ".join(f"{getattr(c, k):g}" for c in g.layers) for k in ("theta_deg", "t_mm", "h_mm")}
    rows = []
    for r, locked in enumerate(wp.regime_locked(stack)):
        opts = {"locked": locked, "member_factor": wp.RIGID_FACTOR}
        rigid = wp.press(g, m, wp.PartOptions(**opts)).drop_mm_per_N
        row = {"name": doc.name, "regime": r + 1, "locked": " ".join(str(j) for j in locked), **cells}
        row |= {"cover_mm": g.housing.cover_mm, "plate_mm": g.housing.plate_mm}
        for key, stiff, base_part in SOLVES:
            others = tuple(tag for tag in wp.MEMBER_TAGS if tag in stiff)
            options = wp.PartOptions(**opts, scaled=others, rigid_base=base_part)
            row[f"rung_{key}"] = 1e3 * (wp.press(g, m, options).drop_mm_per_N - rigid)
        printed = 1e3 * wp.press(g, m, wp.PartOptions(locked=locked)).drop_mm_per_N
        row |= {"rigid": 1e3 * rigid, "printed": printed}
        row["rest"] = printed - row["rigid"] - sum(row[f"rung_{k}"] for k in ("base", "plate", "cap"))
        row |= closed[r]
        print(
            "  " + ", ".join(f"{k} {v:.2f}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()), flush=True
        )
        rows.append(row)
    return rows


def spread(values: list[float], form: str = ".2f") -> str:
    """median (least-most) of ``values``."""
    return f"{statistics.median(values):{form}} ({min(values):{form}} to {max(values):{form}})"


def summary(path: Path) -> None:
    """Per regime over the CSV's designs: the part's closed form against the rung (its error,
    and how many within 5 %), each member's rung / closed-form ratio (median, least, most) and
    the base's split (the cover and the slot's walls alone, and what they add together). A
    regime whose cover lands on the board in the closed form is left out of the part's error
    (a contact the linear rung does not model)."""
    with path.open() as f:
        rows = list(csv.DictReader(f))
    print("| regime | designs | part: closed / rung - 1 | within 5 % | base | plates | cap | rest / part |")
    print("|---|---|---|---|---|---|---|---|")
    splits = []
    for regime in sorted({int(r["regime"]) for r in rows}):
        group = [r for r in rows if int(r["regime"]) == regime]
        free = [r for r in group if float(r["cover_lands_N"]) >= float(r["regime_to_N"])]
        error = [float(r["closed_part"]) / float(r["printed"]) - 1.0 for r in free]
        ratio = {
            k: [float(r[f"rung_{k}"]) / float(r[f"closed_{k}"]) for r in free if float(r[f"closed_{k}"]) > 0]
            for k in ("base", "plate", "cap")
        }
        rest = [float(r["rest"]) / float(r["printed"]) for r in free]
        within = sum(abs(e) <= 0.05 for e in error)
        print(
            f"| {regime} | {len(free)} of {len(group)} | {spread(error, '+.0%')} | {within} | "
            f"{spread(ratio['base'])} | {spread(ratio['plate'])} | {spread(ratio['cap'])} | {spread(rest, '+.1%')} |"
        )
        together = [float(r["rung_base"]) - float(r["rung_cover"]) - float(r["rung_slot_walls"]) for r in group]
        splits.append(
            (regime, [float(r["rung_cover"]) for r in group], [float(r["rung_slot_walls"]) for r in group], together)
        )
    print("\n| regime | the base's cover alone, um/N | its slot walls alone | what they add together |")
    print("|---|---|---|---|")
    for regime, cover, walls, together in splits:
        print(f"| {regime} | {spread(cover)} | {spread(walls)} | {spread(together)} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("member_regimes.csv"))
    ap.add_argument("--designs", type=int, default=0, help="how many sampled designs")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--configs", type=Path, nargs="*", default=[], help="configs to run besides the sampled ones")
    ap.add_argument("--summary", type=Path, help="no rung: summarise this CSV")
    args = ap.parse_args()
    if args.summary:
        summary(args.summary)
        return
    with tempfile.TemporaryDirectory() as tmp, args.out.open("w", newline="") as f:
        out = csv.DictWriter(f, FIELDS)
        out.writeheader()
        for path in [*args.configs, *sampled_designs(Path(tmp), args.designs, args.seed)]:
            try:
                rows = design_rows(path)
            except InputError as e:  # a cell that cannot be drawn, or a part that does not fit
                print(f"  skipped {path.name}: {e}", flush=True)
                continue
            out.writerows({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in row.items()} for row in rows)
            f.flush()


if __name__ == "__main__":
    main()
