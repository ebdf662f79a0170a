"""What every ``bipedal`` command module shares: the console and the common options."""

from __future__ import annotations

import os
from typing import Annotated

import typer
from rich.console import Console

LOG_WIDTH = 160  # columns of output written to a file or a pipe


def make_console() -> Console:
    """The commands' console. Written to a file or a pipe (a ``nohup`` log) rich would wrap at 80
    columns and cut run names short in tables; there it is LOG_WIDTH wide, unless COLUMNS says
    otherwise. A terminal keeps its own width."""
    console = Console()
    if console.is_terminal or "COLUMNS" in os.environ:
        return console
    return Console(width=LOG_WIDTH)


console = make_console()

EnvOpt = Annotated[
    str | None, typer.Option("--env", help="walker | hardcore (or a full Gymnasium id).")
]
DeviceOpt = Annotated[str | None, typer.Option("--device", help="auto | cpu | cuda.")]
