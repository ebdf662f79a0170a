"""``bipedal train``, ``resume`` and ``curriculum``: the commands that train (registered on the
app by :mod:`bipedal_cli.cli`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .cli_common import DeviceOpt, EnvOpt, console
from .cli_report import exit_if_interrupted, report_curriculum, report_result
from .config import resolve_config
from .env_ids import canonical_env_id
from .errors import UserError


def train(
    env: EnvOpt = None,
    config: Annotated[Path | None, typer.Option("--config", help="YAML config file.")] = None,
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", help="Override a config key, e.g. --set agent.lr=3e-4 (repeatable)."),
    ] = None,
    steps: Annotated[
        int | None, typer.Option("--steps", help="Total policy steps (env steps / action repeat).")
    ] = None,
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
    report_result(result)
    exit_if_interrupted(result)


def resume(
    run: Annotated[
        Path,
        typer.Argument(
            metavar="RUN_DIR_OR_CHECKPOINT",
            help="Run directory, its state.pt, or (with --into) its restart.pt.",
        ),
    ],
    steps: Annotated[
        int | None, typer.Option("--steps", help="Train until this many policy steps in all.")
    ] = None,
    until_solved: Annotated[bool, typer.Option("--until-solved")] = False,
    device: DeviceOpt = None,
    threads: Annotated[
        int | None,
        typer.Option("--threads", help="CPU threads from now on (0: every core; same results)."),
    ] = None,
    keep_policies: Annotated[
        bool | None,
        typer.Option(
            "--keep-policies/--no-keep-policies",
            help="Keep the policy of every periodic evaluation from now on (train.keep_policies).",
        ),
    ] = None,
    into: Annotated[
        Path | None,
        typer.Option(
            "--into",
            help="Branch: continue in this new run directory under --config; or continue a "
            "restart.pt there (its replay buffer refilled first).",
        ),
    ] = None,
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="With --into: the branch's config (the run's, plus features that start at or "
            "after the run's step, such as the learning-rate decay, the risk-averse actor or the "
            "actor's smoothness term, and the buffer's size before it wraps; README lists them; "
            "default: the run's own).",
        ),
    ] = None,
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", help="With --into: override a key of the branch's config."),
    ] = None,
    refill_policy: Annotated[
        list[Path] | None,
        typer.Option(
            "--refill-policy",
            help="With --into from a restart.pt: a policy file that plays the refill, one "
            "episode each in turn with the others given (repeat it; train.refill_policies).",
        ),
    ] = None,
) -> None:
    """Continue a run exactly where its last checkpoint left it (or branch it with --into)."""
    from .devices import resolve_device
    from .display import TrainingDisplay
    from .resume import branch
    from .resume import resume as resume_run

    if steps is not None and steps < 0:
        raise UserError(f"--steps {steps}: expected the new total, a non-negative integer")
    if into is None and (config is not None or set_ or refill_policy):
        raise UserError(
            "--config, --set and --refill-policy: only with --into (a branch); a resume keeps "
            "its config"
        )
    if device:
        resolve_device(device)
    display = TrainingDisplay(console, "resume")
    if into is not None:
        explicit = {
            "device": device,
            "train.threads": threads,
            "train.total_steps": steps,
            "train.keep_policies": keep_policies,
            # resolved, so that a resume inside the refill finds them from any directory
            "train.refill_policies": [str(p.resolve()) for p in refill_policy or []] or None,
        }
        if config is not None:
            cfg = resolve_config(config, set_, **explicit)
            result = branch(run, into, cfg, display, until_solved, str(config))
        else:
            result = branch(
                run, into, None, display, until_solved, overrides=set_, explicit=explicit
            )
    else:
        result = resume_run(run, steps, display, until_solved, device, threads, keep_policies)
    if hasattr(result, "stages"):
        report_curriculum(result)
    else:
        report_result(result)
    exit_if_interrupted(result)


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
    report_curriculum(result)
    exit_if_interrupted(result)
