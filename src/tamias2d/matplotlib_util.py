"""Draw a space on a matplotlib Axes (pymunk's ``pymunk.matplotlib_util``).

:class:`DrawOptions` adds one matplotlib artist per primitive: a
``Circle`` patch and a ``Line2D`` for a circle (the line shows its angle),
a ``Line2D`` for a segment (fat segments as thick round-capped lines), a
``Polygon`` patch for a polygon and a ``Circle`` for a dot, in the colours
``space.debug_draw`` hands over (0..255, converted to matplotlib's 0..1).
Coordinates are the space's own; set the axes' limits and aspect yourself.

>>> import tamias2d
>>> from matplotlib.figure import Figure
>>> space = tamias2d.Space()
>>> space.add(tamias2d.Circle(space.static_body, 10))
>>> ax = Figure().add_subplot()
>>> space.debug_draw(DrawOptions(ax))
>>> len(ax.patches), len(ax.lines)
(1, 1)

pymunk 7 marks this module deprecated, and so :class:`DrawOptions` warns
(DeprecationWarning) as pymunk's does. matplotlib is needed
(``pip install 'tamias2d[draw]'`` or ``pip install matplotlib``); it is
imported with this module, but pyplot is not (no backend is chosen).
"""
__docformat__ = "reStructuredText"

import warnings

try:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon
except ModuleNotFoundError as _missing:  # pragma: no cover - only without matplotlib
    raise ModuleNotFoundError(
        "tamias2d.matplotlib_util needs matplotlib: pip install matplotlib",
        name="matplotlib") from _missing

from .space_debug_draw_options import SpaceDebugDrawOptions
from .vector import Vec2d

__all__ = ["DrawOptions"]


def _round_line(xs, ys, width, color):
    line = Line2D(xs, ys, linewidth=width, color=color)
    line.set_solid_capstyle("round")
    return line


class DrawOptions(SpaceDebugDrawOptions):
    """Debug drawing onto a matplotlib ``Axes``.

    A shape's ``color`` attribute sets its fill colour, as (r, g, b, a) in
    0..255.

    :param ax: the matplotlib Axes to draw on.

    >>> from matplotlib.figure import Figure
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", DeprecationWarning)
    ...     options = DrawOptions(Figure().add_subplot())
    >>> options.draw_dot(2, Vec2d(1, 1), options.constraint_color)
    >>> options.ax.patches[0].radius
    2.0
    """

    def __init__(self, ax) -> None:
        warnings.warn(
            "matplotlib_util.DrawOptions is deprecated in pymunk 7 and may be "
            "removed from pymunk; tamias2d keeps it for pymunk programs",
            category=DeprecationWarning, stacklevel=2)
        super().__init__()
        self.ax = ax

    def draw_circle(self, pos, angle, radius, outline_color, fill_color):
        """A filled circle and a line from its centre along ``angle``."""
        self.ax.add_patch(Circle(pos, radius, facecolor=fill_color.as_float(),
                                 edgecolor=outline_color.as_float()))
        edge = pos + Vec2d.from_polar(radius, angle)
        self.ax.add_line(_round_line([pos[0], edge[0]], [pos[1], edge[1]], 1,
                                     outline_color.as_float()))

    def draw_segment(self, a, b, color):
        """A line one point wide."""
        self.ax.add_line(_round_line([a[0], b[0]], [a[1], b[1]], 1, color.as_float()))

    def draw_fat_segment(self, a, b, radius, outline_color, fill_color):
        """A round-capped line 2 * radius points wide (at least 1)."""
        self.ax.add_line(_round_line([a[0], b[0]], [a[1], b[1]], max(1, 2 * radius),
                                     fill_color.as_float()))

    def draw_polygon(self, verts, radius, outline_color, fill_color):
        """A filled polygon with an outline 2 * radius points wide (at least 1)."""
        self.ax.add_patch(Polygon(verts, linewidth=max(1, 2 * radius), joinstyle="round",
                                  facecolor=fill_color.as_float(),
                                  edgecolor=outline_color.as_float()))

    def draw_dot(self, size, pos, color):
        """A filled circle of radius ``size`` without an outline."""
        self.ax.add_patch(Circle(pos, size, facecolor=color.as_float(), edgecolor="None"))
