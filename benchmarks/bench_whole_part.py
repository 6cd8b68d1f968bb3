"""The whole-part rung against L0 + members and L2 (issue 44, docs/design.md section 4.7).

Per bundled config (configs/*.yaml) and regime, the field change per newton at the chip under
a centred 6 mm strip, the base's bottom face held, the layers locked before the regime closed:

* ``part``: the whole-part rung (mst_cli/model/mechanics/whole_part.py; plane strain, the magnet
  resting loose on its pocket's floor, as printed); ``bonded``: the magnet glued in (an N42
  block filling the pocket);
* ``rigid``: the same section with the cap, plates and base 1e4 times stiffer (the control);
* ``L2``: the layers alone between rigid plates, L2's small-strain k (plane strain; regime 1
  only, where no layer is closed), and the control's ratio to it;
* ``L0+m``: the closed form: each open layer's plane-strain small-load L0 compliance, each
  closed one's locked L0 compliance, plus load_path.members(...).total (simply supported; the
  clamped bound in brackets), times the same dB_z/dz;
* ``mst``: what ``mst simulate``'s part model gives (part_stack's secant over each of the part's
  regimes, each member counted while it moves: load_path.motion_shares), times the same
  dB_z/dz: for reference, not like for like (the rung is small-strain and plane strain, and
  has no contact: its cover never lands on the board).

Also the cost (dofs, seconds per solve), a convergence line and the cap alone against the beam.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_whole_part.py [--configs a.yaml ...] [--spacing-mm 0.3]
    PYTHONPATH=. .venv/bin/python benchmarks/bench_whole_part.py --rung-vs-mst --configs configs/*.yaml

``--rung-vs-mst`` prints only the rung as printed against mst's prediction, the members in closed form
and corrected by the rung (``model.load_path: section``), as a secant and as a linear model's
small-load figure (docs/design.md 4.7);
``--attribute`` only each member's extra drop in the rung (the other members rigid) against its
closed form, per regime: where the closed form misses; ``--pairs`` each pair of members as
printed against their own sum: where the attribution's rest comes from; ``--general`` only the
turn per off-centre moment and the slide and turn per tangential newton per regime (the rung's
three loads on one factorised stiffness, wp.press_general) against mst's general load
linearised there (general_load.linear_response), the layers and the members apart
(``--section``: mst's part with ``model.load_path: section``, the members' pose measured on the
rung); ``--off-centre`` the same three in regime 1 with each member class as printed in turn
(the forward design unless ``--configs`` is given; ``--every-regime``: the rung's cases in every
regime, and the base with its cover or its slot walls held rigid; ``--magnet bonded``: the magnet
glued in, in regime 1); ``--general-convergence``
those figures in regime 1 on three meshes and at five levers; ``--base-sway`` the base alone as
printed (all above it rigid) pulled: the cover's slide against two Timoshenko cantilevers;
``--store`` ``mst simulate`` in section mode from a fresh cache folder, then again from the one
it filled (the rung's solves kept between runs).
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

import mst_cli as mst
from mst_cli.cad.whole_part_check import stated_shear_figures
from mst_cli.model import housing_base as hb
from mst_cli.model import load_path as lp
from mst_cli.model.general_load import linear_response, loaded_stack
from mst_cli.model.mechanics import layer_laws, uncached_layer_law
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.mechanics.continuum import linear_stiffness_N_per_mm
from mst_cli.model.section_pose import regime_start_N, section_member_pose
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]


def l0_layers_mm_per_N(g, m, locked: tuple[int, ...]) -> float:
    """Plane-strain L0 layers in series: each open one's small-load, each closed one's locked compliance."""
    laws = [uncached_layer_law(c, m, "spring") for c in g.layers]
    return sum(1.0 / (law.k_locked_N_per_mm if i in locked else law.k_N_per_mm) for i, law in enumerate(laws))


def closed_form_mm_per_N(g, m, locked: tuple[int, ...], support: str) -> float:
    """Plane-strain L0 layers (small-load or locked) plus the members' closed form."""
    return l0_layers_mm_per_N(g, m, locked) + lp.members(g, m, support=support).total_mm_per_N


def config_rows(path: Path, spacing: float | None, times: list[float]) -> list[str]:
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    stack = Stack(layer_laws(g.layers, m, "spring"))
    per_mm = wp.field_per_drop_uT_per_mm(g)
    mst_rows = lp.motion_shares(stack, lp.members(g, m))
    l2 = sum(1.0 / linear_stiffness_N_per_mm(c, m) for c in g.layers)
    rows = []
    for r, locked in enumerate(wp.regime_locked(stack)):
        part = wp.press(g, m, wp.PartOptions(spacing_mm=spacing, locked=locked))
        rigid = wp.press(g, m, wp.PartOptions(spacing_mm=spacing, locked=locked, member_factor=wp.RIGID_FACTOR))
        bonded = wp.press(g, m, wp.PartOptions(spacing_mm=spacing, locked=locked, magnet="bonded"))
        times += [part.seconds, rigid.seconds, bonded.seconds]
        cf, cf_c = (closed_form_mm_per_N(g, m, locked, s) for s in lp.SUPPORTS)
        l2_cell = f"{per_mm * l2:.1f} ({rigid.drop_mm_per_N / l2 - 1:+.1%})" if not locked else ""
        mst_f = per_mm * mst_rows[r]["compliance_mm_per_N"]
        rows.append(
            f"| {doc.name} | {r + 1} | {per_mm * part.drop_mm_per_N:.1f} | {per_mm * bonded.drop_mm_per_N:.1f} | "
            f"{per_mm * rigid.drop_mm_per_N:.1f} | "
            f"{l2_cell} | {per_mm * cf:.1f} ({per_mm * cf_c:.1f}) | {cf / part.drop_mm_per_N - 1:+.1%} | "
            f"{mst_f:.1f} | {part.dofs} |"
        )
    return rows


def rung_vs_mst_rows(path: Path, spacing: float | None) -> list[str]:
    """Per regime: the whole-part rung's field change per newton at the chip (as printed, the
    layers locked before the regime closed) against what mst states for the same part, with the
    members in closed form (``model.load_path: part``) and corrected by the rung
    (``model.load_path: section``, load_path.section_correction): the part's secant over the
    regime (what ``mst simulate`` reports) and a linear model's small-load figure (the rung's own
    kind), each with its ratio to the rung; the issue's 5/8/20 % budget."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    laws = layer_laws(g.layers, m, "spring")
    stack = Stack(laws)
    per_mm = wp.field_per_drop_uT_per_mm(g)
    closed = lp.motion_shares(stack, lp.members(g, m))
    parts, rung = wp.section_members(g, m, laws, options=wp.PartOptions(spacing_mm=spacing))
    section = lp.motion_shares(stack, parts)
    rows = []
    for r, (row, c, s) in enumerate(zip(rung, closed, section)):
        part = per_mm * row["part_mm_per_N"]
        budget = lp.ACCURACY_BUDGET_REL[min(r, len(lp.ACCURACY_BUDGET_REL) - 1)]
        said = [per_mm * x[key] for x in (c, s) for key in ("compliance_mm_per_N", "small_load_compliance_mm_per_N")]
        cells = " | ".join(f"{v:.1f} ({v / part - 1:+.1%})" for v in said)
        rows.append(f"| {doc.name} | {r + 1} | {part:.1f} | {cells} | {budget:.0%} |")
    return rows


def attribution_rows(path: Path, spacing: float | None) -> list[str]:
    """Per regime, where the closed form misses: the rung with every member rigid, then with one
    member class as printed (the others rigid), its extra drop against the closed form's member as
    the forward model moves it in that regime, in MEMBER_TAGS order (the base: the closed form's
    cover, its bending over the slot and the slot walls; the plates; the cap). Drops in um/N;
    "rest" is what the members give together beyond their sum."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    stack = Stack(layer_laws(g.layers, m, "spring"))
    # each member as the closed form moves it in each regime (the plates with their joints, each
    # stopping with its layer; the plates over locked layers; the cover until it lands)
    moving = lp.member_band_compliances(stack, lp.members(g, m))[2]
    rows = []
    for r, locked in enumerate(wp.regime_locked(stack)):
        closed = {"cap": moving["cap"][r], "plate": moving["plates"][r], "base": moving["housing"][r]}
        layers = l0_layers_mm_per_N(g, m, locked)
        opts = {"spacing_mm": spacing, "locked": locked, "member_factor": wp.RIGID_FACTOR}
        rigid = wp.press(g, m, wp.PartOptions(**opts)).drop_mm_per_N
        extra = {}
        for tag in wp.MEMBER_TAGS:
            others = tuple(t for t in wp.MEMBER_TAGS if t != tag)
            extra[tag] = wp.press(g, m, wp.PartOptions(**opts, scaled=others)).drop_mm_per_N - rigid
        part = wp.press(g, m, wp.PartOptions(spacing_mm=spacing, locked=locked)).drop_mm_per_N
        cells = " | ".join(f"{1e3 * extra[t]:.2f} / {1e3 * closed[t]:.2f}" for t in wp.MEMBER_TAGS)
        rest = part - rigid - sum(extra.values())
        rows.append(
            f"| {doc.name} | {r + 1} | {1e3 * layers:.2f} | {1e3 * rigid:.2f} | {cells} | "
            f"{1e3 * rest:+.2f} | {1e3 * part:.2f} |"
        )
    return rows


def pair_rows(path: Path, spacing: float | None) -> list[str]:
    """Per regime, which members' interplay the attribution's "rest" is: each pair of member
    classes as printed (the third rigid), its extra drop against the sum of the pair's own extras
    (:func:`attribution_rows`), um/N."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    rows = []
    for r, locked in enumerate(wp.regime_locked(Stack(layer_laws(g.layers, m, "spring")))):
        opts = {"spacing_mm": spacing, "locked": locked, "member_factor": wp.RIGID_FACTOR}
        rigid = wp.press(g, m, wp.PartOptions(**opts)).drop_mm_per_N

        def extra(flexible: tuple, opts: dict = opts, rigid: float = rigid) -> float:
            scaled = tuple(t for t in wp.MEMBER_TAGS if t not in flexible)
            return wp.press(g, m, wp.PartOptions(**opts, scaled=scaled)).drop_mm_per_N - rigid

        alone = {t: extra((t,)) for t in wp.MEMBER_TAGS}
        cells = []
        for a, b in ((0, 1), (0, 2), (1, 2)):
            pair = (wp.MEMBER_TAGS[a], wp.MEMBER_TAGS[b])
            cells.append(f"{1e3 * extra(pair):.2f} / {1e3 * (alone[pair[0]] + alone[pair[1]]):.2f}")
        rows.append(f"| {doc.name} | {r + 1} | " + " | ".join(cells) + " |")
    return rows


def convergence(spacing: float | None) -> str:
    doc = mst.load(ROOT / "configs" / "mohammadi2021-forward.yaml")
    g, m = doc.geometry(), doc.material
    spacing = wp.default_spacing_mm(g) if spacing is None else spacing
    cells = []
    for s, lv in (
        (2 * spacing, wp.DEFAULT_LEVELS - 1),
        (spacing, wp.DEFAULT_LEVELS),
        (0.5 * spacing, wp.DEFAULT_LEVELS + 1),
    ):
        mo = wp.press(g, m, wp.PartOptions(spacing_mm=s, levels=lv))
        cells.append(f"spacing {s:g} mm, {lv} levels: {mo.drop_mm_per_N:.5f} mm/N ({mo.dofs} dofs, {mo.seconds:.1f} s)")
    return "forward design, regime 1: " + "; ".join(cells)


def general_convergence(path: Path, spacing: float | None, offsets_mm: tuple[float, ...]) -> list[str]:
    """The design at ``path``, regime 1, as printed: the three general-load figures on the mesh
    twice as coarse, the production mesh and one twice as fine (with one refinement round fewer
    and more), then on the production mesh with the off-centre strip at each of ``offsets_mm``
    (a linear model's turn per moment does not depend on the lever: a sawtooth is the mesh)."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    base = wp.default_spacing_mm(g) if spacing is None else spacing
    rows = [
        "| mesh | strip offset, mm | turn per moment, mrad/(N mm) | slide per tangential N, mm/N | "
        "turn per tangential N, mrad/N | dofs | s |",
        "|---|---|---|---|---|---|---|",
    ]
    cases = [(2 * base, wp.DEFAULT_LEVELS - 1, wp.OFF_CENTRE_MM), (base, wp.DEFAULT_LEVELS, wp.OFF_CENTRE_MM)]
    cases += [(0.5 * base, wp.DEFAULT_LEVELS + 1, wp.OFF_CENTRE_MM)]
    cases += [(base, wp.DEFAULT_LEVELS, x) for x in offsets_mm if x != wp.OFF_CENTRE_MM]
    for s, levels, offset in cases:
        x = wp.press_general(g, m, wp.PartOptions(spacing_mm=s, levels=levels), offset_mm=offset)
        rows.append(
            f"| {s:g} mm, {levels} levels | {offset:g} | {1e3 * x.turn_per_moment_rad_per_Nmm:.4f} | "
            f"{x.pull.side_mm_per_N:.4f} | {1e3 * x.pull.turn_rad_per_N:.3f} | {x.press.dofs} | "
            f"{x.off_centre.seconds:.1f} |"
        )
    return rows


def off_centre(path: Path, spacing: float | None, magnet: str = "resting") -> list[str]:
    """The design at ``path``, regime 1: the magnet's turn per off-centre moment, slide and turn
    per tangential newton (wp.press_general), as printed, with rigid members, with one member class
    as printed (the others rigid), and what mst's general-load model gives linearised at small load
    (the part, the layers alone); the magnet ``magnet`` (wp.MAGNET_SEATS: "bonded", glued in, takes
    the pocket's own sway out of the cap's figures)."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    rows = ["| members | turn per moment, mrad/(N mm) | slide per tangential N, mm/N | turn per tangential N, mrad/N |"]
    rows.append("|---|---|---|---|")
    cases = [("as printed", 1.0, wp.MEMBER_TAGS), ("rigid", wp.RIGID_FACTOR, wp.MEMBER_TAGS)]
    cases += [
        (f"only the {tag} as printed", wp.RIGID_FACTOR, tuple(t for t in wp.MEMBER_TAGS if t != tag))
        for tag in wp.MEMBER_TAGS
    ]
    for label, factor, scaled in cases:
        opts = wp.PartOptions(spacing_mm=spacing, member_factor=factor, scaled=scaled, magnet=magnet)
        x = wp.press_general(g, m, opts)
        rows.append(
            f"| {label} | {1e3 * x.turn_per_moment_rad_per_Nmm:.3f} | {x.pull.side_mm_per_N:.3f} | "
            f"{1e3 * x.pull.turn_rad_per_N:.3f} |"
        )
    for label, whole_part in (("mst, the part (general load)", True), ("mst, layers alone", False)):
        stack = loaded_stack(g, m, "spring", 1.0, whole_part)
        turn_off, slide_tan, turn_tan = mst_increments(stack, 0.02 * min(t.lock_force_N for t in stack.tilt))
        rows.append(f"| {label} | {turn_off:.3f} | {slide_tan:.3f} | {turn_tan:.3f} |")
    return rows


def off_centre_regime_rows(path: Path, spacing: float | None, records: list | None = None) -> list[str]:
    """:func:`off_centre`'s rung cases in every regime of the design at ``path`` (the layers locked
    before it closed): how each member class's share of the three general-load figures moves as
    the layers lock (mst's rows are ``--general``'s); ``records`` gains each row as a dict
    (``--out``'s, what tests/test_base_portal.py holds the section frame to)."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    cases = [("as printed", 1.0, wp.MEMBER_TAGS, ""), ("rigid", wp.RIGID_FACTOR, wp.MEMBER_TAGS, "")]
    cases += [
        (f"only the {t}", wp.RIGID_FACTOR, tuple(o for o in wp.MEMBER_TAGS if o != t), "") for t in wp.MEMBER_TAGS
    ]
    # the base's two parts, each alone (the other held rigid): a portal frame is not their sum
    cases += [
        (f"only the base, its {part.replace('_', ' ')} rigid", wp.RIGID_FACTOR, ("plate", "cap"), part)
        for part in ("cover", "slot_walls")
    ]
    rows = []
    for r, locked in enumerate(wp.regime_locked(Stack(layer_laws(g.layers, m, "spring")))):
        for label, factor, scaled, rigid_base in cases:
            opts = wp.PartOptions(
                spacing_mm=spacing, member_factor=factor, scaled=scaled, locked=locked, rigid_base=rigid_base
            )
            x = wp.press_general(g, m, opts)
            figures = (1e3 * x.turn_per_moment_rad_per_Nmm, x.pull.side_mm_per_N, 1e3 * x.pull.turn_rad_per_N)
            rows.append(f"| {doc.name} | {r + 1} | {label} | {figures[0]:.3f} | {figures[1]:.3f} | {figures[2]:.3f} |")
            if records is not None:
                names = ("turn_per_moment_mrad_per_Nmm", "slide_mm_per_N", "turn_per_tangential_mrad_per_N")
                row = {"design": doc.name, "regime": r + 1, "members": label}
                records.append({**row, **{k: f"{v:.6g}" for k, v in zip(names, figures)}})
    return rows


def base_sway_row(path: Path, spacing: float | None) -> str:
    """The base alone as printed (the layers, plates, cap and magnet rigid), pulled at the top face:
    the cover's slide per newton (the magnet's slide carried down the rigid body above by its turn),
    as printed and with the cover rigid too, against mst's closed form
    (housing_base.base_sway_mm_per_N; with a rigid cover its columns' tops held, to the cover's
    underside) and two Timoshenko cantilevers from the floor's top to the cover's underside."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    rigid_above = ("layer", "plate", "cap", "insert", "magnet")
    z_magnet = g.z_magnet_bottom_mm + 0.5 * g.magnet.thickness_mm
    slides = []
    for rigid_base in ("", "cover"):
        opts = wp.PartOptions(
            spacing_mm=spacing, member_factor=wp.RIGID_FACTOR, scaled=rigid_above, rigid_base=rigid_base
        )
        x = wp.press_general(g, m, opts)
        slides.append(x.pull.side_mm_per_N + x.pull.turn_rad_per_N * (z_magnet - g.z_base_top_mm))
    s = lp.member_scene(g, m)
    E, G, D, H = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.slot_height_mm
    walls = s.slot_wall_widths_mm
    closed, held = hb.base_sway_mm_per_N(s), hb.base_sway_mm_per_N(s, tops_held=True)
    cantilevers = 1.0 / sum(1.0 / (H**3 / (3.0 * E * D * w**3 / 12.0) + H / (5.0 / 6.0 * G * D * w)) for w in walls)
    return (
        f"| {doc.name} | {', '.join(f'{w:.2f}' for w in walls)} | {H:.2f} | {g.housing.cover_mm:g} | "
        f"{slides[0]:.4f} | {closed:.4f} ({closed / slides[0] - 1.0:+.0%}) | {slides[1]:.4f} | "
        f"{held:.4f} ({held / slides[1] - 1.0:+.0%}) | {cantilevers:.4f} ({cantilevers / slides[0] - 1.0:+.0%}) |"
    )


def general_rows(path: Path, spacing: float | None, section: bool = False, records: list | None = None) -> list[str]:
    """Per regime (the layers locked before it closed): the rung's turn per off-centre moment,
    slide and turn per tangential newton (wp.press_general) with its members rigid, against mst's
    general-load model of the layers alone (L0), and what the members add: in the rung, as printed
    less rigid; in mst, the part's closed-form members less the layers alone. mst is read where the
    regime starts, where its layers are nearest the rung's linear ones: at 2 % of the first lock,
    else 2 % past the lock that opens the regime, the part and the layers alone each at their own
    (the part's members close a cavity before its layer locks alone; section_pose.regime_start_N).
    The rung's sign (a turn that moves the top toward -x is positive). ``records``, when given,
    gains the rung's figures as printed, a dict a regime (``--out``'s rows)."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    part = Stack(tuple(lp.capped_units(layer_laws(g.layers, m, "spring"), lp.members(g, m))))
    stacks = {kind: loaded_stack(g, m, "spring", 1.0, kind == "part") for kind in ("part", "layers")}
    if section:  # model.load_path: section: the members' pose measured on the rung (section_pose)
        stacks["part"] = loaded_stack(g, m, "spring", 1.0, True, section_member_pose(g, m, "spring"))
    locks = {k: np.sort([t.lock_force_N for t in stacks[k].tilt]) for k in stacks}
    layer_order = np.argsort([t.lock_force_N for t in stacks["layers"].tilt])
    rows = []
    for r, locked in enumerate(wp.regime_locked(part)):
        F = regime_start_N(locks["part"], r)
        if tuple(sorted(int(j) for j in layer_order[:r])) != tuple(locked):
            print(f"{doc.name} regime {r + 1}: the layers alone lock in another order than the part", flush=True)
        printed, rigid = (
            wp.press_general(g, m, wp.PartOptions(spacing_mm=spacing, locked=locked, member_factor=factor))
            for factor in (1.0, wp.RIGID_FACTOR)
        )
        rung = [
            np.array([1e3 * x.turn_per_moment_rad_per_Nmm, x.pull.side_mm_per_N, 1e3 * x.pull.turn_rad_per_N])
            for x in (printed, rigid)
        ]
        mst_part = np.array(mst_increments(stacks["part"], F))
        mst_layers = np.array(mst_increments(stacks["layers"], regime_start_N(locks["layers"], r)))
        cells = []
        for i in range(3):
            layers = f"{rung[1][i]:.3f} / {mst_layers[i]:.3f} ({mst_layers[i] / rung[1][i] - 1:+.0%})"
            members = f"{rung[0][i] - rung[1][i]:+.3f} / {mst_part[i] - mst_layers[i]:+.3f}"
            total = f"{rung[0][i]:.3f} / {mst_part[i]:.3f} ({mst_part[i] / rung[0][i] - 1:+.0%})"
            cells.append(f"{layers} | {members} | {total}")
        rows.append(f"| {doc.name} | {r + 1} | {F:.2f} | " + " | ".join(cells) + " |")
        if records is not None:
            names = ("turn_per_moment_mrad_per_Nmm", "slide_mm_per_N", "turn_per_tangential_mrad_per_N")
            records.append({"design": doc.name, "regime": r + 1, **{k: f"{v:.6g}" for k, v in zip(names, rung[0])}})
    return rows


def mst_increments(stack, force_N: float) -> tuple[float, float, float]:
    """general_load.linear_response in the rung's units and sign (mrad per N mm, mm/N, mrad/N; a
    turn that moves the top toward -x is positive): what ``mst check --whole-part`` reports."""
    return tuple(stated_shear_figures(linear_response(stack, force_N)).values())


def store_rows(paths, repeats: int = 3) -> list[str]:
    """``mst simulate`` of each design in section mode (``model.load_path: section``), from a
    fresh cache folder and once more from the folder the first run filled: median seconds of
    ``repeats`` pairs, each a subprocess (the rung's solves kept by mst_cli/sensor/rung_store.py)."""
    mst = Path(sys.executable).with_name("mst")
    rows = ["| design | first run, s | second run, s | ratio |", "|---|---|---|---|"]
    for path in paths:
        raw = yaml.safe_load(Path(path).read_text())
        raw["model"] = {**(raw.get("model") or {}), "load_path": "section"}
        times: list[tuple[float, float]] = []
        for _ in range(repeats):
            with tempfile.TemporaryDirectory() as tmp:
                spec = Path(tmp) / "section.yaml"
                spec.write_text(yaml.safe_dump(raw, sort_keys=False))
                env = {**os.environ, "MST_CACHE_DIR": str(Path(tmp) / "cache")}
                pair = []
                for _run in range(2):
                    t0 = time.perf_counter()
                    cmd = [str(mst), "simulate", str(spec), "--no-plot", "--out", str(Path(tmp) / "out")]
                    subprocess.run(cmd, check=True, capture_output=True, env=env)
                    pair.append(time.perf_counter() - t0)
                times.append((pair[0], pair[1]))
        cold, warm = (statistics.median(t[i] for t in times) for i in (0, 1))
        rows.append(f"| {Path(path).stem} | {cold:.2f} | {warm:.2f} | {cold / warm:.0f}x |")
    return rows


def section_sway_row(path: Path) -> str:
    """The design at ``path``: the section's sway and turn ratio per regime, the walls' factors, the cost
    (median of 5: BLAS on one thread, as general_load runs it, and threaded) and the counter-turn's."""
    import contextlib

    from mst_cli.model.general_load import part_counter_turn
    from mst_cli.model.plate_sway import section_regimes, stack_section, wall_factors
    from mst_cli.model.stack_pose import tilt_laws
    from mst_cli.parallel import one_blas_thread

    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    order = np.argsort([t.lock_force_N for t in tilt_laws(g, m, "spring", 1.0, True)], kind="stable")
    ms = []
    for limit in (one_blas_thread, contextlib.nullcontext):
        times = []
        for _ in range(5):
            start = time.perf_counter()
            with limit():
                regimes = section_regimes(stack_section(g, m), order)
            times.append(time.perf_counter() - start)
        ms.append(1e3 * float(np.median(times)))
    times = []
    for _ in range(5):  # the counter-turn's layer tangents (general_load keeps it per part, beside the frame)
        start = time.perf_counter()
        part_counter_turn(g, m, "spring", 1.0, regimes)
        times.append(time.perf_counter() - start)
    ms.append(1e3 * float(np.median(times)))
    column = hb.base_sway_mm_per_N(lp.member_scene(g, m))
    walls = " / ".join(f"{w:.2f}" for w in wall_factors(stack_section(g, m)))
    cells = [
        " / ".join(f"{v:{spec}}" for v in values)
        for values, spec in (
            (regimes.base_sway_mm_per_N, ".4f"),
            (regimes.plate_sway_mm_per_N, ".4f"),
            (regimes.member_turn_ratio, ".2f"),
        )
    ]
    return f"| {doc.name} | {' | '.join(cells)} | {column:.4f} | {walls} | {ms[0]:.0f} | {ms[1]:.0f} | {ms[2]:.1f} |"


def member_studies(args) -> bool:
    """``--off-centre``, ``--general-convergence``, ``--store``, ``--section-sway`` or ``--base-sway``:
    print it, True; else False."""
    if args.off_centre and args.every_regime:
        print("per regime, the rung: turn per moment mrad/(N mm), slide per tangential N mm/N, turn per")
        print("tangential N mrad/N")
        print("| design | regime | members | turn per moment | slide per tangential N | turn per tangential N |")
        print("|---|---|---|---|---|---|")
        records: list[dict] = []
        for path in args.configs if args.configs_given else [str(ROOT / "configs" / "mohammadi2021-forward.yaml")]:
            print("\n".join(off_centre_regime_rows(Path(path), args.spacing_mm, records)), flush=True)
        if args.out:
            write_records(args.out, records)
    elif args.off_centre:
        for path in args.configs if args.configs_given else [str(ROOT / "configs" / "mohammadi2021-forward.yaml")]:
            where = "a 6 mm strip 3 mm off centre / pulling along +x"
            print(f"{Path(path).stem}, regime 1, {where}, the magnet {args.magnet}:")
            print("\n".join(off_centre(Path(path), args.spacing_mm, args.magnet)), flush=True)
    elif args.general_convergence:
        for path in args.configs:
            print(f"{Path(path).stem}, regime 1, as printed: the general load's figures against the mesh and the lever")
            print("\n".join(general_convergence(Path(path), args.spacing_mm, (1.0, 2.0, 4.0, 5.0))), flush=True)
    elif args.store:
        print("mst simulate in section mode: the first run solves the rung, the second reads its solves back")
        paths = args.configs if args.configs_given else [str(ROOT / "configs" / "mohammadi2021-forward.yaml")]
        print("\n".join(store_rows(paths)), flush=True)
    elif args.section_sway:
        print("the section's frame (model.plate_sway) as the general load builds it: the base's and the plates'")
        print("sway per regime, mm/N, the members' turn ratio (under the pull over under its moment alone,")
        print("model.counter_turn), beside the base's column form, the walls' factors to L0's k_x, and its cost")
        print("(median of 5: BLAS on one thread, as general_load runs it, and with its own threads)")
        print(
            "| design | base, regimes 1.. | plates, regimes 1.. | turn ratio, regimes 1.. | column form | "
            "walls' factors | ms | ms, threads | counter-turn ms |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for path in args.configs:
            print(section_sway_row(Path(path)), flush=True)
    elif args.base_sway:
        print("the base alone, pulled at the top face: the cover's slide, mm/N, the rung against mst's closed form")
        print(
            "| design | walls, mm | wall height, mm | cover, mm | rung | mst (mst / rung - 1) | rung, cover rigid | "
            "mst, tops held | two cantilevers |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for path in args.configs:
            print(base_sway_row(Path(path), args.spacing_mm), flush=True)
    else:
        return False
    return True


def write_records(path: str, records: list[dict]) -> None:
    """``records`` (dicts with the same keys) as a CSV at ``path``."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(records[0]))
        writer.writeheader()
        writer.writerows(records)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="*", default=sorted(str(p) for p in (ROOT / "configs").glob("*.yaml")))
    ap.add_argument("--spacing-mm", type=float, default=None, help="lattice spacing [default: the rung's own]")
    ap.add_argument("--no-convergence", action="store_true")
    only = {  # each prints one study and nothing else
        "--off-centre": "only the off-centre and tangential loads in regime 1, class by class [default: forward]",
        "--general-convergence": "only the general load's figures in regime 1 on three meshes and at five levers",
        "--base-sway": "only the base's sway under a pull against two cantilevers",
        "--section-sway": "only the section's frame per regime (no rung) and its cost",
        "--store": "only mst simulate in section mode, a fresh cache then a filled one [default: forward design]",
        "--rung-vs-mst": "only the rung (as printed) against mst's prediction, per regime",
        "--attribute": "only each member's drop in the rung vs its closed form, per regime",
        "--pairs": "only each pair of members' drop in the rung vs their own sum, per regime",
        "--general": "only the off-centre and tangential loads per regime: the rung against mst's general-load model",
    }
    for flag, text in only.items():
        ap.add_argument(flag, action="store_true", help=text)
    ap.add_argument("--every-regime", action="store_true", help="with --off-centre: the rung's cases in every regime")
    ap.add_argument("--magnet", choices=wp.MAGNET_SEATS, default="resting", help="with --off-centre: the magnet's seat")
    ap.add_argument("--section", action="store_true", help="with --general: mst's part with model.load_path: section")
    ap.add_argument(
        "--out", default=None, help="with --general or --off-centre --every-regime: the rung's figures to this CSV"
    )
    args = ap.parse_args()
    args.configs_given = any(a.startswith("--configs") for a in sys.argv[1:])
    if args.general:
        print("per regime, mst read at F (N): turn per moment mrad/(N mm), slide per tangential N mm/N, turn per")
        print("tangential N mrad/N; for each: the layers (rung, members rigid / mst, layers alone), what the members")
        print("add (rung / mst's closed form; with --section, its pose measured on the rung) and the part (rung as")
        print("printed / mst)")
        heads = [
            f"{f}: {w}"
            for f in ("turn/moment", "slide/tangential N", "turn/tangential N")
            for w in ("layers", "members", "part")
        ]
        print("| design | regime | F | " + " | ".join(heads) + " |")
        print("|---" * (3 + len(heads)) + "|")
        records: list[dict] = []
        for path in args.configs:
            print("\n".join(general_rows(Path(path), args.spacing_mm, args.section, records)), flush=True)
        if args.out:  # the rung's figures, what tests/test_counter_turn.py holds mst to
            write_records(args.out, records)
        return
    if args.attribute:
        print("the magnet's drop per newton, um/N (centred 6 mm strip, locked layers closed): L0's layers, the rung")
        print("with every member rigid, each member's extra drop in the rung (the others rigid) / its closed form")
        print(
            "| design | regime | L0 layers | rung, members rigid | base (the cover and slot walls) | plates | cap | "
            "rest | rung as printed |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for path in args.configs:
            print("\n".join(attribution_rows(Path(path), args.spacing_mm)), flush=True)
        return
    if args.pairs:
        print("the magnet's drop per newton, um/N (as --attribute): each pair of member classes as printed, the")
        print("third rigid, against the sum of the pair's own extras")
        tags = wp.MEMBER_TAGS
        heads = [f"{tags[a]} + {tags[b]}" for a, b in ((0, 1), (0, 2), (1, 2))]
        print("| design | regime | " + " | ".join(heads) + " |")
        print("|---" * (2 + len(heads)) + "|")
        for path in args.configs:
            print("\n".join(pair_rows(Path(path), args.spacing_mm)), flush=True)
        return
    if member_studies(args):
        return
    if args.rung_vs_mst:
        print("field change per newton at the chip, uT/N (centred 6 mm strip, locked layers closed)")
        print(
            "| design | regime | whole-part rung | closed form: secant | closed form: small load | "
            "section: secant | section: small load | budget |"
        )
        print("|---|---|---|---|---|---|---|---|")
        for path in args.configs:
            print("\n".join(rung_vs_mst_rows(Path(path), args.spacing_mm)), flush=True)
        return
    print("field change per newton at the chip, uT/N (centred 6 mm strip)")
    print(
        "| design | regime | part | bonded | rigid members | L2 layers (rigid/L2 - 1) | "
        "L0+members simple (clamped) | L0+m/part - 1 | mst | dofs |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    times: list[float] = []
    for path in args.configs:
        for line in config_rows(Path(path), args.spacing_mm, times):
            print(line, flush=True)
    print(f"cost: median {statistics.median(times):.2f} s per solve ({len(times)} solves)")
    if not args.no_convergence:
        print(convergence(args.spacing_mm))


if __name__ == "__main__":
    main()
