"""The long help texts of the ``mst`` commands (click prints them with ``--help``), kept apart
from the options so that each command module reads as its options and its few calls."""

DESIGN = """Find theta, t, h of every layer so that the sensor meets SPEC_FILE's targets.

Per layer the spec gives a target sensitivity S (dB/B0 per newton, secant over the
regime) and the force R at which that layer locks (the regime's end). Three variables
per layer meet two targets; the spare freedom picks, among the designs that meet them,
the one that minimises the spec's design.objective: a weighted sum of total height,
worst force resolution and print robustness (how much S and R change when every wall is
printed printer.wall_tolerance_mm off, default 0.05 mm; reported per layer, with the worst
change beside the RMS). --pareto N maps the trade. The walls are designed as printed
(printer.wall_offset_mm, printer.modulus_factor; --calibration takes them from an earlier
print) and design.yaml draws them as drawn. Every achieved number comes from re-running
the forward model on the written design as printed.

Writes design.yaml (loadable by mst simulate and mst export), report.json,
response.csv and response.png (not with --no-plot or --json).

With --refine frame|continuum (or model.accuracy_rel asking for a dearer rung, or
model.mechanics: frame|continuum) the fast L0 optimum is polished for that model and the
targets are judged by it; report.json's refinement section lists the iterations.

\b
Exit codes:
  0  every target within the tolerance (design.tolerance_rel, default 2 %)
  1  physically unreachable: the nearest design is written and the binding
     target or constraint is named (field change the magnet cannot give,
     forces outside what printable walls reach, S rising with force, ...)
  2  invalid or self-contradictory spec (e.g. ranges that do not increase)
"""

DESIGN_REFINE = (
    "Polish the L0 optimum with a dearer mechanics model (output space mapping: "
    "L0 targets corrected by the dear model's miss, L0 re-solved, repeated); every "
    "achieved number then comes from that model [default: model.accuracy_rel's "
    "pick, else model.mechanics if not spring, else no refinement]."
)

DESIGN_PARETO = (
    "Also map the trade among designs that meet the targets: up to N non-dominated "
    "designs over total height, worst force resolution and print robustness, "
    "written to pareto.csv (one design per row, units in the header) and "
    "pareto.png, the chosen one (design.objective's weights) marked."
)

DESIGN_CALIBRATION = (
    "Design for the printer as an earlier print measured it: take the wall offset, modulus "
    "factor, gap offset and remanence that mst calibrate fitted on a print of any design "
    "(same printer and filament) into printer.* and magnet.remanence_T; parameters the "
    "calibration held are not used, and named."
)

READ_ESTIMATE = (
    "What to estimate beside the force. offset: where each reading was pressed, from Bx, By, Bz, and "
    "its force corrected (the tilt model's inverse, from the model's table inverse_table.npz: built "
    "on first use, thousands of readings a second; --serial too): forces.csv adds force_centred_N, "
    "x_mm, y_mm, force_N_sigma, x_mm_sigma, y_mm_sigma (Cramer-Rao 1-sigma) and offset_flag (ok; or "
    "not_identifiable, ambiguous, no_fit: the centred force kept). shear: the tangential force of a "
    "press taken as centred (one chip: three numbers, three unknowns Fz, Fx, Fy; table shear_table.npz, "
    "friction cone |Fx|, |Fy| <= 0.5 Fz): forces.csv adds force_centred_N, shear_x_N, shear_y_N, x_mm, "
    "y_mm (0: assumed), their *_sigma, assumption (centred) and estimate_flag (ok; or ambiguous, no_fit). "
    "With two chips or more (magnetometer.positions_mm) shear estimates all five, Fz, Fx, Fy, x, y "
    "(assumption none), from a file or --serial."
)
READ_COLUMNS = (
    "--serial: which number of a line is which. A preset -- xyz; xyzt (x y z and the chip's temperature "
    "per chip: the MLX90393 library's examples, ReSkin's 5X_burst_stream; reskin is the same); txyz "
    "(anyskin: temperature first, AnySkin's 5X_burst_stream) -- or roles such as t,x,y,z or "
    "x1,y1,z1,-,x2,y2,z2 (- skips a number; numbered roles place chips). A group repeats per chip; a "
    "line of more chips than the model reads the first. [default: by the line: labels (X: .. Y: .. "
    "Z: ..), a header line X,Y,Z,T said before, or 3 or 4 numbers per chip of the model]"
)
READ_SEND = (
    "--serial: send TEXT when the port opens and again after each line received (and after a second "
    "of silence), for a sketch that prints only when asked; backslash escapes such as \\n are read."
)
READ_ESTIMATE_OFFSET = "The same as --estimate offset."
READ_POLISH = "Polish each estimate by the model's exact solve (about 0.1 s a reading: files, not streams)."
READ_MAX_OFFSET_SIGMA = "An offset less certain than this (1-sigma, mm) is not identifiable: the centred force is kept."
READ_TRACK_ZERO = (
    "Re-zero at every rest of the stream (|B| flat within 2 noise sigmas for 0.5 s, within 10 % of the span of "
    "the unloaded field), with the calibration's recovery after each unloading and its drift between rests."
)
CALIBRATE_MISSING_FORCE = (
    "A logger's mark for a row without a force (e.g. -1; nan for empty and nan cells only): such rows are "
    "skipped and counted in one line, never fitted (their field still times the lag). Without it they are "
    "refused."
)
READ_TARE = (
    "Take the first N readings as no load and re-zero the unloaded field on them (a reading within "
    "the noise of no load reads 0 N)."
)

READ_SERIAL = "Read a live stream from this serial port (one sample per line) instead of a file."
READ_COUNT = "Stop --serial after this many samples [default: until the port closes or Ctrl-C]."
READ_TIMEOUT = "Stop --serial after this many seconds without a byte (a positive, finite number)."

CALIBRATE_GAIN_SEL = "GAIN_SEL the load test was read at (needed for raw codes; the C header's setting)."
