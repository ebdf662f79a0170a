"""The episode progress of ``eval`` and ``select``: a live bar, or plain lines in a log."""

import io

from rich.console import Console

from bipedal_cli.episode_progress import episode_progress, progress_line


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_progress_line_states_the_count_the_time_and_the_time_left():
    assert progress_line("held-out", 150, 600, 90.0) == (
        "held-out: 150/600 episodes (25%), 1.5 min, about 4.5 min left"
    )
    assert progress_line("evaluating", 0, 100, 5.0) == "evaluating: 0/100 episodes (0%), 0.1 min"
    assert progress_line("evaluating", 100, 100, 60.0) == (
        "evaluating: 100/100 episodes (100%), 1.0 min"
    )


def test_a_log_file_gets_a_line_every_interval_and_one_at_the_end():
    out, clock = io.StringIO(), FakeClock()
    console = Console(file=out, force_terminal=False, width=200)
    with episode_progress(console, "held-out", 40, line_every_s=30.0, clock=clock) as advance:
        for _ in range(8):  # chunks of 5 episodes, 10 s apart
            clock.now += 10.0
            advance(5)
    lines = out.getvalue().splitlines()
    assert lines == [
        "held-out: 15/40 episodes (38%), 0.5 min, about 0.8 min left",
        "held-out: 30/40 episodes (75%), 1.0 min, about 0.3 min left",
        "held-out: 40/40 episodes (100%), 1.3 min",
    ]


def test_a_terminal_gets_the_live_bar_and_no_lines():
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=100)
    with episode_progress(console, "evaluating", 3) as advance:
        advance(2)
        advance(1)
    text = out.getvalue()
    assert "3/3" in text and "episodes (" not in text
