"""What every ``mst`` command shares: exit codes, the one-line error contract, the group class.

Exit codes (docs/design.md section 5): 0 success, 1 targets not met / checks failed, 2 invalid
input (one line naming the field, the value and what is allowed). Command modules import from
here; nothing here imports a command.
"""

from __future__ import annotations

import errno
import functools
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn, ParamSpec, TypeVar

import click

from mst_cli import api
from mst_cli.cli.sigint import SigintSeen
from mst_cli.errors import InputError

_P = ParamSpec("_P")
_R = TypeVar("_R")
_F = TypeVar("_F", bound=Callable[..., Any])

EXIT_TARGETS, EXIT_INPUT = 1, 2  # success is a normal return (0)
EXIT_FAULT = 1  # the machine failed (full disk, I/O error): not the input's fault


def one_line(text: str) -> str:
    """``text`` with every control character escaped: what goes to stderr is always one line."""
    return "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in str(text))


def fail_input(message: str) -> NoReturn:
    click.echo(one_line(f"mst: invalid input: {message}"), err=True)
    sys.exit(EXIT_INPUT)


def exit_for_os_error(exc: OSError) -> NoReturn:
    """One line naming the path and the errno reason on stderr; exit 2 (a bad path) or 1 (a
    machine fault such as a full disk)."""
    machine = api.is_machine_fault(exc)
    click.echo(one_line(f"mst: {'system error' if machine else 'invalid path'}: {api.os_error_text(exc)}"), err=True)
    sys.exit(EXIT_FAULT if machine else EXIT_INPUT)


def handles_input_errors(func: Callable[_P, _R]) -> Callable[_P, _R]:
    """Turn :class:`~mst_cli.errors.InputError` into one line on stderr and exit code 2, and an
    OSError into one line naming the path and the errno reason (exit 2 for a bad path, 1 for a
    machine fault such as a full disk). The group (:class:`MstGroup`) does the same for any
    command without this decorator."""

    @functools.wraps(func)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        try:
            return func(*args, **kwargs)
        except InputError as exc:
            fail_input(str(exc))
        except OSError as exc:
            if exc.errno == errno.EPIPE:
                raise  # click closes stdout quietly
            exit_for_os_error(exc)

    return wrapper


class MstGroup(click.Group):
    """click's group with the tool's one-line error contract: usage errors (unknown option, bad
    value, missing argument, a folder where a file belongs) are one line ``mst: usage error: ...``
    and exit 2; an interrupt is one line and exit 128 + signal. ``--help`` and ``--version`` are
    click's own."""

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            with SigintSeen.installed():  # an extension import a Ctrl-C broke is the interrupt too
                rv = super().main(args, prog_name or "mst", complete_var, standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:
            exc.show()  # bare 'mst': the help, as click prints it
            sys.exit(exc.exit_code)
        except click.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "mst"
            click.echo(one_line(f"mst: usage error: {exc.format_message()} (see '{where} --help')"), err=True)
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            click.echo(one_line(f"mst: {exc.format_message()}"), err=True)
            sys.exit(exc.exit_code)
        except (click.Abort, KeyboardInterrupt):  # Ctrl-C (SIGINT) or end of input at a prompt
            click.echo("mst: interrupted (SIGINT): nothing half-written was left", err=True)
            sys.exit(130)
        except api.Interrupted as exc:
            click.echo(f"mst: interrupted ({exc.name}): nothing half-written was left", err=True)
            sys.exit(exc.code)
        except InputError as exc:
            fail_input(str(exc))
        except OSError as exc:
            exit_for_os_error(exc)
        except ValueError as exc:
            if "null byte" not in str(exc):  # only os's refusal of a NUL in a path (in-process
                raise  # callers; argv cannot hold one)
            click.echo("mst: invalid path: a path argument holds a NUL byte (EINVAL)", err=True)
            sys.exit(EXIT_INPUT)
        sys.exit(rv if isinstance(rv, int) and not isinstance(rv, bool) else 0)


def seed_type() -> click.IntRange:
    """The click type of every --seed option: the range design.seed has in a spec file."""
    return click.IntRange(*api.SEED_RANGE)


def default_out_dir(name: str) -> Path:
    return Path("mst-out") / name


def out_dir_option(default_text: str = "./mst-out/<name>/") -> Callable[[_F], _F]:
    """The ``--out`` folder option every writing command takes (``out_dir``, None: the default)."""
    return click.option(
        "--out",
        "out_dir",
        type=click.Path(file_okay=False, path_type=Path),
        default=None,
        help=f"Output folder [default: {default_text}].",
    )


def no_plot_option(picture: str, cost: str, has_json: bool = True) -> Callable[[_F], _F]:
    """``--no-plot`` with one meaning on every command that draws: ``picture`` is not drawn,
    matplotlib is never imported, and an old ``picture`` in the output folder is removed with
    the commit. ``cost`` says what the picture costs (measured: benchmarks/bench_simulate.py).
    With ``has_json``, ``--json`` implies it."""
    implied = " --json implies it." if has_json else ""
    return click.option(
        "--no-plot",
        "no_plot",
        is_flag=True,
        help=f"Draw no {picture} and import no matplotlib ({cost}). An old {picture} "
        f"in the output folder is removed, never left beside newer results.{implied}",
    )
