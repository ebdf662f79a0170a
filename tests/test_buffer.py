import numpy as np
import pytest

from bipedal_cli.buffer import ReplayBuffer


def fill(buf, n, start=0):
    for i in range(start, start + n):
        buf.add(np.full(3, i), np.full(2, -i), float(i), np.full(3, i + 1), i % 7 == 0)


def test_ring_buffer_wraps_around_and_keeps_the_newest():
    buf = ReplayBuffer(5, 3, 2)
    fill(buf, 8)  # 0..7; the newest five are 3..7
    assert len(buf) == 5 and buf.pos == 3
    assert sorted(buf.reward.tolist()) == [3.0, 4.0, 5.0, 6.0, 7.0]
    assert buf.obs[0, 0] == 5 and buf.next_obs[0, 0] == 6 and buf.action[0, 0] == -5
    assert buf.terminated[buf.reward == 7.0][0] == 1.0


def test_sample_draws_only_filled_slots():
    buf = ReplayBuffer(100, 3, 2)
    fill(buf, 10)
    batch = buf.sample(500, np.random.default_rng(0))
    assert batch["obs"].shape == (500, 3) and batch["obs"].dtype == np.float32
    assert set(batch["reward"].tolist()) <= set(range(10))
    assert np.all(batch["next_obs"][:, 0] == batch["reward"] + 1)


def test_state_round_trip_samples_identically():
    a, b = ReplayBuffer(6, 3, 2), ReplayBuffer(6, 3, 2)
    fill(a, 9)
    b.load_state_dict(a.state_dict())
    ra, rb = np.random.default_rng(1), np.random.default_rng(1)
    for _ in range(3):
        x, y = a.sample(4, ra), b.sample(4, rb)
        assert all(np.array_equal(x[k], y[k]) for k in x)
    fill(a, 2, 100)
    fill(b, 2, 100)
    assert np.array_equal(a.reward, b.reward)


def test_empty_buffer_refuses_to_sample():
    with pytest.raises(ValueError):
        ReplayBuffer(3, 1, 1).sample(1, np.random.default_rng(0))
