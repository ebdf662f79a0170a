"""``bipedal select``: choose a run's policy on held-out seeds (:mod:`bipedal_cli.selection`;
registered on the app by :mod:`bipedal_cli.cli`)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from .cli_common import console
from .errors import UserError
from .paths import atomic_path, check_output_path, printable
from .selection import HELD_OUT_SEED, distinct, finalists, run_candidates, top_candidates
from .validation import check_count, check_seeds


def select(
    runs: Annotated[
        list[Path],
        typer.Argument(metavar="RUN_DIR...", help="Run directories (or policy files)."),
    ],
    top: Annotated[
        int,
        typer.Option("--top", help="Candidates: the best K by periodic evaluation (0: all)."),
    ] = 5,
    since: Annotated[
        int, typer.Option("--since", help="Only the runs' policies from policy step S on.")
    ] = 0,
    episodes: Annotated[int, typer.Option("--episodes", help="Held-out episodes each.")] = 100,
    seed: Annotated[
        int, typer.Option("--seed", help="Held-out env seeds S.. (not eval's 0-99).")
    ] = HELD_OUT_SEED,
    out: Annotated[
        Path | None, typer.Option("--out", help="Copy the chosen policy file here.")
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write every candidate's scores.")
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite --out / --json.")] = False,
    confirm: Annotated[
        int,
        typer.Option(
            "--confirm",
            help="Then N more seeds for the winner against the incumbent (or the runner-up).",
        ),
    ] = 0,
    workers: Annotated[int, typer.Option("--workers", help="Processes (0: every core).")] = 0,
) -> None:
    """Choose the policy that scores best on held-out seeds among runs' kept policies.

    Its `bipedal eval` on seeds 0-99 is then an estimate that did not choose it."""
    check_count("--top", top, low=0)
    if since < 0:
        raise UserError(f"--since {since}: expected a non-negative policy step")
    check_count("--episodes", episodes)
    check_count("--confirm", confirm, low=0)
    check_seeds("--seed", seed, episodes + confirm)
    if workers < 0:
        raise UserError("--workers: expected 0 (every core) or a positive integer")
    for path, option in ((out, "--out"), (json_out, "--json")):
        if path is not None:
            check_output_path(path, option, force=force)
    named = [c for path in runs if path.is_file() for c in run_candidates(path)]
    found = [c for path in runs if not path.is_file() for c in run_candidates(path)]
    pool = distinct(named + [c for c in found if c.step >= since])
    envs = {c.env for c in pool}
    if len(envs) > 1:
        raise UserError(f"RUN_DIR: the runs' policies are for different envs: {sorted(envs)}")
    # a policy file named on the command line is always a candidate; runs give their top K
    chosen = pool[: len(named)] + top_candidates(pool[len(named) :], top or len(pool))
    seeds = list(range(seed, seed + episodes))
    scores, episodes_of = _evaluate(chosen, seeds, workers)
    best = max(range(len(chosen)), key=lambda i: scores[i]["mean"])
    console.print(_table(chosen, scores, best, seeds))
    means = [s["mean"] for s in scores]
    pair = finalists(means, len(named))
    # the winner against the incumbent or the runner-up (also when the incumbent won)
    ranked = sorted(range(len(means)), key=lambda i: means[i], reverse=True)
    shown = pair if len(pair) == 2 else ranked[:2]
    payload: dict = {"seeds": [seeds[0], seeds[-1]], **_difference(chosen, episodes_of, shown)}
    if confirm:
        final = [chosen[i] for i in pair]
        second = list(range(seeds[-1] + 1, seeds[-1] + 1 + confirm))
        final_scores, final_episodes = _evaluate(final, second, workers)
        pick = max(range(len(final)), key=lambda i: final_scores[i]["mean"])
        console.print(_table(final, final_scores, pick, second, "confirmation"))
        payload["confirm"] = {
            "seeds": [second[0], second[-1]],
            "finalists": _rows(final, final_scores),
            **_difference(final, final_episodes, [pick, 1 - pick][: len(final)]),
        }
        winner = final[pick]
    else:
        winner = chosen[best]
    console.print(f"chosen: {printable(winner.path)} (step {winner.step:,})")
    if out is not None:
        with atomic_path(out) as tmp:
            shutil.copyfile(winner.path, tmp)
        console.print(f"copied to {printable(out)}; report its score with `bipedal eval {out}`")
    if json_out is not None:
        import torch

        from .devices import machine_summary

        payload.update(chosen=str(winner.path), candidates=_rows(chosen, scores))
        payload["machine"] = machine_summary(torch.device("cpu"))  # the CPU's rounding counts
        with atomic_path(json_out) as tmp:
            tmp.write_text(json.dumps(payload, indent=1))


def _evaluate(candidates, seeds: list[int], workers: int) -> tuple[list[dict], list[list]]:
    """Each candidate's summary over one episode per seed, and its episodes, under one
    progress bar."""
    from .checkpoint import actor_from_checkpoint, load_checkpoint
    from .episode_progress import episode_progress
    from .evaluation import evaluate_actor, summarize

    scores, episodes = [], []
    with episode_progress(console, "held-out", len(candidates) * len(seeds)) as advance:
        for c in candidates:
            actor, cfg = actor_from_checkpoint(load_checkpoint(c.path))
            results = evaluate_actor(actor, cfg.agent, c.env, seeds, workers, on_episodes=advance)
            scores.append(summarize(results, cfg.train.solved_threshold))
            episodes.append(results)
    return scores, episodes


def _difference(candidates, episodes: list[list], pair: list[int]) -> dict:
    """Print the round's winner against the other finalist (the incumbent, or the runner-up),
    paired seed by seed, and return it for the JSON report; nothing when the round had one."""
    from .evaluation import paired_difference

    if len(pair) < 2:
        return {}
    first, second = pair
    diff = paired_difference(episodes[first], episodes[second])
    console.print(
        f"{printable(candidates[first].path)} minus {printable(candidates[second].path)}: "
        f"{diff['mean']:+.1f} (95% interval {diff['low']:+.1f} to {diff['high']:+.1f}, "
        f"paired over {diff['episodes']} seeds)"
    )
    return {
        "difference": {
            "of": str(candidates[first].path),
            "minus": str(candidates[second].path),
            **diff,
        }
    }


def _rows(candidates, scores) -> list[dict]:
    return [
        {
            "path": str(c.path),
            "step": c.step,
            "sha256": c.sha256,
            "periodic": c.periodic,
            "held_out": s,
        }
        for c, s in zip(candidates, scores, strict=True)
    ]


def _table(chosen, scores, best: int, seeds: list[int], title: str = "held-out") -> Table:
    from .display import falls_text

    table = Table(title=f"{title}: env seeds {seeds[0]}..{seeds[-1]}")
    for col in ("", "run", "step", "periodic", "held-out mean", "std", "median", "falls"):
        table.add_column(col, justify="right")
    for i, (c, s) in enumerate(zip(chosen, scores, strict=True)):
        periodic = "-" if c.periodic is None else f"{c.periodic:.1f} ({c.periodic_falls} falls)"
        table.add_row(
            "*" if i == best else "",
            printable(c.run),
            f"{c.step:,}",
            periodic,
            f"{s['mean']:.1f}",
            f"{s['std']:.1f}",
            f"{s['median']:.1f}",
            falls_text(s),
        )
    return table
