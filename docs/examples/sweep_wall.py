"""Sweep the wall thickness t of the softest layer and plot its sensitivity S_1 and range R_1.

python docs/examples/sweep_wall.py          # writes mst-out/examples/sweep_wall.png
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mst_cli import api as mst

ROOT = Path(__file__).resolve().parents[2]
OUT = Path("mst-out/examples")

doc = mst.load_design(ROOT / "configs" / "mohammadi2021-forward.yaml")
walls = np.round(np.linspace(0.45, 0.75, 7), 3)  # mm; layer 1 has h = 2 mm
S, R = [], []
for t in walls:
    variant = replace(doc, layers=(replace(doc.layers[0], t_mm=float(t)),) + doc.layers[1:])
    first = next(r for r in mst.simulate(variant).regimes if r.layer == 1)  # the band layer 1 ends
    S.append(first.sensitivity_secant_per_N)
    R.append(first.force_to_N)
    print(f"t = {t:.3f} mm: S_1 = {S[-1]:.4f} 1/N, R_1 = {R[-1]:.4f} N")

fig = Figure(figsize=(5, 3.6))
ax = fig.subplots()
ax.plot(walls, S, "o-", color="C0")
ax.set(xlabel="layer 1 wall t [mm]", ylabel="S_1 [1/N]")
ax_r = ax.twinx()
ax_r.plot(walls, R, "s--", color="C3")
ax_r.set_ylabel("R_1 [N]")
OUT.mkdir(parents=True, exist_ok=True)
fig.savefig(OUT / "sweep_wall.png", dpi=100, bbox_inches="tight")
print(f"wrote {OUT / 'sweep_wall.png'}")
