# Type stub of tamias2d.space_debug_draw_options.
from collections.abc import Sequence
from types import TracebackType
from typing import ClassVar, NamedTuple

from .shape import Shape
from .vector import Transform, Vec2d

__all__ = ["SpaceDebugColor", "SpaceDebugDrawOptions"]

class SpaceDebugColor(NamedTuple):
    r: float
    g: float
    b: float
    a: float
    def as_int(self) -> tuple[int, int, int, int]: ...
    def as_float(self) -> tuple[float, float, float, float]: ...

class SpaceDebugDrawOptions:
    DRAW_SHAPES: ClassVar[int]
    DRAW_CONSTRAINTS: ClassVar[int]
    DRAW_COLLISION_POINTS: ClassVar[int]
    shape_dynamic_color: SpaceDebugColor
    shape_static_color: SpaceDebugColor
    shape_kinematic_color: SpaceDebugColor
    shape_sleeping_color: SpaceDebugColor
    def __init__(self) -> None: ...
    @property
    def flags(self) -> int: ...
    @flags.setter
    def flags(self, f: int) -> None: ...
    # Any six numbers (a, b, c, d, tx, ty) are accepted; reading gives a Transform.
    @property
    def transform(self) -> Transform: ...
    @transform.setter
    def transform(self, t: tuple[float, float, float, float, float, float]) -> None: ...
    # Any four numbers (r, g, b, a) are accepted; reading gives a SpaceDebugColor.
    @property
    def shape_outline_color(self) -> SpaceDebugColor: ...
    @shape_outline_color.setter
    def shape_outline_color(self, c: tuple[float, float, float, float]) -> None: ...
    @property
    def constraint_color(self) -> SpaceDebugColor: ...
    @constraint_color.setter
    def constraint_color(self, c: tuple[float, float, float, float]) -> None: ...
    @property
    def collision_point_color(self) -> SpaceDebugColor: ...
    @collision_point_color.setter
    def collision_point_color(self, c: tuple[float, float, float, float]) -> None: ...
    def __enter__(self) -> None: ...
    def __exit__(
        self,
        type: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None: ...
    def draw_circle(
        self,
        pos: Vec2d,
        angle: float,
        radius: float,
        outline_color: SpaceDebugColor,
        fill_color: SpaceDebugColor,
    ) -> None: ...
    def draw_segment(self, a: Vec2d, b: Vec2d, color: SpaceDebugColor) -> None: ...
    def draw_fat_segment(
        self,
        a: Vec2d,
        b: Vec2d,
        radius: float,
        outline_color: SpaceDebugColor,
        fill_color: SpaceDebugColor,
    ) -> None: ...
    def draw_polygon(
        self,
        verts: Sequence[Vec2d],
        radius: float,
        outline_color: SpaceDebugColor,
        fill_color: SpaceDebugColor,
    ) -> None: ...
    def draw_dot(self, size: float, pos: Vec2d, color: SpaceDebugColor) -> None: ...
    def draw_shape(self, shape: Shape) -> None: ...
    def color_for_shape(self, shape: Shape) -> SpaceDebugColor: ...
