# Type stub of tamias2d.pygame_util. pygame is not needed to import the
# module (nor to type-check against this stub): a surface is anything with
# get_height(), which pygame.Surface is.
from typing import Protocol, type_check_only

from .space_debug_draw_options import SpaceDebugDrawOptions

__all__ = [
    "DrawOptions",
    "get_mouse_pos",
    "to_pygame",
    "from_pygame",
    "positive_y_is_up",
]

@type_check_only
class _Surface(Protocol):
    def get_height(self) -> int: ...

positive_y_is_up: bool

def to_pygame(p: tuple[float, float], surface: _Surface) -> tuple[int, int]: ...
def from_pygame(p: tuple[float, float], surface: _Surface) -> tuple[int, int]: ...
def get_mouse_pos(surface: _Surface) -> tuple[int, int]: ...

class DrawOptions(SpaceDebugDrawOptions):
    surface: _Surface
    def __init__(self, surface: _Surface) -> None: ...
