"""Learning curves like the paper's figures, from runs' ``metrics.csv`` (matplotlib, off-screen)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .errors import UserError
from .metrics import FRESH_KINDS, METRICS_FILE, read_metrics
from .paths import atomic_path, printable

PLOT_SUFFIXES = (".png", ".svg")
PLOT_METRICS = ("return", "alpha", "critic_loss", "actor_loss", "entropy", "q_mean", "length")


@dataclass
class RunCurve:
    label: str
    steps: np.ndarray  # env steps at the end of each training episode
    values: np.ndarray  # the plotted metric per training episode (return by default)
    eval_steps: np.ndarray
    eval_means: np.ndarray
    stages: list[tuple[str, int]]  # (env id, first step) per curriculum stage


def load_run(run_dir: str | Path, label: str | None = None, metric: str = "return") -> RunCurve:
    """A run's training episodes (metric per episode) and evaluations from its metrics.csv."""
    if metric not in PLOT_METRICS:
        raise UserError(f"--metric {metric}: expected one of {', '.join(PLOT_METRICS)}")
    run_dir = Path(run_dir)
    path = run_dir / METRICS_FILE if run_dir.is_dir() else run_dir
    if not path.is_file():
        raise UserError(
            f"RUN_DIR {run_dir}: no {METRICS_FILE}; expected a directory written by `bipedal train`"
        )
    try:
        rows = read_metrics(path)
        # losses and alpha are empty during warm-up: those episodes have nothing to plot
        episodes = [r for r in rows if r["kind"] in FRESH_KINDS and r[metric] != ""]
        evals = [r for r in rows if r["kind"] in ("eval", "full_eval")]
        steps = np.array([_env_steps(r) for r in episodes])
        values = np.array([float(r[metric]) for r in episodes])
        eval_steps = np.array([_env_steps(r) for r in evals])
        eval_means = np.array([float(r["return"]) for r in evals])
    except (KeyError, ValueError):
        raise UserError(
            f"RUN_DIR {run_dir}: {METRICS_FILE} is not a bipedal metrics file"
        ) from None
    if len(episodes) == 0:
        raise UserError(f"RUN_DIR {run_dir}: {METRICS_FILE} has no finished episodes yet")
    stages: list[tuple[str, int]] = []
    for r in episodes:
        if not stages or stages[-1][0] != r["stage"]:
            stages.append((r["stage"], int(_env_steps(r))))
    name = label or printable(run_dir.name if run_dir.is_dir() else run_dir.parent.name)
    if metric != "return":
        eval_steps, eval_means = np.zeros(0), np.zeros(0)
    return RunCurve(name, steps, values, eval_steps, eval_means, stages)


def _env_steps(row: dict) -> float:
    """Env steps at the row; files written before the column existed count policy steps,
    which were env steps then (no action repeat)."""
    return float(row.get("env_steps") or row["step"])


def moving_stats(values: np.ndarray, window: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation over the last ``window`` values (fewer at the start)."""
    means = np.empty(len(values))
    stds = np.empty(len(values))
    for i in range(len(values)):
        chunk = values[max(0, i - window + 1) : i + 1]
        means[i], stds[i] = chunk.mean(), chunk.std()
    return means, stds


def aggregate(
    curves: list[RunCurve], points: int = 200, window: int = 10
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Across runs: the moving mean interpolated on a common step grid -> mean, std."""
    end = min(c.steps[-1] for c in curves)
    grid = np.linspace(0, end, points)
    stacked = np.stack(
        [np.interp(grid, c.steps, moving_stats(c.values, window)[0]) for c in curves]
    )
    return grid, stacked.mean(0), stacked.std(0)


def in_window(steps: np.ndarray, since: float, until: float) -> np.ndarray:
    """Which points a plot draws: env steps in [since, until]."""
    return (steps >= since) & (steps <= until)


def plot_runs(
    run_dirs: list[Path],
    out: Path,
    labels: list[str] | None = None,
    aggregate_by_label: bool = False,
    title: str | None = None,
    threshold: float = 300.0,
    metric: str = "return",
    window: int = 10,
    since: float = 0.0,
    until: float = math.inf,
) -> Path:
    """Episode return against env steps: moving mean over ``window`` episodes with +-1 std
    band, evaluations as points, the solved line; several runs overlaid, or averaged per label.
    Only env steps from ``since`` to ``until`` are drawn (the moving statistics still see earlier
    ones), so that runs of unequal length can be compared at equal steps."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if labels and len(labels) != len(run_dirs):
        raise UserError(f"--label: given {len(labels)} labels for {len(run_dirs)} runs")
    curves = [load_run(d, labels[i] if labels else None, metric) for i, d in enumerate(run_dirs)]
    # alpha spans decades: its statistics are taken in log space (a geometric mean and a band of
    # x/÷ one geometric std), so that the band stays positive on the log axis
    log_space = metric == "alpha"
    if log_space:
        curves = [replace(c, values=np.log(np.maximum(c.values, 1e-30))) for c in curves]
    back = np.exp if log_space else (lambda v: v)
    fig, ax = plt.subplots(figsize=(8, 4.8), dpi=110)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    groups: dict[str, list[RunCurve]] = {}
    for c in curves:
        groups.setdefault(c.label if aggregate_by_label else f"{c.label}#{len(groups)}", []).append(
            c
        )
    for i, (key, members) in enumerate(groups.items()):
        color = colors[i % len(colors)]
        label = key.split("#")[0]
        if len(members) > 1:
            grid, mean, std = aggregate(members, window=window)
            name = f"{label} (mean of {len(members)} runs)"
        else:
            grid, (mean, std), name = (
                members[0].steps,
                moving_stats(members[0].values, window),
                label,
            )
        shown = in_window(grid, since, until)
        grid, mean, std = grid[shown], mean[shown], std[shown]
        ax.plot(grid, back(mean), color=color, label=name)
        ax.fill_between(grid, back(mean - std), back(mean + std), color=color, alpha=0.2)
        for c in members:
            evals = in_window(c.eval_steps, since, until)
            if evals.any():
                ax.scatter(
                    c.eval_steps[evals],
                    c.eval_means[evals],
                    color=color,
                    s=14,
                    marker="o",
                    edgecolors="black",
                    linewidths=0.4,
                    zorder=3,
                )
            for env_id, start in c.stages[1:]:
                if not since <= start <= until:
                    continue  # a switch outside the window would stretch the axis
                ax.axvline(start, color=color, linestyle=":", linewidth=1)
                ax.text(
                    start,
                    ax.get_ylim()[0],
                    f" {env_id}",
                    color=color,
                    fontsize=7,
                    rotation=90,
                    va="bottom",
                )
    if metric == "return":
        ax.axhline(
            threshold, color="black", linestyle="--", linewidth=1, label=f"solved ({threshold:g})"
        )
    if metric == "alpha":
        ax.set_yscale("log")
    ax.set_xlabel("env steps")
    ax.set_ylabel("episode return" if metric == "return" else f"{metric} (at episode end)")
    default_title = (
        f"moving geometric mean over {window} episodes (band: x/÷ 1 geometric std)"
        if log_space
        else f"moving mean over {window} episodes (band: +-1 std)"
    )
    if metric == "return":
        default_title += "; points: evaluations"
    ax.set_title(title or default_title)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right" if metric == "return" else "best", fontsize=8)
    fig.tight_layout()
    try:
        with atomic_path(out) as tmp:
            fig.savefig(tmp, format=out.suffix.lstrip(".").lower())
    finally:
        plt.close(fig)
    return out
