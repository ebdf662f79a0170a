import csv

import numpy as np
import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.resume import resume
from bipedal_cli.train import train

from .conftest import tiny_dict


def flat_state(obj):
    """Every tensor/array in a nested state dict, keyed by path (RNG states included)."""
    out = {}

    def walk(prefix, value):
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}/{k}", v)
        elif isinstance(value, (list, tuple)):
            for i, v in enumerate(value):
                walk(f"{prefix}/{i}", v)
        else:
            out[prefix] = value

    walk("", obj)
    return out


def assert_states_equal(a: dict, b: dict, skip=("/counters/wall_time",)):
    fa, fb = flat_state(a), flat_state(b)
    assert fa.keys() == fb.keys()
    for key in fa:
        if key in skip or key.startswith(("/last_eval", "/full_eval")):
            continue
        va, vb = fa[key], fb[key]
        if torch.is_tensor(va):
            assert torch.equal(va, vb), key
        elif isinstance(va, np.ndarray):
            assert np.array_equal(va, vb), key
        else:
            assert va == vb, key


def test_resume_matches_uninterrupted_run(tmp_path):
    straight = train(config_from_dict(tiny_dict(total_steps=400)), tmp_path / "straight")
    first = train(config_from_dict(tiny_dict(total_steps=230)), tmp_path / "split")
    assert first.steps == 230
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.steps == second.steps == 400
    assert straight.episodes == second.episodes
    a = load_checkpoint(tmp_path / "straight" / "state.pt")
    b = load_checkpoint(tmp_path / "split" / "state.pt")
    assert a["agent"]["updates"] == 300
    assert_states_equal(
        {k: v for k, v in a.items() if k != "path"}, {k: v for k, v in b.items() if k != "path"}
    )
    # The metrics files tell the same story (wall times aside).
    rows = []
    for name in ("straight", "split"):
        with open(tmp_path / name / "metrics.csv") as f:
            rows.append([(r["step"], r["return"], r["critic_loss"]) for r in csv.DictReader(f)])
    assert rows[0] == rows[1] and len(rows[0]) >= 2


def test_same_seed_same_result_and_other_seed_differs(tmp_path):
    a = train(config_from_dict(tiny_dict(total_steps=150)), tmp_path / "a")
    b = train(config_from_dict(tiny_dict(total_steps=150)), tmp_path / "b")
    c_cfg = tiny_dict(total_steps=150)
    c_cfg["seed"] = 4
    c = train(config_from_dict(c_cfg), tmp_path / "c")
    pa, pb, pc = (load_checkpoint(r.run_dir / "policy.pt")["actor"] for r in (a, b, c))
    assert all(torch.equal(pa[k], pb[k]) for k in pa)
    assert not all(torch.equal(pa[k], pc[k]) for k in pa)


def test_periodic_eval_and_metrics_written(tmp_path):
    result = train(
        config_from_dict(tiny_dict(total_steps=200, eval_every=100, checkpoint_every=100)),
        tmp_path / "run",
    )
    with open(tmp_path / "run" / "metrics.csv") as f:
        rows = list(csv.DictReader(f))
    evals = [r for r in rows if r["kind"] == "eval"]
    assert [int(r["step"]) for r in evals] == [100, 200]
    assert result.last_eval["episodes"] == 2 and result.last_eval["step"] == 200
    episodes = [r for r in rows if r["kind"] == "episode"]
    assert len(episodes) == result.episodes
    assert all(r["stage"] == "BipedalWalker-v3" for r in rows)
    meta = load_checkpoint(tmp_path / "run" / "policy.pt")["meta"]
    assert meta["steps"] == 200 and meta["episodes"] == result.episodes


def test_until_solved_runs_full_evaluation_when_threshold_crossed(tmp_path):
    # A threshold of -1000 is crossed at the first evaluation: the full test runs and stops.
    data = tiny_dict(total_steps=400, eval_every=100)
    data["train"]["solved_threshold"] = -1000.0
    result = train(config_from_dict(data), tmp_path / "run", until_solved=True)
    assert result.stopped == "solved" and result.steps == 100
    assert result.full_eval["episodes"] == 2 and result.full_eval["solved"]


def test_new_run_refuses_an_existing_run_dir(tmp_path):
    from bipedal_cli.errors import UserError

    train(config_from_dict(tiny_dict(total_steps=20)), tmp_path / "run")
    with pytest.raises(UserError, match="already holds a run"):
        train(config_from_dict(tiny_dict(total_steps=20)), tmp_path / "run")


def test_evaluations_do_not_change_the_training_trajectory(tmp_path):
    # Evaluation uses its own envs and the deterministic policy: how often it runs must not
    # move any RNG, so runs with different train.eval_every are the same run.
    a = train(config_from_dict(tiny_dict(total_steps=300, eval_every=0)), tmp_path / "a")
    b = train(config_from_dict(tiny_dict(total_steps=300, eval_every=100)), tmp_path / "b")
    sa, sb = (load_checkpoint(r.run_dir / "state.pt") for r in (a, b))
    assert a.episodes == b.episodes
    ignore = ("path", "config", "last_eval", "full_eval")
    assert_states_equal(
        {k: v for k, v in sa.items() if k not in ignore},
        {k: v for k, v in sb.items() if k not in ignore},
    )


def test_two_threads_give_the_one_thread_run_bit_for_bit(tmp_path):
    # threads=2 splits every update over two threads of one intra-op thread each; the order of
    # every floating-point operation stays that of a threads=1 run.
    one = train(config_from_dict(tiny_dict(total_steps=250, threads=1)), tmp_path / "one")
    two = train(config_from_dict(tiny_dict(total_steps=250, threads=2)), tmp_path / "two")
    torch.set_num_threads(1)
    assert one.episodes == two.episodes
    sa, sb = (load_checkpoint(r.run_dir / "state.pt") for r in (one, two))
    ignore = ("path", "config")
    assert_states_equal(
        {k: v for k, v in sa.items() if k not in ignore},
        {k: v for k, v in sb.items() if k not in ignore},
    )


@pytest.mark.parametrize(
    "device",
    [
        "cpu",
        pytest.param(
            "cuda",
            marks=pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU"),
        ),
    ],
)
def test_run_on_device_resumes_and_its_policy_loads_on_cpu(tmp_path, device):
    # The cpu case checks this test itself; the cuda case runs only where a GPU is present.
    from bipedal_cli.checkpoint import actor_from_checkpoint

    data = tiny_dict(total_steps=230)
    data["device"] = device
    train(config_from_dict(data), tmp_path / "run")
    result = resume(tmp_path / "run", total_steps=300)
    assert result.steps == 300
    state = load_checkpoint(result.run_dir / "state.pt")
    assert state["config"]["device"] == device
    actor, _ = actor_from_checkpoint(load_checkpoint(result.run_dir / "policy.pt"))
    assert all(p.device.type == "cpu" for p in actor.parameters())
    assert all(torch.isfinite(p).all() for p in actor.parameters())
    action = actor.deterministic(torch.zeros(3, 24))
    assert action.shape == (3, 4) and bool((action.abs() <= 1).all())


def test_resume_on_two_threads_continues_a_one_thread_run_to_the_bit(tmp_path):
    """`bipedal resume RUN --threads 2`: a run moved to another thread count is the same run."""
    straight = train(config_from_dict(tiny_dict(total_steps=400, threads=1)), tmp_path / "a")
    train(config_from_dict(tiny_dict(total_steps=230, threads=1)), tmp_path / "b")
    moved = resume(tmp_path / "b", total_steps=400, threads=2)
    torch.set_num_threads(1)
    assert moved.episodes == straight.episodes
    sa, sb = (load_checkpoint(p / "state.pt") for p in (tmp_path / "a", tmp_path / "b"))
    assert sb["config"]["train"]["threads"] == 2
    ignore = ("path", "config")
    assert_states_equal(
        {k: v for k, v in sa.items() if k not in ignore},
        {k: v for k, v in sb.items() if k not in ignore},
    )


def test_a_larger_buffer_changes_nothing_until_the_smaller_one_would_wrap(tmp_path):
    """Sampling reads only how many transitions are stored, so a run with a buffer of 2,000 is
    the run with a buffer of 400 to the bit while 400 hold everything (session 48's 2M buffer
    against seed 0's 1M); once the smaller ring wraps, the runs part."""
    runs = {
        n: train(config_from_dict(tiny_dict(total_steps=s, buffer_size=n)), tmp_path / str(n))
        for n, s in ((400, 350), (2000, 350), (250, 350))
    }
    assert all(r.steps == 350 for r in runs.values())
    states = {n: trainable_state(tmp_path / str(n)) for n in runs}
    assert states[2000]["buffer"]["size"] == states[400]["buffer"]["size"] <= 350
    assert_states_equal(states[400], states[2000], skip=("/counters/wall_time", "/buffer/capacity"))
    actors = {n: load_checkpoint(tmp_path / str(n) / "policy.pt")["actor"] for n in runs}
    assert not all(torch.equal(actors[400][k], actors[250][k]) for k in actors[400])


def trainable_state(path):
    state = load_checkpoint(path / "state.pt")
    return {k: v for k, v in state.items() if k not in ("path", "config")}
