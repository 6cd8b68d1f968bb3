"""Measuring the speed/accuracy ladder: what ``mst bench`` reports (docs/design.md section 4).

Pure measurement library (no CLI, no plotting imports at module level): a seeded sample of
valid cells across the design bounds, every mechanics rung timed per layer and compared with
the reference rung L2 (stiffness, lock displacement, lock force), and the field models compared
with magpylib's exact cylinder over the gaps designs use. :func:`cheapest_model_for` reads the
measured errors stored with the package (mst_cli/model/data/ladder_errors.json, written by
benchmarks/bench_ladder.py) and picks the cheapest rung that meets a requested accuracy.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mst_cli.bench.sampling import BOUNDS, sample_cells
from mst_cli.bench.tilt_bench import TILT_CELLS, long_padded, tilt_lines, tilt_rows
from mst_cli.io.outputs import staged
from mst_cli.model import magnet_field as fld
from mst_cli.model.assembly import Magnet
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import uncached_layer_law
from mst_cli.model.mechanics.continuum import MeshOptions, linear_stiffness_N_per_mm
from mst_cli.model.mechanics.spring import spring_arrays, spring_layer

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


# The printable box (mechanics.correction.VERIFIED_BOX, also the default design bounds): every
# rung is fitted and measured on it.
def _law(model, cell, material):
    if model in ("spring-textbook", "spring"):
        return spring_layer(cell, material, corrected=model == "spring")
    return uncached_layer_law(cell, material, model)


def time_per_layer_s(model: str, cells: Iterable[HexCell], material: Material, repeat: int = 1) -> float:
    """Median wall-clock time of one layer law (no caches), s."""
    times = []
    for c in cells:
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            _law(model, c, material)
            best = min(best, time.perf_counter() - t0)
        times.append(best)
    return float(np.median(times))


def spring_vectorised_time_per_layer_s(cells: Sequence[HexCell], material: Material, repeat: int = 20) -> float:
    """Per-layer time of L0 as the design loop calls it: spring_arrays over all cells at once."""
    # the family constants too come from the cells (HexCell's declared defaults), not literals
    theta, t, h, b, width, allowance = (
        np.array([getattr(c, k) for c in cells])
        for k in ("theta_rad", "t_mm", "h_mm", "b_mm", "width_mm", "contact_allowance_mm")
    )
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        spring_arrays(
            theta, t, h, b, width, allowance, material.youngs_modulus_MPa, material.poisson_ratio, corrected=True
        )
        best = min(best, time.perf_counter() - t0)
    return best / len(cells)


def compare_mechanics(
    cells: Iterable[HexCell],
    material: Material,
    models: Sequence[str] = ("spring-textbook", "spring", "frame"),
    reference: str = "continuum",
) -> list[dict]:
    """Per cell and model: k, d_lock, lock force and relative errors against the reference.

    A rung that raises on a cell is recorded with its error message (never dropped silently).
    """
    rows = []
    for c in cells:
        row: dict[str, Any] = {
            "theta_deg": c.theta_deg,
            "t_mm": c.t_mm,
            "h_mm": c.h_mm,
            "t_over_L": c.t_mm / c.wall_length_mm,
        }
        try:
            ref = _law(reference, c, material)
            row[reference] = {
                "k_N_per_mm": ref.k_N_per_mm,
                "d_lock_mm": ref.d_lock_mm,
                "lock_force_N": ref.lock_force_N,
            }
        except Exception as exc:
            row[reference] = {"error": f"{type(exc).__name__}: {exc}"}
            ref = None
        for m in models:
            try:
                law = _law(m, c, material)
                entry: dict[str, Any] = {
                    "k_N_per_mm": law.k_N_per_mm,
                    "d_lock_mm": law.d_lock_mm,
                    "lock_force_N": law.lock_force_N,
                }
                if ref is not None:
                    entry["err_k"] = law.k_N_per_mm / ref.k_N_per_mm - 1.0
                    entry["err_d_lock"] = law.d_lock_mm / ref.d_lock_mm - 1.0
                    entry["err_lock_force"] = law.lock_force_N / ref.lock_force_N - 1.0
            except Exception as exc:
                entry = {"error": f"{type(exc).__name__}: {exc}"}
            row[m] = entry
        rows.append(row)
    return rows


def summarise(rows: Sequence[dict], model: str) -> dict:
    """Median and 90th-percentile |error| of one model over the rows where both solved."""
    out: dict[str, Any] = {"failures": 0}
    for key in ("err_k", "err_d_lock", "err_lock_force"):
        vals = np.array([abs(r[model][key]) for r in rows if key in r.get(model, {})])
        out[key] = {
            "median": float(np.median(vals)) if vals.size else None,
            "p90": float(np.percentile(vals, 90)) if vals.size else None,
            "max": float(vals.max()) if vals.size else None,
            "n": int(vals.size),
        }
    out["failures"] = sum(1 for r in rows if "error" in r.get(model, {}))
    return out


def field_errors(gaps_mm: ArrayLike, magnet: Magnet | None = None) -> dict[str, list[float]]:
    """Relative error of |B| on the axis of the dipole and axial models against magpylib."""
    magnet = Magnet() if magnet is None else magnet
    g = np.asarray(gaps_mm, dtype=float)
    exact = np.linalg.norm(fld.field_at_chip_T(g, magnet, "cylinder"), axis=-1)
    out = {}
    for m in ("dipole", "axial"):
        B = np.linalg.norm(fld.field_at_chip_T(g, magnet, m), axis=-1)
        out[m] = (B / exact - 1.0).tolist()
    return out


def field_times_s(gaps_mm: ArrayLike, magnet: Magnet | None = None, repeat: int = 20) -> dict[str, float]:
    """Per-point time of each field model on the gap array, s."""
    magnet = Magnet() if magnet is None else magnet
    g = np.asarray(gaps_mm, dtype=float)
    out = {}
    for m in ("dipole", "axial", "cylinder"):
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            fld.field_at_chip_T(g, magnet, m)
            best = min(best, time.perf_counter() - t0)
        out[m] = best / g.size
    return out


# --------------------------------------------------------------------------- the whole bench
def mesh_convergence(
    cells: Iterable[HexCell],
    material: Material,
    meshes: Sequence[tuple[int, int, int]] = ((2, 8, 2), (3, 12, 4), (4, 16, 5), (6, 24, 6)),
) -> list[dict]:
    """L2 small-strain k on successively finer meshes (n_thick, n_length, corner levels)."""
    out = []
    for c in cells:
        ks = [linear_stiffness_N_per_mm(c, material, MeshOptions(*m)) for m in meshes]
        out.append(
            {
                "theta_deg": c.theta_deg,
                "t_mm": c.t_mm,
                "h_mm": c.h_mm,
                "meshes": [list(m) for m in meshes],
                "k_N_per_mm": ks,
                "rel_to_finest": [k / ks[-1] - 1.0 for k in ks],
            }
        )
    return out


def run_bench(samples: int = 24, seed: int = 0, quick: bool = False, material: Material | None = None) -> dict:
    """Measure every rung and field model; returns the JSON-ready result."""
    material = material or Material()
    cells = sample_cells(samples, seed)
    rows = compare_mechanics(cells, material)
    timing_cells = cells[: max(3, len(cells) // 4)]
    times = {
        m: time_per_layer_s(m, timing_cells, material) for m in ("spring-textbook", "spring", "frame", "continuum")
    }
    times["spring-vectorised"] = spring_vectorised_time_per_layer_s(cells, material)
    models = {}
    for m in ("spring-textbook", "spring", "frame"):
        s = summarise(rows, m)
        models[m] = {"time_per_layer_s": times[m], "median_abs_err_k": s["err_k"]["median"], "summary": s}
    models["spring"]["time_per_layer_vectorised_s"] = times["spring-vectorised"]
    ref_fail = sum(1 for r in rows if "error" in r["continuum"])
    models["continuum"] = {"time_per_layer_s": times["continuum"], "median_abs_err_k": 0.0, "failures": ref_fail}
    gaps = np.linspace(5.0, 20.0, 31)
    ferr = field_errors(gaps)
    result = {
        "command": f"mst bench --samples {samples} --seed {seed}" + (" --quick" if quick else ""),
        "samples": samples,
        "seed": seed,
        "bounds": BOUNDS,
        "max_t_over_L_sampled": max(r["t_over_L"] for r in rows),
        "models": models,
        "rows": rows,
        "field": {
            "gaps_mm": gaps.tolist(),
            "rel_error": ferr,
            "time_per_point_s": field_times_s(gaps),
            "max_abs_error": {m: float(np.max(np.abs(v))) for m, v in ferr.items()},
        },
    }
    if not quick:
        result["mesh_convergence"] = mesh_convergence(cells[:3], material)
        result["tilt"] = tilt_rows(long_padded(cells)[:TILT_CELLS], material)
    return result


def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.1f} %"


def bench_markdown(result: dict) -> str:
    """The table a person reads (bench.md)."""
    lines = _rung_table(result) + _field_table(result["field"])
    if "mesh_convergence" in result:
        lines += _mesh_lines(result["mesh_convergence"])
    lines += band_lines(result["rows"])
    lines += _worst_lines(result["rows"])
    if "tilt" in result:
        lines += tilt_lines(result["tilt"])
    return "\n".join(lines) + "\n"


def _rung_table(result: dict) -> list[str]:
    """The heading and the rungs' table: time per layer, speed-up, errors against L2."""
    m = result["models"]
    t_ref = m["continuum"]["time_per_layer_s"]
    b = result["bounds"]
    lines = [
        f"# mst bench\n\n`{result['command']}` — {result['samples']} valid cells drawn uniformly in the "
        f"printable box: theta {b['theta_deg'][0]:g}–{b['theta_deg'][1]:g} deg, t {b['t_mm'][0]:g}–"
        f"{b['t_mm'][1]:g} mm, h {b['h_mm'][0]:g}–{b['h_mm'][1]:g} mm, every cell rule met (t/L up to "
        f"{result.get('max_t_over_L_sampled', float('nan')):.2f} in this sample; the L0 fits cover the "
        f"whole box, to t/L 1.7); errors against L2 `continuum` (median / 90th percentile of |error|).\n",
        "| rung | time per layer | speed-up vs L2 | stiffness k | lock displacement | lock force | failures |",
        "|---|---|---|---|---|---|---|",
    ]
    labels = {
        "spring-textbook": "L0 spring, textbook (before correction)",
        "spring": "L0 spring, corrected (after)",
        "frame": "L1 frame",
    }
    for key in ("spring-textbook", "spring", "frame"):
        s = m[key]["summary"]
        t = m[key]["time_per_layer_s"]
        lines.append(
            f"| {labels[key]} | {t * 1e6:.1f} µs | {t_ref / t:,.0f}x | "
            f"{_pct(s['err_k']['median'])} / {_pct(s['err_k']['p90'])} | "
            f"{_pct(s['err_d_lock']['median'])} / {_pct(s['err_d_lock']['p90'])} | "
            f"{_pct(s['err_lock_force']['median'])} / {_pct(s['err_lock_force']['p90'])} | "
            f"{s['failures']} |"
        )
    tv = m["spring"]["time_per_layer_vectorised_s"]
    lines.append(
        f"| L0 corrected, vectorised (design loop) | {tv * 1e6:.3f} µs | {t_ref / tv:,.0f}x | same | same | same | 0 |"
    )
    lines.append(f"| L2 continuum (reference) | {t_ref * 1e3:.0f} ms | 1x | — | — | — | {m['continuum']['failures']} |")
    return lines


def _field_table(f: dict) -> list[str]:
    """The field models against magpylib's exact cylinder."""
    lines = [
        "",
        f"Field models against magpylib's exact cylinder, on the axis, gaps "
        f"{f['gaps_mm'][0]:g}–{f['gaps_mm'][-1]:g} mm (max |error|, time per point):",
        "",
        "| model | max abs error | time per point |",
        "|---|---|---|",
    ]
    for mname in ("dipole", "axial"):
        lines.append(f"| {mname} | {_pct(f['max_abs_error'][mname])} | {f['time_per_point_s'][mname] * 1e6:.2f} µs |")
    lines.append(f"| cylinder (magpylib) | reference | {f['time_per_point_s']['cylinder'] * 1e6:.2f} µs |")
    return lines


def _mesh_lines(convergence: list[dict]) -> list[str]:
    """L2's stiffness on each mesh relative to the finest, per cell."""
    lines = [
        "",
        "L2 mesh convergence (small-strain k relative to the finest mesh; "
        "mesh = elements across t, along the wall, corner refinement rounds):",
        "",
    ]
    for r in convergence:
        parts = ", ".join(f"{tuple(mm)}: {100 * e:+.2f} %" for mm, e in zip(r["meshes"], r["rel_to_finest"]))
        lines.append(f"- theta {r['theta_deg']:g}, t {r['t_mm']:g}, h {r['h_mm']:g}: {parts}")
    return lines


def _worst_lines(rows: list[dict]) -> list[str]:
    """The three cells with the largest L1 lock-force error, and L0's and L1's errors there."""
    worst = sorted(
        (r for r in rows if "err_k" in r.get("frame", {})), key=lambda r: -abs(r["frame"]["err_lock_force"])
    )[:3]
    if not worst:
        return []
    lines = ["", "Where the cheap rungs fail most (largest L1 lock-force error):", ""]
    for r in worst:
        lines.append(
            f"- theta {r['theta_deg']:g}, t {r['t_mm']:g}, h {r['h_mm']:g} (t/L {r['t_over_L']:.2f}): "
            f"L0 k {_pct(r['spring']['err_k'])}, R {_pct(r['spring']['err_lock_force'])}; "
            f"L1 k {_pct(r['frame']['err_k'])}, R {_pct(r['frame']['err_lock_force'])}"
        )
    return lines


BANDS = {
    "t/L": ("t_over_L", ((0.0, 0.6), (0.6, 1.0), (1.0, 1.7))),
    "theta": ("theta_deg", ((5.0, 15.0), (15.0, 60.0), (60.0, 75.0))),
}


def band_summary(rows: Sequence[dict], model: str) -> dict[str, dict]:
    """Median |error| in k and lock force of one rung per band of t/L and of theta (the
    outermost bands take whatever lies past their outer edge)."""
    out = {}
    for name, (key, bands) in BANDS.items():
        for i, (lo, hi) in enumerate(bands):
            lo_ = lo if i > 0 else -np.inf
            hi_ = hi if i < len(bands) - 1 else np.inf
            sel = [r for r in rows if lo_ <= r[key] < hi_]
            s = summarise(sel, model) if sel else None
            out[f"{name} {lo:g}-{hi:g}"] = {
                "n": len(sel),
                "k": s["err_k"]["median"] if s else None,
                "lock_force": s["err_lock_force"]["median"] if s else None,
            }
    return out


def band_lines(rows: Sequence[dict]) -> list[str]:
    """Markdown: the bench's errors per band of t/L and theta (the per-band out-of-sample
    table on 210 cells is in mst_cli/model/data/l0_correction.json, tools/fit_l0_correction.py)."""
    lines = [
        "",
        "Median |error| per band of this sample (k / lock force; n cells):",
        "",
        "| band | n | L0 corrected | L1 frame |",
        "|---|---|---|---|",
    ]
    sp, fr = band_summary(rows, "spring"), band_summary(rows, "frame")
    for band, s in sp.items():
        if s["n"]:
            lines.append(
                f"| {band} | {s['n']} | {_pct(s['k'])} / {_pct(s['lock_force'])} | "
                f"{_pct(fr[band]['k'])} / {_pct(fr[band]['lock_force'])} |"
            )
    return lines


def plot_bench(result: dict, path: str | Path) -> None:
    """Log-log median and p90 |error| against time per layer, one point per rung: stiffness
    on the left, lock force on the right."""
    import matplotlib  # deferred: about 0.5 s of import, for --plot only

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # deferred: as above, after the backend is chosen

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    m = result["models"]
    for ax, key_err, label in ((axes[0], "err_k", "stiffness k"), (axes[1], "err_lock_force", "lock force R")):
        for key, mark in (("spring-textbook", "x"), ("spring", "o"), ("frame", "s")):
            s = m[key]["summary"][key_err]
            t = [m[key]["time_per_layer_s"]]
            ax.loglog(t, [max(s["median"] or 1e-6, 1e-6)], mark, label=f"{key} (median)")
            ax.loglog(t, [max(s["p90"] or 1e-6, 1e-6)], mark, alpha=0.4, label=f"{key} (p90)")
        ax.axvline(m["continuum"]["time_per_layer_s"], color="k", ls="--", label="continuum (reference)")
        ax.set_xlabel("time per layer [s]")
        ax.set_title(f"|error in {label}| against L2")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("relative error")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def ladder_errors(result: dict) -> dict:
    """What cheapest_model_for needs, from a bench result (stored as ladder_errors.json)."""
    return {"command": result["command"], "models": {k: _stored_errors(v) for k, v in result["models"].items()}}


def _stored_errors(entry: dict) -> dict:
    out = {"median_abs_err_k": entry["median_abs_err_k"], "time_per_layer_s": entry["time_per_layer_s"]}
    if "summary" in entry:
        out["median_abs_err_lock_force"] = entry["summary"]["err_lock_force"]["median"]
        out["median_abs_err_d_lock"] = entry["summary"]["err_d_lock"]["median"]
    else:  # the reference itself
        out["median_abs_err_lock_force"] = out["median_abs_err_d_lock"] = 0.0
    return out


class BenchResult(dict):
    """:func:`mst_cli.api.bench`'s answer: bench.json's content (a dict) with bench.md's table."""

    def markdown(self) -> str:
        """bench.md: the table a person reads (:func:`bench_markdown`)."""
        return bench_markdown(self)

    def write(self, out: Path, plot: bool = True) -> list[str]:
        """bench.json, bench.md and (``plot``) bench.png into ``out``, atomically; without ``plot``
        an old bench.png is removed. The names written."""
        with staged(out) as st:
            st.write_json("bench.json", dict(self))
            st.write_text("bench.md", self.markdown())
            if plot:
                plot_bench(self, st.path("bench.png"))
            else:
                st.remove("bench.png")
        return ["bench.md", "bench.json"] + (["bench.png"] if plot else [])
