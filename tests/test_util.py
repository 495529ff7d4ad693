"""tamias2d.util against pymunk.util on random polygons: every function's
result (and convex_hull's reordering of its argument) compared exactly,
floats by their bits."""
import math
import random

import pytest

pymunk_util = pytest.importorskip("pymunk.util")

from tamias2d import util  # noqa: E402
from tamias2d.errors import IllegalPolyline  # noqa: E402


def exact(value):
    """A comparable form that tells -0.0 from 0.0 and ints from floats."""
    if isinstance(value, float):
        return ("f", value.hex())
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, [exact(v) for v in value])
    return (type(value).__name__, value)


def random_points(rng):
    n = rng.randint(3, 14)
    kind = rng.random()
    if kind < 0.35:
        return [(rng.randint(-4, 4), rng.randint(-4, 4)) for _ in range(n)]
    if kind < 0.7:
        return [(rng.uniform(-10, 10), rng.uniform(-10, 10)) for _ in range(n)]
    # a star: simple and counter-clockwise around the origin
    angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(n))
    pts = []
    for a in angles:
        r = rng.uniform(1, 10)
        pts.append((r * math.cos(a), r * math.sin(a)))
    return pts


def same(name, *args):
    ours = getattr(util, name)(*args)
    theirs = getattr(pymunk_util, name)(*args)
    assert exact(ours) == exact(theirs), (name, args)
    return ours


def test_public_names_match_pymunk():
    assert util.__all__ == pymunk_util.__all__
    for name in ("X", "Y", "is_left", "sign"):
        assert hasattr(util, name)
    for name in util.__all__:
        assert callable(getattr(util, name))


def test_functions_equal_pymunk_on_random_polygons():
    rng = random.Random(21)
    for _ in range(600):
        pts = random_points(rng)
        for name in ("is_clockwise", "is_convex", "calc_area", "calc_perimeter"):
            same(name, pts)
        same("reduce_poly", pts)
        same("reduce_poly", pts, rng.choice([0.0, 0.5, 4.0, 20.0]))
        same("is_left", pts[0], pts[1], pts[2])
        same("sign", pts[0][0])
        if util.calc_area(pts) != 0:
            same("calc_center", pts)
            same("poly_vectors_around_center", pts)
            same("poly_vectors_around_center", pts, False)
        # convex_hull reorders its argument, as pymunk's does
        mine, theirs = list(pts), list(pts)
        assert exact(util.convex_hull(mine)) == exact(pymunk_util.convex_hull(theirs))
        assert exact(mine) == exact(theirs)


def test_triangulate_and_convexise_equal_pymunk():
    rng = random.Random(22)
    triangles = 0
    for _ in range(300):
        pts = random_points(rng)
        if util.calc_area(pts) < 0:
            pts.reverse()
        tris = same("triangulate", pts)
        same("convexise", tris)
        triangles += len(tris)
    assert triangles > 1000


def test_short_input():
    assert util.calc_area([(0, 0), (1, 1)]) == 0 and type(util.calc_area([])) is int
    assert util.calc_perimeter([(1, 1)]) == 0
    assert util.triangulate([(0, 0), (1, 0)]) == [] and util.convexise([]) == []
    for call in (lambda: util.is_convex([(0, 0), (1, 0)]),
                 lambda: util.convex_hull([(0, 0), (1, 0)]),
                 lambda: util.reduce_poly([]),
                 lambda: util.calc_center([])):
        with pytest.raises(IllegalPolyline):
            call()
    with pytest.raises(AssertionError):          # what pymunk raises
        util.is_convex([(0, 0)])
    with pytest.raises(ZeroDivisionError):       # no area: pymunk divides by zero too
        util.calc_center([(0, 0), (1, 1)])
