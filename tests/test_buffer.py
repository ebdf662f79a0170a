import numpy as np
import pytest

from bipedal_cli.buffer import ReplayBuffer, fits_resized


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


@pytest.mark.parametrize("new_capacity", [4, 5, 9])
def test_a_ring_that_never_wrapped_loads_into_another_capacity_as_that_ring_would_hold_it(
    new_capacity,
):
    small = ReplayBuffer(6, 3, 2)
    fill(small, 4)
    resized, direct = ReplayBuffer(new_capacity, 3, 2), ReplayBuffer(new_capacity, 3, 2)
    resized.load_state_dict(small.state_dict())
    fill(direct, 4)
    fill(resized, 3, start=4)  # and they go on alike, wrapping where the new capacity says
    fill(direct, 3, start=4)
    assert (resized.size, resized.pos) == (direct.size, direct.pos)
    for name in direct.fields:
        assert np.array_equal(getattr(resized, name), getattr(direct, name)), name


def test_a_ring_that_wrapped_or_does_not_fit_refuses_another_capacity():
    assert fits_resized(4, 4, 6, 4) and not fits_resized(4, 4, 6, 3)
    assert not fits_resized(6, 0, 6, 10)  # full at position 0: it may have wrapped
    wrapped = ReplayBuffer(5, 3, 2)
    fill(wrapped, 7)
    assert not fits_resized(wrapped.size, wrapped.pos, 5, 10)
    with pytest.raises(ValueError, match="has wrapped or does not fit capacity 10"):
        ReplayBuffer(10, 3, 2).load_state_dict(wrapped.state_dict())
