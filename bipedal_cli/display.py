"""Rich rendering: the live training display and result tables (the CLI's view layer)."""

from __future__ import annotations

import time
from typing import Any

from rich.console import Console, Group
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table


def _num(value: Any, fmt: str = "{:.1f}") -> str:
    return "-" if value is None else fmt.format(value)


class TrainingDisplay:
    """A progress bar over env steps and a line of learning statistics under it."""

    def __init__(self, console: Console | None = None, title: str = "training") -> None:
        self.console = console or Console()
        self.title = title
        self.snapshot: dict[str, Any] = {}
        outer = self

        class _Progress(Progress):
            def get_renderables(self):
                yield Group(self.make_tasks_table(self.tasks), outer.stats_table())

        self.progress = _Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TaskProgressColumn(),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=self.console,
            refresh_per_second=4,
        )
        self.task = None
        self.line_every_s = 30.0
        self._last_line = time.monotonic()

    def stats_table(self) -> Table:
        s = self.snapshot
        table = Table.grid(padding=(0, 2))
        for _ in range(4):
            table.add_column(justify="right", style="cyan")
            table.add_column(justify="left")
        table.add_row(
            "episodes",
            _num(s.get("episodes"), "{:d}"),
            "steps/s",
            _num(s.get("steps_per_s")),
            "return (last)",
            _num(s.get("last_return")),
            "return (avg 10)",
            _num(s.get("avg_return")),
        )
        falls = s.get("last_eval_falls")
        table.add_row(
            "last eval",
            _num(s.get("last_eval")) + (f" ({falls} fell)" if falls else ""),
            "alpha",
            _num(s.get("alpha"), "{:.4f}"),
            "critic loss",
            _num(s.get("critic_loss"), "{:.3f}"),
            "actor loss",
            _num(s.get("actor_loss"), "{:.2f}"),
        )
        table.add_row(
            f"falls (last {s.get('falls_over') or 100})",
            _num(s.get("fall_rate"), "{:.0%}"),
            "q mean",
            _num(s.get("q_mean")),
            "entropy",
            _num(s.get("entropy"), "{:.2f}"),
            "learning rate",
            _num(s.get("lr"), "{:.2e}"),
        )
        extra = [text for pair in scheduled_values(s) for text in pair]
        for first in range(0, len(extra), 8):  # four label-value pairs a row
            table.add_row(*extra[first : first + 8])
        return table

    # Reporter protocol
    def start(self, start_step: int, total_steps: int) -> None:
        self.progress.start()
        self.task = self.progress.add_task(self.title, total=total_steps, completed=start_step)

    def update(self, snapshot: dict[str, Any]) -> None:
        self.snapshot = snapshot
        desc = f"{self.title} ({snapshot.get('phase', '')})"
        self.progress.update(self.task, completed=snapshot["step"], description=desc)
        # Not a terminal (nohup, a log file): no live display, so a plain line now and then.
        now = time.monotonic()
        if not self.console.is_terminal and now - self._last_line >= self.line_every_s:
            self._last_line = now
            s = snapshot
            self.console.print(
                f"step {s['step']:,}  episodes {s.get('episodes', 0):,}  "
                f"steps/s {_num(s.get('steps_per_s'))}  return (avg 10) "
                f"{_num(s.get('avg_return'))}  falls {_num(s.get('fall_rate'), '{:.0%}')}  "
                f"last eval {_num(s.get('last_eval'))}  alpha {_num(s.get('alpha'), '{:.4f}')}"
                + "".join(f"  {label} {value}" for label, value in scheduled_values(s)),
                soft_wrap=True,
            )

    def log(self, text: str) -> None:
        self.progress.console.log(text)

    def close(self) -> None:
        self.progress.stop()


def scheduled_values(s: dict) -> list[tuple[str, str]]:
    """(label, value) of each config feature a snapshot shows only when it is on."""
    pairs = []
    if s.get("replay_kept") is not None:  # train.replay_keep_below: FORK's curation
        pairs.append(("replay kept", _num(s["replay_kept"], "{:.0%}")))
    if s.get("fall_penalty") is not None:  # train.fall_penalty_final: a ramp
        pairs.append(("fall penalty", _num(s["fall_penalty"], "{:.1f}")))
    if s.get("actor_cvar") is not None:  # agent.actor_cvar: the risk-averse actor
        pairs.append(("actor objective", f"CVaR {s['actor_cvar']:g}"))
    if s.get("batch_size") is not None:  # agent.batch_size_final: a larger batch later
        pairs.append(("batch", f"{s['batch_size']:,}"))
    if s.get("drop_per_critic") is not None:  # agent.drop_per_critic_final: more truncation
        pairs.append(("atoms dropped/critic", f"{s['drop_per_critic']}"))
    if s.get("target_entropy") is not None:  # agent.target_entropy_final: a decay
        pairs.append(("target entropy", _num(s["target_entropy"], "{:.2f}")))
    if s.get("actor_smooth") is not None:  # agent.actor_smooth: CAPS's spatial term
        pairs.append(("actor smoothness", f"{s['actor_smooth']:g}"))
    if s.get("updates_per_step") is not None:  # train.updates_per_step_final
        pairs.append(("updates/step", f"{s['updates_per_step']}"))
    if s.get("replay_recency") is not None:  # train.replay_recency: ERE
        pairs.append(("recent replay", f"eta {s['replay_recency']:.5f}"))
    if s.get("obstacle_mix") is not None:  # train.obstacle_*: more of some obstacles
        shares = zip(("stump", "stairs", "pit"), s["obstacle_mix"], strict=True)
        pairs.append(("obstacles", " ".join(f"{k} {p:.0%}" for k, p in shares)))
    if s.get("falls_remembered") is not None:  # train.fall_restart: restarts near falls
        pairs.append(("falls remembered", f"{s['falls_remembered']:,}"))
    return pairs


def eval_table(summary: dict, title: str) -> Table:
    table = Table(title=title, show_header=True, header_style="bold")
    for col in ("episodes", "mean", "std", "min", "max", "median", "mean length", "falls"):
        table.add_column(col, justify="right")
    table.add_row(
        str(summary["episodes"]),
        f"{summary['mean']:.1f}",
        f"{summary['std']:.1f}",
        f"{summary['min']:.1f}",
        f"{summary['max']:.1f}",
        f"{summary['median']:.1f}",
        f"{summary['mean_length']:.0f}",
        falls_text(summary),
    )
    return table


def falls_text(summary: dict) -> str:
    """'12 (stairs 6, pit 4, stump 2)': the falls and where they happened, when known."""
    where = summary.get("falls_at") or {}
    parts = ", ".join(f"{kind} {n}" for kind, n in sorted(where.items(), key=lambda kv: -kv[1]))
    return f"{summary['falls']} ({parts})" if parts else str(summary["falls"])


def verdict(summary: dict) -> str:
    """'solved: mean 309.8 > 300 (95% interval 309.6 to 310.0)': the verdict is the mean's; the
    interval says how far these episodes pin the policy's expected return down."""
    from .evaluation import mean_interval

    lo, hi = mean_interval(summary["episodes"], summary["mean"], summary["std"])
    interval = f" (95% interval {lo:.1f} to {hi:.1f})" if summary["episodes"] > 1 else ""
    mean, threshold = summary["mean"], summary["threshold"]
    if summary["solved"]:
        return f"[bold green]solved[/]: mean {mean:.1f} > {threshold:g}{interval}"
    return f"[bold red]not solved[/]: mean {mean:.1f} <= {threshold:g}{interval}"


def curriculum_table(result, run_dir: str) -> Table:
    """One row per finished stage of a curriculum: steps, episodes, wall time, evaluation."""
    table = Table(title=f"curriculum ({result.stopped}): {run_dir}")
    for col in ("stage", "env", "steps", "episodes", "wall time", "evaluation", "result"):
        table.add_column(col, justify="right")
    for i, st in enumerate(result.stages, 1):
        ev = st["full_eval"] or st["last_eval"]
        ev_text = f"{ev['mean']:.1f} +- {ev['std']:.1f} ({ev['episodes']} ep.)" if ev else "-"
        table.add_row(
            str(i),
            st["env"],
            f"{st['steps']:,}",
            f"{st['episodes']:,}",
            f"{st['wall_time'] / 60:.1f} min",
            ev_text,
            st["stopped"],
        )
    return table
