"""The learning-rate decay and `bipedal resume RUN --into DIR --config NEW` (a branch)."""

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.metrics import read_metrics
from bipedal_cli.resume import branch
from bipedal_cli.schedule import learning_rate_at
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_train import assert_states_equal, trainable_state


def test_learning_rate_is_constant_then_linear_then_final():
    assert learning_rate_at(10**6, 1e-3, None, 0, 10) == 1e-3
    assert learning_rate_at(100, 1e-3, 1e-4, 100, 200) == 1e-3
    assert learning_rate_at(150, 1e-3, 1e-4, 100, 200) == pytest.approx(5.5e-4, rel=1e-12)
    assert learning_rate_at(175, 1e-3, 0.0, 100, 200) == pytest.approx(2.5e-4, rel=1e-12)
    assert learning_rate_at(200, 1e-3, 1e-4, 100, 200) == 1e-4
    assert learning_rate_at(10**9, 1e-3, 1e-4, 100, 200) == 1e-4


def decaying(**train_keys):
    data = tiny_dict(**train_keys)
    data["agent"].update(lr_final=1e-5, lr_decay_start=200, lr_decay_end=350)
    return data


def test_branch_equals_the_run_its_config_trains_from_scratch(tmp_path):
    straight = train(config_from_dict(decaying(total_steps=400)), tmp_path / "straight")
    constant = train(config_from_dict(tiny_dict(total_steps=200)), tmp_path / "constant")
    assert constant.steps == 200
    branched = branch(tmp_path / "constant", tmp_path / "branch", config_from_dict(decaying()))
    assert branched.steps == straight.steps == 400
    assert_states_equal(
        trainable_state(tmp_path / "straight"), trainable_state(tmp_path / "branch")
    )
    lrs = {
        g["lr"]
        for g in load_checkpoint(tmp_path / "branch" / "state.pt")["agent"]["actor_opt"][
            "param_groups"
        ]
    }
    assert lrs == {1e-5}
    rows = [
        [(r["step"], r["return"], r["critic_loss"]) for r in read_metrics(p / "metrics.csv")]
        for p in (tmp_path / "straight", tmp_path / "branch")
    ]
    assert rows[0] == rows[1]
    assert (tmp_path / "branch" / "branched_from.txt").read_text().endswith("at step 200\n")
    # the source run is untouched, and the decay is not a no-op
    assert load_checkpoint(tmp_path / "constant" / "state.pt")["counters"]["step"] == 200
    constant_400 = train(config_from_dict(tiny_dict(total_steps=400)), tmp_path / "c400")
    assert constant_400.episodes >= 1
    a = load_checkpoint(tmp_path / "c400" / "state.pt")["agent"]["actor"]
    b = load_checkpoint(tmp_path / "branch" / "state.pt")["agent"]["actor"]
    assert any(not torch.equal(a[k], b[k]) for k in a)


@pytest.mark.parametrize(
    "change, key",
    [
        ({"agent": {"gamma": 0.99}}, "agent.gamma"),
        ({"agent": {"lr_decay_start": 100}}, "agent.lr_decay_start"),
        ({"train": {"buffer_size": 150}}, "train.buffer_size"),  # 200 transitions do not fit
        ({"train": {"replay_keep_below": 250.0}}, "train.replay_curation_start"),
    ],
)
def test_branch_refuses_a_config_that_changes_the_past(tmp_path, change, key):
    train(config_from_dict(tiny_dict(total_steps=200)), tmp_path / "run")
    data = decaying()
    for section, values in change.items():
        data[section].update(values)
    with pytest.raises(UserError, match=key.replace(".", r"\.")):
        branch(
            tmp_path / "run", tmp_path / "branch", config_from_dict(data), config_source="new.yaml"
        )
    assert not (tmp_path / "branch").exists()


def test_branch_refuses_an_existing_run_dir(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=200)), tmp_path / "run")
    with pytest.raises(UserError, match="--into"):
        branch(tmp_path / "run", tmp_path / "run", config_from_dict(decaying()))


def test_cli_branch_and_its_one_line_errors(tmp_path, capsys):
    import yaml

    from .test_cli import run_cli

    base, branched = tmp_path / "base.yaml", tmp_path / "decay.yaml"
    base.write_text(yaml.safe_dump(tiny_dict(total_steps=200)))
    data = decaying(total_steps=300)
    branched.write_text(yaml.safe_dump(data))
    code, _, err = run_cli(["train", "--config", base, "--run-dir", tmp_path / "run"], capsys)
    assert code == 0, err
    code, _, err = run_cli(["resume", tmp_path / "run", "--into", tmp_path / "b"], capsys)
    assert code == 2 and "--into: a branch needs" in err and len(err.strip().splitlines()) == 1
    code, _, err = run_cli(["resume", tmp_path / "run", "--set", "agent.tau=0.5"], capsys)
    assert code == 2 and "only with --into" in err and len(err.strip().splitlines()) == 1
    data["agent"]["tau"] = 0.5
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(data))
    args = ["resume", tmp_path / "run", "--into", tmp_path / "b", "--config", bad]
    code, _, err = run_cli(args, capsys)
    assert code == 2 and f"{bad}: key 'agent.tau'" in err and len(err.strip().splitlines()) == 1
    args = ["resume", tmp_path / "run", "--into", tmp_path / "b", "--config", branched]
    code, out, err = run_cli(args, capsys)
    assert code == 0, err
    assert load_checkpoint(tmp_path / "b" / "state.pt")["counters"]["step"] == 300
    assert load_checkpoint(tmp_path / "run" / "state.pt")["counters"]["step"] == 200


def test_cli_branch_with_set_alone_starts_from_the_runs_own_config(tmp_path, capsys):
    import yaml

    from .test_cli import run_cli

    base = tmp_path / "base.yaml"
    base.write_text(yaml.safe_dump(tiny_dict(total_steps=200)))
    code, _, err = run_cli(["train", "--config", base, "--run-dir", tmp_path / "run"], capsys)
    assert code == 0, err
    sets = ["agent.lr_final=1e-5", "agent.lr_decay_start=200", "agent.lr_decay_end=350"]
    args = ["resume", tmp_path / "run", "--into", tmp_path / "b", "--steps", 400]
    code, _, err = run_cli([*args, *(x for s in sets for x in ("--set", s))], capsys)
    assert code == 0, err
    train(config_from_dict(decaying(total_steps=400)), tmp_path / "straight")
    assert_states_equal(trainable_state(tmp_path / "straight"), trainable_state(tmp_path / "b"))
    code, _, err = run_cli([*args[:3], tmp_path / "c", "--set", "agent.gamma=0.9"], capsys)
    assert code == 2 and "'agent.gamma' is 0.9" in err


def test_branch_may_start_replay_curation_at_its_step(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=200)), tmp_path / "run")
    data = tiny_dict(total_steps=260)
    data["train"].update(replay_keep_below=250.0, replay_curation_start=200)
    result = branch(tmp_path / "run", tmp_path / "branch", config_from_dict(data))
    assert result.steps == 260


def test_branch_may_resize_a_buffer_that_never_wrapped_and_is_then_the_run_of_that_size(tmp_path):
    """At step 200 a buffer of 2,000 and one of 250 hold the same 200 transitions in the same
    slots, so a branch there to either size is, to the bit, the run of that size from scratch:
    250 wraps after the branch, 2,000 never does."""
    for size, other in ((250, 2000), (2000, 250)):
        straight = train(config_from_dict(tiny_dict(buffer_size=size)), tmp_path / f"s{size}")
        train(
            config_from_dict(tiny_dict(total_steps=200, buffer_size=other)), tmp_path / f"h{size}"
        )
        new = config_from_dict(tiny_dict(buffer_size=size))
        branched = branch(tmp_path / f"h{size}", tmp_path / f"b{size}", new)
        assert branched.steps == straight.steps == 400
        a, b = (trainable_state(tmp_path / f"{k}{size}") for k in ("s", "b"))
        assert b["buffer"]["capacity"] == size and b["buffer"]["size"] == min(size, 400)
        assert_states_equal(a, b)


@pytest.mark.parametrize(
    "size, steps, new_size, held",
    [(250, 300, 2000, "holds 250 at position 50"), (2000, 300, 250, "holds 300 at position 300")],
)
def test_branch_refuses_to_resize_a_buffer_that_wrapped_or_does_not_fit(
    tmp_path, size, steps, new_size, held
):
    train(config_from_dict(tiny_dict(total_steps=steps, buffer_size=size)), tmp_path / "run")
    new = config_from_dict(tiny_dict(buffer_size=new_size))
    with pytest.raises(UserError, match=f"'train.buffer_size' is {new_size}.*{held}"):
        branch(tmp_path / "run", tmp_path / "b", new)
    assert not (tmp_path / "b").exists()
