import math

import torch

from bipedal_cli.networks import DenseEnsemble, QuantileCritics, SquashedGaussianActor


def explicit_d2rl(net: DenseEnsemble, x: torch.Tensor, member: int) -> torch.Tensor:
    """The D2RL MLP of one member written with torch.cat, as in the D2RL paper's code."""
    E, H, L = net.ensemble, net.hidden, net.n_layers
    w_x = [w.view(net.in_dim, E, H)[:, member] for w in net.w_x]  # (in, H) each
    h = torch.relu(x @ w_x[0] + net.b[0][member, 0])
    for layer in range(1, L):
        w_h = net.w_h[layer - 1][member]
        if net.d2rl:
            w = torch.cat([w_h, w_x[layer]], dim=0)  # rows for [h, x]
            h = torch.relu(torch.cat([h, x], dim=1) @ w + net.b[layer][member, 0])
        else:
            h = torch.relu(h @ w_h + net.b[layer][member, 0])
    return h @ net.w_out[member] + net.b_out[member, 0]


def test_dense_ensemble_equals_explicit_concatenation_per_member():
    torch.manual_seed(0)
    for d2rl in (True, False):
        for layers in (1, 2, 4):
            net = DenseEnsemble(7, 3, 16, layers, ensemble=3, d2rl=d2rl)
            x = torch.randn(5, 7)
            out = net(x)
            assert out.shape == (5, 3, 3)
            for member in range(3):
                assert torch.allclose(out[:, member], explicit_d2rl(net, x, member), atol=1e-5)


def test_d2rl_input_reaches_every_hidden_layer():
    torch.manual_seed(0)
    for d2rl in (True, False):
        net = DenseEnsemble(4, 1, 8, 3, ensemble=1, d2rl=d2rl)
        with torch.no_grad():
            net.b[0].fill_(-1e3)  # layer 1 outputs zeros: only the dense links carry x on
        x = torch.randn(6, 4, requires_grad=True)
        net(x).sum().backward()
        if d2rl:
            assert x.grad.abs().sum() > 0
        else:
            assert torch.all(x.grad == 0)


def test_init_matches_nn_linear_bounds():
    net = DenseEnsemble(24, 8, 512, 2, ensemble=1, d2rl=True)
    assert net.w_x[0].abs().max() <= 1 / math.sqrt(24) + 1e-7
    assert net.w_x[1].abs().max() <= 1 / math.sqrt(512 + 24) + 1e-7
    assert net.w_x[1].abs().max() > 0.9 / math.sqrt(512 + 24)
    assert net.w_h[0].abs().max() <= 1 / math.sqrt(512 + 24) + 1e-7
    assert net.w_out.abs().max() <= 1 / math.sqrt(512) + 1e-7


def test_squashed_gaussian_log_prob_matches_numerical_density():
    torch.manual_seed(0)
    actor = SquashedGaussianActor(5, 3, hidden=16).double()
    obs = torch.randn(200, 5, dtype=torch.float64)
    action, log_prob = actor.sample(obs)
    mean, log_std = actor.distribution_params(obs)
    u = torch.atanh(action.clamp(-1 + 1e-12, 1 - 1e-12))
    # density of a = tanh(u): p_u(u) / |da/du| with the derivative taken by central differences
    h = 1e-6
    dadu = (torch.tanh(u + h) - torch.tanh(u - h)) / (2 * h)
    normal = torch.distributions.Normal(mean, log_std.exp())
    numeric = (normal.log_prob(u) - torch.log(dadu)).sum(-1)
    ok = action.abs().max(dim=1).values < 0.999  # atanh is ill-conditioned at the edges
    assert ok.sum() > 100
    assert torch.allclose(log_prob[ok], numeric[ok], atol=1e-4)


def test_deterministic_action_is_tanh_of_the_gaussian_mean_set_by_hand():
    """Zero weights: the network outputs its last bias, so mu = b_out[:A] whatever the input,
    and the deterministic action is tanh(mu), known without running any of our code."""
    actor = SquashedGaussianActor(24, 4, hidden=8)
    with torch.no_grad():
        for p in actor.parameters():
            p.zero_()
        actor.net.b_out[0, 0] = torch.tensor([0.5, -2.0, 30.0, 0.0, 1.0, 1.0, 1.0, 1.0])
    obs = torch.randn(10, 24) * 100
    want = torch.tensor([math.tanh(0.5), math.tanh(-2.0), 1.0, 0.0]).expand(10, 4)
    assert torch.allclose(actor.deterministic(obs), want, atol=1e-7)
    action, log_prob = actor.sample(obs)  # sampled actions stay inside [-1, 1]
    assert action.abs().max() <= 1 and torch.isfinite(log_prob).all()
    assert not torch.allclose(action, want)


def test_critics_output_shape_and_detached_params_give_input_gradient_only():
    critics = QuantileCritics(24, 4, hidden=16, n_critics=5, n_quantiles=25)
    obs, act = torch.randn(8, 24), torch.randn(8, 4, requires_grad=True)
    atoms = critics(obs, act, detach_params=True)
    assert atoms.shape == (8, 5, 25)
    atoms.mean().backward()
    assert act.grad is not None and act.grad.abs().sum() > 0
    assert all(p.grad is None for p in critics.parameters())
    assert torch.equal(atoms, critics(obs, act))
