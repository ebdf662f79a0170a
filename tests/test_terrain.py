"""Where a Hardcore fall happened: obstacle boxes classified by size, pits' walls paired, the
nearest obstacle blamed, checked on synthetic boxes and on the env's own courses."""

import gymnasium as gym
import numpy as np
import pytest

from bipedal_cli.config import AgentConfig
from bipedal_cli.evaluation import run_episodes, summarize
from bipedal_cli.terrain import (
    KINDS,
    TERRAIN_STEP,
    Span,
    classify_box,
    course_obstacles,
    fall_site,
    merge_spans,
)


def box(x, y, w, h):
    s = TERRAIN_STEP
    return [(x, y), (x + w * s, y), (x + w * s, y + h * s), (x, y + h * s)]


def test_boxes_are_classified_by_their_size_in_terrain_steps():
    assert classify_box(box(1, 2, 1, 1)).kind == "stump"
    assert classify_box(box(1, 2, 2, 2)).kind == "stump"
    assert classify_box(box(1, 2, 4, 1)).kind == "stairs"
    span = classify_box(box(1, 2, 1, 4))
    assert span.kind == "pit" and span.x0 == 1 and span.x1 == pytest.approx(1 + TERRAIN_STEP)
    assert classify_box(box(1, 2, 3, 3)) is None  # no obstacle has that size
    assert classify_box([(0, 0), (1, 1)]) is None  # the ground's edges


def test_a_pits_walls_and_a_staircases_steps_become_one_span_each():
    boxes = [Span("pit", 10.0, 10.5), Span("stump", 2.0, 2.5), Span("pit", 12.0, 12.5)]
    boxes += [Span("stairs", 20.0, 21.0), Span("stairs", 21.0, 22.0), Span("stairs", 23.0, 24.0)]
    assert merge_spans(boxes) == [
        Span("stump", 2.0, 2.5),
        Span("pit", 10.0, 12.5),
        Span("stairs", 20.0, 22.0),
        Span("stairs", 23.0, 24.0),  # a gap: another staircase
    ]


def test_the_nearest_obstacle_within_reach_is_blamed_else_flat_ground():
    course = [Span("stump", 2.0, 2.5), Span("pit", 10.0, 12.5), Span("stairs", 13.0, 15.0)]
    assert fall_site(course, 11.0) == "pit"  # inside the gap
    assert fall_site(course, 12.6) == "pit"  # 0.1 past the pit, 0.4 short of the stairs
    assert fall_site(course, 12.9) == "stairs"  # 0.1 short of the stairs, 0.4 past the pit
    assert fall_site(course, 1.0) == "stump"
    assert fall_site(course, 6.0) == "flat"
    assert fall_site([], 6.0) == "flat"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_hardcore_course_has_obstacles_that_match_its_ground_line(seed):
    env = gym.make("BipedalWalkerHardcore-v3")
    env.reset(seed=seed)
    course = env.unwrapped
    spans = course_obstacles(course)
    assert {s.kind for s in spans} <= {"stump", "stairs", "pit"} and len(spans) >= 5
    x, y = np.array(course.terrain_x), np.array(course.terrain_y)
    for pit in (s for s in spans if s.kind == "pit"):
        inside = (x > pit.x0 + 0.01) & (x < pit.x1 - TERRAIN_STEP + 0.01)  # Box2D: float32
        edge = y[np.searchsorted(x, pit.x0 - 0.01)]
        assert inside.any() and np.allclose(y[inside], edge - 4 * TERRAIN_STEP)  # the gap
    env.close()
    walker = gym.make("BipedalWalker-v3")
    walker.reset(seed=seed)
    assert course_obstacles(walker.unwrapped) == []  # the normal course has none
    walker.close()


def test_evaluation_reports_where_each_fall_happened():
    def stiff(obs):  # every joint at full torque one way: a fall within a few hundred steps
        return np.ones((len(obs), 4), dtype=np.float32)

    results = run_episodes(stiff, "BipedalWalkerHardcore-v3", [0, 1, 2], AgentConfig())
    assert all(r.fell for r in results)
    assert all(r.fell_at in KINDS for r in results)
    summary = summarize(results)
    assert sum(summary["falls_at"].values()) == summary["falls"] == 3
