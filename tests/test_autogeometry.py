"""tamias2d.autogeometry against pymunk.autogeometry: every vertex of every
result compared bit for bit (float.hex, so -0.0 and 0.0 differ), the sample
function's calls compared point by point, and the bad input that pymunk
crashes or hangs on refused with an exception.

Inputs: seeded random images (grey and black-and-white, 1 to 40 pixels a
side) sampled with random boxes (inverted ones too), sample counts (1 to 45)
and thresholds; random polylines (floats, small integers with repeats,
star-shaped polygons, the loops marching squares produces) for the
simplification, hull and decomposition functions. A hypothesis test adds
shrinking cases on top.
"""
import math
import random

import pytest

pymunk_ag = pytest.importorskip("pymunk.autogeometry")
import pymunk  # noqa: E402
from hypothesis import given, settings, strategies as st  # noqa: E402

import tamias2d  # noqa: E402
from tamias2d import autogeometry as ag  # noqa: E402
from tamias2d.errors import IllegalPolyline  # noqa: E402


def exact(line):
    return [(v[0].hex(), v[1].hex()) for v in line]


def exact_set(lines):
    return [exact(line) for line in lines]


# -- marching squares -------------------------------------------------------------------

class Image:
    """A random picture sampled over a box: records every point it is asked
    for (and the type it came as)."""

    def __init__(self, rng, w, h, grey):
        self.w, self.h = w, h
        self.pixels = [[rng.random() if grey else float(rng.random() < 0.5) for _ in range(w)]
                       for _ in range(h)]
        self.calls = []

    def sampler(self, bb):
        l, b, r, t = bb
        sx = (r - l) or 1.0
        sy = (t - b) or 1.0

        def sample(point):
            self.calls.append((type(point), point[0].hex(), point[1].hex()))
            x, y = point
            i = int((x - l) / sx * (self.w - 1) + 0.5) if x == x else 0
            j = int((y - b) / sy * (self.h - 1) + 0.5) if y == y else 0
            return self.pixels[min(max(j, 0), self.h - 1)][min(max(i, 0), self.w - 1)]
        return sample


def random_march_case(rng):
    w, h = rng.randint(1, 40), rng.randint(1, 40)
    grey = rng.random() < 0.6
    l, b = rng.uniform(-50, 50), rng.uniform(-50, 50)
    r, t = l + rng.uniform(-5, 80), b + rng.uniform(-5, 80)   # sometimes inverted
    if rng.random() < 0.2:
        l, b, r, t = 0, 0, w - 1, h - 1                        # pixel grid
    xs = rng.choice([1, 2, 3]) if rng.random() < 0.1 else rng.choice([rng.randint(2, 45), w])
    ys = rng.choice([1, 2, 3]) if rng.random() < 0.1 else rng.choice([rng.randint(2, 45), h])
    threshold = rng.choice([0.5, rng.random(), 0.0, 1.0])
    return Image(rng, w, h, grey), (l, b, r, t), xs, ys, threshold


@pytest.mark.parametrize("name", ["march_soft", "march_hard"])
def test_march_equals_pymunk_on_random_images(name):
    rng = random.Random(7 if name == "march_soft" else 8)
    lines_seen = 0
    for case in range(300):
        image, bb, xs, ys, threshold = random_march_case(rng)
        ours = getattr(ag, name)(tamias2d.BB(*bb), xs, ys, threshold, image.sampler(bb))
        our_calls, image.calls = image.calls, []
        theirs = getattr(pymunk_ag, name)(pymunk.BB(*bb), xs, ys, threshold, image.sampler(bb))
        assert our_calls == image.calls, f"case {case}: the sample calls differ"
        assert len(our_calls) == xs * ys
        assert exact_set(ours) == exact_set(theirs), f"case {case}: {bb} {xs}x{ys} t={threshold}"
        lines_seen += len(ours)
    assert lines_seen > 1000      # the cases are not all empty


def test_march_passes_a_tuple_like_pymunk():
    seen = []
    ag.march_soft(tamias2d.BB(0, 0, 1, 1), 2, 2, 0.5, lambda p: seen.append(p) or 0.0)
    assert [type(p) for p in seen] == [tuple] * 4
    assert seen == [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]


def test_march_accepts_a_plain_tuple_box_and_number_likes():
    img = Image(random.Random(3), 9, 9, True)
    bb = (0, 0, 8, 8)
    a = ag.march_soft(bb, 9, 9, 0.5, img.sampler(bb))
    b = pymunk_ag.march_soft(pymunk.BB(*bb), 9, 9, 0.5, img.sampler(bb))
    assert exact_set(a) == exact_set(b)
    # ints, bools and objects with __float__ as samples
    flags = ag.march_hard(bb, 9, 9, 0.5, lambda p: int(p[0] > 4))
    assert exact_set(flags) == exact_set(
        pymunk_ag.march_hard(pymunk.BB(*bb), 9, 9, 0.5, lambda p: int(p[0] > 4)))


@settings(max_examples=60, deadline=None)
@given(w=st.integers(1, 12), h=st.integers(1, 12), xs=st.integers(1, 14), ys=st.integers(1, 14),
       threshold=st.floats(-0.5, 1.5), seed=st.integers(0, 2**32 - 1), hard=st.booleans(),
       box=st.tuples(st.floats(-100, 100), st.floats(-100, 100),
                     st.floats(-100, 100), st.floats(-100, 100)))
def test_march_hypothesis(w, h, xs, ys, threshold, seed, hard, box):
    image = Image(random.Random(seed), w, h, seed % 2 == 0)
    name = "march_hard" if hard else "march_soft"
    ours = getattr(ag, name)(box, xs, ys, threshold, image.sampler(box))
    theirs = getattr(pymunk_ag, name)(pymunk.BB(*box), xs, ys, threshold, image.sampler(box))
    assert exact_set(ours) == exact_set(theirs)


def test_march_sample_function_exception_propagates():
    calls = []

    def sample(point):
        calls.append(point)
        if len(calls) == 7:
            raise KeyError("boom")
        return 1.0

    with pytest.raises(KeyError, match="boom"):
        ag.march_soft(tamias2d.BB(0, 0, 10, 10), 5, 5, 0.5, sample)
    assert len(calls) == 7            # nothing sampled after the error


@pytest.mark.parametrize("value, message", [(None, "NoneType"), ("1", "str"), ([1], "list")])
def test_march_sample_must_return_a_number(value, message):
    with pytest.raises(TypeError, match=message):
        ag.march_hard(tamias2d.BB(0, 0, 1, 1), 3, 3, 0.5, lambda p: value)


@pytest.mark.parametrize("xs, ys, exc", [(0, 5, ValueError), (5, 0, ValueError),
                                         (-1, 5, ValueError), (2.5, 5, TypeError),
                                         ("3", 5, TypeError), (10**30, 5, OverflowError)])
def test_march_refuses_bad_sample_counts(xs, ys, exc):
    with pytest.raises(exc):
        ag.march_soft(tamias2d.BB(0, 0, 1, 1), xs, ys, 0.5, lambda p: 0.0)


def test_march_refuses_bad_arguments():
    with pytest.raises(TypeError, match="callable"):
        ag.march_soft(tamias2d.BB(0, 0, 1, 1), 3, 3, 0.5, None)
    with pytest.raises(TypeError, match="threshold"):
        ag.march_soft(tamias2d.BB(0, 0, 1, 1), 3, 3, "x", lambda p: 0.0)
    with pytest.raises(ValueError):
        ag.march_soft((0, 0, 1), 3, 3, 0.5, lambda p: 0.0)


def test_one_sample_wide_grid_like_pymunk():
    # x_samples=1 divides by zero in Munk2D: the sample points get NaN x
    for name in ("march_soft", "march_hard"):
        ours, theirs = [], []
        r1 = getattr(ag, name)((0, 0, 1, 1), 1, 3, 0.5, lambda p: ours.append(p) or 1.0)
        r2 = getattr(pymunk_ag, name)(pymunk.BB(0, 0, 1, 1), 1, 3, 0.5,
                                      lambda p: theirs.append(p) or 1.0)
        assert list(r1) == list(r2) == []
        assert repr(ours) == repr(theirs)


# -- PolylineSet -----------------------------------------------------------------------------

def test_polyline_set_equals_pymunk_on_random_segments():
    rng = random.Random(11)
    for case in range(200):
        ours, theirs = ag.PolylineSet(), pymunk_ag.PolylineSet()
        pts = [(float(rng.randint(0, 6)), float(rng.randint(0, 6))) for _ in range(12)]
        for _ in range(rng.randint(0, 40)):
            a, b = rng.choice(pts), rng.choice(pts)
            ours.collect_segment(a, b)
            theirs.collect_segment(a, b)
        assert len(ours) == len(theirs)
        assert exact_set(ours) == exact_set(theirs), case
        assert [exact(ours[i]) for i in range(len(ours))] == exact_set(theirs)


def test_polyline_set_sequence_protocol():
    from collections.abc import Sequence
    s = ag.PolylineSet()
    assert isinstance(s, Sequence) and len(s) == 0 and list(s) == []
    s.collect_segment((0, 0), (1, 0))
    s.collect_segment((3, 3), (4, 4))
    assert s[-1] == s[1] == [(3, 3), (4, 4)]
    assert list(reversed(s)) == [s[1], s[0]]
    assert [(0, 0), (1, 0)] in s and s.index([(3, 3), (4, 4)]) == 1 and s.count(s[0]) == 1
    with pytest.raises(IndexError):
        s[2]
    with pytest.raises(IndexError):
        s[-3]
    with pytest.raises(TypeError):
        s[0:1]
    with pytest.raises(ValueError):
        s.collect_segment((0, 0, 0), (1, 1))


# -- polylines -----------------------------------------------------------------------------

def star(rng, n, grid=False):
    angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(n))
    pts = []
    for a in angles:
        r = rng.uniform(1, 10)
        p = (r * math.cos(a), r * math.sin(a))
        pts.append((float(round(p[0])), float(round(p[1]))) if grid else p)
    return pts


def random_polyline(rng):
    n = rng.randint(1, 40)
    kind = rng.random()
    if kind < 0.3:
        pts = [(rng.uniform(-10, 10), rng.uniform(-10, 10)) for _ in range(n)]
    elif kind < 0.6:
        pts = [(rng.randint(-5, 5), rng.randint(-5, 5)) for _ in range(n)]    # repeats
    else:
        pts = star(rng, n, grid=kind < 0.8)
    if rng.random() < 0.5 and n > 1:
        pts.append(pts[0])
    return pts


TOLERANCES = [0.0, 0.01, 0.1, 0.5, 1.0, 3.0]


def test_simplify_and_hull_equal_pymunk_on_random_polylines():
    rng = random.Random(5)
    for case in range(1500):
        pts = random_polyline(rng)
        tol = rng.choice(TOLERANCES + [rng.uniform(0, 2)])
        info = f"case {case}: {pts!r}, {tol!r}"
        assert exact(ag.simplify_curves(pts, tol)) == exact(pymunk_ag.simplify_curves(pts, tol)), info
        assert exact(ag.to_convex_hull(pts, tol)) == exact(pymunk_ag.to_convex_hull(pts, tol)), info
        if len(pts) >= 2:
            assert (exact(ag.simplify_vertexes(pts, tol))
                    == exact(pymunk_ag.simplify_vertexes(pts, tol))), info
        assert ag.is_closed(pts) == pymunk_ag.is_closed(pts)


def test_hull_with_negative_tolerance_equals_pymunk():
    rng = random.Random(6)
    for _ in range(200):
        pts = random_polyline(rng)
        tol = -rng.uniform(0, 1)
        assert exact(ag.to_convex_hull(pts, tol)) == exact(pymunk_ag.to_convex_hull(pts, tol))
        if len(pts) >= 2:
            assert exact(ag.simplify_vertexes(pts, tol)) == exact(pymunk_ag.simplify_vertexes(pts, tol))


def march_loops(rng, count):
    """Closed, counter-clockwise loops traced by marching squares."""
    loops = []
    while len(loops) < count:
        w, h = rng.randint(2, 14), rng.randint(2, 14)
        img = Image(rng, w, h, rng.random() < 0.5)
        bb = (0, 0, w - 1, h - 1)
        march = ag.march_hard if rng.random() < 0.5 else ag.march_soft
        for line in march(bb, w, h, rng.random(), img.sampler(bb)):
            if len(line) >= 4 and line[0] == line[-1]:
                loop = [tuple(v) for v in line]
                if pymunk.area_for_poly(loop) < 0:
                    loop.reverse()
                loops.append(loop)
    return loops


def test_convex_decomposition_equals_pymunk():
    # Simple polygons only: pymunk crashes on many degenerate ones (below).
    rng = random.Random(9)
    polys = march_loops(rng, 250)
    while len(polys) < 500:
        p = star(rng, rng.randint(3, 40))
        p.append(p[0])
        if pymunk.area_for_poly(p) < 0:     # the centre can lie outside the star
            p.reverse()
        polys.append(p)
    pieces = 0
    for case, poly in enumerate(polys):
        tol = rng.choice(TOLERANCES)
        ours = ag.convex_decomposition(poly, tol)
        assert exact_set(ours) == exact_set(pymunk_ag.convex_decomposition(poly, tol)), \
            f"case {case}: {poly!r}, {tol!r}"
        pieces += len(ours)
    assert pieces > 1000


def test_convex_decomposition_pieces_are_convex_and_cover_the_area():
    rng = random.Random(10)
    for poly in march_loops(rng, 60):
        parts = ag.convex_decomposition(poly, 0.0)
        for part in parts:
            assert ag.is_closed(part)
            hull = ag.to_convex_hull(part, 0.0)
            assert len(hull) == len(part)
        total = sum(tamias2d.area_for_poly(p) for p in parts)
        assert total == pytest.approx(tamias2d.area_for_poly(poly), rel=1e-9, abs=1e-9)


def test_convex_decomposition_that_does_not_converge_raises():
    # Rounded to the grid, this star has a repeated vertex: Munk2D recurses
    # until the C stack overflows (pymunk segfaults).
    poly = [(8, 0), (9, 2), (2, 1), (2, 1), (4, 3), (3, 4), (2, 3), (0, 1), (2, 6), (3, 9),
            (0, 4), (-1, 6), (-2, 4), (-4, 3), (-8, 4), (-4, 1), (-7, 1), (-5, 0), (-6, 0),
            (-8, -4), (-1, -1), (-6, -5), (-2, -3), (-3, -6), (-4, -7), (0, -7), (0, -5),
            (0, -9), (0, -2), (1, -7), (1, -4), (2, -5), (3, -8), (4, -7), (5, -4), (3, -2),
            (3, -1), (8, 0)]
    with pytest.raises(IllegalPolyline, match="does not converge"):
        ag.convex_decomposition(poly, 0.1)


def test_long_polylines_do_not_overflow_the_stack():
    # Douglas-Peucker and the decomposition run on explicit stacks.
    n = 200_000
    spiral = [(i * math.cos(i * 0.001), i * math.sin(i * 0.001)) for i in range(n)]
    assert exact(ag.simplify_curves(spiral, 0.01)) == exact(pymunk_ag.simplify_curves(spiral, 0.01))
    # pymunk survives 100 teeth; 2000 overflow its C stack (segfault)
    for teeth in (100, 2000):
        comb = [(0.0, 0.0), (2.0 * teeth + 1, 0.0)]
        for i in reversed(range(teeth)):
            comb += [(2.0 * i + 1.5, 10.0), (2.0 * i + 1, 0.5)]
        comb.append((0.0, 0.0))
        assert tamias2d.area_for_poly(comb) > 0
        parts = ag.convex_decomposition(comb, 0.01)
        assert len(parts) >= teeth
        if teeth == 100:
            assert exact_set(parts) == exact_set(pymunk_ag.convex_decomposition(comb, 0.01))


@pytest.mark.parametrize("call, match", [
    (lambda: ag.simplify_curves([], 1), "at least 1 vertex"),
    (lambda: ag.simplify_vertexes([(0, 0)], 1), "at least 2 vertices"),
    (lambda: ag.to_convex_hull([], 1), "at least 1 vertex"),
    (lambda: ag.simplify_curves([(0, 0), (1, 0), (2, 0)], -1), ">= 0"),
    (lambda: ag.simplify_curves([(0, 0), (1, 0)], float("nan")), "finite"),
    (lambda: ag.simplify_vertexes([(0, 0), (1, 0)], float("inf")), "finite"),
    (lambda: ag.to_convex_hull([(0, 0)], float("-inf")), "finite"),
    (lambda: ag.convex_decomposition([(0, 0), (1, 0), (0, 1), (0, 0)], float("nan")), "finite"),
    (lambda: ag.convex_decomposition([(0, 0), (1, 0), (1, 1)], 0.1), "open"),
    (lambda: ag.convex_decomposition([], 0.1), "open"),
    (lambda: ag.convex_decomposition([(0, 0), (1, 1), (1, 0), (0, 0)], 0.1), "Winding"),
    (lambda: ag.convex_decomposition([(0, 0), (float("nan"), 0), (0, 1), (0, 0)], 0.1), "Winding"),
    (lambda: ag.convex_decomposition([(0, 0), (1e308, 0), (1e308, 1e308), (0, 0)], 0.1),
     "Winding"),
])
def test_bad_polylines_raise(call, match):
    with pytest.raises(IllegalPolyline, match=match) as info:
        call()
    # pymunk asserts on the open and clockwise cases: AssertionError still works
    assert isinstance(info.value, (ValueError, AssertionError))


def test_bad_types_raise_type_error():
    for bad in ("abc", 5, None, [("a", 1)], [object()]):
        with pytest.raises(TypeError):
            ag.simplify_curves(bad, 1)
    with pytest.raises(TypeError, match="tolerance"):
        ag.to_convex_hull([(0, 0)], "x")


def test_accepts_any_sequence_of_pairs():
    pts = [(0, 0), (3, 1), (4, 4), (1, 3), (0, 0)]
    expected = exact(pymunk_ag.to_convex_hull(pts, 0))
    assert exact(ag.to_convex_hull(tuple(pts), 0)) == expected
    assert exact(ag.to_convex_hull([list(p) for p in pts], 0)) == expected
    assert exact(ag.to_convex_hull([tamias2d.Vec2d(*p) for p in pts], 0)) == expected
    assert exact(ag.to_convex_hull(iter(pts), 0)) == expected


def test_results_are_vec2d_lists():
    out = ag.simplify_curves([(0, 0), (1, 1)], 0.1)
    assert type(out) is list and all(type(v) is tamias2d.Vec2d for v in out)
    parts = ag.convex_decomposition([(0, 0), (1, 0), (0, 1), (0, 0)], 0.1)
    assert type(parts) is list and type(parts[0]) is list and type(parts[0][0]) is tamias2d.Vec2d


def test_public_names_match_pymunk():
    theirs = {n for n in vars(pymunk_ag) if not n.startswith("_")}
    theirs -= {"ffi", "lib", "TYPE_CHECKING", "Callable", "Sequence", "Union", "overload"}
    missing = sorted(n for n in theirs if not hasattr(ag, n))
    assert not missing
    import inspect
    for name in ag.__all__:
        ours, ref = getattr(ag, name), getattr(pymunk_ag, name)
        if inspect.isclass(ref):
            continue
        assert (list(inspect.signature(ours).parameters)
                == list(inspect.signature(ref).parameters)), name
