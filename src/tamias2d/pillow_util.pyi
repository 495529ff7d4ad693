# Type stub of tamias2d.pillow_util (needs Pillow).
from collections.abc import Iterable, Sequence
from os import PathLike
from types import TracebackType
from typing import Union

from PIL import Image

from .space_debug_draw_options import SpaceDebugColor, SpaceDebugDrawOptions
from .vector import Vec2d

__all__ = ["DrawOptions", "PillowDrawing", "GifWriter", "save_gif", "bb_transform"]

# A BB or any (left, bottom, right, top).
_BBLike = tuple[float, float, float, float]
_Path = Union[str, bytes, PathLike[str], PathLike[bytes]]

def bb_transform(
    bb: _BBLike, size: tuple[float, float], margin: float = 0
) -> tuple[float, float, float, float, float, float]: ...

class PillowDrawing:
    positive_y_is_up: bool
    background: SpaceDebugColor
    line_width: float
    segment_width: float
    supersample: int
    def __init__(
        self,
        image_or_size: Image.Image | tuple[int, int] = (640, 480),
        bb: _BBLike | None = None,
        *,
        positive_y_is_up: bool = True,
        background: tuple[float, float, float, float] = (255, 255, 255, 255),
        margin: float = 0,
        supersample: int = 1,
        line_width: float = 1.0,
        segment_width: float | None = None,
    ) -> None: ...
    @property
    def size(self) -> tuple[int, int]: ...
    def fit(self, bb: _BBLike, margin: float = 0) -> None: ...
    def to_image(self, p: tuple[float, float]) -> tuple[float, float]: ...
    def from_image(self, p: tuple[float, float]) -> tuple[float, float]: ...
    @property
    def image(self) -> Image.Image: ...
    def clear(self, color: tuple[float, float, float, float] | None = None) -> None: ...
    # Writes a supersampled drawing back into the image (Space.debug_draw
    # enters and exits the options around a drawing).
    def __exit__(
        self,
        type: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None: ...
    # The same signatures as SpaceDebugDrawOptions' methods.
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

class DrawOptions(PillowDrawing, SpaceDebugDrawOptions): ...

class GifWriter:
    duration: float
    loop: int
    frames: list[Image.Image]
    def __init__(self, duration: float = 40, loop: int = 0) -> None: ...
    def __len__(self) -> int: ...
    def add(self, image: Image.Image) -> None: ...
    def save(self, path: _Path) -> None: ...

def save_gif(
    frames: Iterable[Image.Image], path: _Path, duration: float = 40, loop: int = 0
) -> None: ...
