import os

import pytest
import torch

from bipedal_cli import checkpoint as ckpt_mod
from bipedal_cli.checkpoint import actor_from_checkpoint, atomic_save, load_checkpoint
from bipedal_cli.checkpoint_contents import policy_payload
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.train import Trainer, train

from .conftest import stats_text, tiny_dict


def test_policy_checkpoint_round_trip_gives_identical_actions(tmp_path):
    result = train(config_from_dict(tiny_dict(total_steps=150)), tmp_path / "run")
    data = load_checkpoint(result.run_dir / "policy.pt")
    actor, cfg = actor_from_checkpoint(data)
    state = load_checkpoint(result.run_dir / "state.pt")
    actor_from_state, _ = actor_from_checkpoint(state)
    trainer = Trainer(cfg, tmp_path / "other")
    trainer.load_state_dict(state)
    obs = torch.randn(32, 24)
    with torch.no_grad():
        want = trainer.agent.actor.deterministic(obs)
        assert torch.equal(actor.deterministic(obs), want)
        assert torch.equal(actor_from_state.deterministic(obs), want)
    assert data["meta"]["steps"] == 150 and data["env"] == "BipedalWalker-v3"
    # optimizer states survive the round trip exactly
    for name in ("actor_opt", "critic_opt", "alpha_opt"):
        a = getattr(trainer.agent, name).state_dict()
        b = state["agent"][name]
        for k, v in a["state"].items():
            for key in v:
                assert torch.equal(v[key], b["state"][k][key]), (name, key)
    assert torch.equal(trainer.agent.log_alpha.detach(), state["agent"]["log_alpha"])


def tiny_policy_payload(fill: float) -> dict:
    from bipedal_cli.networks import make_actor

    cfg = config_from_dict(tiny_dict())
    actor = make_actor(cfg.agent, 24, 4)
    with torch.no_grad():
        for p in actor.parameters():
            p.fill_(fill)
    return policy_payload(actor.state_dict(), cfg.to_dict(), 24, 4, {})


def test_interrupted_write_leaves_the_previous_checkpoint_loadable(tmp_path, monkeypatch):
    path = tmp_path / "policy.pt"
    atomic_save(tiny_policy_payload(1.0), path)

    def crash_midway(obj, f, *args, **kwargs):
        f.write(b"PK\x03\x04 half a zip file")
        raise KeyboardInterrupt  # killed mid-write

    monkeypatch.setattr(ckpt_mod.torch, "save", crash_midway)
    with pytest.raises(KeyboardInterrupt):
        atomic_save(tiny_policy_payload(0.0), path)
    monkeypatch.undo()
    assert all(bool((t == 1).all()) for t in load_checkpoint(path)["actor"].values())
    assert os.listdir(tmp_path) == ["policy.pt"], "the temporary file must be cleaned up"


@pytest.mark.parametrize(
    "content, message",
    [
        (None, "no such file"),
        (b"not a checkpoint", "not a readable bipedal checkpoint"),
        ("truncated", "not a readable bipedal checkpoint"),
        ("foreign", "not a bipedal checkpoint"),
    ],
)
def test_bad_checkpoint_files_raise_one_line_user_errors(tmp_path, content, message):
    path = tmp_path / "ckpt.pt"
    if content == "truncated":
        atomic_save({"format": "bipedal-policy", "version": 1, "x": torch.ones(1000)}, path)
        path.write_bytes(path.read_bytes()[:200])
    elif content == "foreign":
        torch.save({"state_dict": {}}, path)
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(UserError, match=message) as info:
        load_checkpoint(path)
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_the_displays_fall_rate_is_the_last_100_episodes_and_survives_a_resume(tmp_path):
    import csv

    from bipedal_cli.resume import load_trainer

    run = tmp_path / "run"
    train(config_from_dict(tiny_dict(total_steps=3000, warmup_steps=3000)), run)  # random acts
    rows = [r for r in csv.DictReader(open(run / "metrics.csv")) if r["kind"] == "episode"]
    falls = [r["fell"] == "1" for r in rows][-100:]
    assert 0 < sum(falls) < len(falls)  # a fall and a time limit
    trainer = load_trainer(run)
    snap = trainer.snapshot(0.0)
    assert snap["fall_rate"] == pytest.approx(sum(falls) / len(falls))
    assert snap["falls_over"] == len(falls)
    assert f"falls (last {len(falls)})" in stats_text(snap)
    state = torch.load(run / "state.pt", weights_only=True)
    del state["recent_falls"]  # a checkpoint from before the fall rate was kept
    torch.save(state, run / "state.pt")
    old = load_trainer(run)
    assert old.snapshot(0.0)["fall_rate"] is None
