"""Export the bundled design's printable body and measure the mesh against the design.

python docs/examples/export_and_check.py    # writes mst-out/examples/print/
"""

from pathlib import Path

from mst_cli import api as mst

ROOT = Path(__file__).resolve().parents[2]
OUT = Path("mst-out/examples/print")

files = mst.export(ROOT / "configs" / "mohammadi2021-forward.yaml", OUT, stl=True, three_mf=True)
print("wrote " + ", ".join(f.name for f in files))
checks = mst.check(OUT)  # measured on sensor.stl against export.json
for check in checks:
    print(f"{check.name:<16} {'PASS' if check.passed else 'FAIL'}  {check.measured}  (expected {check.expected})")
volume = next(c for c in checks if c.name == "volume").values
print(f"volume {volume['measured_mm3']:.2f} mm3, design {volume['expected_mm3']:.2f} mm3")
