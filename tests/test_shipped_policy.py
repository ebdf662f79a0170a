"""The shipped policies do what their reports say: a few episodes of the 100-episode protocol,
not all of them, and each was trained with its committed config."""

import json
from pathlib import Path

import pytest
import torch

from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint
from bipedal_cli.devices import machine_summary
from bipedal_cli.evaluation import evaluate_actor

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = {  # policy file: (its eval report, env, the config that trained it, solved?)
    "bipedal_walker.pt": ("bipedal_walker.eval.json", "BipedalWalker-v3", "walker.yaml", True),
    "bipedal_hardcore.pt": (
        "bipedal_hardcore.eval.json",
        "BipedalWalkerHardcore-v3",
        "hardcore-lrdecay-cvar-late.yaml",
        False,  # not yet: README's Hardcore section gives its score
    ),
}


def shipped(name):
    policy = ROOT / "checkpoints" / name
    if not policy.exists():
        pytest.skip(f"checkpoints/{name} is not shipped")
    report, env, config, solved = SHIPPED[name]
    return policy, json.loads((ROOT / "checkpoints" / report).read_text()), env, config, solved


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_policy_replays_its_reports_first_episodes(name):
    policy, report, env, _, solved = shipped(name)
    data = load_checkpoint(policy)
    assert data["env"] == env and report["summary"]["env"] == env
    assert report["summary"]["episodes"] == 100 and report["summary"]["seeds"] == [0, 99]
    assert (report["summary"]["mean"] > 300) is solved
    if solved:
        meta = data["meta"]
        assert meta["full_eval"]["episodes"] == 100 and meta["full_eval"]["mean"] > 300
    actor, cfg = actor_from_checkpoint(data)
    episodes = evaluate_actor(actor, cfg.agent, env, [0, 1, 2, 3, 4], workers=1)
    assert [got.seed for got in episodes] == [want["seed"] for want in report["episodes"][:5]]
    # Same chunk of 5 as `bipedal eval`: equal on the kind of machine that wrote the report
    # (reports name it since session 33). On another CPU the float rounding of the matrix
    # products differs and a 1,600-step walk amplifies it (seen: 304.2 against 305.6 on an AMD
    # EPYC for an Intel Xeon's report), and a knife-edge episode can fall on one machine and
    # not on the other (seen: Hardcore's seed 2, 142.0 with a fall in the AMD-era report, 308.3
    # on an Intel Xeon with AVX512): one of the five may then flip, not more.
    same_machine = report["summary"].get("machine") == machine_summary(torch.device("cpu"))
    pairs = list(zip(episodes, report["episodes"][:5], strict=True))
    flipped = [got.seed for got, want in pairs if got.fell != want["fell"]]
    assert len(flipped) <= (0 if same_machine else 1), flipped
    for got, want in pairs:
        if got.seed not in flipped:
            assert got.ret == pytest.approx(want["ret"], rel=1e-9 if same_machine else 0.02)
        if solved:
            assert not got.fell and got.ret > 300


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_policy_was_trained_with_its_committed_config(name):
    from bipedal_cli.config import resolve_config

    policy, _, _, config, _ = shipped(name)
    _, trained = actor_from_checkpoint(load_checkpoint(policy))
    committed = resolve_config(ROOT / "configs" / config)
    # neither the thread count nor keeping evaluated policies changes the run (both tested)
    trained.train.threads = committed.train.threads
    trained.train.keep_policies = committed.train.keep_policies
    trained.seed = committed.seed
    assert trained == committed
