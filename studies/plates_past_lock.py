"""What if a plate kept bending after the layer under it locks (issue 44, docs/design.md 4.7)?
A what-if on `mst check --whole-part`'s own figures; builds no model, changes nothing.

    PYTHONPATH=. .venv/bin/python studies/plates_past_lock.py

mst's closed form stops a plate's bending (model.load_path's beam of the plate across the lower
layer's wall heads) when the layer under it locks. The whole-part rung fills a locked layer's
cavity, and the plate over it keeps bending. Per bundled design (the specs designed first, each
exported as `mst export` writes it), per regime: the check's like-for-like error, stated / rung
- 1, and the same with each plate over a locked layer adding its beam's compliance to the
stated drop (both drops are the field change per newton over the check's dB_z/dz). The lock
forces are left where they are, so this is a first-order estimate of such a model, not one.
The rung's solves are kept in mst's cache: about 1 min a design the first time.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import mst_cli as mst
from mst_cli.model import load_path as lp

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("mohammadi2021-forward", "mohammadi2021", "fingertip")


def what_if(config: Path, part: Path) -> tuple[list[float], list[float]]:
    """(the check's error per regime, the error with the plates' beams past their lock)."""
    mst.export(config, part, stl=True)
    (check,) = [c for c in mst.check(part, whole_part=True) if c.name == "whole_part"]
    doc, _ = mst.designed(config)
    beams = lp.members(doc.geometry(), doc.material).plates_mm_per_N
    per_mm = check.values["field_per_drop_uT_per_mm"]
    now, then = [], []
    for r in check.values["regimes"]:
        stated, rung = r["stated_uT_per_N"] / per_mm, r["rung_uT_per_N"] / per_mm
        past = sum(beams[j - 1] for j in r["locked_layers"] if j - 1 < len(beams))  # plate j - 1 is over layer j
        now.append(stated / rung - 1.0)
        then.append((stated + past) / rung - 1.0)
    return now, then


def main() -> None:
    print("| design | the check, regimes 1 / 2 / 3 | with the beams past the lock |\n|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in CONFIGS:  # a spec is designed by export, as `mst export SPEC` does
            now, then = what_if(ROOT / "configs" / f"{name}.yaml", Path(tmp) / name)
            cells = [" / ".join(f"{100 * v:+.1f}" for v in e) + " %" for e in (now, then)]
            print(f"| {name} | {cells[0]} | {cells[1]} |", flush=True)


if __name__ == "__main__":
    main()
