"""``bipedal sweep`` and ``bipedal sweep show``: the thin CLI over :mod:`bipedal_cli.sweep`."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich import box
from rich.table import Table

from .cli_common import console
from .config import resolve_config
from .env_ids import canonical_env_id
from .errors import UserError
from .paths import check_output_path, printable
from .validation import check_count, check_seeds

sweep_app = typer.Typer(
    help="Optuna TPE search over the config (the paper's sweep); `sweep show` reports a study."
)

StorageOpt = Annotated[
    str | None,
    typer.Option(
        "--storage",
        help="Journal file (default sweeps/<study>/journal.log), sqlite:///FILE or "
        "postgresql+psycopg://USER@HOST/DB shared by every machine.",
    ),
]
DirOpt = Annotated[
    Path, typer.Option("--sweeps-dir", help="Folder of the studies' folders (trial runs).")
]


def _study_table(study) -> Table:
    from .sweep_report import best_trial

    counts = {s: 0 for s in ("COMPLETE", "RUNNING", "PRUNED", "FAIL", "WAITING")}
    for t in study.get_trials(deepcopy=False):
        counts[t.state.name] = counts.get(t.state.name, 0) + 1
    table = Table(title=f"study {study.study_name}", show_header=False)
    table.add_column(style="cyan")
    table.add_column()
    table.add_row("trials", ", ".join(f"{n} {s.lower()}" for s, n in counts.items() if n))
    best = best_trial(study)
    if best is not None:
        solved = "solved" if best.user_attrs.get("solved") else "not solved"
        table.add_row("best", f"trial {best.number}: score {best.value:,.0f} ({solved})")
        table.add_row("its parameters", _params(best.params))
    return table


def _params(params: dict) -> str:
    from .sweep_report import format_value

    return " ".join(f"{k.rsplit('.', 1)[-1]}={format_value(v)}" for k, v in params.items())


@sweep_app.callback(invoke_without_command=True)
def sweep(
    ctx: typer.Context,
    config: Annotated[Path | None, typer.Option("--config", help="Base YAML config.")] = None,
    env: Annotated[str | None, typer.Option("--env", help="walker | hardcore.")] = None,
    set_: Annotated[list[str] | None, typer.Option("--set", help="Override a base key.")] = None,
    study: Annotated[str, typer.Option("--study", help="Study name.")] = "walker-sweep",
    trials: Annotated[int, typer.Option("--trials", help="Trials in the whole study.")] = 16,
    steps_per_trial: Annotated[
        int, typer.Option("--steps-per-trial", help="Policy-step budget of each trial.")
    ] = 150_000,
    storage: StorageOpt = None,
    space: Annotated[
        Path | None, typer.Option("--space", help="YAML search space (default: Table 1's).")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", help="TPE sampler seed.")] = 0,
    heartbeat: Annotated[
        int, typer.Option("--heartbeat", help="RDB storages: seconds between heartbeats.")
    ] = 60,
    pruner_startup: Annotated[
        int, typer.Option("--pruner-startup", help="Trials before the median pruner acts.")
    ] = 3,
    sampler_startup: Annotated[
        int, typer.Option("--sampler-startup", help="Random trials before TPE takes over.")
    ] = 5,
    baseline: Annotated[
        bool,
        typer.Option(
            "--baseline/--no-baseline", help="First trial: the base config itself (if in space)."
        ),
    ] = True,
    pruner_warmup: Annotated[
        int | None, typer.Option("--pruner-warmup", help="Steps before a trial can be pruned.")
    ] = None,
    sweeps_dir: DirOpt = Path("sweeps"),
) -> None:
    """Run trials of an Optuna study until its --trials budget is spent (any number of workers)."""
    if ctx.invoked_subcommand is not None:
        return
    from .display import TrainingDisplay
    from .sweep import SweepSettings, run_worker
    from .sweep_space import load_space

    check_count("--trials", trials, 100_000)
    check_count("--steps-per-trial", steps_per_trial, 10**9)
    check_count("--sampler-startup", sampler_startup, 100_000, low=0)
    check_count("--pruner-startup", pruner_startup, 100_000, low=0)
    if pruner_warmup is not None:
        check_count("--pruner-warmup", pruner_warmup, 10**9, low=0)
    check_seeds("--seed", seed)
    if not 1 <= heartbeat <= 3600:
        raise UserError(f"--heartbeat {heartbeat}: expected seconds in [1, 3600]")
    if not study or "/" in study or study.startswith("."):
        raise UserError(f"--study {study!r}: expected a name without '/'")
    base = resolve_config(config, set_, **{"env": canonical_env_id(env) if env else None})
    settings = SweepSettings(
        study=study,
        base=base,
        space=load_space(space),
        trials=trials,
        steps_per_trial=steps_per_trial,
        storage=storage,
        seed=seed,
        heartbeat=heartbeat,
        pruner_startup=pruner_startup,
        pruner_warmup=pruner_warmup,
        sampler_startup=sampler_startup,
        baseline=baseline,
        root=sweeps_dir,
    )
    result = run_worker(
        settings,
        lambda n: TrainingDisplay(console, f"trial {n}"),
        lambda s: console.print(_study_table(s)),
    )
    ran = ", ".join(map(str, result.ran)) or "none"
    console.print(f"this worker ran trials: {ran}; report: bipedal sweep show {study}")
    if result.signal is not None:
        from .signals import exit_status

        sys.exit(exit_status(result.signal))


@sweep_app.command("show")
def show(
    study: Annotated[str, typer.Argument(metavar="STUDY")],
    storage: StorageOpt = None,
    sweeps_dir: DirOpt = Path("sweeps"),
    best_config: Annotated[
        Path | None, typer.Option("--best-config", help="Write the best trial's config (YAML).")
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite --best-config.")] = False,
) -> None:
    """A study's trials, best parameters, history and importance plots (PNG in its folder)."""
    from .sweep_report import (
        format_value,
        load_study,
        plot_history,
        plot_importances,
        short_name,
        trial_rows,
    )

    if best_config is not None:
        check_output_path(best_config, "--best-config", (".yaml", ".yml"), force)
    loaded = load_study(study, storage, sweeps_dir / study)
    rows = trial_rows(loaded)
    hosts = {str(r["worker"]).rpartition(":")[0] for r in rows if r["worker"]}
    table = Table(
        title=f"study {study}: trials (score: env steps to solve; best eval: of the periodic "
        "evaluations; test: the 100-episode test)",
        box=box.SIMPLE_HEAD,
    )
    columns = ("trial", "state", "score", "solved", "env steps", "best eval", "test", "worker pid")
    for col in columns:
        table.add_column(col, justify="right")
    keys = list(dict.fromkeys(k for r in rows for k in r["params"]))
    params = Table(
        title="their parameters (base: the base config's own values)", box=box.SIMPLE_HEAD
    )
    for col in ("trial", *map(short_name, keys)):
        params.add_column(col, justify="right")
    for r in rows:
        best = r["best_eval"]
        number = (
            str(r["number"])
            + (" base" if r["baseline"] else "")
            + (f" (retry of {r['retry_of']})" if r["retry_of"] is not None else "")
        )
        table.add_row(
            number,
            r["state"].lower(),
            "-" if r["value"] is None or r["state"] != "COMPLETE" else f"{r['value']:,.0f}",
            {True: "yes", False: "no"}.get(r["solved"], "-"),
            "-" if r["env_steps"] is None else f"{r['env_steps']:,}",
            "-" if best is None else f"{best:.1f}",
            "-" if r["test"] is None else f"{r['test']:.1f}",
            str(r["worker"] or "-").rpartition(":")[2] if len(hosts) < 2 else str(r["worker"]),
        )
        params.add_row(number, *(format_value(r["params"].get(k, "-")) for k in keys))
    console.print(table)
    console.print(params)
    console.print(_study_table(loaded))
    folder = sweeps_dir / study
    folder.mkdir(parents=True, exist_ok=True)
    console.print(f"wrote {printable(plot_history(loaded, folder / 'history.png'))}")
    importances = plot_importances(loaded, folder / "importances.png")
    if importances is None:
        console.print("parameter importances: not enough completed trials yet")
    else:
        console.print(f"wrote {printable(importances)}")
    if best_config is not None:
        from .sweep_report import write_best_config

        write_best_config(loaded, best_config)
        console.print(f"wrote {best_config}: bipedal train --config {best_config}")
