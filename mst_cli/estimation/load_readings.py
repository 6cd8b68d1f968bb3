"""What ``mst read --estimate shear`` gives each reading: the load's five numbers (Fz, Fx, Fy
and where it was pressed), each with its Cramer-Rao 1-sigma, the assumption the estimate made
and its flag; forces.csv's columns for them and the lines a person reads.

The assumption is what the chips cannot tell and the estimate therefore took as known:

* ``centred``: one 3-axis chip gives three numbers, so three unknowns: (Fz, Fx, Fy) of a press
  taken at the face's centre (x = y = 0 written, no 1-sigma: assumed, not measured);
* ``none``: two chips or more give six numbers or more: all five estimated.

Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

ASSUMPTIONS = ("centred", "none")
# forces.csv's columns after the reading's own: the centred model's force, the five estimates,
# their 1-sigma, the assumption and the estimate's flag (ok; ambiguous or no_fit, whose force is
# the centred one; empty where the reading is flagged itself)
LOAD_COLUMNS = (
    "force_centred_N",
    "shear_x_N",
    "shear_y_N",
    "x_mm",
    "y_mm",
    "force_N_sigma",
    "shear_x_N_sigma",
    "shear_y_N_sigma",
    "x_mm_sigma",
    "y_mm_sigma",
    "assumption",
    "estimate_flag",
)


@dataclass
class LoadReadings:
    """Per reading: the normal force (the estimate where ``ok``, else the centred model's), the
    tangential force and the position (NaN unless ok; the assumed 0 where ``assumption`` fixes
    them), their 1-sigma ``sigma`` (n, 5) in the order force, Fx, Fy, x, y (NaN where assumed or
    not ok) and the flag (ok, ambiguous, no_fit; "" where the reading is flagged itself)."""

    force_N: np.ndarray
    shear_x_N: np.ndarray
    shear_y_N: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    sigma: np.ndarray
    flag: np.ndarray
    assumption: str

    @classmethod
    def concat(cls, parts: list[LoadReadings]) -> LoadReadings:
        """The readings of ``parts`` one after the other (a stream's samples)."""
        arrays = {
            f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(cls) if f.name != "assumption"
        }
        return cls(**arrays, assumption=parts[0].assumption)

    @property
    def force_sigma_N(self) -> np.ndarray:
        return self.sigma[:, 0]

    def scaled(self, modulus_scale: np.ndarray) -> LoadReadings:
        """The estimates of a sensor whose modulus is ``modulus_scale`` (n,) times the
        calibration's: every layer law is linear in E, so the three forces and their 1-sigma
        scale by it, the position not (:mod:`~mst_cli.calibration.temperature`)."""
        m = np.asarray(modulus_scale, dtype=float)
        sigma = self.sigma.copy()
        sigma[:, :3] *= m[:, None]
        return replace(
            self, force_N=self.force_N * m, shear_x_N=self.shear_x_N * m, shear_y_N=self.shear_y_N * m, sigma=sigma
        )

    def summary(self) -> str:
        ok = self.flag == "ok"
        kept = ", ".join(f"{int(np.sum(self.flag == f))} {f.replace('_', ' ')}" for f in ("ambiguous", "no_fit"))
        what = "Fz, Fx, Fy of a centred press" if self.assumption == "centred" else "Fz, Fx, Fy, x, y"
        if not ok.any():
            return f"shear ({what}): fitted no reading ({kept}: the centred force kept)"
        ft = np.hypot(self.shear_x_N[ok], self.shear_y_N[ok])
        s = np.median(self.sigma[ok], axis=0)
        where = "" if self.assumption == "centred" else f", x {s[3]:.2g} mm, y {s[4]:.2g} mm"
        return (
            f"shear ({what}): estimated on {int(ok.sum())} readings (median 1-sigma Fz {s[0]:.2g} N, "
            f"Fx {s[1]:.2g} N, Fy {s[2]:.2g} N{where}; |F_t| up to {ft.max():.3g} N); "
            f"{kept} (the centred force kept)"
        )

    def terminal(self, i: int) -> str:
        """What a live line adds for reading ``i`` (its flag where not ok)."""
        if self.flag[i] != "ok":
            return f"  {self.flag[i]}" if self.flag[i] else ""
        s = self.sigma[i]
        line = f"  Ft ({self.shear_x_N[i]:.3f}, {self.shear_y_N[i]:.3f}) N +- ({s[1]:.3f}, {s[2]:.3f})"
        if self.assumption != "centred":
            line += f"  at ({self.x_mm[i]:.2f}, {self.y_mm[i]:.2f}) mm +- ({s[3]:.2f}, {s[4]:.2f})"
        return line

    def append_columns(self, forces_csv_text: str, centred_force_N: np.ndarray) -> str:
        """forces.csv with :data:`LOAD_COLUMNS` appended."""
        lines = forces_csv_text.splitlines()
        out = [lines[0] + "," + ",".join(LOAD_COLUMNS)]
        for i, line in enumerate(lines[1:]):
            vals = [
                centred_force_N[i],
                self.shear_x_N[i],
                self.shear_y_N[i],
                self.x_mm[i],
                self.y_mm[i],
                *self.sigma[i],
            ]
            cells = ["" if not np.isfinite(v) else f"{v:.6g}" for v in vals]
            out.append(line + "," + ",".join(cells) + f",{self.assumption},{self.flag[i]}")
        return "\n".join(out) + "\n"


def from_estimates(
    estimates: np.ndarray, sigma: np.ndarray, flag: np.ndarray, force_axial_N: np.ndarray, assumption: str
) -> LoadReadings:
    """The readings of estimates (m, 5) with their sigma (m, 5) and flags (m,) of the readings
    with a finite centred force among ``force_axial_N`` (n,) (the others: "" and the centred
    force); a reading not ok keeps its centred force and has NaN elsewhere."""
    n = len(force_axial_N)
    use = np.isfinite(force_axial_N)
    est, sig = np.full((n, 5), np.nan), np.full((n, 5), np.nan)
    flags = np.full(n, "", dtype=object)
    est[use], sig[use], flags[use] = estimates, sigma, flag
    ok = flags == "ok"
    est[~ok], sig[~ok] = np.nan, np.nan
    F = np.where(ok, est[:, 0], force_axial_N)
    return LoadReadings(F, est[:, 1], est[:, 2], est[:, 3], est[:, 4], sig, flags, assumption)
