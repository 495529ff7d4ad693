"""Shape module (MIS section 7) against pymunk 7.3.

Every numeric check builds the same object in tamias2d and in pymunk and
compares the results bit for bit (``same``: equal values with equal signs, or
both NaN). pymunk answers point and segment queries from the cached world
geometry, so both sides call cache_bb() (or update()) before querying.

A failing random case names its seed and inputs so it can be rebuilt.
"""
import copy
import math
import pickle
import random
import zlib

import pytest

pymunk = pytest.importorskip("pymunk")
tamias2d = pytest.importorskip("tamias2d")
shape_mod = pytest.importorskip("tamias2d.shape")
_testing = pytest.importorskip("tamias2d._testing")
from pymunk._chipmunk_cffi import ffi as pm_ffi, lib as pm_lib  # noqa: E402
from tamias2d import errors  # noqa: E402

try:
    import tamias2d.space  # noqa: F401
    HAVE_SPACE = hasattr(tamias2d, "Space")
except ImportError:
    HAVE_SPACE = False
try:
    import tamias2d.collision  # noqa: F401
    HAVE_COLLISION = True
except ImportError:
    HAVE_COLLISION = False

needs_space = pytest.mark.skipif(not HAVE_SPACE, reason="tamias2d.Space not built yet")
needs_collision = pytest.mark.skipif(not HAVE_COLLISION, reason="tamias2d.collision not built yet")


# -- bitwise comparison ----------------------------------------------------------------------

def same(x, y):
    """Equal as doubles with equal signs (0.0 and -0.0 differ), or both NaN.
    Sequences (Vec2d, BB, tuples, lists) are compared element by element."""
    if isinstance(x, (tuple, list)) or isinstance(y, (tuple, list)):
        return len(x) == len(y) and all(same(a, b) for a, b in zip(x, y))
    if x is None or y is None:
        return x is None and y is None
    x = float(x)
    y = float(y)
    if x != x or y != y:
        return x != x and y != y
    return x == y and math.copysign(1.0, x) == math.copysign(1.0, y)


def assert_same(ours, ref, what):
    assert same(ours, ref), f"{what}: tamias2d {ours!r} != pymunk {ref!r}"


# -- random inputs -------------------------------------------------------------------------

def rand_vec(rng, s=10.0):
    return (rng.uniform(-s, s), rng.uniform(-s, s))


def rand_cloud(rng):
    """A point cloud of one of several flavours: uniform, integer grid (many
    duplicates and collinear triples), all equal, on one line, tiny."""
    kind = rng.randrange(6)
    n = rng.randint(1, 20)
    if kind == 0:
        return [rand_vec(rng) for _ in range(n)]
    if kind == 1:
        return [(float(rng.randint(-2, 2)), float(rng.randint(-2, 2))) for _ in range(n)]
    if kind == 2:
        p = rand_vec(rng)
        return [p] * n
    if kind == 3:
        a, d = rand_vec(rng), rand_vec(rng)
        return [(a[0] + t * d[0], a[1] + t * d[1]) for t in (rng.randint(-3, 3) for _ in range(n))]
    if kind == 4:
        return [rand_vec(rng, 1e-6) for _ in range(n)]
    # A convex polygon with extra interior points.
    k = rng.randint(3, 12)
    r = rng.uniform(0.5, 20)
    pts = [(r * math.cos(2 * math.pi * i / k), r * math.sin(2 * math.pi * i / k)) for i in range(k)]
    pts += [rand_vec(rng, r / 3) for _ in range(rng.randint(0, 5))]
    rng.shuffle(pts)
    return pts


def rand_transform(rng):
    kind = rng.randrange(4)
    if kind == 0:
        return (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    if kind == 1:
        a = rng.uniform(-4, 4)
        return (math.cos(a), math.sin(a), -math.sin(a), math.cos(a), *rand_vec(rng))
    if kind == 2:   # mirroring
        return (-1.0, 0.0, 0.0, 1.0, *rand_vec(rng))
    return tuple(rng.uniform(-3, 3) for _ in range(6))


def radius_choice(rng):
    return rng.choice([0.0, 0.0, rng.uniform(0, 2), rng.uniform(0, 0.01)])


def massive_ok(pymunk_shape):
    """pymunk's mass data of the shape would be finite once it has mass."""
    pymunk_shape.mass = 1.0
    ok = math.isfinite(pymunk_shape.moment) and all(map(math.isfinite, pymunk_shape.center_of_gravity))
    pymunk_shape.mass = 0.0
    return ok


def make_pair(rng, kind, t_body=None, p_body=None):
    """The same random shape in both engines, with its constructor args."""
    if kind == "circle":
        args = (rng.uniform(0, 5), rand_vec(rng, 3))
        return tamias2d.Circle(t_body, *args), pymunk.Circle(p_body, *args), args
    if kind == "segment":
        args = (rand_vec(rng), rand_vec(rng), radius_choice(rng))
        return tamias2d.Segment(t_body, *args), pymunk.Segment(p_body, *args), args
    if kind == "poly":
        # A polygon with finite mass data (degenerate hulls, whose moment or
        # center of gravity is NaN in pymunk, are tested on their own).
        pts = rand_cloud(rng)
        while not massive_ok(pymunk.Poly(None, pts)):
            pts = rand_cloud(rng)
        r = radius_choice(rng)
        return tamias2d.Poly(t_body, pts, radius=r), pymunk.Poly(p_body, pts, radius=r), (pts, r)
    if kind == "box":
        args = ((rng.uniform(0, 10), rng.uniform(0, 10)), radius_choice(rng))
        return (tamias2d.Poly.create_box(t_body, *args), pymunk.Poly.create_box(p_body, *args), args)
    raise AssertionError(kind)


def body_pair(rng, mass=1.0, moment=1.0):
    tb = tamias2d.Body(mass, moment)
    pb = pymunk.Body(mass, moment)
    pos = rand_vec(rng)
    angle = rng.uniform(-7, 7)
    tb.position = pos
    pb.position = pos
    tb.angle = angle
    pb.angle = angle
    return tb, pb


def compare_mass_data(ts, ps, what):
    assert_same(ts.mass, ps.mass, what + " mass")
    assert_same(ts.density, ps.density, what + " density")
    assert_same(ts.moment, ps.moment, what + " moment")
    assert_same(ts.area, ps.area, what + " area")
    assert_same(ts.center_of_gravity, ps.center_of_gravity, what + " center_of_gravity")


def compare_body_mass(tb, pb, what):
    assert_same(tb.mass, pb.mass, what + " body mass")
    assert_same(tb.moment, pb.moment, what + " body moment")
    assert_same(tb.center_of_gravity, pb.center_of_gravity, what + " body cog")
    assert_same(tb.position, pb.position, what + " body position")


# -- moment / area / centroid helpers ----------------------------------------------------------

def test_helpers_random():
    rng = random.Random(1)
    for case in range(600):
        m = rng.choice([1.0, rng.uniform(0, 100), 0.0])
        r1, r2 = rng.uniform(0, 5), rng.uniform(0, 5)
        off = rand_vec(rng)
        a, b = rand_vec(rng), rand_vec(rng)
        rad = radius_choice(rng)
        size = (rng.uniform(-5, 5), rng.uniform(-5, 5))
        verts = rand_cloud(rng)
        what = f"case {case}"
        assert_same(tamias2d.moment_for_circle(m, r1, r2, off),
                    pymunk.moment_for_circle(m, r1, r2, off), what + " moment_for_circle")
        assert_same(tamias2d.moment_for_segment(m, a, b, rad),
                    pymunk.moment_for_segment(m, a, b, rad), what + " moment_for_segment")
        assert_same(tamias2d.moment_for_box(m, size), pymunk.moment_for_box(m, size),
                    what + " moment_for_box")
        assert_same(tamias2d.moment_for_poly(m, verts, off, rad),
                    pymunk.moment_for_poly(m, verts, off, rad), f"{what} moment_for_poly {verts}")
        assert_same(tamias2d.area_for_circle(r1, r2), pymunk.area_for_circle(r1, r2),
                    what + " area_for_circle")
        assert_same(tamias2d.area_for_segment(a, b, rad), pymunk.area_for_segment(a, b, rad),
                    what + " area_for_segment")
        assert_same(tamias2d.area_for_poly(verts, rad), pymunk.area_for_poly(verts, rad),
                    f"{what} area_for_poly {verts}")
        ref = pm_lib.cpCentroidForPoly(len(verts), verts)
        assert_same(tamias2d.centroid_for_poly(verts), (ref.x, ref.y), f"{what} centroid {verts}")
        bb = (min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1]))
        assert_same(_testing._moment_for_box2(m, bb), pm_lib.cpMomentForBox2(m, bb),
                    what + " cpMomentForBox2")


def test_helpers_pymunk_values():
    # The numbers of pymunk's test_common, exactly.
    assert tamias2d.moment_for_circle(1, 2, 3, (1, 2)) == pymunk.moment_for_circle(1, 2, 3, (1, 2))
    assert tamias2d.moment_for_box(1, (2, 3)) == pymunk.moment_for_box(1, (2, 3))
    assert tamias2d.area_for_circle(1, 2) == pymunk.area_for_circle(1, 2)


def test_helpers_two_vertex_poly_is_a_segment():
    verts = [(0.0, 0.0), (3.0, 4.0)]
    assert tamias2d.moment_for_poly(2, verts) == tamias2d.moment_for_segment(2, *verts, 0)
    assert tamias2d.moment_for_poly(2, verts) == pymunk.moment_for_poly(2, verts)


def test_helpers_accept_iterables():
    assert tamias2d.area_for_poly(iter([(0, 0), (1, 0), (0, 1)])) == 0.5


# -- convex hull and vertex order --------------------------------------------------------------

def test_poly_vertex_order_random_clouds():
    rng = random.Random(2)
    for case in range(1500):
        pts = rand_cloud(rng)
        tr = rand_transform(rng)
        if rng.random() < 0.5:
            tp = tamias2d.Poly(None, pts)
            pp = pymunk.Poly(None, pts)
        else:
            tp = tamias2d.Poly(None, pts, tamias2d.Transform(*tr))
            pp = pymunk.Poly(None, pts, pymunk.Transform(*tr))
        assert_same(tp.get_vertices(), pp.get_vertices(), f"case {case} points {pts} transform {tr}")
        compare_mass_data(tp, pp, f"case {case} {pts}")


def test_convex_hull_with_tolerance_against_to_convex_hull():
    # pymunk's autogeometry.to_convex_hull runs cpConvexHull with a tolerance
    # into a separate result array, then closes the loop.
    from pymunk.autogeometry import to_convex_hull
    rng = random.Random(3)
    for case in range(500):
        pts = rand_cloud(rng)
        tol = rng.choice([0.0, rng.uniform(0, 0.5), rng.uniform(0, 5)])
        hull, first = _testing._convex_hull(pts, tol)
        ref = to_convex_hull(pts, tol)
        assert_same(hull + [hull[0]], ref, f"case {case} points {pts} tol {tol}")
        assert 0 <= first < len(pts)
        if len(set(pts)) > 1:
            assert same(pts[first], hull[0])


def test_hull_starts_at_lowest_x_then_y_and_is_ccw():
    p = tamias2d.Poly(None, [(-1, -1), (-1, 1), (1, 1), (1, -1)])
    assert p.get_vertices() == [(-1, -1), (1, -1), (1, 1), (-1, 1)]


def test_large_poly_uses_heap_planes():
    rng = random.Random(4)
    for n in (7, 8, 50, 400):
        pts = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n)) for i in range(n)]
        rng.shuffle(pts)
        tp, pp = tamias2d.Poly(None, pts, radius=0.5), pymunk.Poly(None, pts, radius=0.5)
        assert_same(tp.get_vertices(), pp.get_vertices(), f"{n} vertices")
        compare_mass_data(tp, pp, f"{n} vertices")
        assert_same(tp.update(tamias2d.Transform.identity()),
                    pp.update(pymunk.Transform.identity()), f"{n} vertices bb")
        # Heap -> inline -> heap through the unsafe setter.
        for m in (3, 12):
            vs = pts[:m]
            tp.unsafe_set_vertices(vs)
            pp.unsafe_set_vertices(vs)
            assert_same(tp.get_vertices(), pp.get_vertices(), f"{n} -> {m} vertices")
            compare_mass_data(tp, pp, f"{n} -> {m}")


def test_create_box_raw_order():
    rng = random.Random(5)
    for case in range(200):
        size = (rng.uniform(0, 10), rng.uniform(0, 10))
        r = radius_choice(rng)
        tp, pp = tamias2d.Poly.create_box(None, size, r), pymunk.Poly.create_box(None, size, r)
        assert_same(tp.get_vertices(), pp.get_vertices(), f"box {size}")
        assert_same(tp.radius, pp.radius, "box radius")
        compare_mass_data(tp, pp, f"box {size}")
        l, b = rand_vec(rng)
        bb = (l, b, l + rng.uniform(0, 5), b + rng.uniform(0, 5))
        tp = tamias2d.Poly.create_box_bb(None, tamias2d.BB(*bb), r)
        pp = pymunk.Poly.create_box_bb(None, pymunk.BB(*bb), r)
        assert_same(tp.get_vertices(), pp.get_vertices(), f"box bb {bb}")
        compare_mass_data(tp, pp, f"box bb {bb}")
    assert tamias2d.Poly.create_box(None).get_vertices() == [(5, -5), (5, 5), (-5, 5), (-5, -5)]


def test_c_new_functions_match_python_constructors():
    rng = random.Random(6)
    for case in range(100):
        pts = rand_cloud(rng)
        tr = rand_transform(rng)
        r = radius_choice(rng)
        s = _testing._new_shape_summary("poly", pts, tamias2d.Transform(*tr), r)
        pp = pymunk.Poly(None, pts, pymunk.Transform(*tr), r)
        assert_same(s[6], pp.get_vertices(), f"cpPolyShapeNew {pts}")
        assert_same(s[5], pp.update(pymunk.Transform.identity()), "cpPolyShapeNew bb")
        raw = pm_lib.cpPolyShapeNewRaw(pm_ffi.NULL, len(pts), pts, r)
        try:
            s = _testing._new_shape_summary("poly_raw", pts, r)
            ref = [pm_lib.cpPolyShapeGetVert(raw, i) for i in range(pm_lib.cpPolyShapeGetCount(raw))]
            assert_same(s[6], [(v.x, v.y) for v in ref], f"cpPolyShapeNewRaw {pts}")
            assert_same(s[4], pm_lib.cpShapeGetArea(raw), "cpPolyShapeNewRaw area")
            assert_same(s[3], (pm_lib.cpShapeGetCenterOfGravity(raw).x,
                               pm_lib.cpShapeGetCenterOfGravity(raw).y), "NewRaw cog")
        finally:
            pm_lib.cpShapeFree(raw)
    c = _testing._new_shape_summary("circle", 3.0, (1, 2))
    assert c[0] == 0 and c[3] == (1, 2) and c[7] == 3.0
    assert c[4] == pymunk.Circle(None, 3.0, (1, 2)).area
    s = _testing._new_shape_summary("segment", (0, 0), (3, 4), 1.0)
    assert s[0] == 1 and s[4] == pymunk.Segment(None, (0, 0), (3, 4), 1.0).area
    b2 = _testing._new_shape_summary("box2", (1, 2, 3, 4), 0.5)
    assert b2[6] == [(3, 2), (3, 4), (1, 4), (1, 2)] and b2[7] == 0.5


# -- mass data of single shapes -------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["circle", "segment", "poly", "box"])
def test_mass_density_moment_area_cog(kind):
    rng = random.Random(zlib.crc32(kind.encode()))
    for case in range(200):
        ts, ps, args = make_pair(rng, kind)
        what = f"{kind} case {case} args {args}"
        compare_mass_data(ts, ps, what)
        m = rng.uniform(0, 10)
        ts.mass = m
        ps.mass = m
        compare_mass_data(ts, ps, what + " after mass")
        d = rng.uniform(0, 10)
        ts.density = d
        ps.density = d
        compare_mass_data(ts, ps, what + " after density")


def test_pymunk_shape_defaults():
    for ts, ps in [(tamias2d.Circle(None, 1), pymunk.Circle(None, 1))]:
        assert ts.friction == ps.friction == 0
        assert ts.elasticity == ps.elasticity == 0
        assert ts.sensor is ps.sensor is False
        assert ts.collision_type == ps.collision_type == 0
        assert tuple(ts.filter) == tuple(ps.filter)
        assert ts.surface_velocity == ps.surface_velocity
        assert ts._hashid == ps._hashid == 0
        assert same(ts.bb, ps.bb)


# -- body mass accumulation ----------------------------------------------------------------

def test_mass_setter_without_space_resets_body_mass_like_pymunk():
    # Outside a space the body's shape list is empty, so pymunk's
    # accumulation gives the body mass 0 (and keeps its position).
    rng = random.Random(7)
    for case in range(50):
        tb, pb = body_pair(rng, rng.uniform(1, 5), rng.uniform(1, 5))
        ts, ps, _ = make_pair(rng, rng.choice(["circle", "segment", "poly", "box"]), tb, pb)
        ts.mass = 2.0
        ps.mass = 2.0
        compare_body_mass(tb, pb, f"case {case}")


@needs_space
def test_body_accumulation_mixed_shapes_in_space():
    rng = random.Random(8)
    kinds = ["circle", "segment", "poly", "box"]
    for case in range(60):
        tspace, pspace = tamias2d.Space(), pymunk.Space()
        tb, pb = body_pair(rng, 0.0, 0.0)
        tb.center_of_gravity = pb.center_of_gravity = rand_vec(rng, 1)
        pairs = []
        for _ in range(rng.randint(1, 6)):
            ts, ps, _ = make_pair(rng, rng.choice(kinds), tb, pb)
            how = rng.randrange(3)
            if how == 0:
                m = rng.uniform(0.1, 5)
                ts.mass = m
                ps.mass = m
            elif how == 1 and ps.area > 0:
                d = rng.uniform(0.1, 5)
                ts.density = d
                ps.density = d
            pairs.append((ts, ps))
        tspace.add(tb)
        pspace.add(pb)
        order = list(range(len(pairs)))
        rng.shuffle(order)
        for i in order:
            tspace.add(pairs[i][0])
            pspace.add(pairs[i][1])
            compare_body_mass(tb, pb, f"case {case} after adding shape {i}")
        # Change masses of shapes inside the space.
        for i, (ts, ps) in enumerate(pairs):
            if rng.random() < 0.5 and ps.area > 0:
                d = rng.uniform(0.1, 5)
                ts.density = d
                ps.density = d
                compare_body_mass(tb, pb, f"case {case} density of shape {i}")
        # Remove some again.
        rng.shuffle(order)
        for i in order[: len(order) // 2]:
            tspace.remove(pairs[i][0])
            pspace.remove(pairs[i][1])
            compare_body_mass(tb, pb, f"case {case} after removing shape {i}")


@needs_space
def test_body_change_refused_while_in_space():
    space = tamias2d.Space()
    b1, b2 = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    c = tamias2d.Circle(b1, 1)
    space.add(b1, c)
    with pytest.raises(errors.AlreadyInSpace):
        c.body = b2
    assert c.body is b1 and c in b1.shapes
    space.remove(c)
    c.body = b2
    assert c in b2.shapes and c not in b1.shapes


def test_body_switching_updates_shape_sets():
    b1, b2 = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    c = tamias2d.Circle(b1, 1)
    assert c.body is b1 and c in b1.shapes and c not in b2.shapes
    c.body = b2
    assert c.body is b2 and c not in b1.shapes and c in b2.shapes
    c.body = None
    assert c.body is None and len(b2.shapes) == 0
    # The shape keeps its body alive.
    c.body = tamias2d.Body(1, 1)
    import gc
    gc.collect()
    assert c.body is not None and c in c.body.shapes


# -- bounding boxes ---------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["circle", "segment", "poly", "box"])
def test_bb_cache_and_update(kind):
    rng = random.Random(9 + len(kind))
    for case in range(200):
        tb, pb = body_pair(rng)
        ts, ps, args = make_pair(rng, kind, tb, pb)
        what = f"{kind} case {case} args {args}"
        assert_same(ts.cache_bb(), ps.cache_bb(), what + " cache_bb")
        assert_same(ts.bb, ps.bb, what + " bb")
        tr = rand_transform(rng)
        assert_same(ts.update(tamias2d.Transform(*tr)), ps.update(pymunk.Transform(*tr)),
                    f"{what} update {tr}")
        assert_same(ts.bb, ps.bb, what + " bb after update")


# -- point and segment queries -------------------------------------------------------------------

def query_points(rng, ps):
    """Random points plus the awkward ones: vertices, edge midpoints, the
    centre of gravity in world coordinates."""
    bb = ps.bb
    pts = [(rng.uniform(bb.left - 3, bb.right + 3), rng.uniform(bb.bottom - 3, bb.top + 3))
           for _ in range(8)]
    body = ps.body
    if isinstance(ps, pymunk.Poly):
        vs = [body.local_to_world(v) for v in ps.get_vertices()]
        pts += vs
        pts += [((a.x + b.x) / 2, (a.y + b.y) / 2) for a, b in zip(vs, vs[1:] + vs[:1])]
    elif isinstance(ps, pymunk.Segment):
        pts += [body.local_to_world(ps.a), body.local_to_world(ps.b)]
    else:
        pts.append(body.local_to_world(ps.offset))
    return pts


def compare_point_query(ts, ps, p, what):
    ti, pi = ts.point_query(p), ps.point_query(p)
    assert ti.shape is ts, what
    assert_same(ti.point, pi.point, what + " point")
    assert_same(ti.distance, pi.distance, what + " distance")
    assert_same(ti.gradient, pi.gradient, what + " gradient")


def compare_segment_query(ts, ps, a, b, r, what):
    ti, pi = ts.segment_query(a, b, r), ps.segment_query(a, b, r)
    assert (ti is None) == (pi is None), f"{what}: hit {ti} vs {pi}"
    if ti is not None:
        assert ti.shape is ts, what
        assert_same(ti.point, pi.point, what + " point")
        assert_same(ti.normal, pi.normal, what + " normal")
        assert_same(ti.alpha, pi.alpha, what + " alpha")


@pytest.mark.parametrize("kind", ["circle", "segment", "poly", "box"])
def test_point_and_segment_queries(kind):
    rng = random.Random(10 + 7 * len(kind))
    for case in range(150):
        tb, pb = body_pair(rng)
        ts, ps, args = make_pair(rng, kind, tb, pb)
        ts.cache_bb()
        ps.cache_bb()
        what = f"{kind} case {case} args {args} body {tuple(pb.position)} {pb.angle}"
        pts = query_points(rng, ps)
        for p in pts:
            compare_point_query(ts, ps, p, f"{what} point {p}")
        for _ in range(10):
            a, b = rng.choice(pts), rng.choice(pts)
            if rng.random() < 0.5:
                b = (b[0] + rng.uniform(-5, 5), b[1] + rng.uniform(-5, 5))
            r = rng.choice([0.0, rng.uniform(0, 1), rng.uniform(0, 5)])
            compare_segment_query(ts, ps, a, b, r, f"{what} segment {a} {b} r {r}")


def test_queries_without_body_use_update():
    rng = random.Random(11)
    for case in range(100):
        ts, ps, args = make_pair(rng, rng.choice(["circle", "segment", "poly"]))
        tr = rand_transform(rng)
        ts.update(tamias2d.Transform(*tr))
        ps.update(pymunk.Transform(*tr))
        for _ in range(5):
            p = rand_vec(rng)
            compare_point_query(ts, ps, p, f"case {case} {args} {tr} point {p}")
            a, b = rand_vec(rng), rand_vec(rng)
            compare_segment_query(ts, ps, a, b, 0.5, f"case {case} {args} {tr} seg {a} {b}")


def test_pymunk_query_values():
    b = tamias2d.Body(10, 10)
    c = tamias2d.Circle(b, 5)
    c.cache_bb()
    info = c.point_query((0, 0))
    assert info == (c, (0, 0), -5, (0, 1))
    info = c.segment_query((0, -50), (0, 50))
    assert info.shape is c and info.alpha == 0.45
    assert c.segment_query((10, -50), (10, 50)) is None
    assert c.segment_query((10, -50), (10, 50), 6).shape is c
    # A query starting inside: alpha 0 and Munk2D reports the END point.
    info = c.segment_query((1, 0), (30, 0))
    assert info.alpha == 0 and info.point == (30, 0)


def test_point_exactly_on_poly_edge_gives_nan_point_like_pymunk():
    tp = tamias2d.Poly.create_box(None, (2, 2))
    pp = pymunk.Poly.create_box(None, (2, 2))
    tp.update(tamias2d.Transform.identity())
    pp.update(pymunk.Transform.identity())
    compare_point_query(tp, pp, (1, 0), "edge midpoint")
    assert math.isnan(tp.point_query((1, 0)).point.x)


def test_poly_segment_query_near_parallel_faces():
    # Munk2D skips a face when |an - bn| < 1e-5 (its "10e-6"); queries
    # parallel or nearly parallel to a box face, both sides of that limit.
    rng = random.Random(17)
    for case in range(600):
        w, h = rng.uniform(1, 5), rng.uniform(1, 5)
        r = rng.choice([0.0, 0.5])
        tp, pp = tamias2d.Poly.create_box(None, (w, h), r), pymunk.Poly.create_box(None, (w, h), r)
        ang = rng.choice([0.0, rng.uniform(-3, 3)])
        tr = (math.cos(ang), math.sin(ang), -math.sin(ang), math.cos(ang), 0.0, 0.0)
        tp.update(tamias2d.Transform(*tr))
        pp.update(pymunk.Transform(*tr))
        # From just above the top face to just below it (or level with it):
        # the face is crossed at t = d1 / (d1 + d2), skipped when d1 + d2 < 1e-5.
        y = rng.choice([h / 2, h / 2 + r, rng.uniform(-h, h)])
        d1 = rng.choice([0.0, 1e-6, 4e-6, 6e-6, 1e-3])
        d2 = rng.choice([0.0, 1e-6, 4e-6, 6e-6, 1e-3])
        a = (-10 * tr[0] + (y + d1) * tr[2], -10 * tr[1] + (y + d1) * tr[3])
        b = (10 * tr[0] + (y - d2) * tr[2], 10 * tr[1] + (y - d2) * tr[3])
        for rad in (0.0, 0.3):
            compare_segment_query(tp, pp, a, b, rad, f"case {case} box {w} {h} r {r} angle {ang} {a} {b} {rad}")


def test_rounded_poly_corners():
    rng = random.Random(12)
    for case in range(200):
        r = rng.uniform(0.1, 3)
        pts = [rand_vec(rng, 5) for _ in range(rng.randint(3, 9))]
        ts, ps = tamias2d.Poly(None, pts, radius=r), pymunk.Poly(None, pts, radius=r)
        ts.update(tamias2d.Transform.identity())
        ps.update(pymunk.Transform.identity())
        for v in ps.get_vertices():
            p = (v.x + rng.uniform(-2 * r, 2 * r), v.y + rng.uniform(-2 * r, 2 * r))
            compare_point_query(ts, ps, p, f"case {case} near corner {p}")
            far = (v.x * 4 + rng.uniform(-1, 1), v.y * 4 + rng.uniform(-1, 1))
            compare_segment_query(ts, ps, far, (0, 0), rng.uniform(0, 1), f"case {case} to corner")


# -- unsafe setters ---------------------------------------------------------------------------

def test_unsafe_setters_match_pymunk():
    rng = random.Random(13)
    for case in range(100):
        tb, pb = body_pair(rng)
        tc, pc = tamias2d.Circle(tb, 2, (1, 1)), pymunk.Circle(pb, 2, (1, 1))
        tc.mass = pc.mass = 3
        r, o = rng.uniform(0, 5), rand_vec(rng)
        tc.unsafe_set_radius(r)
        pc.unsafe_set_radius(r)
        tc.unsafe_set_offset(o)
        pc.unsafe_set_offset(o)
        assert_same((tc.radius, tc.offset), (pc.radius, pc.offset), "circle")
        compare_mass_data(tc, pc, f"case {case} circle")
        compare_body_mass(tb, pb, f"case {case} circle")

        ts, ps = tamias2d.Segment(None, (0, 0), (1, 0), 1), pymunk.Segment(None, (0, 0), (1, 0), 1)
        ts.mass = ps.mass = 2
        a, b = rand_vec(rng), rand_vec(rng)
        ts.unsafe_set_endpoints(a, b)
        ps.unsafe_set_endpoints(a, b)
        r = rng.uniform(0, 3)
        ts.unsafe_set_radius(r)
        ps.unsafe_set_radius(r)
        # unsafe_set_endpoints flips the normal's orientation (perp, not rperp).
        assert_same((ts.a, ts.b, ts.normal, ts.radius), (ps.a, ps.b, ps.normal, ps.radius), "segment")
        compare_mass_data(ts, ps, f"case {case} segment")

        tp, pp = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)]), pymunk.Poly(None, [(0, 0), (1, 0), (0, 1)])
        tp.mass = pp.mass = 1
        pts = [rand_vec(rng) for _ in range(rng.randint(3, 9))]
        tr = rand_transform(rng)
        if rng.random() < 0.5:
            tp.unsafe_set_vertices(pts)
            pp.unsafe_set_vertices(pts)
        elif abs(tr[0] * tr[3] - tr[1] * tr[2]) > 1e-3:
            tp.unsafe_set_vertices(pts, tamias2d.Transform(*tr))
            pp.unsafe_set_vertices(pts, pymunk.Transform(*tr))
        r = rng.uniform(0, 2)
        tp.unsafe_set_radius(r)
        pp.unsafe_set_radius(r)
        assert_same(tp.get_vertices(), pp.get_vertices(), f"case {case} poly {pts} {tr}")
        assert_same(tp.radius, pp.radius, "poly radius")
        # The area is not updated by unsafe_set_radius, in both.
        compare_mass_data(tp, pp, f"case {case} poly")


def test_segment_init_normal_and_set_endpoints_normal():
    ts, ps = tamias2d.Segment(None, (2, 2), (2, 3), 4), pymunk.Segment(None, (2, 2), (2, 3), 4)
    assert_same(ts.normal, ps.normal, "init normal")
    ts.unsafe_set_endpoints((2, 2), (2, 3))
    ps.unsafe_set_endpoints((2, 2), (2, 3))
    assert_same(ts.normal, ps.normal, "normal after unsafe_set_endpoints")
    assert ts.normal == (-1, 0)


# -- segment neighbours ---------------------------------------------------------------------------

@needs_collision
def test_segment_neighbors_change_end_cap_contacts_like_pymunk():
    rng = random.Random(14)
    for case in range(200):
        a, b = rand_vec(rng), rand_vec(rng)
        prev, nxt = rand_vec(rng), rand_vec(rng)
        r = radius_choice(rng)
        ts, ps = tamias2d.Segment(tamias2d.Body(1, 1), a, b, r), pymunk.Segment(pymunk.Body(1, 1), a, b, r)
        if rng.random() < 0.8:
            ts.set_neighbors(prev, nxt)
            ps.set_neighbors(prev, nxt)
        end = rng.choice([a, b])
        cr = rng.uniform(0.5, 3)
        tcb, pcb = tamias2d.Body(1, 1), pymunk.Body(1, 1)
        tcb.position = pcb.position = (end[0] + rng.uniform(-2, 2), end[1] + rng.uniform(-2, 2))
        tc, pc = tamias2d.Circle(tcb, cr), pymunk.Circle(pcb, cr)
        for s in (ts, ps, tc, pc):
            s.cache_bb()
        ref = pm_lib.cpShapesCollide(pc._shape, ps._shape)
        got = tc.shapes_collide(ts)
        what = f"case {case} seg {a} {b} r {r} neighbors {prev} {nxt} circle {tuple(pcb.position)} {cr}"
        assert len(got.points) == ref.count, what
        if ref.count:
            assert_same(got.normal, (ref.normal.x, ref.normal.y), what + " normal")


# -- filters ---------------------------------------------------------------------------------

def test_shape_filter_like_pymunk():
    f = tamias2d.ShapeFilter()
    assert tuple(f) == tuple(pymunk.ShapeFilter()) and f._fields == pymunk.ShapeFilter._fields
    assert tamias2d.ShapeFilter.ALL_MASKS() == pymunk.ShapeFilter.ALL_MASKS()
    assert tamias2d.ShapeFilter.ALL_CATEGORIES() == pymunk.ShapeFilter.ALL_CATEGORIES()
    rng = random.Random(15)
    for _ in range(2000):
        fa = (rng.randint(0, 3), rng.randint(0, 15), rng.randint(0, 15))
        fb = (rng.randint(0, 3), rng.randint(0, 15), rng.randint(0, 15))
        ref = pymunk.ShapeFilter(*fa).rejects_collision(pymunk.ShapeFilter(*fb))
        assert tamias2d.ShapeFilter(*fa).rejects_collision(tamias2d.ShapeFilter(*fb)) == ref
        assert _testing._filter_reject(fa, fb) == ref
    c = tamias2d.Circle(None, 1)
    c.filter = tamias2d.ShapeFilter(1, 0xFFFFFFF2, 0xFFFFFFF3)
    assert c.filter == (1, 0xFFFFFFF2, 0xFFFFFFF3)
    assert pickle.loads(pickle.dumps(c.filter)) == c.filter


# -- copy and pickle -------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["circle", "segment", "poly", "box"])
def test_pickle_and_copy(kind):
    rng = random.Random(16)
    tb = tamias2d.Body(3, 4)
    tb.position = (1, 2)
    ts, ps, _ = make_pair(rng, kind, tb, pymunk.Body(3, 4))
    ts.sensor = True
    ts.collision_type = 6
    ts.filter = tamias2d.ShapeFilter(2, 3, 5)
    ts.elasticity = 0.7
    ts.friction = 0.8
    ts.surface_velocity = (9, 10)
    ts.color = (255, 0, 0, 255)
    if ts.area > 0:
        ts.density = 1.5
    for clone in (pickle.loads(pickle.dumps(ts)), ts.copy(), copy.deepcopy(ts)):
        assert type(clone) is type(ts)
        for attr in ("sensor", "collision_type", "filter", "elasticity", "friction",
                     "surface_velocity", "mass", "density", "moment", "area",
                     "center_of_gravity", "color"):
            assert same(getattr(clone, attr), getattr(ts, attr)) or getattr(clone, attr) == getattr(ts, attr), attr
        assert clone.body is not tb and clone.body.mass == tb.mass
        assert clone.body.position == tb.position
        assert clone in clone.body.shapes
        if kind in ("poly", "box"):
            # Restoring re-runs the convex hull (a box's raw order becomes
            # hull order), exactly as in pymunk.
            assert_same(clone.get_vertices(), pickle.loads(pickle.dumps(ps)).get_vertices(),
                        "restored vertices")
            assert clone.radius == ts.radius


def test_pickle_state_layout_like_pymunk():
    ts, ps = tamias2d.Circle(None, 3, (4, 5)), pymunk.Circle(None, 3, (4, 5))
    ts.density = ps.density = 3
    t_state, p_state = ts.__getstate__(), ps.__getstate__()
    assert [k for k, _ in t_state["init"]] == [k for k, _ in p_state["init"]]
    assert [k for k, _ in t_state["general"]] == [k for k, _ in p_state["general"]]
    c2, p2 = pickle.loads(pickle.dumps(ts)), pickle.loads(pickle.dumps(ps))
    assert_same((c2.mass, c2.density), (p2.mass, p2.density), "restored mass")


def test_reinit_detaches_from_old_body():
    b1, b2 = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    c = tamias2d.Circle(b1, 1)
    c.__init__(b2, 2)
    assert c.body is b2 and c not in b1.shapes and c in b2.shapes and c.radius == 2
    p = tamias2d.Poly(b1, [(0, 0), (1, 0), (0, 1)] + [(0.1, 0.1)] * 10)
    p.__init__(None, [(math.cos(i), math.sin(i)) for i in range(20)])
    assert p.body is None and p not in b1.shapes and len(p.get_vertices()) == 20


def test_user_attributes():
    c = tamias2d.Circle(None, 1)
    c.color = (1, 2, 3, 4)
    assert c.__dict__ == {"color": (1, 2, 3, 4)}


# -- bad input ----------------------------------------------------------------------------

@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), -0.001])
def test_bad_radius(bad):
    with pytest.raises(errors.IllegalShape):
        tamias2d.Circle(None, bad)
    with pytest.raises(errors.IllegalShape):
        tamias2d.Segment(None, (0, 0), (1, 0), bad)
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)], radius=bad)
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly.create_box(None, (1, 1), bad)
    with pytest.raises(errors.IllegalShape):
        tamias2d.Circle(None, 1).unsafe_set_radius(bad)
    with pytest.raises(errors.IllegalShape):
        tamias2d.Segment(None, (0, 0), (1, 0), 1).unsafe_set_radius(bad)
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)]).unsafe_set_radius(bad)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_bad_coordinates(bad):
    with pytest.raises(ValueError):
        tamias2d.Circle(None, 1, (bad, 0))
    with pytest.raises(ValueError):
        tamias2d.Segment(None, (0, bad), (1, 0), 0)
    with pytest.raises(ValueError):
        tamias2d.Poly(None, [(0, 0), (1, bad), (0, 1)])
    with pytest.raises(ValueError):
        tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)]).unsafe_set_vertices([(bad, 0), (1, 1), (2, 0)])
    with pytest.raises(ValueError):
        tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)], tamias2d.Transform(bad, 0, 0, 1, 0, 0))
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly.create_box_bb(None, tamias2d.BB(0, 0, bad, 1))
    with pytest.raises(ValueError):
        tamias2d.Circle(None, 1).surface_velocity = (bad, 0)


def test_bad_vertices():
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly(None, [])
    with pytest.raises(TypeError):
        tamias2d.Poly(None, 5)
    with pytest.raises(TypeError):
        tamias2d.Poly(None, "abc")
    with pytest.raises((TypeError, ValueError)):
        tamias2d.Poly(None, [(0, 0), (1,), (0, 1)])
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)]).unsafe_set_vertices([])
    for f in (tamias2d.moment_for_poly, tamias2d.area_for_poly):
        with pytest.raises(errors.IllegalShape):
            f(*((1, []) if f is tamias2d.moment_for_poly else ([],)))
    with pytest.raises(errors.IllegalShape):
        tamias2d.centroid_for_poly([])


def test_bad_body_and_misc():
    with pytest.raises(errors.IllegalBody):
        tamias2d.Circle(pymunk.Body(1, 1), 1)
    with pytest.raises(errors.IllegalBody):
        tamias2d.Circle(None, 1).body = "body"
    with pytest.raises(TypeError):
        tamias2d.Shape()
    with pytest.raises(errors.IllegalBody):
        tamias2d.Circle(None, 1).cache_bb()
    c = tamias2d.Circle(None, 1)
    for attr, bad in [("friction", -1), ("elasticity", float("nan")), ("mass", -1),
                      ("mass", float("inf")), ("density", float("nan"))]:
        with pytest.raises(errors.IllegalShape):
            setattr(c, attr, bad)
    with pytest.raises(OverflowError):
        c.collision_type = -1
    with pytest.raises(OverflowError):
        c.filter = tamias2d.ShapeFilter(categories=1 << 40)
    with pytest.raises(TypeError):
        c.filter = 5
    p = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)])
    with pytest.raises(errors.IndexOutOfBounds):
        p.get_vertex(3)
    with pytest.raises(errors.IndexOutOfBounds):
        p.get_vertex(-1)
    assert p.get_vertex(2) == p.get_vertices()[2]
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly.create_box(None, (-1, 1))
    with pytest.raises(errors.IllegalShape):
        tamias2d.Poly.create_box_bb(None, tamias2d.BB(1, 0, 0, 1))


def test_nearly_collinear_poly_refuses_mass_where_pymunk_breaks():
    # A hull of nearly collinear points can have a tiny non-zero area while
    # the moment (computed about the centroid) divides by a zero sum. pymunk
    # then gives the shape and its body an infinite or NaN moment; tamias2d
    # refuses the mass.
    a, b, c = (3.169235664436882, -9.713072793965372), (0.9240068894814986, -10.944721847421338), \
        (7.659693214347649, -7.24977468705344)
    d, e, f = (12.150150764258417, -4.786476580141509), (9.904921989303032, -6.018125633597474), \
        (5.414464439392265, -8.481423740509406)
    pts = [a, b, b, a, c, d, e, c, f, d, a]
    tp, pp = tamias2d.Poly(None, pts), pymunk.Poly(None, pts)
    assert_same(tp.get_vertices(), pp.get_vertices(), "vertices")
    compare_mass_data(tp, pp, "mass data")
    pp.mass = 1
    assert not math.isfinite(pp.moment)
    with pytest.raises(errors.IllegalShape):
        tp.mass = 1
    assert tp.mass == 0


def test_degenerate_poly_is_built_but_refuses_mass():
    # pymunk builds these (hull of 1 or 2 points) with a NaN center of
    # gravity; giving them mass would make the body NaN, so tamias2d refuses.
    for pts in ([(1, 1)], [(0, 0), (1, 1), (2, 2)], [(3, 3)] * 5):
        tp, pp = tamias2d.Poly(None, pts), pymunk.Poly(None, pts)
        assert_same(tp.get_vertices(), pp.get_vertices(), f"{pts}")
        compare_mass_data(tp, pp, f"{pts}")
        tp.density = 5      # area 0: mass stays 0, allowed
        assert tp.mass == 0
        with pytest.raises(errors.IllegalShape):
            tp.mass = 1
    p = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)])
    p.mass = 1
    with pytest.raises(errors.IllegalShape):
        p.unsafe_set_vertices([(0, 0), (1, 1)])
    assert len(p.get_vertices()) == 3


# -- doctests (properties included: doctest's finder skips C getset descriptors) ---------------

def _docstring_owners():
    yield "tamias2d.shape", shape_mod
    for name, obj in vars(shape_mod).items():
        if name.startswith("__") or getattr(obj, "__module__", "tamias2d.shape") != "tamias2d.shape":
            continue
        if callable(obj) or isinstance(obj, type):
            yield f"tamias2d.shape.{name}", obj
        if isinstance(obj, type):
            for attr, member in vars(obj).items():
                if attr.startswith("__") and attr not in ("__getstate__", "__setstate__"):
                    continue
                yield f"tamias2d.shape.{name}.{attr}", member


def test_doctests():
    import doctest
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    n = 0
    for name, obj in _docstring_owners():
        doc = getattr(obj, "__doc__", None)
        if not isinstance(doc, str) or ">>>" not in doc:
            continue
        runner.run(parser.get_doctest(doc, dict(vars(shape_mod)), name, None, 0))
        n += 1
    result = runner.summarize(verbose=False)
    assert result.failed == 0
    assert n > 50


def test_every_public_name_has_a_doctest():
    missing = []
    for name in shape_mod.__all__:
        obj = getattr(shape_mod, name)
        if ">>>" not in (obj.__doc__ or ""):
            missing.append(name)
        if isinstance(obj, type):
            for attr, member in vars(obj).items():
                # NamedTuple fields are documented by the class docstring.
                if (attr.startswith("_") or attr in getattr(obj, "_fields", ())
                        or isinstance(member, (list, str))):
                    continue
                if ">>>" not in (getattr(member, "__doc__", None) or ""):
                    missing.append(f"{name}.{attr}")
    assert not missing, missing
