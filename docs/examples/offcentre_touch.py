"""Press the bundled sensor off its axis: the tilt, the field on three axes, the force a
centred reading gets wrong, and where the press was, read back from Bx, By, Bz.

    python docs/examples/offcentre_touch.py
"""

from pathlib import Path

import numpy as np

from mst_cli import api as mst

DESIGN = Path(__file__).resolve().parents[2] / "configs" / "mohammadi2021-forward.yaml"

for x, y in [(5.0, 0.0), (-5.0, 0.0), (0.0, 5.0)]:
    r = mst.simulate_offcentre(DESIGN, (x, y))
    i = np.argmin(np.abs(r.force_N - 20.0))  # the sample nearest 20 N
    Bx, By, Bz = r.B_T[i] * 1e6
    print(f"press ({x:+.0f}, {y:+.0f}) mm at {r.force_N[i]:.2f} N: Bx {Bx:+.2f} uT, By {By:+.2f} uT, Bz {Bz:.1f} uT")
    print(f"  read as axial {r.force_read_axial_N[i]:.2f} N; sides lock at (N, nan: never) {r.side_lock_N.round(3)}")

# readings of a press at (6, 3) mm, read back with all three axes
r = mst.simulate_offcentre(DESIGN, (6.0, 3.0))
keep = r.axial.in_range & (r.force_N > 0)
rows = [",".join(f"{v:.6f}" for v in (*b * 1e6, f)) for b, f in zip(r.B_T[keep][::40], r.force_N[keep][::40])]
Path("readings.csv").write_text("Bx_uT,By_uT,Bz_uT,force_N\n" + "\n".join(rows) + "\n")
# the table's roots (built on first use, about a minute; mst calibrate --offset-table writes it
# beside a calibrated model) polished by the exact solve: noise-free readings come back exactly
got = mst.read(DESIGN, "readings.csv", estimate="offset", polish=True)
est = got.offset
for k, F_ref in enumerate(got.readings.force_N):
    print(
        f"true {F_ref:6.2f} N: centred {got.force_centred_N[k]:6.2f} N, corrected {got.force_N[k]:6.2f} N "
        f"at ({est.x_mm[k]:.2f}, {est.y_mm[k]:.2f}) mm {est.flag[k]}"
    )
