"""The trade among designs that meet the targets: part height, force resolution, print robustness.

Every design that meets a spec still has one free variable per layer (three variables, two
targets). ``design.objective`` prices three things against each other (:mod:`.problem`):

* the part's total height (mm) -- what a fingertip has room for;
* the worst force resolution over the regimes (N): the chip's field resolution over B0 S_i,
  i.e. how small a force step the sensor can tell apart in its least sensitive band;
* print robustness: the RMS relative change of every S_i and R_i when every wall is printed
  printer.wall_tolerance_mm (default 0.05 mm) off; pareto.csv, pareto.png and the table give the
  worst change of any S_i or R_i beside it.

:func:`pareto_front` maps that trade: one match, then the preference polish for a sequence of
weightings spread over the simplex (:func:`mst_cli.design.solver.pareto_weights`), each design
re-simulated by the forward model and kept when it meets the targets and no other design is
at least as good in all three numbers and better in one. The numbers that decide dominance
are the forward model's, the same the report prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.design.batching import prefer_many
from mst_cli.design.document import design_document
from mst_cli.design.problem import DesignProblem
from mst_cli.design.result import ROUND_DECIMALS, DesignResult
from mst_cli.design.solver import SolveResult, pareto_weights
from mst_cli.design.verify import verify_design
from mst_cli.sensor.document import Document
from mst_cli.sensor.sections import OBJECTIVE_TERMS

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

# Two designs are the same point of the front when they differ by less than one print layer
# in height, 2 % in force resolution and 1 percentage point in print robustness: differences a
# user cannot act on (a weight lattice crowds its points where the trade is flat).
SAME_POINT = np.array([0.2, 0.02, 0.01])  # mm, relative, absolute
MAX_WEIGHTINGS_PER_POINT = 4  # weightings tried per requested point before giving up
WAVE_PER_POINT = MAX_WEIGHTINGS_PER_POINT  # weightings polished together (one batched wave)


@dataclass
class ParetoDesign:
    """One design of the front, judged by the forward model."""

    result: DesignResult
    weights: tuple[float, float, float] | None  # None for the chosen design (design.objective)
    chosen: bool = False

    @property
    def height_mm(self) -> float:
        return float(self.result.geometry.total_height_mm)

    @property
    def worst_force_resolution_N(self) -> float:
        return max(r.force_resolution_N for r in self.result.response.regimes)

    @property
    def print_robustness_rms(self) -> float:
        return float(self.result.print_error["rms_log_change"])

    @property
    def print_worst_change(self) -> float:
        """Worst relative change of any S_i or R_i at walls +- the printer's tolerance."""
        return float(self.result.print_error["worst_change_rel"])

    @property
    def metrics(self) -> np.ndarray:
        return np.array([self.height_mm, self.worst_force_resolution_N, self.print_robustness_rms])


def non_dominated(metrics: np.ndarray) -> np.ndarray:
    """Boolean mask of the rows of ``metrics`` (k, m), all minimised, that no other row
    dominates (<= in every column and < in one)."""
    m = np.asarray(metrics, dtype=float)
    le = np.all(m[:, None, :] <= m[None, :, :], axis=-1)  # le[j, i]: j <= i everywhere
    lt = np.any(m[:, None, :] < m[None, :, :], axis=-1)
    dominated = np.any(le & lt, axis=0)
    return ~dominated


def _same_point(a: np.ndarray, b: np.ndarray) -> bool:
    diff = np.array([abs(a[0] - b[0]), abs(math.log(a[1] / b[1])), abs(a[2] - b[2])])
    return bool(np.all(diff < SAME_POINT))


def _spread(front: list[ParetoDesign], count: int) -> list[ParetoDesign]:
    """At most ``count`` designs of a front, sorted by height: the chosen one and the best in
    each number, then those nearest to heights evenly spaced between the extremes (a weight
    lattice crowds its points where the trade is flat)."""
    front = sorted(front, key=lambda p: p.height_mm)
    if len(front) <= count:
        return front
    M = np.array([p.metrics for p in front])
    keep = {i for i, p in enumerate(front) if p.chosen}
    keep |= {int(np.argmin(M[:, j])) for j in range(M.shape[1])}
    for target in np.linspace(M[:, 0].min(), M[:, 0].max(), count):
        if len(keep) >= count:
            break
        free = [i for i in range(len(front)) if i not in keep]
        keep.add(min(free, key=lambda i: abs(M[i, 0] - target)))
    return [front[i] for i in sorted(keep)]


def _waves(weights: np.ndarray, size: int) -> list[np.ndarray]:
    return [weights[i : i + size] for i in range(0, len(weights), size)]


def pareto_front(
    doc: Document,
    count: int,
    *,
    seed: int | None = None,
    progress: Callable[[int, int, str, float], None] | None = None,
    max_evaluations: int | None = None,
    local: str = "slsqp",
) -> tuple[DesignResult, list[ParetoDesign]]:
    """(chosen DesignResult, front): up to ``count`` non-dominated designs meeting the targets.

    The chosen design is the one ``mst design`` writes (design.objective's weights); it is on
    the front unless another design dominates it (it then is listed all the same, marked).
    Fewer than ``count`` designs come back when the spec's free variables do not give that
    many distinct trade-offs (a one-layer spec with tight bounds, say).

    The work is shared: the screening and the match run once (the chosen design's solve), and
    every weighting starts its polish from that matched point; the weightings are polished
    together, each in its own local run, with their kernel calls batched into one
    (:func:`mst_cli.design.batching.prefer_many`). Designs are then judged in the weightings'
    order, as one at a time would be, until the front holds ``count`` designs.
    """
    solution: list = []
    chosen = design_document(
        doc, seed=seed, progress=progress, max_evaluations=max_evaluations, local=local, solution=solution
    )
    if chosen.status != "met":
        return chosen, []
    points = [ParetoDesign(chosen, None, chosen=True)]
    sol = solution[0]
    if sol.u_matched is None:
        return chosen, points
    front = _Front(
        doc,
        sol,
        points,
        seed=int(doc.design["seed"] if seed is None else seed),
        max_evaluations=int(doc.design["max_evaluations"] if max_evaluations is None else max_evaluations),
        local=local,
    )
    for wave in _waves(pareto_weights(MAX_WEIGHTINGS_PER_POINT * count), WAVE_PER_POINT * count):
        if front.add_wave(wave, count):
            break
    return chosen, _spread(_front_of(points), count)


def _front_of(points: list[ParetoDesign]) -> list[ParetoDesign]:
    """The non-dominated designs of ``points``, and the chosen one whatever it is."""
    mask = non_dominated(np.array([p.metrics for p in points]))
    return [p for p, keep in zip(points, mask) if keep or p.chosen]


class _Front:
    """The designs of a front as they are found: each weighting's polish from the chosen
    design's matched point, judged by the forward model, kept when it meets the targets and is
    not the same point as one already kept."""

    def __init__(
        self,
        doc: Document,
        sol: SolveResult,
        points: list[ParetoDesign],
        *,
        seed: int,
        max_evaluations: int,
        local: str,
    ):
        assert sol.u_matched is not None  # the caller's match succeeded
        self.doc, self.u_matched, self.points = doc, sol.u_matched, points
        self.seed, self.max_evaluations, self.local = seed, max_evaluations, local
        self.problem = DesignProblem(doc)
        # what a front design reports of the solver: the shared match and its own polish
        self.front_sol = replace(sol, preference_before=None, preference_after=None, stops=[])
        self.judged: set[bytes] = set()  # designs (as written) already judged: the same verdict again

    def add_wave(self, wave: np.ndarray, count: int) -> bool:
        """Polish the weightings of ``wave`` together and judge each design in their order; True
        once the front holds ``count`` designs."""
        polished = prefer_many(
            self.problem,
            [self.u_matched] * len(wave),
            list(wave),
            max_evaluations=self.max_evaluations,
            local=self.local,
            stops=self.front_sol.stops,
        )
        for w, (u, used) in zip(wave, polished):
            self.front_sol.evaluations += used
            cand = self._judge(w, u)
            if cand is None or any(_same_point(cand.metrics, p.metrics) for p in self.points):
                continue
            self.points.append(cand)
            if len(_front_of(self.points)) >= count:
                return True
        return False

    def _judge(self, w: np.ndarray, u: np.ndarray) -> ParetoDesign | None:
        """The design of weighting ``w`` polished to ``u``, when it meets the targets and was not
        judged before (many weightings polish to one design: met or not, it is a repeat)."""
        theta, t, h = (np.round(a, ROUND_DECIMALS) for a in self.problem.to_physical(u))
        key = np.concatenate([theta, t, h]).tobytes()
        if key in self.judged:
            return None
        self.judged.add(key)
        res = verify_design(
            self.doc,
            self.problem,
            theta,
            t,
            h,
            self.front_sol,
            seed=self.seed,
            max_evaluations=self.max_evaluations,
            mechanics="spring",
        )
        return ParetoDesign(res, (float(w[0]), float(w[1]), float(w[2]))) if res.status == "met" else None


# --------------------------------------------------------------------------- output
CSV_LAYER_COLUMNS = ("theta_deg", "t_mm", "h_mm")


def pareto_rows(front: list[ParetoDesign]) -> tuple[list[str], list[list]]:
    """(header, rows) of pareto.csv: one design per row, units in the header."""
    n = len(front[0].result.targets)
    header = (
        [
            "design",
            "chosen",
            "total_height_mm",
            "worst_force_resolution_mN",
            "print_robustness_rms_pct",
            "print_worst_change_pct",
            "gap0_mm",
            "B0_mT",
        ]
        + [f"weight_{k}" for k in OBJECTIVE_TERMS]
        + [f"layer{i + 1}_{c}" for i in range(n) for c in CSV_LAYER_COLUMNS]
    )
    rows = []
    for k, p in enumerate(front):
        resp = p.result.response
        w = (
            p.weights
            if p.weights is not None
            else tuple(p.result.document.design["objective"][key] for key in OBJECTIVE_TERMS)
        )
        row = [
            k + 1,
            int(p.chosen),
            round(p.height_mm, 3),
            round(1e3 * p.worst_force_resolution_N, 3),
            round(100 * p.print_robustness_rms, 2),
            round(100 * p.print_worst_change, 2),
            round(resp.gap0_mm, 3),
            round(resp.B0_T * 1e3, 4),
        ]
        row += [round(x, 3) for x in w]
        for c in p.result.targets:
            row += [c["theta_deg"], c["t_mm"], c["h_mm"]]
        rows.append(row)
    return header, rows


def pareto_csv(front: list[ParetoDesign]) -> str:
    header, rows = pareto_rows(front)
    return "\n".join([",".join(header)] + [",".join(str(x) for x in r) for r in rows]) + "\n"


def plot_pareto(front: list[ParetoDesign], path: str | Path, title: str = "") -> None:
    """Two views of the front against part height: print robustness (the trade a short part
    pays) and worst force resolution; the chosen design ringed, every design numbered as in
    pareto.csv."""
    from matplotlib.figure import Figure  # deferred: matplotlib loads only for pareto.png

    M = np.array([p.metrics for p in front])
    x = M[:, 0]
    fig = Figure(figsize=(10, 4.2))
    axes = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.13, top=0.88, wspace=0.25)
    tol_mm = front[0].result.print_error["print_error_t_mm"]
    worst = np.array([100 * p.print_worst_change for p in front])
    panels = (
        (100 * M[:, 2], f"change of S_i, R_i at t +- {tol_mm:g} mm [%]"),
        (1e3 * M[:, 1], "worst force resolution [mN]"),
    )
    for ax, (y, label) in zip(axes, panels):
        ax.plot(x, y, "-", color="0.7", zorder=1)
        ax.scatter(x, y, s=40, color="C0", zorder=3, label="RMS" if ax is axes[0] else None)
        if ax is axes[0]:  # the worst case beside the RMS
            ax.plot(x, worst, "-", color="0.85", zorder=1)
            ax.scatter(x, worst, s=40, marker="^", color="C1", zorder=3, label="worst S_i or R_i")
            for k in range(len(front)):
                ax.annotate(str(k + 1), (x[k], worst[k]), textcoords="offset points", xytext=(5, 4), fontsize=8)
        for k, p in enumerate(front):
            ax.annotate(str(k + 1), (x[k], y[k]), textcoords="offset points", xytext=(5, 4), fontsize=8)
            if p.chosen:
                ax.scatter(
                    [x[k]],
                    [y[k]],
                    s=190,
                    facecolors="none",
                    edgecolors="C3",
                    linewidths=1.8,
                    zorder=4,
                    label="chosen (design.objective)",
                )
        ax.set_xlabel("total part height [mm]")
        ax.set_ylabel(label, fontsize=9)
        ax.margins(0.08)
        ax.grid(alpha=0.3)
        if any(p.chosen for p in front) or ax is axes[0]:
            ax.legend(loc="best", fontsize=8)
    fig.suptitle(title or "designs that meet every target")
    fig.savefig(path, dpi=110, format="png")


def front_table(front: list[ParetoDesign]) -> str:
    """The front as ``mst design --pareto`` prints it."""
    lines = [
        f"Pareto front: {len(front)} designs that meet every target (forward model)",
        f"{'#':>3} {'height':>7} {'dF worst':>9} {'print':>6} {'worst':>6}  {'theta [deg]':<20} {'t [mm]':<18} h [mm]",
        f"{'':>3} {'[mm]':>7} {'[mN]':>9} {'RMS %':>6} {'[%]':>6}",
    ]
    for k, p in enumerate(front):
        rows = p.result.targets
        mark = "  <-- chosen" if p.chosen else ""
        theta = "/".join(f"{r['theta_deg']:.1f}" for r in rows)
        t = "/".join(f"{r['t_mm']:.2f}" for r in rows)
        h = "/".join(f"{r['h_mm']:.2f}" for r in rows)
        lines.append(
            f"{k + 1:>3} {p.height_mm:>7.2f} {1e3 * p.worst_force_resolution_N:>9.2f} "
            f"{100 * p.print_robustness_rms:>6.1f} {100 * p.print_worst_change:>6.1f}  "
            f"{theta:<20} {t:<18} {h}{mark}"
        )
    return "\n".join(lines)


__all__ = ["ParetoDesign", "pareto_front", "non_dominated", "pareto_csv", "plot_pareto", "front_table"]
