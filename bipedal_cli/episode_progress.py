"""Progress over a known number of episodes, for ``eval`` and ``select``.

On a terminal it is rich's live bar. When the output is a file (``nohup``, a CI log) a live bar
shows nothing until it ends, so a plain line is printed now and then instead, with the rate so
far and the time left at that rate, like the training display's lines.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console

LINE_EVERY_S = 30.0


def progress_line(label: str, done: int, total: int, elapsed_s: float) -> str:
    """``label: done/total episodes (p%), m.m min, about r.r min left`` (the time left at the
    mean rate so far; left out until an episode has ended)."""
    share = done / total if total else 1.0
    text = f"{label}: {done:,}/{total:,} episodes ({share:.0%}), {elapsed_s / 60:.1f} min"
    if 0 < done < total:
        text += f", about {elapsed_s / done * (total - done) / 60:.1f} min left"
    return text


@contextmanager
def episode_progress(
    console: Console,
    label: str,
    total: int,
    line_every_s: float = LINE_EVERY_S,
    clock: Callable[[], float] = time.monotonic,
) -> Iterator[Callable[[int], None]]:
    """Yield ``advance(n)``, to be called as episodes end; the bar or the lines follow it."""
    if console.is_terminal:
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

        columns = (BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
        with Progress(f"[bold]{label}", *columns, console=console) as progress:
            task = progress.add_task(label, total=total)
            yield lambda n: progress.advance(task, n)
        return
    started = last_line = clock()
    done = 0

    def advance(n: int) -> None:
        nonlocal done, last_line
        done += n
        now = clock()
        if now - last_line >= line_every_s and done < total:
            last_line = now
            console.print(progress_line(label, done, total, now - started), soft_wrap=True)

    yield advance
    console.print(progress_line(label, done, total, clock() - started), soft_wrap=True)
