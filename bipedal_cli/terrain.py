"""Where on a Hardcore course the walker fell: stump, stairs, pit, or flat ground.

BipedalWalkerHardcore-v3 builds its obstacles as static boxes, measured in terrain steps
(14/30 world units): a stump is a 1x1 or 2x2 box on the ground, each step of a staircase a 4x1
box, and a pit two 1x4 walls with the gap between them; a staircase counts as one obstacle. A
fall is put down to the obstacle whose span lies nearest the hull's x when the episode ended, if
one lies within ``REACH`` world units (about the walker's length), else to flat ground. This is
a diagnostic: it says which obstacles a policy has not mastered, not why it fell.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

TERRAIN_STEP = 14 / 30  # gymnasium.envs.box2d.bipedal_walker.TERRAIN_STEP
REACH = 2.0  # world units around the hull in which an obstacle is blamed for a fall
KINDS = ("stump", "stairs", "pit", "flat")


@dataclass(frozen=True)
class Span:
    kind: str
    x0: float
    x1: float

    def distance(self, x: float) -> float:
        """0 inside the span, else the gap between ``x`` and its nearer end."""
        return max(self.x0 - x, 0.0, x - self.x1)


def classify_box(vertices: Sequence[tuple[float, float]]) -> Span | None:
    """The obstacle a terrain box belongs to, from its size in terrain steps; None for other
    shapes (the ground's edges, or boxes of a size no obstacle has)."""
    if len(vertices) != 4:
        return None
    xs, ys = [v[0] for v in vertices], [v[1] for v in vertices]
    width = round((max(xs) - min(xs)) / TERRAIN_STEP, 2)
    height = round((max(ys) - min(ys)) / TERRAIN_STEP, 2)
    kind = {(1.0, 1.0): "stump", (2.0, 2.0): "stump", (4.0, 1.0): "stairs", (1.0, 4.0): "pit"}
    found = kind.get((width, height))
    return Span(found, min(xs), max(xs)) if found else None


def merge_spans(spans: Iterable[Span]) -> list[Span]:
    """Spans sorted by x, each pit's two walls joined into one span over the gap and each
    staircase's steps (boxes that touch end to end) into one span."""
    merged: list[Span] = []
    wall: Span | None = None
    for span in sorted(spans, key=lambda s: s.x0):
        if span.kind == "pit" and wall is None:
            wall = span
            continue
        if span.kind == "pit":
            merged.append(Span("pit", wall.x0, span.x1))
            wall = None
            continue
        last = merged[-1] if merged else None
        if span.kind == "stairs" and last and last.kind == "stairs" and span.x0 - last.x1 < 1e-3:
            merged[-1] = Span("stairs", last.x0, span.x1)
            continue
        merged.append(span)
    if wall is not None:  # an unpaired wall (none on an unmodified course) is a pit of its own
        merged.append(wall)
    return sorted(merged, key=lambda s: s.x0)


def course_obstacles(unwrapped_env) -> list[Span]:
    """The obstacles of a BipedalWalker env's current course (none on the normal one)."""
    boxes = []
    for body in getattr(unwrapped_env, "terrain", []):
        for fixture in body.fixtures:
            span = classify_box([tuple(v) for v in getattr(fixture.shape, "vertices", [])])
            if span is not None:
                boxes.append(span)
    return merge_spans(boxes)


def fall_site(obstacles: Sequence[Span], hull_x: float, reach: float = REACH) -> str:
    """The kind of the obstacle nearest ``hull_x`` within ``reach``, else "flat"."""
    near = [s for s in obstacles if s.distance(hull_x) <= reach]
    return min(near, key=lambda s: s.distance(hull_x)).kind if near else "flat"
