"""The housing's base under an off-centre press's moment, regime by regime (issue 44, docs/design.md
4.7, "The base's portal under a moment"): the whole-part rung's base against mst's cover and the
section frame's base. Prints a table; solves nothing on the rung (it reads the rows
``benchmarks/bench_whole_part.py --off-centre --every-regime --out studies/data/member_turns.csv``
stored).

    PYTHONPATH=. .venv/bin/python studies/base_portal.py [--rows studies/data/member_turns.csv]

Per design and regime (the bench's: the layers alone's lock order), mrad/(N mm) of turn per N mm:

* the rung: the base alone in TPU (the rest rigid) less every member rigid;
* mst's cover: the cover's turn per N mm in mst's tilt rung where the part's regime starts;
* the closed form before the portal: the cover's centred rate over the chevron lever squared, C /
  x_c^2 (what the tilt rung took in every regime until 2026-12-04);
* the frame: model.plate_sway's base alone in TPU under a pure moment at the cap, layer 1 open
  and locked.

A second table takes the base under a pull at the top face apart, past layer 1's lock: the pull's
moment about the cover's mid-plane turns it by H k_M, the portal's sway turns it back by S, and
the net is S - H k_M. On a thin cover the two nearly cancel, so an error in S is several times
larger in the net (the last column).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import plate_sway as ps
from mst_cli.model.counter_turn import regime_start_N
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.tilt import member_compliance
from mst_cli.model.stack import Stack
from mst_cli.model.stack_pose import tilt_laws

ROOT = Path(__file__).resolve().parents[1]


def mst_cover_turns(g, m) -> tuple[list[float], list[float]]:
    """(the cover's turn per N mm in mst's tilt rung where each regime of the part starts,
    mrad/(N mm); the same as the centred rate's C / x_c^2, the closed form before the portal)."""
    laws = tilt_laws(g, m, "spring")
    (unit,) = [law for law in laws if law.member is not None]
    locks = np.sort([t.lock_force_N for t in laws])
    starts = [regime_start_N(locks, r) for r in range(len(locks))]
    now = [1e3 * float(member_compliance(unit, F)[1]) for F in starts]
    before = [1e3 * float(unit.member.rate_mm_per_N(F)) / unit.lever_mm**2 for F in starts]
    return now, before


def cover_depth_mm(sec) -> float:
    """H: the cover's mid-plane under the top face of the section ``sec`` (a plate_sway.StackSection),
    mm: the pull's lever on the base."""
    return float(sec.bottom_mm[-1] + sec.h_mm[-1] + sec.cap_above_stack_mm - ps.member_planes_mm(sec)[0])


def member_rows(rows: list[dict], name: str) -> tuple[dict, dict]:
    """({(regime, members): turn per moment, mrad/(N mm)}, {...: turn per tangential N, mrad/N}) of
    design ``name`` in the rows of member_turns.csv."""
    mine = [r for r in rows if r["design"] == name]
    turn = {(int(r["regime"]), r["members"]): float(r["turn_per_moment_mrad_per_Nmm"]) for r in mine}
    pull = {(int(r["regime"]), r["members"]): float(r["turn_per_tangential_mrad_per_N"]) for r in mine}
    return turn, pull


def pull_rows(name: str, g, m, turn: dict, pull: dict, order: list[int]) -> list[str]:
    """The base under the pull, past layer 1's lock: the pull's moment turns it by H k_M (H the
    cover's mid-plane under the top face, k_M its turn per N mm), the portal's sway turns it back by
    S; the net is S - H k_M, the rung's (its member rows) and the frame's (model.plate_sway), mrad/N."""
    sec = ps.stack_section(g, m)
    H = cover_depth_mm(sec)
    motion = ps.member_motions(sec, [-1], (0,))
    frame_net, frame_kM = 1e3 * float(motion.turn_rad_per_N[0]), 1e3 * ps.base_turn_per_moment_rad_per_Nmm(sec, (0,))
    rows = []
    for regime in sorted({k[0] for k in turn}):
        if 0 not in order[: regime - 1]:
            continue
        kM = turn[(regime, "rigid")] - turn[(regime, "only the base")]
        net = pull[(regime, "only the base")] - pull[(regime, "rigid")]
        rung = f"{H * kM:.3f} | {net + H * kM:.3f} | {net:.3f}"
        frame = f"{H * frame_kM:.3f} | {frame_net + H * frame_kM:.3f} | {frame_net:.3f}"
        rows.append(f"| {name} | {regime} | {H:.2f} | {rung} | {frame} | {(net + H * kM) / net:.1f} |")
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=Path, default=ROOT / "studies" / "data" / "member_turns.csv")
    args = ap.parse_args()
    with args.rows.open() as f:
        rows = list(csv.DictReader(f))
    names = list(dict.fromkeys(r["design"] for r in rows))
    print("| design | regime | layer 1 | rung | mst's cover | C / x_c^2 (before) | frame |")
    print("|---|---|---|---|---|---|---|")
    under_pull = []
    for name in names:
        doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
        g, m = doc.geometry(), doc.material
        order = [int(i) for i in Stack(layer_laws(g.layers, m, "spring")).lock_order]
        sec = ps.stack_section(g, m)
        frame = {lock: 1e3 * ps.base_turn_per_moment_rad_per_Nmm(sec, lock) for lock in ((), (0,))}
        now, before = mst_cover_turns(g, m)
        turn, pull = member_rows(rows, name)
        under_pull += pull_rows(name, g, m, turn, pull, order)
        for regime in sorted({k[0] for k in turn}):
            locked = 0 in order[: regime - 1]
            rung = turn[(regime, "rigid")] - turn[(regime, "only the base")]  # the rung's turns: the other sign
            print(
                f"| {name} | {regime} | {'locked' if locked else 'open'} | {rung:.3f} | {now[regime - 1]:.3f} | "
                f"{before[regime - 1]:.3f} | {frame[(0,) if locked else ()]:.3f} |"
            )

    print("\nunder a pull past layer 1's lock, the base alone, mrad/N: the moment's turn H k_M, the portal's")
    print("sway turning it back S, the net S - H k_M; and how many times the net S is (an error e in S is")
    print("about that times e in the net)")
    heads = ("H, mm", "rung: H k_M", "rung: S", "rung: net", "frame: H k_M", "frame: S", "frame: net", "S / net")
    print("| design | regime | " + " | ".join(heads) + " |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(under_pull))


if __name__ == "__main__":
    main()
