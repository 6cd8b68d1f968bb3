"""Calibrate a printed sensor from its load test (a CSV) and read forces from field readings.

loadtest.csv beside this script is a load test of the bundled forward design (the whole part,
its insert too) printed with known errors: walls 0.05 mm thicker, modulus x 0.85, the board
0.3 mm further from the magnet, the magnet x 0.95; 2 uT of chip noise. `python
tools/make_examples.py` writes it from the current model; tests/test_examples.py checks it.

    python docs/examples/calibrate_and_read.py  # writes mst-out/examples/calibration/
"""

from pathlib import Path

from mst_cli import api as mst

HERE = Path(__file__).resolve().parent
OUT = Path("mst-out/examples/calibration")

cal = mst.calibrate(HERE.parents[1] / "configs" / "mohammadi2021-forward.yaml", HERE / "loadtest.csv", out=OUT)
for name in cal.fit.names:
    print(f"{name:<18} {cal.fit.values[name]:.4f} +- {cal.fit.std[name]:.4f}")
for name, why in cal.fit.held.items():
    print(f"{name:<18} held: {why}")

# the same readings through the calibrated model; their force_N column is the reference
forces = mst.read(OUT / "calibrated.yaml", HERE / "loadtest.csv")
for F_ref, F, flag in list(zip(forces.readings.force_N, forces.force_N, forces.flag))[::12]:
    print(f"load cell {F_ref:7.3f} N   read {F:7.3f} N   {flag}")
err = forces.errors()
print(f"median force error {100 * err['median_rel']:.2f} % above {err['from_force_N']:.2f} N")
