"""bipedal select: ranking by periodic evaluation, re-evaluation on held-out seeds."""

import hashlib
import json
from pathlib import Path

import pytest

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.selection import Candidate, distinct, finalists, run_candidates, top_candidates
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_cli import run_cli


def candidate(step, periodic):
    return Candidate(Path(f"step-{step}.pt"), "run", step, "BipedalWalker-v3", periodic, 0)


def test_top_candidates_rank_by_periodic_evaluation_then_step():
    pool = [candidate(100, 5.0), candidate(200, None), candidate(300, 9.0), candidate(400, 5.0)]
    assert [c.step for c in top_candidates(pool, 3)] == [300, 400, 100]
    assert [c.step for c in top_candidates(pool, 10)] == [300, 400, 100, 200]


@pytest.fixture
def kept_run(tmp_path):
    data = tiny_dict(total_steps=300, eval_every=100)
    data["train"]["keep_policies"] = True
    train(config_from_dict(data), tmp_path / "run")
    return tmp_path / "run"


def test_run_candidates_are_one_per_step_with_their_own_evaluation(kept_run):
    found = run_candidates(kept_run)
    assert sorted(c.step for c in found) == [100, 200, 300]
    assert all(c.periodic is not None for c in found)
    branch = kept_run.parent / "branch"  # a branch's copy of its source's best policy
    branch.mkdir()
    (branch / "best_policy.pt").write_bytes((kept_run / "policies" / "step-100.pt").read_bytes())
    pool = distinct(found + run_candidates(branch))
    assert sorted(c.step for c in pool) == [100, 200, 300]
    assert all(c.run == "run" for c in pool)
    shipped = kept_run.parent / "shipped.pt"  # a policy file: one candidate, named by its file
    shipped.write_bytes((kept_run / "policies" / "step-200.pt").read_bytes())
    (only,) = run_candidates(shipped)
    assert (only.run, only.step, only.periodic is not None) == ("shipped.pt", 200, True)
    with pytest.raises(UserError, match="not a run directory"):
        run_candidates(kept_run / "missing")


def test_select_copies_the_held_out_winner(tmp_path, kept_run, capsys):
    out, report = tmp_path / "chosen.pt", tmp_path / "select.json"
    args = ["select", kept_run, "--top", 2, "--episodes", 2, "--workers", 1, "--out", out]
    code, stdout, err = run_cli([*args, "--json", report], capsys)
    assert code == 0, err
    data = json.loads(report.read_text())
    assert data["seeds"] == [2_000_000, 2_000_001] and len(data["candidates"]) == 2
    assert data["machine"].endswith(" kernels)")
    means = {r["path"]: r["held_out"]["mean"] for r in data["candidates"]}
    assert means[data["chosen"]] == max(means.values())
    chosen_step = load_checkpoint(data["chosen"])["meta"]["steps"]
    assert load_checkpoint(out)["meta"]["steps"] == chosen_step
    for r in data["candidates"]:  # the file's identity, for pooling reports across sessions
        assert r["sha256"] == hashlib.sha256(Path(r["path"]).read_bytes()).hexdigest()
    assert "chosen:" in stdout
    code, _, err = run_cli([*args], capsys)  # --out exists now
    assert code == 2 and "--force" in err and len(err.strip().splitlines()) == 1


def test_a_named_policy_file_is_always_a_candidate(tmp_path, kept_run, capsys):
    """The incumbent competes even when its periodic evaluation is below the runs' top K."""
    import torch

    incumbent = tmp_path / "incumbent.pt"
    data = load_checkpoint(kept_run / "policies" / "step-100.pt")
    data.pop("path")
    data["meta"]["last_eval"]["mean"] = -1e9  # ranked last by periodic evaluation
    torch.save(data, incumbent)
    report = tmp_path / "select.json"
    args = ["select", incumbent, kept_run, "--top", 1, "--episodes", 1, "--workers", 1]
    code, _, err = run_cli([*args, "--json", report], capsys)
    assert code == 0, err
    paths = [r["path"] for r in json.loads(report.read_text())["candidates"]]
    assert paths[0] == str(incumbent) and len(paths) == 2


def test_top_zero_takes_every_policy_from_since_on(tmp_path, kept_run, capsys):
    report = tmp_path / "select.json"
    args = ["select", kept_run, "--top", 0, "--since", 200, "--episodes", 1, "--workers", 1]
    code, _, err = run_cli([*args, "--json", report], capsys)
    assert code == 0, err
    steps = sorted(r["step"] for r in json.loads(report.read_text())["candidates"])
    assert steps == [200, 300]
    code, _, err = run_cli(["select", kept_run, "--since", -1], capsys)
    assert code == 2 and "--since" in err and len(err.strip().splitlines()) == 1


def test_finalists_are_the_winner_and_the_incumbent_or_the_runner_up():
    assert finalists([250.0, 280.0, 270.0], named=1) == [1, 0]  # winner against the incumbent
    assert finalists([290.0, 280.0, 270.0], named=1) == [0]  # the incumbent won: nothing to confirm
    assert finalists([250.0, 280.0, 270.0], named=0) == [1, 2]  # winner against the runner-up
    assert finalists([250.0], named=0) == [0]


def test_confirm_plays_the_finalists_on_the_next_seeds(tmp_path, kept_run, capsys):
    """The choice is the confirmation round's winner, on seeds after the first round's."""
    report = tmp_path / "select.json"
    args = ["select", kept_run, "--top", 0, "--episodes", 2, "--confirm", 3, "--workers", 1]
    code, stdout, err = run_cli([*args, "--json", report], capsys)
    assert code == 0, err
    data = json.loads(report.read_text())
    first = {r["path"]: r["held_out"]["mean"] for r in data["candidates"]}
    final = {r["path"]: r["held_out"]["mean"] for r in data["confirm"]["finalists"]}
    assert data["confirm"]["seeds"] == [2_000_002, 2_000_004]
    assert len(final) == 2 and max(first, key=first.get) in final
    assert data["chosen"] == max(final, key=final.get)
    assert all(r["held_out"]["episodes"] == 3 for r in data["confirm"]["finalists"])
    assert "confirmation: env seeds 2000002..2000004" in stdout
    # each round reports its winner minus the other finalist, paired over the round's seeds
    diff = data["confirm"]["difference"]
    assert diff["of"] == data["chosen"] and diff["minus"] in final and diff["episodes"] == 3
    assert diff["mean"] == pytest.approx(final[diff["of"]] - final[diff["minus"]], abs=1e-9)
    assert diff["low"] <= diff["mean"] <= diff["high"]
    assert data["difference"]["of"] == max(first, key=first.get)
    assert "paired over 3 seeds" in stdout and "paired over 2 seeds" in stdout
    code, _, err = run_cli(["select", kept_run, "--confirm", -1], capsys)
    assert code == 2 and "--confirm" in err and len(err.strip().splitlines()) == 1
