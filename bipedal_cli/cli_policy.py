"""``bipedal eval``, ``record``, ``plot``, ``export`` and ``info``: the commands that read a
policy or a run without training it (registered on the app by :mod:`bipedal_cli.cli`)."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Annotated

import typer

from .cli_common import EnvOpt, console
from .env_ids import canonical_env_id
from .errors import UserError
from .paths import check_output_path, printable
from .validation import check_count, check_seeds


def eval_(
    ckpt: Annotated[
        Path, typer.Argument(metavar="CKPT", help="policy.pt, state.pt or a run directory.")
    ],
    episodes: Annotated[int, typer.Option("--episodes", help="Episodes to run.")] = 100,
    env: EnvOpt = None,
    seed: Annotated[int, typer.Option("--seed", help="Episode i uses env seed S + i.")] = 0,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write per-episode returns and the summary.")
    ] = None,
    workers: Annotated[int, typer.Option("--workers", help="Processes (0: every core).")] = 0,
) -> None:
    """Evaluate the deterministic policy tanh(mean) on fixed env seeds (solved: mean > 300)."""
    import torch

    from .devices import machine_summary
    from .display import eval_table, verdict
    from .episode_progress import episode_progress
    from .evaluation import evaluate_actor, summarize

    check_count("--episodes", episodes)
    check_seeds("--seed", seed, episodes)
    if workers < 0:
        raise UserError("--workers: expected 0 (every core) or a positive integer")
    if json_out is not None:
        check_output_path(json_out, "--json")
    data, actor, cfg, env_id = _load_policy(ckpt, env)
    seeds = list(range(seed, seed + episodes))
    started = time.perf_counter()
    with episode_progress(console, "evaluating", episodes) as advance:
        results = evaluate_actor(actor, cfg.agent, env_id, seeds, workers, on_episodes=advance)
    elapsed = time.perf_counter() - started
    summary = summarize(results, cfg.train.solved_threshold)
    summary.update({"env": env_id, "seeds": [seeds[0], seeds[-1]], "checkpoint": str(ckpt)})
    # the policy runs on the CPU, whose rounding can flip a knife-edge episode (session 33)
    summary["machine"] = machine_summary(torch.device("cpu"))
    console.print(eval_table(summary, f"{env_id}: {ckpt} (env seeds {seeds[0]}..{seeds[-1]})"))
    console.print(verdict(summary) + f"   [{elapsed:.1f} s]")
    if json_out is not None:
        from .checkpoint import atomic_write_text

        payload = {
            "summary": summary,
            "episodes": [r.__dict__ for r in results],
            "meta": data.get("meta", {}),
        }
        atomic_write_text(json_out, json.dumps(payload, indent=2))
        console.print(f"wrote {json_out}")


def _load_policy(ckpt: Path, env: str | None):
    """(checkpoint data, actor, config, env id) with the dims checked against the env."""
    from .checkpoint import actor_from_checkpoint, check_dims, load_checkpoint
    from .envs import policy_dims

    data = load_checkpoint(ckpt)
    actor, cfg = actor_from_checkpoint(data)
    env_id = canonical_env_id(env) if env else data["env"]
    check_dims(data, *policy_dims(env_id, cfg.agent), env_id)
    return data, actor, cfg, env_id


def record(
    ckpt: Annotated[
        Path, typer.Argument(metavar="CKPT", help="policy.pt, state.pt or a run directory.")
    ],
    out: Annotated[Path, typer.Option("--out", help="Output .mp4 (H.264) or .gif.")] = Path(
        "bipedal.mp4"
    ),
    episodes: Annotated[int, typer.Option("--episodes", help="Episodes to record.")] = 1,
    seed: Annotated[int, typer.Option("--seed", help="Episode i uses env seed S + i.")] = 0,
    env: EnvOpt = None,
    fps: Annotated[
        float | None, typer.Option("--fps", help="Frame rate (default: the env's, 50).")
    ] = None,
    frame_step: Annotated[
        int | None, typer.Option("--frame-step", help="Keep every n-th frame (GIF default 2).")
    ] = None,
    scale: Annotated[
        float | None, typer.Option("--scale", help="Resize frames (GIF default 0.5).")
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing file.")] = False,
) -> None:
    """Record the deterministic policy off-screen (no display needed) to MP4 or GIF."""
    from rich.progress import BarColumn, Progress, TimeElapsedColumn

    from .evaluation import actor_policy
    from .video import VIDEO_SUFFIXES
    from .video import record as record_video

    check_output_path(out, "--out", VIDEO_SUFFIXES, force)
    check_count("--episodes", episodes, 1000)
    check_seeds("--seed", seed, episodes)
    if fps is not None and not (math.isfinite(fps) and 0 < fps <= 1000):
        raise UserError(f"--fps {fps}: expected a frame rate in (0, 1000]")
    if frame_step is not None and not 1 <= frame_step <= 1000:
        raise UserError(f"--frame-step {frame_step}: expected an integer in [1, 1000]")
    if scale is not None and not (math.isfinite(scale) and 0 < scale <= 4):
        raise UserError(f"--scale {scale}: expected a number in (0, 4]")
    gif = out.suffix.lower() == ".gif"
    frame_step = frame_step or (2 if gif else 1)
    scale = scale or (0.5 if gif else 1.0)
    import gymnasium

    data, actor, cfg, env_id = _load_policy(ckpt, env)
    max_steps = gymnasium.spec(env_id).max_episode_steps or 2000
    seeds = list(range(seed, seed + episodes))
    with Progress(
        "[bold]rendering",
        BarColumn(),
        "{task.completed} frames",
        TimeElapsedColumn(),
        console=console,
    ) as progress:
        task = progress.add_task("render", total=episodes * (max_steps // frame_step + 1))
        recorded, frames, rate = record_video(
            actor_policy(actor),
            env_id,
            out,
            seeds,
            fps,
            frame_step,
            scale,
            on_frame=lambda: progress.advance(task),
            agent_cfg=cfg.agent,
        )
        progress.update(task, total=progress.tasks[0].completed)
    for ep in recorded:
        fell = "  (fell)" if ep.fell else ""
        console.print(f"episode seed {ep.seed}: return {ep.ret:.1f}, {ep.length} steps{fell}")
    console.print(f"wrote {out}: {frames} frames, {frames / rate:.1f} s at {rate:g} fps")


def plot(
    runs: Annotated[list[Path], typer.Argument(metavar="RUN_DIR...", help="Run directories.")],
    out: Annotated[Path, typer.Option("--out", help="Output .png or .svg.")] = Path("curve.png"),
    label: Annotated[
        list[str] | None, typer.Option("--label", help="Legend label per run (repeat).")
    ] = None,
    aggregate: Annotated[
        bool, typer.Option("--aggregate", help="Average runs that share a label (seeds).")
    ] = False,
    title: Annotated[str | None, typer.Option("--title")] = None,
    metric: Annotated[
        str,
        typer.Option(
            "--metric", help="return | alpha | critic_loss | actor_loss | entropy | q_mean | length"
        ),
    ] = "return",
    window: Annotated[int, typer.Option("--window", help="Episodes per moving mean.")] = 10,
    since: Annotated[
        int, typer.Option("--since", help="Draw from this many env steps on (zoom in).")
    ] = 0,
    until: Annotated[
        int | None,
        typer.Option("--until", help="Draw up to this many env steps (runs of unequal length)."),
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing file.")] = False,
) -> None:
    """Learning curves: moving mean with a +-1 std band, evaluations, the 300 line."""
    from .plotting import PLOT_SUFFIXES, plot_runs

    check_count("--window", window)
    check_count("--since", since, limit=10**12, low=0)
    if until is not None:
        check_count("--until", until, limit=10**12, low=since + 1)
    check_output_path(out, "--out", PLOT_SUFFIXES, force)
    last = math.inf if until is None else until
    plot_runs(
        runs, out, label, aggregate, title, metric=metric, window=window, since=since, until=last
    )
    console.print(f"wrote {out}")


def export(
    ckpt: Annotated[Path, typer.Argument(metavar="CKPT")],
    out: Annotated[Path, typer.Option("--out", help="Output .pt2 (torch.export).")] = Path(
        "policy.pt2"
    ),
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing file.")] = False,
) -> None:
    """Export the deterministic policy for use with torch alone: torch.export.load(out).module()."""
    from .export import EXPORT_SUFFIXES, export_policy, input_shape

    check_output_path(out, "--out", EXPORT_SUFFIXES, force)
    data, actor, cfg, _ = _load_policy(ckpt, None)
    a = cfg.agent
    export_policy(actor, out, a.history, a.action_repeat)
    shape = ", ".join(str(d) for d in ("B", *input_shape(data["obs_dim"], a.history)))
    held = f"; hold each action for {a.action_repeat} env steps" if a.action_repeat > 1 else ""
    console.print(
        f"wrote {out}: torch.export program, obs ({shape}) -> actions (B, {data['act_dim']})"
        f"{held}; load with torch.export.load({str(out)!r}).module()"
    )


def info(ckpt: Annotated[Path, typer.Argument(metavar="CKPT")]) -> None:
    """What a checkpoint holds: env, steps, episodes, config, evaluations, format version."""
    from .checkpoint import load_checkpoint
    from .info_table import checkpoint_table

    console.print(checkpoint_table(load_checkpoint(ckpt), printable(ckpt)))
