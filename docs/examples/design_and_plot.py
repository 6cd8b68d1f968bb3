"""Design the paper's sensor from its targets (S_i, R_i) and plot its curves.

python docs/examples/design_and_plot.py     # writes mst-out/examples/design.png
"""

from pathlib import Path

from matplotlib.figure import Figure

from mst_cli import api as mst

ROOT = Path(__file__).resolve().parents[2]
OUT = Path("mst-out/examples")

result = mst.design(ROOT / "configs" / "mohammadi2021.yaml", seed=0)
print(f"{result.document.name}: targets {result.status}, part height {result.geometry.total_height_mm:.2f} mm")
for row in result.targets:
    print(
        f"layer {row['layer']}: theta {row['theta_deg']:.2f} deg, t {row['t_mm']:.3f} mm, h {row['h_mm']:.3f} mm"
        f" | S {row['achieved_sensitivity_per_N']:.5f} 1/N (target {row['target_sensitivity_per_N']:g})"
        f" | R {row['achieved_range_N']:.4f} N (target {row['target_range_N']:g})"
    )

resp = result.response  # the forward model on the designed sensor
fig = Figure(figsize=(10, 4))
ax1, ax2 = fig.subplots(1, 2)
ax1.plot(resp.force_N, resp.displacement_mm)
ax1.set(xlabel="force F [N]", ylabel="stack compression [mm]")
ax2.plot(resp.force_N, resp.dB_rel)
for r in resp.regimes:  # each layer's lock ends a regime
    ax2.axvline(r.force_to_N, color="0.7", lw=0.8)
ax2.set(xlabel="force F [N]", ylabel="field change (|B| - B0) / B0")
OUT.mkdir(parents=True, exist_ok=True)
fig.savefig(OUT / "design.png", dpi=100)
print(f"wrote {OUT / 'design.png'}")
