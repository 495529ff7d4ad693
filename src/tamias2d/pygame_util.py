"""Draw a space on a pygame (or pygame-ce) surface, for quick prototypes.

Same API as ``pymunk.pygame_util``: :class:`DrawOptions`,
:data:`positive_y_is_up`, :func:`to_pygame`, :func:`from_pygame` and
:func:`get_mouse_pos`. Importing this module does not need pygame; drawing
and reading the mouse do (``pip install pygame`` or ``pygame-ce``).

>>> class Surface:                 # anything with get_height() will do
...     def get_height(self):
...         return 100
>>> to_pygame((10.4, 20.6), Surface())
(10, 21)
"""
__docformat__ = "reStructuredText"

__all__ = [
    "DrawOptions",
    "get_mouse_pos",
    "to_pygame",
    "from_pygame",
    "positive_y_is_up",
]

import math

from .space_debug_draw_options import SpaceDebugDrawOptions

positive_y_is_up: bool = False
"""Flip drawing so that increasing y points up (True) or down (False, the
default, pygame's own orientation). It changes drawing and the conversion
functions, not the simulation."""


def _pygame():
    """Import pygame on first use, with a clear message when it is missing."""
    try:
        import pygame
    except ImportError as exc:
        raise ImportError(
            "tamias2d.pygame_util needs pygame: pip install pygame "
            "(or pip install pygame-ce)"
        ) from exc
    return pygame


def to_pygame(p, surface):
    """A point in physics coordinates -> integer surface coordinates.

    With :data:`positive_y_is_up` False it only rounds; when True it also
    flips y against ``surface.get_height()``.

    >>> class Surface:
    ...     def get_height(self):
    ...         return 100
    >>> to_pygame((1.2, 3.7), Surface())
    (1, 4)
    """
    if positive_y_is_up:
        return round(p[0]), surface.get_height() - round(p[1])
    return round(p[0]), round(p[1])


def from_pygame(p, surface):
    """Integer surface coordinates -> physics coordinates (the flip is its
    own inverse, so this is :func:`to_pygame` again).

    >>> class Surface:
    ...     def get_height(self):
    ...         return 100
    >>> from_pygame((5, 6), Surface())
    (5, 6)
    """
    return to_pygame(p, surface)


def get_mouse_pos(surface):
    """The mouse position in physics coordinates (needs pygame).

    >>> x, y = get_mouse_pos(screen)  # doctest: +SKIP
    """
    pygame = _pygame()
    return from_pygame(pygame.mouse.get_pos(), surface)


class DrawOptions(SpaceDebugDrawOptions):
    """Debug drawing on a pygame.Surface.

    Positions go through :func:`to_pygame`, so set the module's
    :data:`positive_y_is_up` to True to draw a y-up simulation the right way
    up. A shape's ``color`` attribute (for example a pygame.Color) sets its
    fill colour.

    :param surface: the pygame.Surface to draw on.

    >>> import pygame, tamias2d                          # doctest: +SKIP
    >>> screen = pygame.Surface((200, 100))              # doctest: +SKIP
    >>> options = DrawOptions(screen)                    # doctest: +SKIP
    >>> tamias2d.Space().debug_draw(options)             # doctest: +SKIP
    """

    def __init__(self, surface) -> None:
        self._pg = _pygame()
        self.surface = surface
        super().__init__()

    def draw_circle(self, pos, angle, radius, outline_color, fill_color):
        """A filled circle with a line from the centre showing its angle."""
        draw = self._pg.draw
        p = to_pygame(pos, self.surface)
        draw.circle(self.surface, fill_color.as_int(), p, round(radius), 0)
        edge = (pos[0] + radius * math.cos(angle), pos[1] + radius * math.sin(angle))
        width = 2 if radius > 20 else 1
        draw.lines(self.surface, outline_color.as_int(), False,
                   [p, to_pygame(edge, self.surface)], width)

    def draw_segment(self, a, b, color):
        """An antialiased thin line."""
        self._pg.draw.aalines(self.surface, color.as_int(), False,
                              [to_pygame(a, self.surface), to_pygame(b, self.surface)])

    def draw_fat_segment(self, a, b, radius, outline_color, fill_color):
        """A thick segment with round ends."""
        draw = self._pg.draw
        color = fill_color.as_int()
        p1 = to_pygame(a, self.surface)
        p2 = to_pygame(b, self.surface)
        r = abs(radius)
        if r < 1:
            draw.line(self.surface, color, p1, p2, 1)
            return
        dx = p2[0] - p1[0]
        dy = p2[1] - p1[1]
        length = math.hypot(dx, dy)
        if length > 0:
            # The body of the segment is a quad 2r wide around p1-p2.
            nx = -dy / length * r
            ny = dx / length * r
            draw.polygon(self.surface, color, [
                (p1[0] + nx, p1[1] + ny), (p2[0] + nx, p2[1] + ny),
                (p2[0] - nx, p2[1] - ny), (p1[0] - nx, p1[1] - ny),
            ])
        draw.circle(self.surface, color, p1, round(r))
        draw.circle(self.surface, color, p2, round(r))

    def draw_polygon(self, verts, radius, outline_color, fill_color):
        """A filled polygon; a positive radius adds rounded edges in the
        outline colour."""
        points = [to_pygame(v, self.surface) for v in verts]
        points.append(points[0])
        self._pg.draw.polygon(self.surface, fill_color.as_int(), points)
        if radius > 0:
            n = len(verts)
            for i in range(n):
                self.draw_fat_segment(verts[i], verts[(i + 1) % n], radius,
                                      outline_color, outline_color)

    def draw_dot(self, size, pos, color):
        """A filled dot of radius size pixels."""
        self._pg.draw.circle(self.surface, color.as_int(),
                             to_pygame(pos, self.surface), round(size), 0)
