"""What every ``bipedal`` command module shares: the console and the common options."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.console import Console

console = Console()

EnvOpt = Annotated[
    str | None, typer.Option("--env", help="walker | hardcore (or a full Gymnasium id).")
]
DeviceOpt = Annotated[str | None, typer.Option("--device", help="auto | cpu | cuda.")]
