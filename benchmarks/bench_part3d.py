"""The 3D linear check of the exported body against the plane-strain whole-part rung and mst
(issue 44, docs/design.md section 4.8).

Per config (configs/*.yaml; a spec is designed first, as `mst export` does), regime 1 (no layer
locked), a centred 6 mm strip, the field change per newton at the chip:

* ``3D``: mst_cli/cad/part3d_check.py on the export (sensor.stl + export.json): tetrahedra,
  the body TPU, the declared insert in its material, the magnet resting on its pocket's floor,
  the bottom face held; dB_z/dF at the chip from the magnet's fitted pose (exact cylinder);
  the magnet's drop, side motion (y: the board slot's open side) and turn per newton;
* ``rung``: the plane-strain whole-part rung (mst_cli/model/mechanics/whole_part.py), its
  drop times |dB_z/dz| on the axis;
* ``mst``: what `mst simulate` states for regime 1 (the layers' laws plus the members).

With the mesh (TetGen's radius-edge bound, largest tetrahedron, element order), tetrahedra, dofs
and the seconds to mesh and to solve; ``--convergence`` adds the forward design at several
radius-edge bounds (the thin walls, not the volume bound, set the tetrahedra's count).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_part3d.py [--configs a.yaml ...] [--order 2]
        [--max-volume-mm3 4] [--radius-edge 2] [--convergence 3 2 1.5] [--out DIR]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import mst_cli as mst
from mst_cli.cad.part3d_check import DEFAULT_MAX_VOLUME_MM3, DEFAULT_RADIUS_EDGE, Check3DOptions, press_exported
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]


def exported(config: Path, out: Path, reuse: bool = False):
    """(the export folder, the designed geometry, its material); ``reuse``: an export already in
    the folder (its design.yaml for a spec) is taken as it is."""
    folder = out / config.stem
    if reuse and (folder / "export.json").exists():
        doc = mst.load(folder / "design.yaml" if (folder / "design.yaml").exists() else config)
        return folder, doc.geometry(), doc.material
    files = mst.export(config, folder)
    doc = files.designed.document if files.designed is not None else mst.load(config)
    return folder, files.geometry, doc.material


def row(config: Path, out: Path, options: Check3DOptions, reuse: bool) -> str:
    folder, g, m = exported(config, out, reuse)
    try:
        r3 = press_exported(folder, options)
    except RuntimeError as exc:  # TetGen could not mesh this surface at this bound: say so, go on
        return f"| {config.stem} | {exc} |"
    t0 = time.perf_counter()
    rung = wp.press(g, m, wp.PartOptions())
    t_rung = time.perf_counter() - t0
    per_mm = wp.field_per_drop_uT_per_mm(g)
    mst_uT = (
        per_mm * lp.motion_shares(Stack(layer_laws(g.layers, m, "spring")), lp.members(g, m))[0]["compliance_mm_per_N"]
    )
    dBz = r3.field_uT_per_N[2]
    return (
        f"| {r3.name} | {dBz:.1f} | {per_mm * rung.drop_mm_per_N:.1f} | {mst_uT:.1f} | {dBz / mst_uT - 1:+.1%} | "
        f"{r3.drop_mm_per_N:.4f} | {1e3 * r3.translation_mm_per_N[1]:.2f} | "
        f"{1e3 * abs(r3.rotation_rad_per_N[0]):.2f} | {rung.drop_mm_per_N:.4f} | "
        f"q{options.radius_edge_ratio:g}, {options.max_volume_mm3:g} mm3, P{options.order} | {r3.tets} | {r3.dofs} | "
        f"{r3.mesh_seconds:.0f} + {r3.solve_seconds:.0f} | {t_rung:.0f} |"
    )


def convergence(out: Path, order: int, ratios: list[float], volume: float) -> list[str]:
    folder, *_ = exported(ROOT / "configs" / "mohammadi2021-forward.yaml", out)
    lines = [
        "| radius-edge bound | order | tets | dofs | drop, mm/N | dB_z/dF, uT/N | mesh + solve, s |",
        "|---|---|---|---|---|---|---|",
    ]
    print("\n".join(lines))
    for q in ratios:
        r = press_exported(folder, Check3DOptions(max_volume_mm3=volume, radius_edge_ratio=q, order=order))
        lines.append(
            f"| {q:g} | P{order} | {r.tets} | {r.dofs} | {r.drop_mm_per_N:.5f} | {r.field_uT_per_N[2]:.2f} | "
            f"{r.mesh_seconds:.0f} + {r.solve_seconds:.0f} |"
        )
        print(lines[-1], flush=True)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="*", default=sorted(str(p) for p in (ROOT / "configs").glob("*.yaml")))
    ap.add_argument("--order", type=int, default=2, choices=(1, 2))
    ap.add_argument("--max-volume-mm3", type=float, default=DEFAULT_MAX_VOLUME_MM3)
    ap.add_argument("--radius-edge", type=float, default=DEFAULT_RADIUS_EDGE, help="TetGen's quality bound (3, 2, 1.5)")
    ap.add_argument("--convergence", nargs="*", type=float, default=None, metavar="RATIO",
                    help="also the forward design at these radius-edge bounds (e.g. 3 2 1.5)")  # fmt: skip
    ap.add_argument("--out", type=Path, default=None, help="export folder [default: a temporary one]")
    ap.add_argument("--reuse", action="store_true", help="take an export already in --out as it is")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp)
        options = Check3DOptions(
            max_volume_mm3=args.max_volume_mm3, radius_edge_ratio=args.radius_edge, order=args.order
        )
        print("regime 1, centred 6 mm strip, bottom face held: field change per newton at the chip, uT/N")
        print(
            "| design | 3D dB_z/dF | plane-strain rung | mst | 3D/mst - 1 | 3D drop, mm/N | 3D side y, um/N | "
            "3D turn, mrad/N | rung drop, mm/N | mesh | tets | dofs | 3D mesh + solve, s | rung, s |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for path in args.configs:
            print(row(Path(path), out, options, args.reuse), flush=True)
        if args.convergence:
            print("forward design, regime 1, mesh convergence:")
            convergence(out, args.order, args.convergence, args.max_volume_mm3)


if __name__ == "__main__":
    main()
