"""The LSTM window encoder against the LSTM equations written out in float64 (values and
gradients), its reading of ObservationHistory's window in time order, and its place in the
actor and the critics."""

import numpy as np
import pytest
import torch

from bipedal_cli.config import AgentConfig, config_from_dict
from bipedal_cli.encoders import WindowLSTM, make_encoder
from bipedal_cli.envs import make_env
from bipedal_cli.errors import UserError
from bipedal_cli.networks import make_actor, make_critics

H, F, W = 5, 3, 4  # window length, observation size, LSTM width


def sigmoid(x: torch.Tensor) -> torch.Tensor:
    return 1.0 / (1.0 + torch.exp(-x))


def reference_lstm(frames: list[torch.Tensor], lstm: torch.nn.LSTM) -> torch.Tensor:
    """h_H of the LSTM equations, one gate at a time from the weight rows (i, f, g, o), h_0 = c_0
    = 0; frames[s]: (B, F), oldest first. Returns [h_H, frames[-1]]: (B, W + F)."""
    w_ih, w_hh = lstm.weight_ih_l0, lstm.weight_hh_l0  # (4W, F), (4W, W)
    b_ih, b_hh = lstm.bias_ih_l0, lstm.bias_hh_l0  # (4W,) each
    width = w_hh.shape[1]

    def gate(k: int, x: torch.Tensor, h: torch.Tensor) -> torch.Tensor:
        rows = slice(k * width, (k + 1) * width)
        return x @ w_ih[rows].T + b_ih[rows] + h @ w_hh[rows].T + b_hh[rows]

    batch = frames[0].shape[0]
    h = torch.zeros(batch, width, dtype=frames[0].dtype)
    c = torch.zeros(batch, width, dtype=frames[0].dtype)
    for x in frames:
        i, f = sigmoid(gate(0, x, h)), sigmoid(gate(1, x, h))
        g, o = torch.tanh(gate(2, x, h)), sigmoid(gate(3, x, h))
        c = f * c + i * g
        h = o * torch.tanh(c)
    return torch.cat([h, frames[-1]], dim=-1)


def test_window_lstm_equals_the_equations_in_values_and_gradients():
    torch.manual_seed(0)
    enc = WindowLSTM(H, F, W).double()
    window = torch.randn(7, H * F, dtype=torch.float64, requires_grad=True)
    out = enc(window)
    frames = [window[:, s * F : (s + 1) * F] for s in range(H)]
    want = reference_lstm(frames, enc.lstm)
    assert out.shape == (7, W + F)
    torch.testing.assert_close(out, want, rtol=1e-12, atol=1e-12)
    weights = torch.randn(7, W + F, dtype=torch.float64)  # a loss that weighs every output
    params = [window, *enc.parameters()]
    got = torch.autograd.grad((out * weights).sum(), params)
    ref = torch.autograd.grad((want * weights).sum(), params)
    for g, r in zip(got, ref, strict=True):
        torch.testing.assert_close(g, r, rtol=1e-10, atol=1e-12)
    assert all(g.abs().sum() > 0 for g in got)


def test_the_encoder_reads_the_env_window_oldest_first():
    """ObservationHistory's stacked vector, fed to the encoder, is the LSTM run over the raw
    observations in the order the env produced them (the first one repeated at reset)."""
    torch.manual_seed(0)
    enc = WindowLSTM(4, 24, 6).double()
    env, plain = make_env("BipedalWalker-v3", history=4), make_env("BipedalWalker-v3")
    stacked, _ = env.reset(seed=3)
    seen = [plain.reset(seed=3)[0]] * 4
    rng = np.random.default_rng(0)
    for _ in range(6):  # the same actions in both: the plain env's observations are the window's
        action = rng.uniform(-1, 1, 4).astype(np.float32)
        stacked, *_ = env.step(action)
        seen.append(plain.step(action)[0])
    env.close()
    plain.close()
    frames = [torch.as_tensor(o, dtype=torch.float64)[None] for o in seen[-4:]]
    got = enc(torch.as_tensor(stacked, dtype=torch.float64)[None])
    torch.testing.assert_close(got, reference_lstm(frames, enc.lstm), rtol=1e-12, atol=1e-12)
    shuffled = reference_lstm(frames[::-1], enc.lstm)
    assert not torch.allclose(got, shuffled)  # the order matters, so the test can fail


def lstm_config(**agent) -> AgentConfig:
    keys = dict(history=H, encoder="lstm", encoder_hidden=W, actor_hidden=8, critic_hidden=8)
    return AgentConfig(**{**keys, **agent})


def test_the_actor_reads_the_encoding_and_trains_its_encoder():
    torch.manual_seed(0)
    actor = make_actor(lstm_config(), H * F, 2).double()
    obs = torch.randn(6, H * F, dtype=torch.float64)
    frames = [obs[:, s * F : (s + 1) * F] for s in range(H)]
    mean = actor.net(reference_lstm(frames, actor.encoder.lstm))[:, 0, :2]
    torch.testing.assert_close(actor.deterministic(obs), torch.tanh(mean))
    action, log_prob = actor.sample(obs)
    (action.sum() + log_prob.sum()).backward()
    assert all(p.grad is not None and p.grad.abs().sum() > 0 for p in actor.encoder.parameters())


def test_the_critics_share_one_encoder_and_detached_params_give_the_action_gradient_only():
    torch.manual_seed(0)
    critics = make_critics(lstm_config(n_critics=3, n_quantiles=5), H * F, 2).double()
    assert sum(1 for m in critics.modules() if isinstance(m, torch.nn.LSTM)) == 1
    obs = torch.randn(6, H * F, dtype=torch.float64)
    act = torch.randn(6, 2, dtype=torch.float64, requires_grad=True)
    frames = [obs[:, s * F : (s + 1) * F] for s in range(H)]
    want = critics.net(torch.cat([reference_lstm(frames, critics.encoder.lstm), act], -1))
    atoms = critics(obs, act, detach_params=True)
    assert atoms.shape == (6, 3, 5)
    torch.testing.assert_close(atoms, want)
    (g_detached,) = torch.autograd.grad(atoms.sum(), act)
    assert all(p.grad is None for p in critics.parameters())
    (g_full,) = torch.autograd.grad(critics(obs, act).sum(), act)
    torch.testing.assert_close(g_detached, g_full)
    critics(obs, act).sum().backward()
    assert all(p.grad.abs().sum() > 0 for p in critics.encoder.parameters())


def test_no_encoder_keeps_the_flat_networks_and_their_weights_names():
    cfg = AgentConfig(history=4)
    assert make_encoder(cfg, 96) is None
    names = set(make_actor(cfg, 96, 4).state_dict())
    assert names == {n for n in names if n.startswith("net.")}
    lstm_names = set(make_actor(AgentConfig(history=4, encoder="lstm"), 96, 4).state_dict())
    assert {n for n in lstm_names if n.startswith("encoder.")}


@pytest.mark.parametrize(
    "agent, needle",
    [
        ({"encoder": "gru"}, "agent.encoder"),
        ({"encoder": "lstm", "encoder_hidden": 0}, "agent.encoder_hidden"),
    ],
)
def test_a_bad_encoder_is_one_line_naming_the_key(agent, needle):
    with pytest.raises(UserError, match=needle) as err:
        config_from_dict({"agent": agent}, "cfg.yaml")
    assert "\n" not in str(err.value) and "cfg.yaml" in str(err.value)
