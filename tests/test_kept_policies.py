"""train.keep_policies: the policy of every periodic evaluation, kept without changing the run."""

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.resume import resume
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_train import assert_states_equal, trainable_state


def test_kept_policies_change_nothing_and_record_their_evaluation(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=300, eval_every=100)), tmp_path / "plain")
    data = tiny_dict(total_steps=200, eval_every=100)
    data["train"]["keep_policies"] = True
    train(config_from_dict(data), tmp_path / "kept")
    kept = sorted(p.name for p in (tmp_path / "kept" / "policies").iterdir())
    assert kept == ["step-100.pt", "step-200.pt"]
    meta = load_checkpoint(tmp_path / "kept" / "policies" / "step-100.pt")["meta"]
    assert meta["steps"] == 100 and meta["last_eval"]["step"] == 100
    # `resume --no-keep-policies` turns it off; the run is the plain one to the bit
    resume(tmp_path / "kept", total_steps=300, keep_policies=False)
    assert len(list((tmp_path / "kept" / "policies").iterdir())) == 2
    assert_states_equal(trainable_state(tmp_path / "plain"), trainable_state(tmp_path / "kept"))
    assert (
        load_checkpoint(tmp_path / "kept" / "state.pt")["config"]["train"]["keep_policies"] is False
    )
