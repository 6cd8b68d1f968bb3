"""Turning a :class:`~mst_cli.model.response.Response` into what people and programs read.

``report_dict`` (JSON, units in every key), ``response_csv``, ``terminal_table`` and
``plot_response`` (PNG through matplotlib's Figure API -- no pyplot -- imported only when called).
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mst_cli.io.outputs import Staging, staged
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.chip import quantise_lsb
from mst_cli.model.cover_air import LANDING_MARGIN_REL, air_keeping_cover_off_mm
from mst_cli.model.load_path import FINGERTIP_PATCH_MM
from mst_cli.model.load_path_report import dominant_member, load_path_report
from mst_cli.model.magnet_field import axial_dBz_dz_T_per_mm
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.lateral import small_load_lateral_N_per_mm  # not model.general_load's tilt laws
from mst_cli.model.response import Regime, Response
from mst_cli.model.stack import Stack
from mst_cli.sensor.as_printed import as_printed

if TYPE_CHECKING:
    from mst_cli.sensor.document import Document

SCHEMA_VERSION = 1


def report_dict(doc: Document, geometry: SensorGeometry, resp: Response, extra: dict | None = None) -> dict:
    """Machine-readable report of one simulated design."""
    out = {
        "schema_version": SCHEMA_VERSION,
        "name": doc.name,
        "source": doc.source,
        "models": {"mechanics": resp.mechanics, "field": resp.field_model},
        "layers": _layer_rows(geometry, resp, _lateral_stiffness(doc, resp.mechanics)),
        "regimes": [_regime_row(r) for r in resp.regimes],
        "range_N": resp.max_force_N,
        "out_of_range_above_N": resp.max_force_N,
        "magnet": {
            "diameter_mm": geometry.magnet.diameter_mm,
            "thickness_mm": geometry.magnet.thickness_mm,
            "grade": geometry.magnet.grade,
            "remanence_T": resp.remanence_T,
        },
        "gap0_mm": resp.gap0_mm,
        "gap_min_mm": resp.gap_min_mm,
        "B0_mT": resp.B0_T * 1e3,
        "B_full_load_mT": resp.B_full_T * 1e3,
        "dB_rel_full_load": resp.B_full_T / resp.B0_T - 1.0,
        "magnetometer": _magnetometer_section(geometry, resp),
        "geometry": _geometry_section(geometry),
        "height_budget": geometry.height_budget_mm(),
        "load_path": load_path_section(doc, geometry, resp),
        "warnings": list(resp.warnings),
    }
    if extra:
        out.update(extra)
    return nulls_with_reasons(out, _undefined_reasons(resp))


def load_path_section(
    doc: Document, geometry: SensorGeometry, resp: Response, patch_mm: float = FINGERTIP_PATCH_MM
) -> dict:
    """Where the magnet's motion goes under a centred press ``patch_mm`` wide, per regime: the
    layers of this response's rung, and the cap, plates and cover in closed form (docs/design.md
    4.6), corrected by the whole-part rung with model.load_path: section (4.7); and each regime's
    field change per newton as a linear model of the part gives it."""
    stack = Stack(layer_laws(geometry.layers, doc.material, resp.mechanics))
    extra = resp.members.regime_extra_mm_per_N if resp.members.patch_mm == patch_mm else ()
    if doc.section_rung and not extra:  # another press than the response's: the rung for it
        from mst_cli.model.mechanics.whole_part import section_members  # deferred: scikit-fem's rung

        extra = section_members(geometry, doc.material, stack.layers, patch_mm)[0].regime_extra_mm_per_N
    report = load_path_report(geometry, doc.material, stack, patch_mm, extra)
    m = geometry.magnet  # a linear model's field change: the drop times dB_z/dz on the axis at the unloaded gap
    per_mm = 1e6 * abs(float(axial_dBz_dz_T_per_mm(geometry.gap0_mm, m.radius_mm, m.thickness_mm, m.remanence_T)))
    for row in report["regimes"]:
        row["field_change_small_load_uT_per_N"] = per_mm * row["small_load_compliance_mm_per_N"]
    return report


def load_path_line(
    doc: Document, geometry: SensorGeometry, resp: Response, patch_mm: float = FINGERTIP_PATCH_MM
) -> str:
    """One terminal line: the share of a centred press's motion outside the layers, per regime."""
    lp = load_path_section(doc, geometry, resp, patch_mm)
    shares = " / ".join(f"{100 * r['outside_layers']:.0f}" for r in lp["regimes"])
    member, _ = dominant_member(max(lp["regimes"], key=lambda r: r["outside_layers"]))
    line = (
        f"load path: {shares} % of the magnet's motion per regime is outside the layers, mostly the {member} "
        f"(cap {lp['cap_mm_per_N']:.3g} mm/N under a {lp['patch_mm']:g} mm press); the prediction above includes "
        "it in series (the layers' alone: report.json sensitivity_layers_secant_per_N, docs/design.md 4.6)"
    )
    if lp.get("section_correction_mm_per_N"):
        added = " / ".join(f"{1e3 * c:+.3g}" for c in lp["section_correction_mm_per_N"])
        line += (
            f"; the whole-part rung (model.load_path: section, the part's section in plane strain) adds {added} "
            "um/N per regime to the members' closed form, in the prediction above (docs/design.md 4.7)"
        )
    lands, end = lp["cover_lands_N"], lp["regimes"][-1]["force_N"][1]
    if lands is not None and lands < end:
        air = air_keeping_cover_off_mm(geometry, doc.material, end, patch_mm, mechanics=resp.mechanics)
        line += (
            f"; the cover lands on the board's parts at {lands:.3g} N, inside the range (to {end:.3g} N): past it "
            "the press bears on the chip and connectors, a support the printed body alone lacks "
            f"(housing.chip_clearance_mm >= {air:.2f} mm "
            f"keeps it off past {1 + LANDING_MARGIN_REL:g} x the range's end)"
        )
    return line


def _lateral_stiffness(doc: Document, mechanics: str) -> list[tuple[float, float]]:
    """Every layer's small-load (k_x, k_y) as printed, from the rung ``mst simulate`` uses: L0's
    closed forms for the spring and frame rungs, L2 for the continuum (docs/design.md 4.4)."""
    printed = as_printed(doc)
    return [small_load_lateral_N_per_mm(c, printed.material, mechanics) for c in printed.geometry().layers]


def _layer_rows(geometry: SensorGeometry, resp: Response, lateral: list[tuple[float, float]]) -> list[dict]:
    """report.json's layers: each cell as drawn, the regime it locks in, its lateral stiffness."""
    layers = []
    for i, cell in enumerate(geometry.layers):
        reg = next(r for r in resp.regimes if r.layer == i + 1)
        layers.append(
            {
                "layer": i + 1,
                "theta_deg": cell.theta_deg,
                "t_mm": cell.t_mm,
                "h_mm": cell.h_mm,
                "b_mm": cell.b_mm,
                "pad_half_width_mm": cell.p_mm,
                "wall_length_mm": cell.wall_length_mm,
                "cavity_height_mm": cell.cavity_height_mm,
                "d_lock_mm": cell.d_lock_mm,
                "k_N_per_mm": reg.k_layer_N_per_mm,
                "lock_force_N": reg.force_to_N,
                "locks_in_regime": reg.index,
                "lateral_stiffness_x_N_per_mm": lateral[i][0],
                "lateral_stiffness_y_N_per_mm": lateral[i][1],
            }
        )
    return layers


def _regime_row(r: Regime) -> dict:
    """report.json's row of one regime: its band, stiffness, sensitivity and resolution."""
    return {
        "regime": r.index,
        "locking_layer": r.layer,
        "force_from_N": r.force_from_N,
        "force_to_N": r.force_to_N,
        "k_effective_N_per_mm": r.k_effective_N_per_mm,
        "sensitivity_secant_per_N": r.sensitivity_secant_per_N,
        "sensitivity_local_min_per_N": r.sensitivity_min_per_N,
        "sensitivity_local_max_per_N": r.sensitivity_max_per_N,
        "force_resolution_N": r.force_resolution_N,
        "force_resolution_worst_N": r.force_resolution_worst_N,
        "sensitivity_layers_secant_per_N": r.sensitivity_layers_secant_per_N,
    }


def _magnetometer_section(geometry: SensorGeometry, resp: Response) -> dict:
    """report.json's magnetometer: the chip setting chosen (None where saturated)."""
    setting = resp.chip_setting
    return {
        "model": "MLX90393",
        "board": geometry.board.key,
        "gain_sel": setting.gain_sel if setting else None,
        "res": setting.res if setting else None,
        "z_uT_per_lsb": setting.z_uT_per_lsb if setting else None,
        "xy_uT_per_lsb": setting.xy_uT_per_lsb if setting else None,
        "z_range_mT": setting.z_range_T * 1e3 if setting else None,
        "noise_uT_rms": resp.noise_uT_rms,
        "field_resolution_uT": resp.field_resolution_T * 1e6 if setting else None,
        "saturated": resp.saturated,
    }


def _geometry_section(geometry: SensorGeometry) -> dict:
    """report.json's geometry: the part's overall sizes and the magnet pause."""
    return {
        "total_height_mm": geometry.total_height_mm,
        "base_length_mm": geometry.base_length_mm,
        "base_width_mm": geometry.base_width_mm,
        "z_hall_mm": geometry.z_hall_mm,
        "z_magnet_bottom_mm": geometry.z_magnet_bottom_mm,
        "print_height_mm": geometry.depth_mm,
        "magnet_pause_after_layer": geometry.pause_after_layer,
        "magnet_pause_height_mm": geometry.pause_height_mm,
        "chip_offset_mm": list(geometry.chip_offset_mm),
        "magnet_tilt_deg": geometry.magnet_tilt_deg,
    }


def _undefined_reasons(resp: Response) -> dict:
    """Why a quantity of this response has no value (key -> sentence)."""
    reasons: dict[str, str] = {}
    if resp.chip_setting is None or not math.isfinite(resp.field_resolution_T):
        why = "undefined: the field saturates the MLX90393 at full load, so no gain setting resolves it (see warnings)"
        reasons.update(force_resolution_N=why, force_resolution_worst_N=why, field_resolution_uT=why)
    return reasons


def nulls_with_reasons(data: Any, reasons: dict | None = None) -> Any:
    """``data`` with every non-finite number replaced by null and, in a mapping, a ``<key>_reason``
    key beside it saying why (JSON has no NaN; report.json never holds one)."""
    reasons = reasons or {}
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for key, value in data.items():
            if isinstance(value, float) and not math.isfinite(value):
                out[key] = None
                out[f"{key}_reason"] = reasons.get(key, "undefined: not a finite number for this design")
            else:
                out[key] = nulls_with_reasons(value, reasons)
        for key, value in data.items():  # a None the code set on purpose: say why too
            if value is None and key in reasons and f"{key}_reason" not in out:
                out[f"{key}_reason"] = reasons[key]
        return out
    if isinstance(data, (list, tuple)):
        return [None if isinstance(v, float) and not math.isfinite(v) else nulls_with_reasons(v, reasons) for v in data]
    return data


def response_csv(resp: Response) -> str:
    """One row per force sample; units in the header."""
    buf = io.StringIO()
    buf.write(
        "force_N,displacement_mm,gap_mm,Bx_mT,By_mT,Bz_mT,B_abs_mT,dB_rel,in_range,Bz_code_lsb,"
        "displacement_layers_mm,dB_rel_layers\n"
    )
    data = np.column_stack(
        [resp.force_N, resp.displacement_mm, resp.gap_mm, resp.B_T * 1e3, resp.B_abs_T * 1e3, resp.dB_rel]
    )
    assert resp.displacement_layers_mm is not None and resp.dB_rel_layers is not None  # simulate fills both
    layers = np.column_stack([resp.displacement_layers_mm, resp.dB_rel_layers])
    # what the chip would output along z at the chosen GAIN_SEL/RES (empty when saturated)
    setting = resp.chip_setting
    codes = quantise_lsb(resp.B_T[:, 2], setting.z_uT_per_lsb).tolist() if setting is not None else [""] * len(data)
    # one format per row (%.9g is format(v, ".9g")) of Python numbers (tolist: the same digits, faster)
    numbers, alone_numbers = (",".join(["%.9g"] * a.shape[1]) for a in (data, layers))
    for row, ok, code, alone in zip(data.tolist(), np.asarray(resp.in_range).tolist(), codes, layers.tolist()):
        buf.write(numbers % tuple(row) + f",{int(ok)},{code}," + alone_numbers % tuple(alone) + "\n")
    return buf.getvalue()


def height_budget_line(geometry: SensorGeometry) -> str:
    """One line: the part's height split into layers and housing, and the gap's split."""
    b = geometry.height_budget_mm()
    return (
        f"height {b['total_height_mm']:.2f} mm = layers {b['layers_mm']:.2f} + housing "
        f"{b['housing_overhead_mm']:.2f} (base {b['base_mm']:.2f}, plates {b['plates_mm']:.2f}, "
        f"cap {b['cap_mm']:.2f}); gap {b['gap0_mm']:.2f} mm = chip side {b['gap_chip_side_mm']:.2f} "
        f"(board parts {b['board_headroom_mm']:.2f} mm tall) + stack {b['gap_stack_mm']:.2f} "
        f"+ magnet side {b['gap_magnet_side_mm']:.2f}"
    )


def terminal_table(
    doc: Document, geometry: SensorGeometry, resp: Response, patch_mm: float = FINGERTIP_PATCH_MM
) -> str:
    """The short table ``mst simulate`` prints (its load-path line for a press ``patch_mm`` wide)."""
    targets = {i + 1: la for i, la in enumerate(doc.layers)}
    lines = [
        f"{doc.name}: {len(geometry.layers)} layers, mechanics={resp.mechanics}, field={resp.field_model}"
        + (", load path=section (the whole-part rung)" if resp.members.regime_extra_mm_per_N else ""),
        f"{'regime':>6} {'layer':>5} {'theta':>6} {'t':>5} {'h':>5} {'k':>7} "
        f"{'band [N]':>15} {'S [1/N]':>8} {'S min..max':>15} {'dF [mN]':>8}",
        f"{'':>6} {'':>5} {'[deg]':>6} {'[mm]':>5} {'[mm]':>5} {'[N/mm]':>7}",
    ]
    for r in resp.regimes:
        c = geometry.layers[r.layer - 1]
        lines.append(
            f"{r.index:>6} {r.layer:>5} {c.theta_deg:>6.1f} {c.t_mm:>5.2f} {c.h_mm:>5.2f} "
            f"{r.k_layer_N_per_mm:>7.3f} {r.force_from_N:>7.3f}-{r.force_to_N:<7.3f} "
            f"{r.sensitivity_secant_per_N:>8.4f} {r.sensitivity_min_per_N:>7.4f}..{r.sensitivity_max_per_N:<6.4f} "
            + (f"{r.force_resolution_N * 1e3:>8.2f}" if math.isfinite(r.force_resolution_N) else f"{'-':>8}")
        )
        t = targets.get(r.index)
        if t is not None and t.has_targets:
            lines[-1] += f"   target S {t.target_sensitivity_per_N:g}, R {t.target_range_N:g}"
    s = resp.chip_setting
    chip = f"GAIN_SEL {s.gain_sel}, RES {s.res} ({s.z_uT_per_lsb} uT/LSB z)" if s else "SATURATED"
    lines.append(
        f"gap {resp.gap0_mm:.2f} -> {resp.gap_min_mm:.2f} mm, B0 {resp.B0_T * 1e3:.3f} mT, "
        f"B full load {resp.B_full_T * 1e3:.3f} mT, Br {resp.remanence_T:g} T; chip {chip}"
    )
    lines.append(f"range ends at {resp.max_force_N:.3f} N (all layers locked; beyond is out of range)")
    lines.append(height_budget_line(geometry))
    lines.append(load_path_line(doc, geometry, resp, patch_mm))
    for w in resp.warnings:
        lines.append(f"warning: {w}")
    return "\n".join(lines)


def plot_response(resp: Response, path: str | Path, title: str = "") -> None:
    """F-d with the lock points, and dB/B0-F with the regimes shaded."""
    # Figure without pyplot: no GUI backend machinery, and Figure.savefig renders with Agg
    from matplotlib.figure import Figure  # deferred: matplotlib is 0.45 s; --no-plot never imports it

    fig = Figure(figsize=(10, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.9, wspace=0.22)
    inr = resp.in_range
    ax1.plot(resp.displacement_mm[inr], resp.force_N[inr], color="C0", label="in range")
    ax1.plot(resp.displacement_mm[~inr], resp.force_N[~inr], color="C0", ls=":", label="out of range")
    locks = np.array(resp.lock_forces_N)
    d_locks = np.interp(locks, resp.force_N, resp.displacement_mm)
    ax1.plot(d_locks, locks, "o", color="C3", label="layer locks")
    ax1.set_xlabel("stack compression d [mm]")
    ax1.set_ylabel("force F [N]")
    ax1.legend(loc="upper left")
    ax1.grid(alpha=0.3)

    edges = [0.0] + list(locks)
    for i in range(len(locks)):
        ax2.axvspan(
            edges[i],
            edges[i + 1],
            color=f"C{i}",
            alpha=0.12,
            label=f"regime {i + 1}: S={resp.regimes[i].sensitivity_secant_per_N:.3g}/N",
        )
    ax2.plot(resp.force_N[inr], resp.dB_rel[inr], color="k")
    ax2.plot(resp.force_N[~inr], resp.dB_rel[~inr], color="k", ls=":")
    ax2.set_xlabel("force F [N]")
    ax2.set_ylabel("dB/B0")
    ax2.legend(loc="upper left", fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(title or f"mechanics={resp.mechanics}, field={resp.field_model}")
    fig.savefig(path, dpi=110, format="png")


def write_simulation(
    doc: Document,
    geometry: SensorGeometry,
    resp: Response,
    out_dir: Path,
    extra_files: dict[str, Any] | None = None,
    extra_report: dict | None = None,
    more: Callable[[Staging], None] | None = None,
    plot: bool = True,
) -> dict:
    """report.json, response.csv, response.png (+ extra YAML files, + whatever ``more(staging)``
    writes) into out_dir, atomically; returns the report written (what ``--json`` prints).
    ``plot=False``: no response.png (any old one is removed) and matplotlib is not imported."""
    with staged(out_dir) as st:
        for name, data in (extra_files or {}).items():
            st.write_yaml(name, data)
        report = report_dict(doc, geometry, resp, extra_report)
        st.write_json("report.json", report)
        st.write_text("response.csv", response_csv(resp))
        if plot:
            plot_response(resp, st.path("response.png"), title=doc.name)
        if more is not None:
            more(st)
        if not plot:
            st.remove("response.png")
    return report
