"""The restart files committed under ``checkpoints/restarts/`` (a long run's state without its
replay buffer, so that the run outlives a move to another machine) are what docs/hardcore.md says
they are: restart files of the named config and seed, whose metrics are the committed copy's."""

import csv
import io
from pathlib import Path

import pytest

from bipedal_cli.branch_rules import BRANCH_MAY_CHANGE, _flat
from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict, resolve_config
from bipedal_cli.metrics import parse_metrics, read_metrics, restart_metrics_text

ROOT = Path(__file__).resolve().parent.parent
RESTARTS = ROOT / "checkpoints" / "restarts"
# restart file: (the config that trained it, its seed, the committed copy of its metrics)
COMMITTED = {
    "hardcore-lrdecay-cvar25-seed2.pt": (
        "hardcore-lrdecay-cvar25.yaml",
        2,
        "docs/runs/hardcore-lrdecay-cvar25-seed2/metrics.csv",
    ),
    "hardcore-lrdecay-cvar25-wide-seed0.pt": (
        "hardcore-lrdecay-cvar25-wide.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-wide-seed0/metrics.csv",
    ),
    "hardcore-lstm12-seed0.pt": (
        "hardcore-lstm12.yaml",
        0,
        "docs/runs/hardcore-lstm12-seed0/metrics.csv",
    ),
    "hardcore-lrdecay-cvar25-ar2-seed0.pt": (
        "hardcore-lrdecay-cvar25-ar2.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-ar2-seed0/metrics.csv",
    ),
    "hardcore-lrdecay-cvar25-ere-seed0.pt": (
        "hardcore-lrdecay-cvar25-ere.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-ere-seed0/metrics.csv",
    ),
    "hardcore-lrdecay-cvar25-ere-stumps-seed0.pt": (
        "hardcore-lrdecay-cvar25-ere-stumps.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-ere-stumps-seed0/metrics.csv",
    ),
    "hardcore-lrdecay-cvar10-ere-seed0.pt": (
        "hardcore-lrdecay-cvar10-ere.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar10-ere-seed0/metrics.csv",
    ),
    "hardcore-lrdecay-cvar25-buffer2m-seed0.pt": (
        "hardcore-lrdecay-cvar25-buffer2m.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-buffer2m-seed0/metrics.csv",
    ),
    # the 2M-buffer run's control (session 49)
    "hardcore-lrdecay-cvar25-buffer1m-seed0.pt": (
        "hardcore-lrdecay-cvar25.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-buffer1m-seed0/metrics.csv",
    ),
    # the 2M-buffer run's control, branched from its state at 1M to the 1M buffer of seed 0's
    # recipe (session 49), at 1.1M: the branch point of the smooth, entropy8 and drop4 configs
    "hardcore-lrdecay-cvar25-buffer1m-seed0-at-1100000.pt": (
        "hardcore-lrdecay-cvar25.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-buffer1m-seed0/metrics.csv",
    ),
    # the candidates' control, restarted on a new machine from the file above (session 50)
    "hardcore-lrdecay-cvar25-control-seed0.pt": (
        "hardcore-lrdecay-cvar25.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-control-seed0/metrics.csv",
    ),
    # the smoothness candidate, restarted from the same file under its config (session 50)
    "hardcore-lrdecay-cvar25-smooth-seed0.pt": (
        "hardcore-lrdecay-cvar25-smooth.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-smooth-seed0/metrics.csv",
    ),
    # the branch point of hardcore-lrdecay-cvar25-ere-stumps.yaml (session 46) and
    # hardcore-lrdecay-cvar10-ere.yaml (session 47)
    "hardcore-lrdecay-cvar25-ere-seed0-at-1100000.pt": (
        "hardcore-lrdecay-cvar25-ere.yaml",
        0,
        "docs/runs/hardcore-lrdecay-cvar25-ere-seed0/metrics.csv",
    ),
}


def test_every_committed_restart_file_is_listed_here():
    assert sorted(p.name for p in RESTARTS.glob("*.pt")) == sorted(COMMITTED)


@pytest.mark.parametrize("name", sorted(COMMITTED))
def test_committed_restart_file_is_its_configs_run_with_the_committed_metrics(name):
    config, seed, metrics = COMMITTED[name]
    data = load_checkpoint(RESTARTS / name)  # checkpoint.py checks every field
    assert data["restart"] is not None and data["buffer"]["size"] == 0
    step = data["counters"]["step"]
    run_cfg = config_from_dict(data["config"])
    committed_cfg = resolve_config(ROOT / "configs" / config, seed=seed)
    # the file's config is the committed one but for what changes no bit (threads, budget)
    assert flat(run_cfg.to_dict()) == flat(committed_cfg.to_dict())
    text = restart_metrics_text(data["restart"])
    rows = parse_metrics(text)
    assert rows and int(float(rows[-1]["step"])) <= step
    copy = read_metrics(ROOT / metrics)
    assert copy[: len(rows)] == rows, f"{metrics} is not the restart file's metrics"
    header = next(csv.reader(io.StringIO(text)))
    assert header == list(copy[0])


def flat(data: dict) -> dict:
    """A config dict as dotted keys, without those a branch may change (device, threads...)."""
    return {k: v for k, v in _flat(data).items() if k not in BRANCH_MAY_CHANGE}
