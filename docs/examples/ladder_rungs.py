"""Compare the mechanics ladder's rungs on one cell: spring (L0), frame (L1), continuum (L2).

python docs/examples/ladder_rungs.py        # about 2 s: the continuum rung is a FE model
"""

import time
from pathlib import Path

from mst_cli import api as mst
from mst_cli.model.mechanics import MODELS, layer_law

ROOT = Path(__file__).resolve().parents[2]

doc = mst.load_design(ROOT / "configs" / "mohammadi2021-forward.yaml")
cell = doc.geometry().layers[0]
print(
    f"cell: theta {cell.theta_deg:g} deg, t {cell.t_mm:g} mm, h {cell.h_mm:g} mm, "
    f"E {doc.material.youngs_modulus_MPa:g} MPa"
)
laws = {}
for rung in MODELS:
    t0 = time.perf_counter()
    laws[rung] = layer_law(cell, doc.material, rung)
    law = laws[rung]
    print(
        f"{rung:<10} k {law.k_N_per_mm:.3f} N/mm, locks at {law.lock_force_N:.3f} N after "
        f"{law.d_lock_mm:.4f} mm ({time.perf_counter() - t0:.3f} s)"
    )
ref = laws["continuum"]
for rung in MODELS[:-1]:
    print(
        f"{rung} against continuum: k {100 * (laws[rung].k_N_per_mm / ref.k_N_per_mm - 1):+.1f} %, "
        f"lock force {100 * (laws[rung].lock_force_N / ref.lock_force_N - 1):+.1f} %"
    )
