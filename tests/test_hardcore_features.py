"""The Hardcore capabilities end to end on tiny Walker runs: shaping, action repeat, history and
n-step returns together keep exact resume; evaluation, export and the metrics apply them."""

import csv
import json

import numpy as np
import pytest
import torch

from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.envs import make_env
from bipedal_cli.evaluation import actor_policy, evaluate_actor
from bipedal_cli.resume import resume
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_train import assert_states_equal

FEATURES = {"action_repeat": 2, "history": 3, "n_step": 3}
LSTM = {**FEATURES, "encoder": "lstm", "encoder_hidden": 8}  # the window read by an LSTM
SHAPING = {"fall_penalty": -7.0, "reward_scale": 2.0}


def featured(agent: dict = FEATURES, **train_keys) -> dict:
    data = tiny_dict(**SHAPING, **train_keys)
    data["agent"].update(agent)
    return data


@pytest.mark.parametrize("agent", [FEATURES, LSTM], ids=["flat", "lstm"])
def test_resume_is_exact_with_every_hardcore_feature_on(tmp_path, agent):
    straight = train(config_from_dict(featured(agent, total_steps=400)), tmp_path / "straight")
    train(config_from_dict(featured(agent, total_steps=230)), tmp_path / "split")
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes >= 2
    a = load_checkpoint(tmp_path / "straight" / "state.pt")
    b = load_checkpoint(tmp_path / "split" / "state.pt")
    assert a["buffer"]["obs"].shape[1] == 3 * 24 and "discount" in a["buffer"]
    assert_states_equal(
        {k: v for k, v in a.items() if k != "path"}, {k: v for k, v in b.items() if k != "path"}
    )
    rows = [list(csv.DictReader(open(tmp_path / n / "metrics.csv"))) for n in ("straight", "split")]
    strip = [[{k: v for k, v in r.items() if k != "wall_time"} for r in rs] for rs in rows]
    assert strip[0] == strip[1]


def test_metrics_keep_the_env_return_apart_from_the_shaped_one(tmp_path):
    train(config_from_dict(featured(total_steps=300)), tmp_path / "run")
    episodes = [r for r in csv.DictReader(open(tmp_path / "run" / "metrics.csv"))]
    episodes = [r for r in episodes if r["kind"] == "episode"]
    assert episodes
    for r in episodes:
        env_ret, shaped = float(r["return"]), float(r["shaped_return"])
        # the learner saw 2 * (return with the -100 fall replaced by -7)
        expected = 2 * (env_ret + 93.0) if r["fell"] == "1" else 2 * env_ret
        assert abs(shaped - expected) <= 1e-4 * max(1.0, abs(expected))
    # env steps: two per policy step, one fewer where an episode ended on the first of two
    for i, r in enumerate(episodes, 1):
        assert 2 * int(r["step"]) - i <= int(r["env_steps"]) <= 2 * int(r["step"])


@pytest.mark.parametrize("agent", [FEATURES, LSTM], ids=["flat", "lstm"])
def test_evaluation_runs_the_policy_with_its_repeat_and_history(tmp_path, agent):
    train(config_from_dict(featured(agent, total_steps=150)), tmp_path / "run")
    data = load_checkpoint(tmp_path / "run" / "policy.pt")
    actor, cfg = actor_from_checkpoint(data)
    assert data["obs_dim"] == 3 * 24
    (result,) = evaluate_actor(actor, cfg.agent, cfg.env, [5], workers=1)
    # the same episode by hand: hold each action 2 env steps, feed the last 3 observations
    env = make_env(cfg.env)
    policy = actor_policy(actor)
    obs, _ = env.reset(seed=5)
    frames = [obs] * 3
    ret, length, done = 0.0, 0, False
    while not done:
        action = policy(np.concatenate(frames)[None].astype(np.float32))[0]
        for _ in range(2):
            obs, r, term, trunc, _ = env.step(action)
            ret, length = ret + float(r), length + 1  # as the evaluation sums
            done = term or trunc
            if done:
                break
        frames = frames[1:] + [obs]
    assert (result.ret, result.length) == (ret, length)


@pytest.mark.parametrize("agent", [FEATURES, LSTM], ids=["flat", "lstm"])
def test_export_takes_the_observation_history(tmp_path, agent):
    from bipedal_cli.cli import main

    train(config_from_dict(featured(agent, total_steps=150)), tmp_path / "run")
    out = tmp_path / "p.pt2"
    try:
        main(["export", str(tmp_path / "run" / "policy.pt"), "--out", str(out)])
    except SystemExit as exc:
        assert not exc.code
    extra = {"bipedal.json": ""}
    program = torch.export.load(str(out), extra_files=extra).module()
    meta = json.loads(extra["bipedal.json"])
    assert meta["input_shape"] == ["B", 3, 24] and meta["action_repeat"] == 2
    actor, _ = actor_from_checkpoint(load_checkpoint(tmp_path / "run" / "policy.pt"))
    obs = torch.randn(5, 3, 24)
    assert torch.allclose(program(obs), actor.deterministic(obs.reshape(5, 72)), atol=1e-6)


def test_the_readme_loop_runs_an_exported_policy_with_gymnasium_alone(tmp_path):
    """docs/examples/run_exported_policy.py (README's plain Gymnasium loop) scores what
    bipedal's evaluation scores for the same policy and seed."""
    import subprocess
    import sys
    from pathlib import Path

    from bipedal_cli.export import export_policy

    train(config_from_dict(featured(total_steps=150)), tmp_path / "run")
    actor, cfg = actor_from_checkpoint(load_checkpoint(tmp_path / "run" / "policy.pt"))
    export_policy(actor, tmp_path / "p.pt2", cfg.agent.history, cfg.agent.action_repeat)
    script = Path(__file__).resolve().parent.parent / "docs" / "examples" / "run_exported_policy.py"
    out = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "p.pt2"), "BipedalWalker-v3", "4"],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    ).stdout
    (result,) = evaluate_actor(actor, cfg.agent, cfg.env, [4], workers=1)
    assert float(out.split()[-1]) == pytest.approx(result.ret, abs=0.01)
