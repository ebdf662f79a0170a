"""README's sweep table: every trial of a study, from its journal and its trials' metrics.csv.

    python benchmarks/sweep_table.py docs/runs/walker-sweep

The folder holds the study's ``journal.log`` (the Optuna journal ``bipedal sweep`` wrote) and
``trial-NNNN/metrics.csv`` for each trial. Evaluations and the 100-episode tests are read from
the metrics, the parameters and each trial's state from the journal.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import optuna

SHORT = {
    "agent.gamma": "gamma",
    "agent.lr": "lr",
    "agent.batch_size": "batch",
    "train.warmup_steps": "warm-up",
    "agent.tau": "tau",
    "agent.n_critics": "critics",
    "agent.n_quantiles": "atoms",
}


def value(v) -> str:
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def trial_outcome(trial, rows: list[dict]) -> list[str]:
    evals = [r for r in rows if r["kind"] == "eval"]
    tests = [float(r["return"]) for r in rows if r["kind"] == "full_eval"]
    episodes = [r for r in rows if r["kind"] == "episode"]
    state = trial.state.name.lower()
    last = rows[-1] if rows else None
    if trial.user_attrs.get("solved"):
        outcome = f"solved at {int(trial.value):,} env steps"
    elif state == "pruned" and evals:
        outcome = f"pruned at {int(evals[-1]['env_steps']):,}"
    elif state == "complete":
        outcome = "not solved in budget"
    else:
        outcome = state
    best = max((float(r["return"]) for r in evals), default=None)
    minutes = float(last["wall_time"]) / 60 if last else 0.0
    return [
        outcome,
        "-" if best is None else f"{best:.1f}",
        ", ".join(f"{t:.1f}" for t in tests) or "-",
        str(len(episodes)),
        f"{minutes:.1f}",
    ]


def main(folder: str) -> None:
    root = Path(folder)
    backend = optuna.storages.journal.JournalFileBackend(str(root / "journal.log"))
    storage = optuna.storages.JournalStorage(backend)
    (name,) = optuna.study.get_all_study_names(storage)
    study = optuna.load_study(study_name=name, storage=storage)
    trials = study.get_trials(deepcopy=False)
    keys = list(dict.fromkeys(k for t in trials for k in t.params))
    head = ["trial", *(SHORT.get(k, k) for k in keys)]
    head += ["outcome", "best evaluation", "100-episode tests", "episodes", "minutes"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for t in trials:
        metrics = root / f"trial-{t.number:04d}" / "metrics.csv"
        rows = list(csv.DictReader(open(metrics))) if metrics.exists() else []
        label = f"{t.number} (base config)" if t.user_attrs.get("baseline") else str(t.number)
        cells = [label, *(value(t.params[k]) if k in t.params else "-" for k in keys)]
        print("| " + " | ".join(cells + trial_outcome(t, rows)) + " |")


if __name__ == "__main__":
    main(sys.argv[1])
