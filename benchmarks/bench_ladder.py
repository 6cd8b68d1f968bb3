"""The speed/accuracy ladder benchmark: runs the same measurement as `mst bench`, prints the
table, writes bench.md/json/png to --out, and stores the measured median errors (stiffness,
lock force, lock displacement) in
mst_cli/model/data/ladder_errors.json (read by mst_cli.model.ladder.cheapest_model_for).

Run:  .venv/bin/python benchmarks/bench_ladder.py --samples 48 --seed 0 --out mst-out/bench

The cells are drawn uniformly in the printable box (mst_cli.bench.ladder_bench.BOUNDS: theta 5-75 deg,
t 0.4-3 mm, h 1.2-8 mm, every cell rule met; t/L up to 1.7). 48 cells rather than the 24 of
`mst bench`'s default: the box is larger and the stored medians pick the rung.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mst_cli.bench.ladder_bench import bench_markdown, ladder_errors, plot_bench, run_bench
from mst_cli.io.outputs import staged
from mst_cli.model.ladder import ERRORS_FILE


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("mst-out/bench"))
    args = ap.parse_args()
    result = run_bench(args.samples, args.seed)
    result["command"] = f".venv/bin/python benchmarks/bench_ladder.py --samples {args.samples} --seed {args.seed}"
    md = bench_markdown(result)
    with staged(args.out) as st:
        st.write_json("bench.json", result)
        st.write_text("bench.md", md)
        plot_bench(result, st.path("bench.png"))
    ERRORS_FILE.write_text(json.dumps(ladder_errors(result), indent=2) + "\n")
    print(md)
    print(f"wrote {args.out}/bench.md, bench.json, bench.png and {ERRORS_FILE}")


if __name__ == "__main__":
    main()
