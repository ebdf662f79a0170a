"""The ``bipedal`` command: parse, resolve config, call the library, print with rich.

Every :class:`UserError` (and every usage error) becomes one line on stderr and exit code 2.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Annotated

import click
import typer
from rich.console import Console

from .config import canonical_env_id, resolve_config
from .errors import UserError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Train, resume and evaluate TQC + D2RL agents on BipedalWalker(-Hardcore)-v3.",
)
console = Console()


def _exception_types(name: str) -> tuple[type[BaseException], ...]:
    """``name`` from click and from the click copy newer typer releases vendor."""
    found = [getattr(click.exceptions, name)]
    try:
        from typer._click import exceptions as vendored
    except ImportError:
        vendored = None
    if vendored is not None and hasattr(vendored, name):
        found.append(getattr(vendored, name))
    return tuple(found)


_CLICK_ERRORS = _exception_types("ClickException")
_ABORTS = _exception_types("Abort") + (typer.Abort,)

EnvOpt = Annotated[
    str | None, typer.Option("--env", help="walker | hardcore (or a full Gymnasium id).")
]
DeviceOpt = Annotated[str | None, typer.Option("--device", help="auto | cpu | cuda.")]


def _summary_line(result) -> str:
    minutes = result.wall_time / 60
    return (
        f"{result.stopped}: {result.steps:,} env steps, {result.episodes:,} episodes, "
        f"{minutes:.1f} min; run directory {result.run_dir}"
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
    console.print(
        f"policy: {result.run_dir / 'policy.pt'}   resume: bipedal resume {result.run_dir}"
    )


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
    if steps is not None and steps < 0:
        raise UserError("--steps: expected a non-negative integer")
    result = train_run(cfg, run_dir, TrainingDisplay(console, cfg.env), until_solved)
    _report_result(result)


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
) -> None:
    """Continue a run exactly where its last checkpoint left it."""
    from .display import TrainingDisplay
    from .train import resolve_device
    from .train import resume as resume_run

    if device:
        resolve_device(device)
    result = resume_run(run, steps, TrainingDisplay(console, "resume"), until_solved, device)
    _report_result(result)


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

    from .checkpoint import actor_from_checkpoint, check_dims, load_checkpoint
    from .display import eval_table, verdict
    from .envs import env_dims, make_env
    from .evaluation import evaluate_actor, summarize

    if episodes < 1:
        raise UserError("--episodes: expected a positive integer")
    if workers < 0:
        raise UserError("--workers: expected 0 (every core) or a positive integer")
    if json_out is not None:
        _check_writable(json_out, "--json")
    data = load_checkpoint(ckpt)
    actor, cfg = actor_from_checkpoint(data)
    env_id = canonical_env_id(env) if env else data["env"]
    probe = make_env(env_id)
    check_dims(data, *env_dims(probe), env_id)
    probe.close()
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


def _check_writable(path: Path, option: str) -> None:
    parent = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise UserError(f"{option} {path}: is a directory; expected a file path")
    if not parent.is_dir():
        raise UserError(f"{option} {path}: directory {parent} does not exist")


def main(argv: list[str] | None = None) -> None:
    """Console entry point: one-line errors with exit code 2 instead of tracebacks."""
    try:
        rv = app(args=argv, standalone_mode=False, prog_name="bipedal")
    except UserError as exc:
        _fail(str(exc))
    except _ABORTS:
        print("aborted", file=sys.stderr)
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
