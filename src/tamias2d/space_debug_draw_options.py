"""Options for ``Space.debug_draw``: what to draw, in which colours, where.

:class:`SpaceDebugDrawOptions` is the base class of every drawing backend
(:mod:`tamias2d.pillow_util`, :mod:`tamias2d.pygame_util`). It keeps the
settings the engine reads while it walks a space (the flags, the colours and
the transform) and has one overridable method per primitive. The base
methods print each call, which is handy in doctests and for debugging.

How ``Space.debug_draw(options)`` uses it (a port of Munk2D's
``cpSpaceDebugDraw``):

- ``with options:`` is entered around the whole drawing (backends that batch
  or buffer use ``__enter__`` / ``__exit__``);
- if ``options.flags & DRAW_SHAPES``, for each shape, in the space's shape
  order: the fill colour is ``options._c(options.color_for_shape(shape))``,
  the outline colour ``options.shape_outline_color``, and one of
  ``draw_circle`` / ``draw_fat_segment`` / ``draw_polygon`` is called with
  points already mapped through ``options.transform``;
- then constraints (``draw_dot`` / ``draw_segment`` in ``constraint_color``),
  if ``DRAW_CONSTRAINTS`` is set;
- then, if ``DRAW_COLLISION_POINTS`` is set, one ``draw_segment`` per contact
  point in ``collision_point_color``.

Colours cross the engine as four C ``float`` values, so every colour handed to
a draw method is a :class:`SpaceDebugColor` of Python floats rounded to single
precision, exactly as pymunk delivers them.
"""
import math
import struct
from typing import ClassVar, NamedTuple, Optional, Sequence

__all__ = ["SpaceDebugColor", "SpaceDebugDrawOptions"]

__docformat__ = "reStructuredText"

# cpBodyType values (tamias2d.Body.DYNAMIC / KINEMATIC / STATIC); written out
# so that this module does not import the compiled engine at load time.
_BODY_KINEMATIC = 1
_BODY_STATIC = 2

_FLOAT32 = struct.Struct("f")


def _to_c_float(value, what):
    """Round a real number to the nearest C float, as a C struct field would."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__float__"):
        raise TypeError(f"{what} must be a real number, not {type(value).__name__}")
    x = float(value)
    try:
        return _FLOAT32.unpack(_FLOAT32.pack(x))[0]
    except OverflowError:
        # A double beyond float range rounds to an infinity of the same sign.
        return math.copysign(math.inf, x)


def _color_from(value, what="colour"):
    """A SpaceDebugColor of single-precision floats from any 4-sequence."""
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{what} must be a sequence of 4 numbers (r, g, b, a), not str")
    try:
        items = tuple(value)
    except TypeError:
        raise TypeError(
            f"{what} must be a sequence of 4 numbers (r, g, b, a), "
            f"not {type(value).__name__}"
        ) from None
    if len(items) != 4:
        raise ValueError(
            f"{what} must have 4 components (r, g, b, a), got {len(items)}"
        )
    return SpaceDebugColor(*(_to_c_float(c, what) for c in items))


class SpaceDebugColor(NamedTuple):
    """An RGBA colour for debug drawing, each component nominally 0..255.

    >>> c = SpaceDebugColor(52, 152, 219, 255)
    >>> c.r, c.a
    (52, 255)
    """

    r: float
    g: float
    b: float
    a: float

    def as_int(self) -> tuple:
        """The colour as four ints, each rounded to the nearest integer.

        >>> SpaceDebugColor(0, 51.1, 101.9, 255).as_int()
        (0, 51, 102, 255)
        """
        return tuple(round(c) for c in self)

    def as_float(self) -> tuple:
        """The colour as four floats in 0..1 (each component over 255).

        >>> SpaceDebugColor(0, 51, 102, 255).as_float()
        (0.0, 0.2, 0.4, 1.0)
        """
        return tuple(c / 255.0 for c in self)


SpaceDebugColor.r.__doc__ = "Red, nominally 0..255."
SpaceDebugColor.g.__doc__ = "Green, nominally 0..255."
SpaceDebugColor.b.__doc__ = "Blue, nominally 0..255."
SpaceDebugColor.a.__doc__ = "Alpha (opacity), nominally 0..255: 255 is opaque."


class SpaceDebugDrawOptions(object):
    """Settings and drawing callbacks for ``Space.debug_draw``.

    Subclass it and override the ``draw_*`` methods to draw with any
    graphics library; the ready-made backends are
    :class:`tamias2d.pillow_util.DrawOptions` (headless, into an image) and
    :class:`tamias2d.pygame_util.DrawOptions`.

    >>> options = SpaceDebugDrawOptions()
    >>> options.flags == (SpaceDebugDrawOptions.DRAW_SHAPES
    ...     | SpaceDebugDrawOptions.DRAW_CONSTRAINTS
    ...     | SpaceDebugDrawOptions.DRAW_COLLISION_POINTS)
    True
    >>> options.shape_outline_color
    SpaceDebugColor(r=44.0, g=62.0, b=80.0, a=255.0)
    """

    DRAW_SHAPES: ClassVar[int] = 1 << 0
    """Flag bit: draw the shapes."""

    DRAW_CONSTRAINTS: ClassVar[int] = 1 << 1
    """Flag bit: draw the constraints."""

    DRAW_COLLISION_POINTS: ClassVar[int] = 1 << 2
    """Flag bit: draw the contact points of touching shapes."""

    # Fill colours by body state; plain attributes, read by color_for_shape.
    shape_dynamic_color: SpaceDebugColor = SpaceDebugColor(52, 152, 219, 255)
    shape_static_color: SpaceDebugColor = SpaceDebugColor(149, 165, 166, 255)
    shape_kinematic_color: SpaceDebugColor = SpaceDebugColor(39, 174, 96, 255)
    shape_sleeping_color: SpaceDebugColor = SpaceDebugColor(114, 148, 168, 255)

    def __init__(self) -> None:
        self._flags = (
            SpaceDebugDrawOptions.DRAW_SHAPES
            | SpaceDebugDrawOptions.DRAW_CONSTRAINTS
            | SpaceDebugDrawOptions.DRAW_COLLISION_POINTS
        )
        self._transform = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
        self._shape_outline_color = _color_from((44, 62, 80, 255))
        self._constraint_color = _color_from((142, 68, 173, 255))
        self._collision_point_color = _color_from((231, 76, 60, 255))
        # False makes Space.debug_draw call draw_shape(shape) for each shape
        # instead of walking the space itself (as pymunk allows).
        self._use_chipmunk_debug_draw = True

    # -- settings ---------------------------------------------------------

    @property
    def flags(self) -> int:
        """Bit mask of what to draw: DRAW_SHAPES | DRAW_CONSTRAINTS |
        DRAW_COLLISION_POINTS (all three by default).

        >>> options = SpaceDebugDrawOptions()
        >>> options.flags = SpaceDebugDrawOptions.DRAW_SHAPES
        >>> options.flags |= SpaceDebugDrawOptions.DRAW_COLLISION_POINTS
        >>> options.flags
        5
        """
        return self._flags

    @flags.setter
    def flags(self, f: int) -> None:
        if isinstance(f, float) or not hasattr(f, "__index__"):
            raise TypeError(f"flags must be an integer, not {type(f).__name__}")
        f = f.__index__()
        # Stored in an unsigned 32-bit C enum, as in Munk2D.
        if f < 0:
            raise OverflowError("flags must not be negative")
        if f >= 1 << 32:
            raise OverflowError(f"flags {f} does not fit in 32 bits")
        self._flags = f

    @property
    def transform(self):
        """The transform applied to every point before it is drawn (for
        example a camera: scaling and translation).

        Only uniform scaling and translation are fully supported: radii and
        circle angles are derived from the transformed x axis.

        >>> import tamias2d
        >>> options = SpaceDebugDrawOptions()
        >>> options.transform = tamias2d.Transform.scaling(2)
        >>> options.transform
        Transform(a=2.0, b=0.0, c=0.0, d=2.0, tx=0.0, ty=0.0)
        """
        from .vector import Transform

        return Transform(*self._transform)

    @transform.setter
    def transform(self, t) -> None:
        if isinstance(t, (str, bytes)):
            raise TypeError("transform must be a Transform or 6 numbers, not str")
        try:
            items = tuple(t)
        except TypeError:
            raise TypeError(
                f"transform must be a Transform or 6 numbers, not {type(t).__name__}"
            ) from None
        if len(items) != 6:
            raise ValueError(
                f"transform must have 6 components (a, b, c, d, tx, ty), got {len(items)}"
            )
        values = []
        for v in items:
            if isinstance(v, (str, bytes)) or not hasattr(v, "__float__"):
                raise TypeError(
                    f"transform components must be real numbers, not {type(v).__name__}"
                )
            values.append(float(v))
        self._transform = tuple(values)

    @property
    def shape_outline_color(self) -> SpaceDebugColor:
        """The outline colour of every shape, (r, g, b, a).

        >>> options = SpaceDebugDrawOptions()
        >>> options.shape_outline_color = (10, 20, 30, 40)
        >>> options.shape_outline_color
        SpaceDebugColor(r=10.0, g=20.0, b=30.0, a=40.0)
        """
        return self._shape_outline_color

    @shape_outline_color.setter
    def shape_outline_color(self, c) -> None:
        self._shape_outline_color = _color_from(c, "shape_outline_color")

    @property
    def constraint_color(self) -> SpaceDebugColor:
        """The colour of constraints (joints and springs), (r, g, b, a).

        >>> SpaceDebugDrawOptions().constraint_color
        SpaceDebugColor(r=142.0, g=68.0, b=173.0, a=255.0)
        """
        return self._constraint_color

    @constraint_color.setter
    def constraint_color(self, c) -> None:
        self._constraint_color = _color_from(c, "constraint_color")

    @property
    def collision_point_color(self) -> SpaceDebugColor:
        """The colour of contact points, (r, g, b, a).

        >>> SpaceDebugDrawOptions().collision_point_color
        SpaceDebugColor(r=231.0, g=76.0, b=60.0, a=255.0)
        """
        return self._collision_point_color

    @collision_point_color.setter
    def collision_point_color(self, c) -> None:
        self._collision_point_color = _color_from(c, "collision_point_color")

    # -- context manager: Space.debug_draw wraps one drawing in it ---------

    def __enter__(self) -> None:
        """Called before a space is drawn; backends may prepare a buffer.

        >>> with SpaceDebugDrawOptions():
        ...     pass
        """
        return None

    def __exit__(self, type, value, traceback) -> None:
        """Called after a space is drawn; backends may flush a buffer."""
        return None

    def _c(self, color) -> SpaceDebugColor:
        """A colour as the engine passes it on: 4 single-precision floats.

        >>> SpaceDebugDrawOptions()._c((1, 2, 3.3, 4))
        SpaceDebugColor(r=1.0, g=2.0, b=3.299999952316284, a=4.0)
        """
        return _color_from(color)

    # -- the primitives (override these) -----------------------------------

    def draw_circle(self, pos, angle: float, radius: float,
                    outline_color: SpaceDebugColor,
                    fill_color: SpaceDebugColor) -> None:
        """Draw a filled circle at pos; angle is the body's rotation.

        >>> SpaceDebugDrawOptions().draw_circle((0, 0), 0.0, 5.0,
        ...     SpaceDebugColor(1, 2, 3, 4), SpaceDebugColor(5, 6, 7, 8))
        draw_circle ((0, 0), 0.0, 5.0, SpaceDebugColor(r=1, g=2, b=3, a=4), SpaceDebugColor(r=5, g=6, b=7, a=8))
        """
        print("draw_circle", (pos, angle, radius, outline_color, fill_color))

    def draw_segment(self, a, b, color: SpaceDebugColor) -> None:
        """Draw a thin line from a to b.

        >>> SpaceDebugDrawOptions().draw_segment((0, 0), (1, 1),
        ...     SpaceDebugColor(1, 2, 3, 4))
        draw_segment ((0, 0), (1, 1), SpaceDebugColor(r=1, g=2, b=3, a=4))
        """
        print("draw_segment", (a, b, color))

    def draw_fat_segment(self, a, b, radius: float,
                         outline_color: SpaceDebugColor,
                         fill_color: SpaceDebugColor) -> None:
        """Draw a segment of the given radius, with round ends.

        >>> SpaceDebugDrawOptions().draw_fat_segment((0, 0), (1, 1), 2.0,
        ...     SpaceDebugColor(1, 2, 3, 4), SpaceDebugColor(5, 6, 7, 8))
        draw_fat_segment ((0, 0), (1, 1), 2.0, SpaceDebugColor(r=1, g=2, b=3, a=4), SpaceDebugColor(r=5, g=6, b=7, a=8))
        """
        print("draw_fat_segment", (a, b, radius, outline_color, fill_color))

    def draw_polygon(self, verts: Sequence, radius: float,
                     outline_color: SpaceDebugColor,
                     fill_color: SpaceDebugColor) -> None:
        """Draw a convex polygon (counter-clockwise vertices), its corners
        rounded by radius.

        >>> SpaceDebugDrawOptions().draw_polygon([(0, 0), (1, 0), (0, 1)], 0.0,
        ...     SpaceDebugColor(1, 2, 3, 4), SpaceDebugColor(5, 6, 7, 8))
        draw_polygon ([(0, 0), (1, 0), (0, 1)], 0.0, SpaceDebugColor(r=1, g=2, b=3, a=4), SpaceDebugColor(r=5, g=6, b=7, a=8))
        """
        print("draw_polygon", (verts, radius, outline_color, fill_color))

    def draw_dot(self, size: float, pos, color: SpaceDebugColor) -> None:
        """Draw a dot of the given size in pixels (not scaled by transform).

        >>> SpaceDebugDrawOptions().draw_dot(5.0, (1, 2), SpaceDebugColor(1, 2, 3, 4))
        draw_dot (5.0, (1, 2), SpaceDebugColor(r=1, g=2, b=3, a=4))
        """
        print("draw_dot", (size, pos, color))

    def draw_shape(self, shape) -> None:
        """Draw one shape by itself; used instead of the engine's walk when
        ``_use_chipmunk_debug_draw`` is False.

        >>> SpaceDebugDrawOptions().draw_shape("a shape")
        draw_shape a shape
        """
        print("draw_shape", shape)

    def color_for_shape(self, shape) -> SpaceDebugColor:
        """The fill colour of a shape.

        A ``color`` attribute set on the shape wins (any 4 numbers, e.g. a
        pygame.Color); otherwise the colour follows the body: static,
        kinematic, sleeping or dynamic (also for a shape without a body).

        >>> import tamias2d
        >>> options = SpaceDebugDrawOptions()
        >>> space = tamias2d.Space()
        >>> options.color_for_shape(tamias2d.Circle(space.static_body, 1))
        SpaceDebugColor(r=149, g=165, b=166, a=255)
        >>> c = tamias2d.Circle(None, 1)
        >>> c.color = (255, 0, 0, 255)
        >>> options.color_for_shape(c)
        SpaceDebugColor(r=255, g=0, b=0, a=255)
        """
        if hasattr(shape, "color"):
            return SpaceDebugColor(*shape.color)

        body = shape.body
        if body is None:
            return self.shape_dynamic_color
        body_type = body.body_type
        if body_type == _BODY_STATIC:
            return self.shape_static_color
        if body_type == _BODY_KINEMATIC:
            return self.shape_kinematic_color
        if body.is_sleeping:
            return self.shape_sleeping_color
        return self.shape_dynamic_color
