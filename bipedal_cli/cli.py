"""The ``bipedal`` command: parse, resolve config, call the library, print with rich.

Every :class:`UserError` (and every usage error) becomes one line on stderr and exit code 2.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from .config import canonical_env_id, resolve_config
from .errors import UserError
from .paths import check_output_path, printable
from .validation import check_count, check_seeds

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Train, resume and evaluate TQC + D2RL agents on BipedalWalker(-Hardcore)-v3.",
)
console = Console()


# typer >= 0.29 carries its own click: its usage errors derive from the public
# typer.TyperException, and typer.Abort is what it raises on an abort.
_CLICK_ERRORS = (typer.TyperException,)
_ABORTS = (typer.Abort,)

EnvOpt = Annotated[
    str | None, typer.Option("--env", help="walker | hardcore (or a full Gymnasium id).")
]
DeviceOpt = Annotated[str | None, typer.Option("--device", help="auto | cpu | cuda.")]


def _summary_line(result) -> str:
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


def _report_result(result) -> None:
    from .display import eval_table, verdict

    console.print(_summary_line(result))
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


@app.command()
def train(
    env: EnvOpt = None,
    config: Annotated[Path | None, typer.Option("--config", help="YAML config file.")] = None,
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", help="Override a config key, e.g. --set agent.lr=3e-4 (repeatable)."),
    ] = None,
    steps: Annotated[int | None, typer.Option("--steps", help="Total env steps.")] = None,
    seed: Annotated[int | None, typer.Option("--seed", help="Random seed.")] = None,
    run_dir: Annotated[
        Path | None,
        typer.Option("--run-dir", help="Run directory (default runs/<env>-seed<S>-<time>)."),
    ] = None,
    device: DeviceOpt = None,
    until_solved: Annotated[
        bool,
        typer.Option("--until-solved", help="Stop once the 100-episode evaluation passes 300."),
    ] = False,
) -> None:
    """Train a new agent (default: BipedalWalker-v3 with the paper's hyperparameters)."""
    from .display import TrainingDisplay
    from .train import train as train_run

    cfg = resolve_config(
        config,
        set_,
        **{
            "env": canonical_env_id(env) if env else None,
            "seed": seed,
            "device": device,
            "train.total_steps": steps,
        },
    )
    result = train_run(cfg, run_dir, TrainingDisplay(console, cfg.env), until_solved)
    _report_result(result)
    _exit_if_interrupted(result)


def _exit_if_interrupted(result) -> None:
    """128 + the signal's number after a run stopped by Ctrl-C (130) or SIGTERM (143)."""
    if result.signal is not None:
        from .signals import exit_status

        sys.exit(exit_status(result.signal))


@app.command()
def resume(
    run: Annotated[
        Path, typer.Argument(metavar="RUN_DIR_OR_CHECKPOINT", help="Run directory or its state.pt.")
    ],
    steps: Annotated[
        int | None, typer.Option("--steps", help="Train until this many env steps in all.")
    ] = None,
    until_solved: Annotated[bool, typer.Option("--until-solved")] = False,
    device: DeviceOpt = None,
    threads: Annotated[
        int | None,
        typer.Option("--threads", help="CPU threads from now on (0: every core; same results)."),
    ] = None,
) -> None:
    """Continue a run exactly where its last checkpoint left it."""
    from .devices import resolve_device
    from .display import TrainingDisplay
    from .resume import resume as resume_run

    if steps is not None and steps < 0:
        raise UserError(f"--steps {steps}: expected the new total, a non-negative integer")
    if device:
        resolve_device(device)
    result = resume_run(
        run, steps, TrainingDisplay(console, "resume"), until_solved, device, threads
    )
    if hasattr(result, "stages"):
        _report_curriculum(result)
    else:
        _report_result(result)
    _exit_if_interrupted(result)


@app.command("eval")
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
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    from .display import eval_table, verdict
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
    with Progress(
        "[bold]evaluating", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), console=console
    ) as progress:
        task = progress.add_task("eval", total=episodes)
        results = evaluate_actor(
            actor,
            cfg.agent,
            env_id,
            seeds,
            workers=workers,
            on_episodes=lambda n: progress.advance(task, n),
        )
    elapsed = time.perf_counter() - started
    summary = summarize(results, cfg.train.solved_threshold)
    summary.update({"env": env_id, "seeds": [seeds[0], seeds[-1]], "checkpoint": str(ckpt)})
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


@app.command()
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


@app.command()
def curriculum(
    config: Annotated[
        Path | None,
        typer.Option("--config", help="YAML config (default configs/curriculum.yaml values)."),
    ] = None,
    set_: Annotated[list[str] | None, typer.Option("--set", help="Override a config key.")] = None,
    walker_steps: Annotated[
        int | None, typer.Option("--walker-steps", help="Stage 1 budget (BipedalWalker-v3).")
    ] = None,
    hardcore_steps: Annotated[
        int | None, typer.Option("--hardcore-steps", help="Stage 2 budget (Hardcore).")
    ] = None,
    replay: Annotated[
        str | None, typer.Option("--replay", help="keep | clear the buffer at the switch.")
    ] = None,
    seed: Annotated[int | None, typer.Option("--seed")] = None,
    run_dir: Annotated[Path | None, typer.Option("--run-dir")] = None,
    device: DeviceOpt = None,
) -> None:
    """Walker until solved (or its budget), then Hardcore with the same agent."""
    from .curriculum import start_curriculum
    from .display import TrainingDisplay

    cfg = resolve_config(
        config,
        set_,
        **{
            "seed": seed,
            "device": device,
            "curriculum.walker_steps": walker_steps,
            "curriculum.hardcore_steps": hardcore_steps,
            "curriculum.replay": replay,
        },
    )
    result = start_curriculum(cfg, run_dir, TrainingDisplay(console, "curriculum"))
    _report_curriculum(result)
    _exit_if_interrupted(result)


def _report_curriculum(result) -> None:
    from .display import curriculum_table

    console.print(curriculum_table(result, printable(result.run_dir)))
    console.print(f"resume: bipedal resume {printable(result.run_dir)}")


@app.command()
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
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing file.")] = False,
) -> None:
    """Learning curves: 10-episode moving mean with a +-1 std band, evaluations, the 300 line."""
    from .plotting import PLOT_SUFFIXES, plot_runs

    check_output_path(out, "--out", PLOT_SUFFIXES, force)
    plot_runs(runs, out, label, aggregate, title, metric=metric)
    console.print(f"wrote {out}")


@app.command()
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


@app.command()
def info(ckpt: Annotated[Path, typer.Argument(metavar="CKPT")]) -> None:
    """What a checkpoint holds: env, steps, episodes, config, evaluations, format version."""
    from .checkpoint import load_checkpoint
    from .display import checkpoint_table

    console.print(checkpoint_table(load_checkpoint(ckpt), printable(ckpt)))


def _add_sweep() -> None:
    from .cli_sweep import sweep_app

    app.add_typer(sweep_app, name="sweep")


_add_sweep()


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
