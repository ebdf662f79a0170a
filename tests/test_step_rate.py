"""The display's clock and rate (``training_loop.WallClock`` and ``StepRate``) on a fake clock:
the wall time adds earlier sessions' seconds, and the rate follows the current window."""

from __future__ import annotations

import pytest

from bipedal_cli import training_loop
from bipedal_cli.training_loop import StepRate, WallClock


class FakeClock:
    """``time.perf_counter`` that moves only when told to."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> FakeClock:
    fake = FakeClock()
    monkeypatch.setattr(training_loop.time, "perf_counter", fake)
    return fake


def test_wall_clock_adds_earlier_sessions(clock: FakeClock) -> None:
    wall = WallClock(earlier_s=3600.0)
    assert wall() == 3600.0
    clock.now += 12.5
    assert wall() == 3612.5


def test_step_rate_is_steps_over_seconds_in_the_window(clock: FakeClock) -> None:
    rate = StepRate(step=1000, window_s=5.0)
    clock.now += 2.0
    assert rate.update(1100) == pytest.approx(50.0)
    clock.now += 2.0  # 4 s into the window: still measured from its start
    assert rate.update(1400) == pytest.approx(100.0)
    assert rate.per_s == pytest.approx(100.0)


def test_step_rate_restarts_its_window_so_it_follows_the_current_speed(clock: FakeClock) -> None:
    rate = StepRate(step=0, window_s=5.0)
    clock.now += 6.0
    assert rate.update(600) == pytest.approx(100.0)  # past the window: it restarts here
    clock.now += 2.0
    assert rate.update(640) == pytest.approx(20.0)  # the new window's speed alone


def test_step_rate_with_no_time_passed_is_finite(clock: FakeClock) -> None:
    rate = StepRate(step=10)
    assert rate.update(10) == 0.0
    assert rate.update(11) > 0.0  # a step in no measurable time: large, finite, not an error
