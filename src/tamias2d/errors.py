"""Exceptions of the Tamias2D specification.

Every class derives from :class:`Tamias2DError` and from the builtin that fits
the misuse, so ``except ValueError`` keeps working. Where pymunk signals the
same misuse with an ``assert``, the class also derives from AssertionError, so
code written against pymunk that catches AssertionError is not broken.
Checks in tamias2d are real ``raise`` statements: ``python -O`` keeps them.
"""

__all__ = [
    "Tamias2DError", "NotCircleShape", "NotPolyShape", "NotSegmentShape",
    "IndexOutOfBounds", "IllegalBody", "IllegalShape", "IllegalVector",
    "IllegalConstraint",
    "UnsolvableCollision",
    "CollisionContactOverflow", "SameVertices", "CollisionError",
    "SpaceLocked", "AlreadyInSpace", "NotInSpace", "CallbackError",
    "IllegalCollisionType", "CopyError", "IllegalPolyline",
    "HighIterWarning",
]


class Tamias2DError(Exception):
    """Base class of every tamias2d exception."""


class NotCircleShape(Tamias2DError, TypeError):
    """A circle-only operation was given another kind of shape."""

    def __init__(self, msg="Shape is not a circle shape."):
        super().__init__(msg)


class NotPolyShape(Tamias2DError, TypeError):
    """A polygon-only operation was given another kind of shape."""

    def __init__(self, msg="Shape is not a poly shape."):
        super().__init__(msg)


class NotSegmentShape(Tamias2DError, TypeError):
    """A segment-only operation was given another kind of shape."""

    def __init__(self, msg="Shape is not a segment shape."):
        super().__init__(msg)


class IndexOutOfBounds(Tamias2DError, IndexError):
    """A vertex or contact index outside ``0 <= i < count``."""

    def __init__(self, msg="Index out of range."):
        super().__init__(msg)


class IllegalBody(Tamias2DError, ValueError, AssertionError):
    """A body would break its invariants: NaN or negative mass or moment,
    non-finite position, velocity, force, angle, angular velocity or torque,
    or a body of the wrong type for the operation."""


class IllegalShape(Tamias2DError, ValueError, AssertionError):
    """A shape definition that cannot be built: negative radius, no vertices,
    non-finite coordinates."""


class IllegalConstraint(Tamias2DError, ValueError, AssertionError):
    """A joint parameter the solver cannot use: NaN, an infinity that is not
    an open limit, a magnitude above ``tamias2d.constraints.PARAMETER_LIMIT``
    (1e100), a ratio or ratchet whose inverse is not finite, a negative
    damping, a groove of zero length; or a joint whose bodies belong to
    another space than the joint's."""


class IllegalVector(Tamias2DError, ValueError, AssertionError):
    """A vector, bounding box or transform argument with the wrong number of
    items, or with a NaN or infinite component where a finite one is needed."""


class UnsolvableCollision(Tamias2DError, ArithmeticError):
    """The effective mass of a contact is zero (both bodies infinitely heavy)."""

    def __init__(self, msg="Unsolvable collision or constraint."):
        super().__init__(msg)


class CollisionContactOverflow(Tamias2DError, RuntimeError):
    """Internal error: more than two contacts were pushed for one pair."""

    def __init__(self, msg="Internal Error: Tried to push too many contacts."):
        super().__init__(msg)


class SameVertices(Tamias2DError, RuntimeError):
    """Internal error: EPA found two identical hull vertices."""


class CollisionError(Tamias2DError, RuntimeError):
    """Internal error: the collision table was indexed with unsorted types."""

    def __init__(self, msg="Internal Error: Shape types are not sorted."):
        super().__init__(msg)


class SpaceLocked(Tamias2DError, RuntimeError, AssertionError):
    """An operation that is not allowed while the space is stepping or querying."""


class AlreadyInSpace(Tamias2DError, ValueError, AssertionError):
    """An object was added to a space it (or another space) already holds."""


class NotInSpace(Tamias2DError, ValueError, AssertionError):
    """An object was removed from a space that does not hold it."""


class IllegalCollisionType(Tamias2DError, ValueError, AssertionError):
    """A collision type pair that cannot key a handler (a wildcard first and a
    type second)."""


class CopyError(Tamias2DError, ValueError, AssertionError):
    """A space, body or shape cannot be copied, pickled or restored: a
    pickle from another tamias2d version or build, a corrupt state, or a copy
    that reaches the object being copied from that object's own state (a
    circular reference, which pymunk also refuses with an AssertionError)."""


class IllegalPolyline(Tamias2DError, ValueError, AssertionError):
    """A polyline an autogeometry function cannot use: too few vertices, a
    non-finite tolerance, an open or clockwise polygon where a closed
    counter-clockwise one is needed (pymunk asserts there too), or a polygon
    whose decomposition does not converge."""


class CallbackError(Tamias2DError, RuntimeError):
    """Wraps nothing: raised only when a callback failed in a way that left no
    Python exception to re-raise."""


class HighIterWarning(UserWarning):
    """GJK or EPA reached its iteration warning threshold (20 of at most 30)."""
