"""README's sweep table: every trial of a study, from its journal and its trials' metrics.csv.

    python benchmarks/sweep_table.py docs/runs/walker-sweep

The folder holds the study's ``journal.log`` (the Optuna journal ``bipedal sweep`` wrote) and
``trial-NNNN/metrics.csv`` for each trial. Evaluations and the 100-episode tests are read from
the metrics, the parameters and each trial's state from the journal; the last line gives the
study's wall-clock time and its trial-minutes.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import optuna

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.sweep_report import format_value, short_name  # noqa: E402


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
    recent = [float(r["return"]) for r in episodes[-10:]]
    minutes = float(last["wall_time"]) / 60 if last else 0.0
    return [
        outcome,
        "-" if best is None else f"{best:.1f}",
        ", ".join(f"{t:.1f}" for t in tests) or "-",
        "-" if not recent else f"{sum(recent) / len(recent):.1f}",
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
    head = ["trial", *map(short_name, keys)]
    head += ["outcome", "best evaluation", "100-episode tests", "last 10 training returns"]
    head += ["episodes", "minutes"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for t in trials:
        metrics = root / f"trial-{t.number:04d}" / "metrics.csv"
        rows = list(csv.DictReader(open(metrics))) if metrics.exists() else []
        label = f"{t.number} (base config)" if t.user_attrs.get("baseline") else str(t.number)
        cells = [label, *(format_value(t.params[k]) if k in t.params else "-" for k in keys)]
        print("| " + " | ".join(cells + trial_outcome(t, rows)) + " |")
    finished = [t for t in trials if t.datetime_complete is not None]
    wall = max(t.datetime_complete for t in finished) - min(t.datetime_start for t in finished)
    busy = sum((t.datetime_complete - t.datetime_start).total_seconds() for t in finished)
    print(
        f"\n{len(trials)} trials; {wall.total_seconds() / 60:.0f} min from the first trial's start "
        f"to the last one's end, {busy / 60:.0f} trial-minutes"
    )


if __name__ == "__main__":
    main(sys.argv[1])
