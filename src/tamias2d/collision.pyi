# Type stub of tamias2d.collision (compiled).
from typing_extensions import disjoint_base

from .body import Body
from .shape import Shape
from .vector import Vec2d

__all__ = [
    "ContactPoint",
    "ContactPointSet",
    "shapes_collide",
    "relative_velocity",
    "normal_relative_velocity",
    "apply_impulse",
    "apply_impulses",
    "apply_bias_impulse",
    "apply_bias_impulses",
    "k_scalar_body",
    "k_scalar",
]

@disjoint_base
class ContactPoint:
    point_a: Vec2d
    point_b: Vec2d
    distance: float
    def __init__(self, point_a: Vec2d, point_b: Vec2d, distance: float) -> None: ...

@disjoint_base
class ContactPointSet:
    normal: Vec2d
    points: tuple[ContactPoint, ...]
    def __init__(self, normal: Vec2d, points: tuple[ContactPoint, ...]) -> None: ...

def shapes_collide(shape_a: Shape, shape_b: Shape) -> ContactPointSet: ...

# Munk2D's contact helpers (chipmunk_private.h), on Python bodies.
def relative_velocity(
    body_a: Body, body_b: Body, r1: tuple[float, float], r2: tuple[float, float]
) -> Vec2d: ...
def normal_relative_velocity(
    body_a: Body,
    body_b: Body,
    r1: tuple[float, float],
    r2: tuple[float, float],
    n: tuple[float, float],
) -> float: ...
def apply_impulse(body: Body, j: tuple[float, float], r: tuple[float, float]) -> None: ...
def apply_impulses(
    body_a: Body,
    body_b: Body,
    r1: tuple[float, float],
    r2: tuple[float, float],
    j: tuple[float, float],
) -> None: ...
def apply_bias_impulse(body: Body, j: tuple[float, float], r: tuple[float, float]) -> None: ...
def apply_bias_impulses(
    body_a: Body,
    body_b: Body,
    r1: tuple[float, float],
    r2: tuple[float, float],
    j: tuple[float, float],
) -> None: ...
def k_scalar_body(body: Body, r: tuple[float, float], n: tuple[float, float]) -> float: ...
def k_scalar(
    body_a: Body,
    body_b: Body,
    r1: tuple[float, float],
    r2: tuple[float, float],
    n: tuple[float, float],
) -> float: ...
