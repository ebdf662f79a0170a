"""The risk-averse actor (agent.actor_cvar): the loss against a float64 reference in value and
gradient; off, it is eq. 2 to the bit; a run switches it on after its step, resumes exactly across
it, and may be branched into it at its step but not before."""

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.losses import actor_loss
from bipedal_cli.resume import branch, resume
from bipedal_cli.schedule import actor_lowest_atoms
from bipedal_cli.train import Trainer, train

from .conftest import stats_text, tiny_dict
from .reference import ref_actor_cvar_loss, ref_actor_loss
from .test_train import assert_states_equal

f64 = torch.float64
CVAR = {"actor_cvar": 0.4, "actor_cvar_start": 250}  # tiny: N*M = 2*5 = 10 atoms, L = 4


def cvar_dict(**agent_keys) -> dict:
    data = tiny_dict()
    data["agent"].update({**CVAR, **agent_keys})
    return data


@pytest.mark.parametrize("lowest", [1, 3, 7, 11])
def test_cvar_loss_matches_reference_value_and_gradient(lowest):
    gen = torch.Generator().manual_seed(lowest)
    log_prob = torch.randn(3, dtype=f64, generator=gen).requires_grad_()
    atoms = (torch.randn(3, 3, 4, dtype=f64, generator=gen) * 5).requires_grad_()
    got = actor_loss(log_prob, atoms, 0.3, lowest)
    want = ref_actor_cvar_loss(log_prob, atoms, 0.3, lowest)
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    g_got = torch.autograd.grad(got, (log_prob, atoms))
    g_want = torch.autograd.grad(want, (log_prob, atoms))
    for a, b in zip(g_got, g_want, strict=True):
        assert torch.allclose(a, b, rtol=1e-12, atol=0)
    moved = (g_got[1] != 0).reshape(3, -1).sum(1)
    assert moved.tolist() == [min(lowest, 12)] * 3  # only the lowest L atoms of each row


def test_all_atoms_is_eq_2_to_the_bit():
    gen = torch.Generator().manual_seed(5)
    log_prob, atoms = torch.randn(6, generator=gen), torch.randn(6, 5, 25, generator=gen)
    plain = actor_loss(log_prob, atoms, 0.2)
    assert torch.equal(actor_loss(log_prob, atoms, 0.2, 125), plain)
    assert torch.equal(actor_loss(log_prob, atoms, 0.2, None), plain)
    want = ref_actor_loss(log_prob.double(), atoms.double(), 0.2)
    assert plain.item() == pytest.approx(want.item(), rel=1e-6)


def test_the_objective_switches_after_its_step():
    agent = config_from_dict(cvar_dict()).agent
    assert [actor_lowest_atoms(s, agent) for s in (0, 250, 251, 10**9)] == [None, None, 4, 4]
    agent.actor_cvar = 0.01  # 0.1 atoms: at least one
    assert actor_lowest_atoms(251, agent) == 1
    agent.actor_cvar = 0.25  # 2.5 atoms: rounded half up
    assert actor_lowest_atoms(251, agent) == 3
    assert actor_lowest_atoms(10**9, config_from_dict(tiny_dict()).agent) is None


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"actor_cvar": 0.0}, "agent.actor_cvar"),
        ({"actor_cvar": 1.5}, "agent.actor_cvar"),
        ({"actor_cvar_start": -1}, "agent.actor_cvar_start"),
    ],
)
def test_config_errors_name_the_key(keys, key):
    with pytest.raises(UserError, match=rf"risk\.yaml: key '{key}' expects"):
        config_from_dict(cvar_dict(**keys), "risk.yaml")


def test_the_run_is_the_plain_run_up_to_the_start_and_resumes_exactly_across_it(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "plain")
    early = cvar_dict()
    early["train"]["total_steps"] = 250
    train(config_from_dict(early), tmp_path / "early")
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("plain", "early"))
    for name in ("actor", "critic"):
        assert_states_equal(a["agent"][name], b["agent"][name])

    data = cvar_dict()
    data["train"]["total_steps"] = 400
    straight = train(config_from_dict(data), tmp_path / "straight")
    data["train"]["total_steps"] = 230
    train(config_from_dict(data), tmp_path / "split")
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes
    s, r = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in s.items() if k != "path"}, {k: v for k, v in r.items() if k != "path"}
    )
    resume(tmp_path / "plain", total_steps=400)
    p = load_checkpoint(tmp_path / "plain" / "state.pt")
    actor_p, actor_s = p["agent"]["actor"], s["agent"]["actor"]
    assert any(not torch.equal(v, actor_s[k]) for k, v in actor_p.items())  # it changed the run


def test_a_branch_may_switch_it_on_at_its_step_but_not_before(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=200)), tmp_path / "run")
    late = cvar_dict(actor_cvar_start=200)
    late["train"]["total_steps"] = 260
    assert branch(tmp_path / "run", tmp_path / "late", config_from_dict(late)).steps == 260
    with pytest.raises(UserError, match=r"agent\.actor_cvar_start"):
        early = config_from_dict(cvar_dict(actor_cvar_start=150))
        branch(tmp_path / "run", tmp_path / "early", early)
    assert not (tmp_path / "early").exists()


def test_the_display_shows_the_objective_once_it_is_on(tmp_path):

    trainer = Trainer(config_from_dict(cvar_dict()), tmp_path / "run")
    assert trainer.snapshot(0.0)["actor_cvar"] is None  # before its step
    trainer.step = 300
    assert "actor objective  CVaR 0.4 " in stats_text(trainer.snapshot(0.0))
