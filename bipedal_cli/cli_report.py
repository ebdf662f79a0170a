"""What ``bipedal train``, ``resume`` and ``curriculum`` print when a run stops, and the exit
status a stop by a signal gives (:mod:`bipedal_cli.cli_train`'s commands call these)."""

from __future__ import annotations

import sys

from .cli_common import console
from .paths import printable


def summary_line(result) -> str:
    minutes = result.wall_time / 60
    why = {
        "budget": "step budget reached",
        "solved": "solved",
        "interrupted": "interrupted, checkpoint saved",
        "pruned": "pruned by the sweep",
    }[result.stopped]
    return (
        f"{why}: {result.steps:,} steps ({result.env_steps or result.steps:,} env steps), "
        f"{result.episodes:,} episodes, "
        f"{minutes:.1f} min; run directory {printable(result.run_dir)}"
    )


def report_result(result) -> None:
    from .display import eval_table, verdict

    console.print(summary_line(result))
    if result.full_eval:
        console.print(eval_table(result.full_eval, "full evaluation"))
        console.print(verdict(result.full_eval))
    elif result.last_eval:
        e = result.last_eval
        console.print(
            f"last evaluation ({e['episodes']} episodes at step {e['step']:,}): "
            f"{e['mean']:.1f} +- {e['std']:.1f}"
        )
    run_dir = printable(result.run_dir)
    console.print(f"policy: {run_dir}/policy.pt   resume: bipedal resume {run_dir}")


def exit_if_interrupted(result) -> None:
    """128 + the signal's number after a run stopped by Ctrl-C (130) or SIGTERM (143)."""
    if result.signal is not None:
        from .signals import exit_status

        sys.exit(exit_status(result.signal))


def report_curriculum(result) -> None:
    from .display import curriculum_table

    console.print(curriculum_table(result, printable(result.run_dir)))
    console.print(f"resume: bipedal resume {printable(result.run_dir)}")
