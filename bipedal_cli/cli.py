"""The ``bipedal`` command: the app, its commands (:mod:`~bipedal_cli.cli_train`,
:mod:`~bipedal_cli.cli_policy`, :mod:`~bipedal_cli.cli_sweep`: each parses, resolves config,
calls the library and prints with rich) and :func:`main`.

Every :class:`UserError` (and every usage error) becomes one line on stderr and exit code 2.
"""

from __future__ import annotations

import sys

import typer

from .errors import UserError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Train, resume and evaluate TQC + D2RL agents on BipedalWalker(-Hardcore)-v3.",
)


# typer >= 0.29 carries its own click: its usage errors derive from the public
# typer.TyperException, and typer.Abort is what it raises on an abort.
_CLICK_ERRORS = (typer.TyperException,)
_ABORTS = (typer.Abort,)


def _add_commands() -> None:
    from .cli_policy import eval_, export, info, plot, record
    from .cli_select import select
    from .cli_sweep import sweep_app
    from .cli_train import curriculum, resume, train

    for command in (train, resume, curriculum):
        app.command()(command)
    app.command("eval")(eval_)
    app.command()(select)
    for command in (record, plot, export, info):
        app.command()(command)
    app.add_typer(sweep_app, name="sweep")


_add_commands()


def main(argv: list[str] | None = None) -> None:
    """Console entry point: one-line errors with exit code 2 instead of tracebacks."""
    try:
        rv = app(args=argv, standalone_mode=False, prog_name="bipedal")
    except UserError as exc:
        _fail(str(exc))
    except (KeyboardInterrupt, *_ABORTS):
        print("bipedal: aborted", file=sys.stderr)
        sys.exit(130)
    except _CLICK_ERRORS as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            sys.exit(2)
        ctx = getattr(exc, "ctx", None)
        where = f" ({ctx.command_path})" if ctx is not None else ""
        _fail(exc.format_message().replace("\n", " ") + where)
    except PermissionError as exc:
        _fail(f"{exc.filename}: permission denied")
    except OSError as exc:
        if exc.filename is None:
            raise
        _fail(f"{exc.filename}: {exc.strerror}")
    if isinstance(rv, int) and rv:
        sys.exit(rv)


def _fail(message: str) -> None:
    print(f"bipedal: error: {message}", file=sys.stderr)
    sys.exit(2)
