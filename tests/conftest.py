import importlib
import sys
from pathlib import Path
from types import ModuleType

import pytest

from bipedal_cli.config import Config, config_from_dict

TINY = {
    "seed": 3,
    "device": "cpu",
    "agent": {
        "lr": 3.296e-4,  # pinned, so that tuning the default config does not move these runs
        "batch_size": 16,
        "n_critics": 2,
        "n_quantiles": 5,
        "drop_per_critic": 1,
        "actor_hidden": 16,
        "critic_hidden": 16,
    },
    "train": {
        "total_steps": 400,
        "warmup_steps": 100,
        "buffer_size": 250,  # smaller than the run: the ring buffer wraps
        "eval_every": 0,
        "eval_episodes": 2,
        "solved_episodes": 2,
        "checkpoint_every": 0,
        "threads": 1,
    },
}


def tiny_dict(**train) -> dict:
    data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in TINY.items()}
    data["train"].update(train)
    return data


@pytest.fixture
def tiny_config() -> Config:
    return config_from_dict(tiny_dict())


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    """Rich tables fit the terminal width; keep captured output from being truncated."""
    monkeypatch.setenv("COLUMNS", "200")


def stats_text(snapshot: dict) -> str:
    """The training display's statistics table for ``snapshot``, as the terminal shows it."""
    from rich.console import Console

    from bipedal_cli.display import TrainingDisplay

    display = TrainingDisplay(Console(width=200, record=True))
    display.snapshot = snapshot
    display.console.print(display.stats_table())
    return display.console.export_text()


BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


def load_benchmark(name: str) -> ModuleType:
    """Import ``benchmarks/<name>.py``. The folder is not a package: its scripts run as
    ``python benchmarks/<name>.py`` and import each other by name, so it goes first on the path,
    as it does for a script run that way."""
    if str(BENCHMARKS) not in sys.path:
        sys.path.insert(0, str(BENCHMARKS))
    return importlib.import_module(name)
