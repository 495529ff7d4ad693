"""A typed pymunk-style program for tests/test_stubs.py.

mypy --strict must accept it with tamias2d's stubs, and assert_type pins the
types the stubs give; the test also runs it, so every line is real API.
"""
from __future__ import annotations

import math
from collections.abc import KeysView, Sequence
from typing import Any

from typing_extensions import assert_type

import tamias2d as pymunk
import tamias2d.batch
from tamias2d import errors
from tamias2d.space_debug_draw_options import SpaceDebugColor


def build() -> tuple[pymunk.Space, pymunk.Body, pymunk.Circle]:
    space = pymunk.Space()
    space.gravity = (0, -900)
    space.iterations = 20
    space.sleep_time_threshold = 0.5
    assert_type(space.gravity, pymunk.Vec2d)

    ground = pymunk.Segment(space.static_body, (-300, 0), (300, 0), 5)
    ground.friction = 1.0
    ground.filter = pymunk.ShapeFilter(categories=0b1)
    space.add(ground)

    body = pymunk.Body(1, pymunk.moment_for_circle(1, 0, 10))
    body.position = (0, 50)
    body.velocity = pymunk.Vec2d(1, 0) * 10
    ball = pymunk.Circle(body, 10, offset=(0, 0))
    ball.elasticity = 0.5
    ball.collision_type = 1
    # User attributes, as pymunk allows (and types, through TypingAttrMixing).
    ball.color = (255, 0, 0, 255)
    space.add(body, ball)

    box = pymunk.Body(2, pymunk.moment_for_box(2, (20, 20)))
    box.position = 40, 40
    poly = pymunk.Poly.create_box(box, (20, 20), radius=1)
    space.add(box, poly)
    spring = pymunk.DampedSpring(body, box, (0, 0), (0, 0), 30, 100, 1)
    pivot = pymunk.PivotJoint(space.static_body, box, (40, 80))
    pin = pymunk.PinJoint(body, box, anchor_a=(0, 0))
    space.add(spring, pivot, pin)
    return space, body, ball


def vectors() -> float:
    v = pymunk.Vec2d(3, 4)
    assert_type(v + (1, 2), pymunk.Vec2d)
    assert_type((1, 2) + v, pymunk.Vec2d)
    assert_type(v - v, pymunk.Vec2d)
    assert_type(2 * v, pymunk.Vec2d)
    assert_type(v / 2, pymunk.Vec2d)
    assert_type(-v, pymunk.Vec2d)
    assert_type(abs(v), float)
    assert_type(v.length, float)
    assert_type(v.normalized_and_length(), tuple[pymunk.Vec2d, float])
    assert_type(v.int_tuple, tuple[int, int])
    assert_type(v._replace(y=0), pymunk.Vec2d)
    x, y = v
    t = pymunk.Transform.rotation(math.pi / 2) @ pymunk.Transform.translation(1, 0)
    assert_type(t, pymunk.Transform)
    assert_type(t @ v, pymunk.Vec2d)
    bb = pymunk.BB(0, 0, 10, 10).expand((20, 5))
    assert_type(bb.center(), pymunk.Vec2d)
    return x + y + bb.area() + v.dot((1, 0)) + v.get_angle_degrees_between(pymunk.Vec2d.unit())


def run(space: pymunk.Space, body: pymunk.Body, ball: pymunk.Circle) -> list[float]:
    impulses: list[float] = []

    def begin(arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        a, b = arbiter.shapes
        assert_type(a, pymunk.Shape)
        points = arbiter.contact_point_set.points
        if points:
            assert_type(points[0].point_a, pymunk.Vec2d)
        arbiter.process_collision = True

    def post_solve(arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        impulses.append(arbiter.total_impulse.length)

    space.on_collision(1, None, begin=begin, post_solve=post_solve, data={"n": 0})
    space.on_collision(separate=pymunk.empty_callback)

    def gravity_off(b: pymunk.Body, gravity: pymunk.Vec2d, damping: float, dt: float) -> None:
        pymunk.Body.update_velocity(b, (0, 0), damping, dt)

    body.velocity_func = gravity_off
    body.velocity_func = None  # the built-in integrator again
    space.add_post_step_callback(lambda s, key: None, "once")
    for _ in range(60):
        space.step(1 / 60)
    assert_type(space.bodies, KeysView[pymunk.Body])
    return impulses


def queries(space: pymunk.Space) -> int:
    hits = space.point_query((0, 0), 20, pymunk.ShapeFilter())
    assert_type(hits, list[pymunk.PointQueryInfo])
    nearest = space.point_query_nearest((0, 0), 100, pymunk.ShapeFilter())
    if nearest is not None:
        assert_type(nearest.shape, pymunk.Shape)
        assert_type(nearest.distance, float)
    first = space.segment_query_first((0, 100), (0, -100), 0, pymunk.ShapeFilter())
    if first is not None:
        assert_type(first.normal, pymunk.Vec2d)
    shapes = space.bb_query(pymunk.BB(-50, -50, 50, 50), pymunk.ShapeFilter())
    for info in space.shape_query(pymunk.Circle(None, 5)):
        assert_type(info.contact_point_set, pymunk.ContactPointSet)
    return len(hits) + len(shapes)


def batch(space: pymunk.Space) -> float:
    positions = tamias2d.batch.get_bodies(space, ("position", "angle"))
    tamias2d.batch.set_bodies(space, positions, ("position", "angle"))
    arbiters = tamias2d.batch.get_arbiters(space, ["total_ke"])
    return float(positions.sum()) + float(len(arbiters))


def errors_and_drawing(space: pymunk.Space) -> str:
    try:
        pymunk.Body(-1, 1)
    except errors.IllegalBody as e:
        message = str(e)

    class Recorder(pymunk.SpaceDebugDrawOptions):
        drawn = 0

        def draw_circle(
            self,
            pos: pymunk.Vec2d,
            angle: float,
            radius: float,
            outline_color: SpaceDebugColor,
            fill_color: SpaceDebugColor,
        ) -> None:
            self.drawn += 1

        def draw_fat_segment(
            self,
            a: pymunk.Vec2d,
            b: pymunk.Vec2d,
            radius: float,
            outline_color: SpaceDebugColor,
            fill_color: SpaceDebugColor,
        ) -> None:
            self.drawn += 1

        def draw_polygon(
            self,
            verts: Sequence[pymunk.Vec2d],
            radius: float,
            outline_color: SpaceDebugColor,
            fill_color: SpaceDebugColor,
        ) -> None:
            self.drawn += 1

    options = Recorder()
    options.flags = pymunk.SpaceDebugDrawOptions.DRAW_SHAPES
    space.debug_draw(options)
    assert options.drawn == 3
    return message


def main() -> None:
    space, body, ball = build()
    vectors()
    run(space, body, ball)
    queries(space)
    batch(space)
    errors_and_drawing(space)
    copy = space.copy()
    assert_type(copy, pymunk.Space)
    assert_type(body.copy(), pymunk.Body)


if __name__ == "__main__":
    main()
