"""The designed specs' parts on the whole-part rung as the plates between their layers thicken
(issue 44, docs/design.md 4.7, "The plates, swept with the check"). Prints a table, changes
nothing.

    PYTHONPATH=. .venv/bin/python studies/plate_sweep.py [--configs a.yaml ...] [--plates 0.8 1.6 ...]

Each spec is written again with ``housing.plate_mm`` set, designed and exported as ``mst export
SPEC`` does, and checked as ``mst check --whole-part`` does: per regime, the design's stated
field change per newton at the chip against the rung's (stated / rung - 1), the 5 / 8 / 20 %
budget, and the part's height. About 20 s a point on a quiet 2-core machine.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import yaml

import mst_cli as mst
from mst_cli.cad.manifest import load_manifest

ROOT = Path(__file__).resolve().parents[1]


def sweep_row(spec: Path, plate_mm: float, folder: Path) -> str:
    raw = yaml.safe_load(spec.read_text())
    raw["housing"] = {**(raw.get("housing") or {}), "plate_mm": plate_mm}
    path = folder / f"{spec.stem}-{plate_mm}.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    out = folder / f"{spec.stem}-{plate_mm}"
    mst.export(path, out, stl=True)
    (check,) = [c for c in mst.check(out, whole_part=True) if c.name == "whole_part"]
    errors = " / ".join(f"{100 * r['error_rel']:+.1f}" for r in check.values["regimes"])
    height = load_manifest(out / "export.json").design.geometry().total_height_mm
    return f"| {spec.stem} | {plate_mm:g} | {errors} | {'pass' if check.passed else 'fail'} | {height:.2f} |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = [ROOT / "configs" / "mohammadi2021.yaml", ROOT / "configs" / "fingertip.yaml"]
    ap.add_argument("--configs", nargs="*", type=Path, default=default)
    ap.add_argument("--plates", nargs="*", type=float, default=[0.8, 1.2, 1.6, 2.0, 2.4])
    args = ap.parse_args()
    print("| spec | plate_mm | stated / rung - 1 per regime, % | budget 5 / 8 / 20 % | part height, mm |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for spec in args.configs:
            for plate in args.plates:
                print(sweep_row(spec, plate, Path(tmp)), flush=True)


if __name__ == "__main__":
    main()
