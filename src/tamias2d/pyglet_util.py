"""Draw a space with pyglet 2 (pymunk's ``pymunk.pyglet_util``), for quick
prototypes and debugging.

:class:`DrawOptions` turns each primitive of ``space.debug_draw`` into
``pyglet.shapes`` objects in a ``pyglet.graphics.Batch``: a circle is a
``Circle`` with a ``Line`` over it showing its angle, a segment a ``Line``,
a fat segment a ``Polygon`` quad between two ``Circle`` caps, a polygon a
``Polygon`` (with fat-segment edges when it has a radius), a dot a
``Circle``. Coordinates are the space's own (pyglet's y axis points up).

Without a batch of your own, ``space.debug_draw`` fills a new batch and draws
it at the end; with ``DrawOptions(batch=my_batch)`` the shapes go into your
batch and you draw it. The shapes are kept in ``options.draw_shapes`` until
the next ``debug_draw``, since pyglet drops a shape that is garbage collected.

>>> options = DrawOptions()
>>> options.flags == DrawOptions.DRAW_SHAPES | DrawOptions.DRAW_CONSTRAINTS | \\
...     DrawOptions.DRAW_COLLISION_POINTS
True
>>> import tamias2d                                 # doctest: +SKIP
>>> window = pyglet.window.Window()                 # doctest: +SKIP
>>> space = tamias2d.Space()                        # doctest: +SKIP
>>> @window.event                                   # doctest: +SKIP
... def on_draw():
...     window.clear()
...     space.debug_draw(options)

pyglet 2.1 or later is needed (``pip install 'tamias2d[draw]'`` or ``pip
install pyglet``); it is imported with this module
(only its top level: nothing opens a window or a GL context until drawing).
"""
__docformat__ = "reStructuredText"

import math
from typing import Any

try:
    import pyglet
except ModuleNotFoundError as _missing:  # pragma: no cover - only without pyglet
    raise ModuleNotFoundError("tamias2d.pyglet_util needs pyglet 2: pip install pyglet",
                              name="pyglet") from _missing

if str(getattr(pyglet, "version", "2")).startswith("1."):
    raise ImportError(f"tamias2d.pyglet_util needs pyglet 2, found pyglet {pyglet.version}")

from .space_debug_draw_options import SpaceDebugDrawOptions
from .vector import Vec2d

__all__ = ["DrawOptions"]


class DrawOptions(SpaceDebugDrawOptions):
    """Debug drawing with ``pyglet.shapes`` into a batch.

    :param batch: an optional ``pyglet.graphics.Batch`` (keyword only, as in
        pymunk). Without it each ``space.debug_draw`` makes a new batch and
        draws it; with it, drawing the batch is up to you.

    A shape's ``color`` attribute sets its fill colour, as (r, g, b, a) in
    0..255.
    """

    def __init__(self, **kwargs) -> None:
        self.new_batch = "batch" not in kwargs
        # a batch of our own is made in __enter__, once per debug_draw
        self.batch: Any = None if self.new_batch else kwargs["batch"]
        self.draw_shapes: list[Any] = []
        super().__init__()

    def __enter__(self) -> None:
        self.draw_shapes = []
        if self.new_batch:
            self.batch = pyglet.graphics.Batch()

    def __exit__(self, type, value, traceback) -> None:
        if self.new_batch:
            self.batch.draw()

    def draw_circle(self, pos, angle, radius, outline_color, fill_color):
        """A filled circle, and over it (a later group) a line from the
        centre along ``angle``."""
        below = pyglet.graphics.Group(0)
        above = pyglet.graphics.Group(1)
        x, y = pos[0], pos[1]
        self.draw_shapes.append(pyglet.shapes.Circle(
            x, y, radius, color=fill_color.as_int(), batch=self.batch, group=below))
        edge = Vec2d(x, y) + Vec2d.from_polar(radius, angle)
        self.draw_shapes.append(pyglet.shapes.Line(
            x, y, edge.x, edge.y, thickness=1, color=outline_color.as_int(),
            batch=self.batch, group=above))

    def draw_segment(self, a, b, color):
        """A line one pixel thick."""
        self.draw_shapes.append(pyglet.shapes.Line(
            a[0], a[1], b[0], b[1], thickness=1, color=color.as_int(), batch=self.batch))

    def draw_fat_segment(self, a, b, radius, outline_color, fill_color):
        """A quad 2 * radius wide (radius at least 1) with a circle on each end."""
        ax, ay, bx, by = a[0], a[1], b[0], b[1]
        # the quad's half-width offset, perpendicular to a-b
        direction = -math.atan2(bx - ax, by - ay)
        radius = max(radius, 1)
        dx = radius * math.cos(direction)
        dy = radius * math.sin(direction)
        self.draw_shapes.append(pyglet.shapes.Polygon(
            (ax + dx, ay + dy), (ax - dx, ay - dy), (bx - dx, by - dy), (bx + dx, by + dy),
            color=fill_color.as_int(), batch=self.batch))
        self.draw_circle(a, 0, radius, fill_color, fill_color)
        self.draw_circle(b, 0, radius, fill_color, fill_color)

    def draw_polygon(self, verts, radius, outline_color, fill_color):
        """A filled polygon; with a radius, fat segments along its edges in the
        outline colour."""
        self.draw_shapes.append(pyglet.shapes.Polygon(
            *[(v[0], v[1]) for v in verts], color=fill_color.as_int(), batch=self.batch))
        if radius > 0:
            n = len(verts)
            for i in range(n):
                self.draw_fat_segment(verts[i], verts[(i + 1) % n], radius,
                                      outline_color, outline_color)

    def draw_dot(self, size, pos, color):
        """A filled circle of radius ``size``."""
        self.draw_shapes.append(pyglet.shapes.Circle(
            pos[0], pos[1], size, color=color.as_int(), batch=self.batch))
