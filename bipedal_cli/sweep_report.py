"""``bipedal sweep show``: a study's trials, its best parameters, its plots, its best config."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import yaml

from .checkpoint import atomic_write_text
from .errors import UserError
from .paths import atomic_path
from .sweep import DEFINITION
from .sweep_storage import open_storage, redact

SHORT_NAMES = {  # a searched key's name in a table's header
    "agent.batch_size": "batch",
    "train.warmup_steps": "warmup",
    "agent.n_critics": "critics",
    "agent.n_quantiles": "atoms",
}


def short_name(key: str) -> str:
    """agent.n_quantiles -> atoms, agent.lr -> lr: a searched key in a table's header."""
    return SHORT_NAMES.get(key, key.rsplit(".", 1)[-1])


def format_value(value: Any) -> str:
    """A parameter's value in a table: floats to 3 significant digits."""
    return f"{value:.3g}" if isinstance(value, float) else str(value)


def load_study(study: str, storage: str | None, study_dir: Path):
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    if storage is None and not (study_dir / "journal.log").exists():
        raise UserError(f"STUDY {study}: no study in {study_dir}; start one with bipedal sweep")
    backend = open_storage(storage, study_dir, heartbeat=60)
    try:
        loaded = optuna.load_study(study_name=study, storage=backend)
    except KeyError:
        where = redact(storage) if storage else str(study_dir)
        raise UserError(f"STUDY {study}: no such study in {where}") from None
    if DEFINITION not in loaded.user_attrs:
        raise UserError(f"STUDY {study}: not a study made by bipedal sweep")
    return loaded


def trial_rows(study) -> list[dict[str, Any]]:
    """One dict per trial: number, state, value, solved, env steps, best evaluation, params."""
    rows = []
    for t in study.get_trials(deepcopy=False):
        rows.append(
            {
                "number": t.number,
                "state": t.state.name,
                "value": t.value,
                "solved": t.user_attrs.get("solved"),
                "env_steps": t.user_attrs.get("env_steps"),
                "best_eval": t.user_attrs.get("best_eval"),
                "test": t.user_attrs.get("test"),  # the 100-episode test's mean, if one ran
                "params": dict(t.params),
                "retry_of": t.user_attrs.get("retry_of", t.system_attrs.get("failed_trial")),
                "worker": t.user_attrs.get("worker"),
                "baseline": bool(t.user_attrs.get("baseline")),
            }
        )
    return rows


def best_trial(study):
    from optuna.trial import TrialState

    done = study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
    return min(done, key=lambda t: t.value) if done else None


def write_best_config(study, out: Path) -> dict:
    """The best trial's whole config as YAML that ``bipedal train --config`` takes as is."""
    best = best_trial(study)
    if best is None:
        raise UserError(f"--best-config {out}: the study has no completed trial yet")
    cfg = dict(best.user_attrs["config"])
    head = (
        f"# best trial {best.number} of study {study.study_name} (bipedal sweep): "
        f"score {best.value:g}\n"
    )
    atomic_write_text(out, head + yaml.safe_dump(cfg, sort_keys=False))
    return cfg


def plot_history(study, out: Path) -> Path:
    """Left: each finished trial's score (solved ones: env steps to solve) and the best so far.
    Right: what every trial reported to the pruner (its best evaluation so far) against its
    steps, ending in a dot where it solved and a cross where it was pruned."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator
    from optuna.trial import TrialState

    trials = study.get_trials(deepcopy=False)
    done = [t for t in trials if t.state == TrialState.COMPLETE]
    fig, (ax, curves) = plt.subplots(1, 2, figsize=(12, 4.2))
    solved = [t for t in done if t.user_attrs.get("solved")]
    unsolved = [t for t in done if not t.user_attrs.get("solved")]
    ax.scatter([t.number for t in solved], [t.value for t in solved], label="solved: env steps")
    if unsolved:
        ax.scatter(
            [t.number for t in unsolved],
            [t.value for t in unsolved],
            marker="x",
            label="not solved (budget + 1000 - best eval)",
        )
    best, xs, ys = float("inf"), [], []
    for t in sorted(done, key=lambda t: t.number):
        best = min(best, t.value)
        xs.append(t.number)
        ys.append(best)
    ax.step(xs, ys, where="post", color="k", label="best so far")
    pruned = [t.number for t in trials if t.state == TrialState.PRUNED]
    if pruned:
        ax.plot(
            pruned, [0] * len(pruned), "|", color="0.5", ms=12, transform=ax.get_xaxis_transform()
        )
        ax.plot([], [], "|", color="0.5", label=f"pruned ({len(pruned)})")
    ax.set_xlabel("trial")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")
    ax.set_ylabel("score (lower is better)")
    ax.set_title(f"{study.study_name}: optimization history")
    ax.legend(fontsize=8)
    for t in trials:
        steps = sorted(t.intermediate_values)
        if not steps:
            continue
        returns = [-t.intermediate_values[s] for s in steps]
        (line,) = curves.plot(steps, returns, lw=1, label=str(t.number))
        end = {TrialState.PRUNED: "x"}.get(t.state, "o" if t.user_attrs.get("solved") else None)
        if end:
            curves.plot(steps[-1], returns[-1], end, color=line.get_color())
    curves.set_xlabel("policy steps")
    curves.set_ylabel("evaluation reported to the pruner")
    curves.set_title("trials: o solved, x pruned")
    curves.legend(fontsize=7, ncol=2, title="trial", title_fontsize=7)
    return _save(fig, out)


def plot_importances(study, out: Path) -> Path | None:
    """Optuna's parameter importances (PED-ANOVA) as a bar chart; None with too few trials."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import optuna

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            importances = optuna.importance.get_param_importances(study)
        except (RuntimeError, ValueError):
            return None
    if not importances or any("too small" in str(w.message) for w in caught):
        return None  # Optuna would return equal importances: nothing to show
    names = list(importances)[::-1]
    fig, ax = plt.subplots(figsize=(7, 0.4 * len(names) + 1.5))
    ax.barh(names, [importances[n] for n in names])
    ax.set_xlabel("importance")
    complete = sum(t.state.name == "COMPLETE" for t in study.get_trials(deepcopy=False))
    ax.set_title(
        f"{study.study_name}: parameter importances (from {complete} completed trials"
        + (": a hint, not a measurement)" if complete < 10 else ")")
    )
    return _save(fig, out)


def _save(fig, out: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    with atomic_path(out) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
    return out
