"""Polygon helpers of pymunk's ``pymunk.util``: winding, convexity, area,
centre, perimeter, a Graham-scan hull, point reduction, ear-clipping
triangulation and the merging of triangles into convex polygons.

pymunk 7.3 still ships this module although it is deprecated in favour of
:mod:`tamias2d.autogeometry`; it is here so that programs using it run
unchanged. The results are pymunk's to the last bit: the same arithmetic in
the same order, the same comparisons, the same quirks (``convex_hull``
reorders the list it is given; ``calc_area`` returns the integer 0 for fewer
than three points).

Points are anything indexable as ``p[0]``, ``p[1]``: tuples, lists,
:class:`~tamias2d.Vec2d`.

>>> square = [(0, 0), (2, 0), (2, 2), (0, 2)]
>>> calc_area(square), calc_center(square), is_clockwise(square)
(4.0, (1.0, 1.0), False)
>>> triangulate(square)
[[(0, 0), (2, 0), (2, 2)], [(0, 2), (0, 0), (2, 2)]]
>>> convexise(triangulate(square))
[[(0, 0), (2, 0), (2, 2), (0, 2)]]
"""
__docformat__ = "reStructuredText"

import functools
import math

from .errors import IllegalPolyline
from .vector import Vec2d

__all__ = [
    "is_clockwise",
    "reduce_poly",
    "convex_hull",
    "calc_area",
    "calc_center",
    "poly_vectors_around_center",
    "is_convex",
    "calc_perimeter",
    "triangulate",
    "convexise",
]

# Index names for a point's coordinates, as pymunk.util has them.
X, Y = 0, 1


def _need(points, n, what):
    # pymunk asserts these counts: the exception is an AssertionError too
    if len(points) < n:
        raise IllegalPolyline(f"{what} needs at least {n} points, got {len(points)}")


def _closed_pairs(points):
    """(p, next p) around the polygon, ending with (last, first)."""
    n = len(points)
    return [(points[i], points[(i + 1) % n]) for i in range(n)]


def is_clockwise(points):
    """True if the polygon's vertices run clockwise (or it has no area).

    >>> is_clockwise([(0, 0), (0, 1), (1, 1)]), is_clockwise([(0, 0), (1, 0), (1, 1)])
    (True, False)
    """
    total = 0
    for a, b in _closed_pairs(points):
        total += a[X] * b[Y] - a[Y] * b[X]
    return total <= 0


def is_left(p0, p1, p2):
    """Which side of the line through p0 and p1 the point p2 lies on: 1 to
    the left, -1 to the right, 0 on it.

    >>> is_left((0, 0), (1, 0), (0, 5)), is_left((0, 0), (1, 0), (3, 0))
    (1, 0)
    """
    cross = (p1[X] - p0[X]) * (p2[Y] - p0[Y]) - (p2[X] - p0[X]) * (p1[Y] - p0[Y])
    return 1 if cross > 0 else (-1 if cross < 0 else 0)


def sign(x):
    """-1 for a negative number, 1 otherwise (0 included).

    >>> sign(-2.5), sign(0), sign(3)
    (-1, 1, 1)
    """
    return -1 if x < 0 else 1


def is_convex(points):
    """True if the polygon (at least 3 points) is convex: every turn goes
    the same way and the outline crosses each axis direction at most twice.

    >>> is_convex([(0, 0), (2, 0), (2, 2), (0, 2)])
    True
    >>> is_convex([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2)])
    False
    """
    _need(points, 3, "is_convex")
    p0, p1 = points[0], points[1]
    winding = is_left(p0, p1, points[2])
    x_changes = y_changes = 0
    # every vertex from the third on, then around again through the first two
    for p2 in list(points[2:]) + [points[0], points[1]]:
        if is_left(p0, p1, p2) != winding:
            return False
        if sign(p1[X] - p0[X]) != sign(p2[X] - p1[X]):
            x_changes += 1
        if sign(p1[Y] - p0[Y]) != sign(p2[Y] - p1[Y]):
            y_changes += 1
        p0, p1 = p1, p2
    return x_changes <= 2 and y_changes <= 2


def reduce_poly(points, tolerance=0.5):
    """The points without those closer than sqrt(tolerance) to the last kept
    one (``tolerance`` is a squared distance).

    >>> reduce_poly([(0, 0), (0.5, 0), (1, 0), (1, 0.2), (3, 0)])
    [(0, 0), (1, 0), (3, 0)]
    """
    _need(points, 1, "reduce_poly")
    kept = [points[0]]
    last = points[0]
    for p in points[1:]:
        if (last[X] - p[X]) ** 2 + (last[Y] - p[Y]) ** 2 > tolerance:
            kept.append(p)
            last = p
    return kept


def convex_hull(points):
    """The convex hull of at least 3 points by Graham scan, starting at the
    lowest (then rightmost) point. As in pymunk, the list passed in is
    reordered: sorted by angle around that point.

    >>> convex_hull([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2)])
    [(2, 0), (2, 2), (0, 2), (0, 0)]
    """
    _need(points, 3, "convex_hull")
    start = points[0]
    for p in points[1:]:
        if p[Y] < start[Y] or (p[Y] == start[Y] and p[X] > start[X]):
            start = p
    points.remove(start)
    points.sort(key=functools.cmp_to_key(functools.partial(is_left, start)))
    points.reverse()
    points.insert(0, start)

    hull = [start, points[1]]
    for p in points[2:]:
        turn = is_left(hull[-2], hull[-1], p)
        # drop the points the new one makes concave (keep two at least)
        while turn <= 0 and len(hull) > 2:
            hull.pop()
            turn = is_left(hull[-2], hull[-1], p)
        hull.append(p)
    return hull


def calc_area(points):
    """The signed area of a polygon (positive counter-clockwise); the
    integer 0 for fewer than 3 points.

    >>> calc_area([(0, 0), (3, 0), (0, 2)]), calc_area([(0, 0), (1, 1)])
    (3.0, 0)
    """
    if len(points) < 3:
        return 0
    twice = 0
    for a, b in _closed_pairs(points):
        twice += a[X] * b[Y] - b[X] * a[Y]
    return 0.5 * twice


def calc_center(points):
    """The centroid (x, y) of a polygon with non-zero area.

    >>> calc_center([(0, 0), (3, 0), (0, 3)])
    (1.0, 1.0)
    """
    _need(points, 1, "calc_center")
    area = calc_area(points)
    cx = cy = 0
    for a, b in _closed_pairs(points):
        cross = a[X] * b[Y] - b[X] * a[Y]
        cx += (a[X] + b[X]) * cross
        cy += (a[Y] + b[Y]) * cross
    return 1 / (6.0 * area) * cx, 1 / (6.0 * area) * cy


def poly_vectors_around_center(pointlist, points_as_Vec2d=True):
    """The points moved so that the polygon's centroid is at the origin: as
    Vec2d, or else as (x, y) tuples with y flipped (screen coordinates).

    >>> poly_vectors_around_center([(0, 0), (3, 0), (0, 3)])
    [Vec2d(-1.0, -1.0), Vec2d(2.0, -1.0), Vec2d(-1.0, 2.0)]
    >>> poly_vectors_around_center([(0, 0), (3, 0), (0, 3)], False)
    [(-1.0, 1.0), (2.0, 1.0), (-1.0, -2.0)]
    """
    cx, cy = calc_center(pointlist)
    if points_as_Vec2d:
        return [Vec2d(p[X] - cx, p[Y] - cy) for p in pointlist]
    return [(p[X] - cx, cy - p[Y]) for p in pointlist]


def calc_perimeter(points):
    """The length of the closed outline; 0 for fewer than 2 points.

    >>> calc_perimeter([(0, 0), (3, 0), (3, 4)])
    12.0
    """
    if len(points) < 2:
        return 0
    length = 0
    for a, b in _closed_pairs(points):
        length += math.sqrt((b[X] - a[X]) ** 2 + (b[Y] - a[Y]) ** 2)
    return length


# -- triangulation and convex merging ---------------------------------------------------

def _inside_triangle(p, a, b, c):
    # p is inside (or on) abc when the three sub-triangles add up to abc
    whole = abs(calc_area([a, b, c]))
    parts = abs(calc_area([a, b, p])) + abs(calc_area([b, c, p])) + abs(calc_area([c, a, p]))
    return parts < whole + 0.0000001


def _clip_ear(poly):
    """(ear, rest): the first convex corner with no other vertex inside its
    triangle, and the polygon without it; ([], []) if there is none."""
    n = len(poly)
    if n < 3:
        return [], []
    if n == 3:
        return poly, []
    for i in range(n):
        ia, ic = (i - 1) % n, (i + 1) % n
        a, b, c = poly[ia], poly[i], poly[ic]
        if is_clockwise([a, b, c]):
            continue
        if any(_inside_triangle(poly[j], a, b, c) for j in range(n) if j not in (ia, i, ic)):
            continue
        return [a, b, c], [poly[j] for j in range(n) if j != i]
    return [], []


def triangulate(poly):
    """Ear-clipping triangulation of a simple counter-clockwise polygon:
    a list of triangles (lists of 3 points). Self-intersecting input gives
    undefined results, as in pymunk.

    >>> triangulate([(0, 0), (4, 0), (4, 4), (2, 1), (0, 4)])
    [[(4, 0), (4, 4), (2, 1)], [(2, 1), (0, 4), (0, 0)], [(0, 0), (4, 0), (2, 1)]]
    """
    triangles = []
    rest = poly[:]
    while len(rest) > 2:
        # start from the next vertex each time, which avoids thin fans
        rest = rest[1:] + rest[:1]
        ear, rest = _clip_ear(rest)
        if ear != []:
            triangles.append(ear)
    return triangles


def _merge(hull_a, hull_b):
    """The two polygons joined along their one shared edge, if that is
    convex; else None."""
    shared = [v for v in hull_a if v in hull_b]
    if len(shared) != 2:
        return None
    i = hull_a.index(shared[1])
    j = hull_b.index(shared[0])
    merged = (hull_a[i:] + hull_a[:i])[1:] + (hull_b[j:] + hull_b[:j])[1:]
    return merged if is_convex(merged) else None


def convexise(triangles):
    """Merge counter-clockwise triangles (as :func:`triangulate` returns)
    pairwise into convex polygons until no pair merges; not optimal.

    >>> convexise([[(0, 0), (2, 0), (0, 2)], [(2, 0), (2, 2), (0, 2)]])
    [[(0, 0), (2, 0), (2, 2), (0, 2)]]
    """
    hulls = triangles[:]
    while len(hulls) >= 2:
        for ia in range(len(hulls) - 1):
            for ib in range(ia + 1, len(hulls)):
                merged = _merge(hulls[ia], hulls[ib])
                if merged is not None:
                    hulls = [merged] + [h for k, h in enumerate(hulls) if k not in (ia, ib)]
                    break
            else:
                continue
            break
        else:
            break
    return hulls
