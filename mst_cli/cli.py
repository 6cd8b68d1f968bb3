"""The ``mst`` command line. Thin: it parses options, calls the library, writes files.

Exit codes (DESIGN.md section 5): 0 success, 1 targets not met / checks failed, 2 invalid
input (one line naming the field, the value and what is allowed). Heavy libraries
(build123d, scikit-fem, matplotlib.pyplot) are imported inside the commands that need them.
"""

from __future__ import annotations

import errno
import functools
import json
import os
import sys
from pathlib import Path

import click

from . import __version__

EXIT_TARGETS, EXIT_INPUT = 1, 2  # success is a normal return (0)
EXIT_FAULT = 1                   # the machine failed (full disk, I/O error): not the input's fault

# errno values that are the machine's fault rather than a bad path: exit 1, not 2
MACHINE_FAULTS = frozenset(getattr(errno, name) for name in (
    "ENOSPC", "EDQUOT", "EIO", "ENOMEM", "EMFILE", "ENFILE", "EFBIG", "EAGAIN", "EBUSY",
    "ETXTBSY", "ESTALE", "ENOLCK", "EREMOTEIO", "ENOBUFS", "EINTR") if hasattr(errno, name))


def one_line(text: str) -> str:
    """``text`` with every control character escaped: what goes to stderr is always one line."""
    return "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in str(text))


def fail_input(message: str) -> None:
    click.echo(one_line(f"mst: invalid input: {message}"), err=True)
    sys.exit(EXIT_INPUT)


def os_error_line(exc: OSError) -> tuple[str, int]:
    """(one line naming the path and the errno reason, exit code) of a file-system error."""
    code = EXIT_FAULT if exc.errno in MACHINE_FAULTS else EXIT_INPUT
    name = errno.errorcode.get(exc.errno, "") if exc.errno is not None else ""
    reason = exc.strerror or (os.strerror(exc.errno) if exc.errno else str(exc))
    paths = " -> ".join(str(p) for p in (exc.filename, exc.filename2) if p is not None) or "(unknown path)"
    kind = "system error" if code == EXIT_FAULT else "invalid path"
    return one_line(f"mst: {kind}: {paths}: {reason}" + (f" ({name})" if name else "")), code


def handles_input_errors(func):
    """Turn :class:`~mst_cli.schema.InputError` into one line on stderr and exit code 2, and an
    OSError into one line naming the path and the errno reason (exit 2 for a bad path, 1 for a
    machine fault such as a full disk). The group (:class:`MstGroup`) does the same for any
    command without this decorator."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        from .schema import InputError
        try:
            return func(*args, **kwargs)
        except InputError as exc:
            fail_input(str(exc))
        except OSError as exc:
            if exc.errno == errno.EPIPE:
                raise                     # click closes stdout quietly
            line, code = os_error_line(exc)
            click.echo(line, err=True)
            sys.exit(code)
    return wrapper


class MstGroup(click.Group):
    """click's group with the tool's one-line error contract: usage errors (unknown option, bad
    value, missing argument, a folder where a file belongs) are one line ``mst: usage error: ...``
    and exit 2; an interrupt is one line and exit 128 + signal. ``--help`` and ``--version`` are
    click's own."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        from .outputs import Interrupted
        from .schema import InputError
        try:
            rv = super().main(args, prog_name or "mst", complete_var, standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:
            exc.show()                    # bare 'mst': the help, as click prints it
            sys.exit(exc.exit_code)
        except click.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "mst"
            click.echo(one_line(f"mst: usage error: {exc.format_message()} "
                                f"(see '{where} --help')"), err=True)
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            click.echo(one_line(f"mst: {exc.format_message()}"), err=True)
            sys.exit(exc.exit_code)
        except click.Abort:               # Ctrl-C (SIGINT) or end of input at a prompt
            click.echo("mst: interrupted (SIGINT): nothing half-written was left", err=True)
            sys.exit(130)
        except Interrupted as exc:
            click.echo(f"mst: interrupted ({exc.name}): nothing half-written was left", err=True)
            sys.exit(exc.code)
        except InputError as exc:
            fail_input(str(exc))
        except OSError as exc:
            line, code = os_error_line(exc)
            click.echo(line, err=True)
            sys.exit(code)
        except ValueError as exc:
            if "null byte" not in str(exc):   # only os's refusal of a NUL in a path (in-process
                raise                         # callers; argv cannot hold one)
            click.echo("mst: invalid path: a path argument holds a NUL byte (EINVAL)", err=True)
            sys.exit(EXIT_INPUT)
        sys.exit(rv if isinstance(rv, int) and not isinstance(rv, bool) else 0)


def default_out_dir(name: str) -> Path:
    return Path("mst-out") / name


def load_design_document(path):
    """Load a design file and check its cells; InputError on any broken rule."""
    from .schema import InputError, load_document
    doc = load_document(path)
    geometry = doc.geometry()
    for i, v in geometry.violations(doc.printer):
        raise InputError(f"layers[{i}]", {"theta_deg": geometry.layers[i].theta_deg,
                                          "t_mm": geometry.layers[i].t_mm,
                                          "h_mm": geometry.layers[i].h_mm},
                         f"invalid cell ({v.rule}): {v.message}")
    return doc, geometry


def write_simulation(doc, geometry, resp, out_dir: Path, extra_files=None, extra_report=None, more=None):
    """report.json, response.csv, response.png (+ extra YAML files, + whatever ``more(staging)``
    writes) into out_dir, atomically."""
    from .outputs import staged
    from .report import plot_response, report_dict, response_csv

    with staged(out_dir) as st:
        for name, data in (extra_files or {}).items():
            st.write_yaml(name, data)
        st.write_json("report.json", report_dict(doc, geometry, resp, extra_report))
        st.write_text("response.csv", response_csv(resp))
        plot_response(resp, st.path("response.png"), title=doc.name)
        if more is not None:
            more(st)
    return out_dir


@click.group(cls=MstGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="mst")
def main():
    """Design multi-sensitivity soft tactile (MST) sensors.

    A stack of collapsible 3D-printed TPU layers, a magnet above it and an MLX90393
    magnetometer below: each layer locks at its own force, so one sensor has several
    sensitivities over several force bands. Units: mm, N, MPa, degrees, mT.

    \b
    mst simulate DESIGN.yaml   forward model: curves, S_i, R_i, field, chip settings
    mst design SPEC.yaml       inverse design from target S_i and R_i to theta, t, h
    mst export DESIGN.yaml     printable STL / STEP of the stacked assembly
    mst check PATH             geometry checks of what export wrote
    mst bench                  measured speed/accuracy table of the models

    Exit codes: 0 success, 1 targets not met or checks failed, 2 invalid input.
    """


@main.command()
@click.argument("design_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder [default: ./mst-out/<name>/].")
@click.option("--field-model", type=click.Choice(["auto", "dipole", "axial", "cylinder"]), default=None,
              help="Magnet field model [default: the file's model.field, else auto = the cheapest "
                   "exact one: axial on the axis, cylinder off it].")
@click.option("--mechanics", type=click.Choice(["spring", "frame", "continuum"]), default=None,
              help="Layer mechanics model [default: the cheapest whose measured error meets the "
                   "file's model.accuracy_rel, else the file's model.mechanics, else spring].")
@click.option("--json", "as_json", is_flag=True, help="Print report.json to stdout instead of the table.")
@handles_input_errors
def simulate(design_file, out_dir, field_model, mechanics, as_json):
    """Predict force-displacement and field-force curves of DESIGN_FILE.

    Writes report.json (units in keys), response.csv and response.png into the output
    folder and prints a per-regime table: stiffness, force band, secant sensitivity S
    (dB/B0 per newton) with its local min..max, and the force resolution dF of the chip.
    """
    from .ladder import choose_mechanics
    from .report import report_dict, terminal_table
    from .response import simulate as run

    from .outputs import check_out_dir

    doc, geometry = load_design_document(design_file)
    out = out_dir or default_out_dir(doc.name)
    check_out_dir(out)                    # a bad output path is refused before any work
    field_choice = field_model or doc.field_model
    choice = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics)
    if choice.message() and not as_json:
        click.echo(choice.message())
    resp = run(geometry, doc.material, mechanics=choice.mechanics,
               field_model=None if field_choice == "auto" else field_choice,
               noise_uT_rms=doc.noise_uT_rms)
    write_simulation(doc, geometry, resp, out)
    if as_json:
        click.echo(json.dumps(report_dict(doc, geometry, resp), indent=2, allow_nan=False))
    else:
        click.echo(terminal_table(doc, geometry, resp))
        click.echo(f"wrote {out}/report.json, response.csv, response.png")


# Commands that live in their own modules (each keeps its heavy imports inside the command
# function). One add_command line per command, below this comment.
from .cli_export import check, export  # noqa: E402
main.add_command(export)
main.add_command(check)
from .cli_design import design  # noqa: E402
main.add_command(design)
from .cli_bench import bench  # noqa: E402
main.add_command(bench)
from .cli_slice import slice_  # noqa: E402
main.add_command(slice_)
from .cli_calibrate import calibrate, read  # noqa: E402
main.add_command(calibrate)
main.add_command(read)
