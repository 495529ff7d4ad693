"""Collision Solver module (MIS section 10): hand-worked cases.

Each expected value below is worked out on paper from the shapes' geometry;
where the arithmetic is exact in binary (sums and products of small powers of
two) the comparison is exact, elsewhere it is to 1e-12.
"""
import math
import pickle
import warnings

import pytest

import tamias2d
from tamias2d import collision
from tamias2d import _testing
from tamias2d.collision import (ContactPoint, ContactPointSet, shapes_collide,
    relative_velocity, normal_relative_velocity, apply_impulse, apply_impulses,
    apply_bias_impulse, apply_bias_impulses, k_scalar_body, k_scalar)
from tamias2d.errors import (CollisionError, HighIterWarning, UnsolvableCollision,
    Tamias2DError)


def body_at(x, y, angle=0.0, mass=1.0, moment=1.0):
    b = tamias2d.Body(mass, moment)
    b.angle = angle
    b.position = (x, y)
    return b


def cached(*shapes):
    for s in shapes:
        s.cache_bb()
    return shapes


def approx_vec(v, expected, tol=1e-12):
    return abs(v[0] - expected[0]) <= tol and abs(v[1] - expected[1]) <= tol


# -- circle on circle ------------------------------------------------------------------------

def test_circle_circle_overlap():
    # Centres 4 apart, radii 2 and 3: 1 of overlap along +x.
    a, b = cached(tamias2d.Circle(body_at(0, 0), 2), tamias2d.Circle(body_at(4, 0), 3))
    s = shapes_collide(a, b)
    assert tuple(s.normal) == (1.0, 0.0)
    assert len(s.points) == 1
    p = s.points[0]
    assert tuple(p.point_a) == (2.0, 0.0)      # a's surface towards b
    assert tuple(p.point_b) == (1.0, 0.0)      # b's surface towards a
    assert p.distance == -1.0


def test_circle_circle_diagonal_and_order():
    # Centres (0,0) and (3,4): distance 5, radii 3 and 3 -> overlap 1 along (0.6, 0.8).
    a, b = cached(tamias2d.Circle(body_at(0, 0), 3), tamias2d.Circle(body_at(3, 4), 3))
    s = shapes_collide(a, b)
    assert approx_vec(s.normal, (0.6, 0.8))
    p = s.points[0]
    assert approx_vec(p.point_a, (1.8, 2.4))
    assert approx_vec(p.point_b, (1.2, 1.6))
    assert p.distance == pytest.approx(-1.0, abs=1e-12)
    # Reversed arguments: same contact seen from b.
    r = shapes_collide(b, a)
    assert approx_vec(r.normal, (-0.6, -0.8))
    assert approx_vec(r.points[0].point_a, (1.2, 1.6))
    assert approx_vec(r.points[0].point_b, (1.8, 2.4))


def test_circle_circle_separated_and_exactly_touching():
    a, b = cached(tamias2d.Circle(body_at(0, 0), 1), tamias2d.Circle(body_at(3, 0), 1))
    assert shapes_collide(a, b).points == ()
    # Exactly touching (distance == r1 + r2) is not a collision: the test is strict.
    a, b = cached(tamias2d.Circle(body_at(0, 0), 1), tamias2d.Circle(body_at(2, 0), 1))
    assert shapes_collide(a, b).points == ()


def test_circle_circle_coincident():
    # No direction between the centres: Munk2D uses +x.
    a, b = cached(tamias2d.Circle(body_at(5, 5), 10), tamias2d.Circle(body_at(5, 5), 10))
    s = shapes_collide(a, b)
    assert tuple(s.normal) == (1.0, 0.0)
    assert tuple(s.points[0].point_a) == (15.0, 5.0)
    assert tuple(s.points[0].point_b) == (-5.0, 5.0)
    assert s.points[0].distance == -20.0


def test_shape_method_uncached_world_data():
    # As pymunk's testShapesCollide: without cache_bb the world centre of a
    # shape not in a space is still the origin, so the circles coincide.
    s1 = tamias2d.Circle(tamias2d.Body(1, 1), 10)
    b2 = tamias2d.Body(1, 1)
    b2.position = 30, 30
    s2 = tamias2d.Circle(b2, 10)
    c = s1.shapes_collide(s2)
    assert c.normal == (1, 0)
    assert len(c.points) == 1
    assert c.points[0].point_a == (10, 0)
    assert c.points[0].point_b == (-10, 0)
    assert c.points[0].distance == -20


# -- box on box, face to face ----------------------------------------------------------------

def test_box_on_box_face_to_face():
    # Two 2x2 boxes, the second 1.5 above: faces y = 1 (a) and y = 0.5 (b)
    # overlap by 0.5 over x in [-1, 1]. Two contacts at the ends of the overlap.
    a = tamias2d.Poly.create_box(body_at(0, 0), (2, 2))
    b = tamias2d.Poly.create_box(body_at(0, 1.5), (2, 2))
    cached(a, b)
    s = shapes_collide(a, b)
    assert tuple(s.normal) == (0.0, 1.0)
    assert len(s.points) == 2
    got = sorted((tuple(p.point_a), tuple(p.point_b), p.distance) for p in s.points)
    assert got == [((-1.0, 1.0), (-1.0, 0.5), -0.5), ((1.0, 1.0), (1.0, 0.5), -0.5)]


def test_box_on_box_offset_overlap_region():
    # Second box shifted right by 1: the faces overlap over x in [0, 1] only.
    a = tamias2d.Poly.create_box(body_at(0, 0), (2, 2))
    b = tamias2d.Poly.create_box(body_at(1, 1.75), (2, 2))
    cached(a, b)
    s = shapes_collide(a, b)
    assert tuple(s.normal) == (0.0, 1.0)
    got = sorted((tuple(p.point_a), tuple(p.point_b), p.distance) for p in s.points)
    assert got == [((0.0, 1.0), (0.0, 0.75), -0.25), ((1.0, 1.0), (1.0, 0.75), -0.25)]


def test_box_on_box_separated():
    a = tamias2d.Poly.create_box(body_at(0, 0), (2, 2))
    b = tamias2d.Poly.create_box(body_at(0, 2.5), (2, 2))
    cached(a, b)
    assert shapes_collide(a, b).points == ()


# -- box corner into a segment ----------------------------------------------------------------

def test_box_corner_into_segment():
    # A 2x2 box turned 45 degrees stands on its corner; its centre is
    # sqrt(2) - 0.1 above the segment y = 0, so the corner is 0.1 below it.
    seg = tamias2d.Segment(body_at(0, 0), (-5, 0), (5, 0), 0)
    box = tamias2d.Poly.create_box(body_at(0, math.sqrt(2) - 0.1, math.pi / 4), (2, 2))
    cached(seg, box)
    s = shapes_collide(seg, box)
    assert approx_vec(s.normal, (0.0, 1.0))
    assert len(s.points) == 1
    p = s.points[0]
    assert approx_vec(p.point_a, (0.0, 0.0), 1e-9)      # on the segment
    assert approx_vec(p.point_b, (0.0, -0.1), 1e-9)     # the box corner
    assert p.distance == pytest.approx(-0.1, abs=1e-9)
    # Seen from the box, the normal points down.
    r = shapes_collide(box, seg)
    assert approx_vec(r.normal, (0.0, -1.0))
    assert approx_vec(r.points[0].point_a, (0.0, -0.1), 1e-9)


def test_segment_end_cap_rejected_by_neighbour():
    # A circle touching the end b = (1, 0) of a segment from the right. With a
    # neighbour continuing to (2, 0), the end cap is inside a chain and the
    # contact is dropped.
    body = body_at(0, 0)
    seg = tamias2d.Segment(body, (0, 0), (1, 0), 0)
    circle = tamias2d.Circle(body_at(1.25, 0), 0.5)
    cached(seg, circle)
    s = shapes_collide(circle, seg)
    assert tuple(s.normal) == (-1.0, 0.0)
    assert len(s.points) == 1
    assert tuple(s.points[0].point_b) == (1.0, 0.0)
    seg.set_neighbors((-1, 0), (2, 0))
    cached(seg)
    assert shapes_collide(circle, seg).points == ()


# -- rounded polygons ------------------------------------------------------------------------

def test_rounded_box_against_circle():
    # A 2x2 box with radius 0.5 has its top surface at y = 1.5; a circle of
    # radius 1 centred at y = 2.25 reaches down to 1.25: overlap 0.25.
    box = tamias2d.Poly.create_box(body_at(0, 0), (2, 2), 0.5)
    circle = tamias2d.Circle(body_at(0, 2.25), 1)
    cached(box, circle)
    s = shapes_collide(box, circle)
    assert tuple(s.normal) == (0.0, 1.0)
    assert len(s.points) == 1
    assert tuple(s.points[0].point_a) == (0.0, 1.5)
    assert tuple(s.points[0].point_b) == (0.0, 1.25)
    # Munk2D quirk, kept: when cpCollide sorted the pair by swapping it (a
    # polygon before a circle), cpShapesCollide turns the normal back but
    # computes the distance from the unswapped points, so its sign flips.
    # pymunk 7.3 reports +0.25 here too; the other argument order gives -0.25.
    assert s.points[0].distance == 0.25
    r = shapes_collide(circle, box)
    assert tuple(r.normal) == (0.0, -1.0)
    assert r.points[0].distance == -0.25


def test_rounded_boxes_face_to_face():
    # Radii 0.25 each. With b at y = 3 the cores (faces y = 1 and y = 2) are
    # 1 apart and the radii add up to 0.5: separated by 0.5.
    a = tamias2d.Poly.create_box(body_at(0, 0), (2, 2), 0.25)
    b = tamias2d.Poly.create_box(body_at(0, 3), (2, 2), 0.25)
    cached(a, b)
    assert shapes_collide(a, b).points == ()
    # Lower b to 2.25: cores 0.25 apart, radii 0.5, overlap 0.25. Surfaces at
    # y = 1.25 (a) and y = 1.0 (b).
    b.body.position = (0, 2.25)
    cached(b)
    s = shapes_collide(a, b)
    assert tuple(s.normal) == (0.0, 1.0)
    got = sorted((tuple(p.point_a), tuple(p.point_b), p.distance) for p in s.points)
    assert got == [((-1.0, 1.25), (-1.0, 1.0), -0.25), ((1.0, 1.25), (1.0, 1.0), -0.25)]


# -- the C-level collide: ids, hashes, warm start -----------------------------------------------

def test_collide_swaps_sorted_types_and_hashes():
    box = tamias2d.Poly.create_box(body_at(0, 0), (2, 2))
    circle = tamias2d.Circle(body_at(0, 1.5), 1)
    cached(box, circle)
    a_first, cid, n, contacts = _testing._collide(box, circle)
    assert a_first is False                   # circle (type 0) goes first
    assert tuple(n) == (0.0, -1.0)            # from the circle to the box
    assert len(contacts) == 1 and contacts[0][2] == 0   # circle contacts hash 0
    # Poly contacts carry CP_HASH_PAIR of the two edge-point hashes.
    a = tamias2d.Poly.create_box(body_at(0, 0), (2, 2))
    b = tamias2d.Poly.create_box(body_at(0, 1.5), (2, 2))
    cached(a, b)
    _, cid, n, contacts = _testing._collide(a, b)
    assert len(contacts) == 2
    hashes = [h for _, _, h in contacts]
    assert all(h != 0 for h in hashes) and hashes[0] != hashes[1]
    assert cid != 0


def test_warm_start_gives_the_same_contacts():
    # Separated polygons (GJK only): restarting from the cached id lands on
    # the same closest edge.
    a = tamias2d.Poly(body_at(0, 0), [(-1, -1), (1, -1), (1.2, 1), (-1, 1.1)])
    b = tamias2d.Poly(body_at(0.3, 2.05, 0.2), [(-1, -1), (1, -1), (0, 1)])
    cached(a, b)
    cold = _testing._collide(a, b, 0)
    warm = _testing._collide(a, b, cold[1])
    assert warm[1:] == cold[1:]


def test_unsorted_table_slots_raise_collision_error():
    body = body_at(0, 0)
    circle = tamias2d.Circle(body, 1)
    seg = tamias2d.Segment(body, (0, 0), (1, 0), 1)
    poly = tamias2d.Poly.create_box(body, (1, 1))
    for a, b in ((seg, circle), (poly, circle), (poly, seg)):
        with pytest.raises(CollisionError):
            _testing._collision_table_call(a, b)
    # The sorted slots work.
    assert _testing._collision_table_call(circle, poly) >= 0
    assert issubclass(CollisionError, Tamias2DError)


def test_bad_arguments():
    c = tamias2d.Circle(body_at(0, 0), 1)
    with pytest.raises(TypeError):
        shapes_collide(c, None)
    with pytest.raises(TypeError):
        shapes_collide("circle", c)
    with pytest.raises(TypeError):
        apply_impulse(None, (1, 0), (0, 0))
    with pytest.raises((TypeError, ValueError)):
        apply_impulse(tamias2d.Body(1, 1), (float("nan"), 0), (0, 0))


# -- GJK / EPA iteration limits ------------------------------------------------------------------
# Munk2D gives up after 30 iterations of GJK or EPA and (in debug builds)
# warns from 20 on. Both limits are reached by ordinary inputs:
# - EPA: two nearly concentric many-sided polygons. Each EPA step adds one
#   hull point, and the difference of two 32-gons has 64 vertices near the
#   closest edge, so EPA runs out of its 30 iterations.
# - GJK: a point below a polygon whose vertices lie on the parabola y = x**2
#   at x = 1.5**-k. The chord normal of each GJK edge finds the next vertex
#   towards the small end, so GJK walks one vertex per iteration and stops at
#   its cap (reported as iteration 31).

def ngon(body, n, r):
    return tamias2d.Poly(body, [(r * math.cos(2 * math.pi * i / n), r * math.sin(2 * math.pi * i / n))
                                for i in range(n)])


def parabola_poly(body, count=60, base=1.5):
    return tamias2d.Poly(body, [(base ** -k, base ** (-2 * k)) for k in range(count)])


def collide_recording(a, b):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = shapes_collide(a, b)
    return result, [str(w.message) for w in caught if issubclass(w.category, HighIterWarning)]


def test_epa_iteration_limit_warns():
    a = ngon(body_at(0, 0), 32, 1.0)
    b = ngon(body_at(0.01, 0.0, 0.1), 32, 1.0)
    cached(a, b)
    result, messages = collide_recording(a, b)
    assert messages == ["High EPA iterations: 30"]
    # The answer is the edge EPA had reached: still a valid contact set.
    assert len(result.points) in (1, 2)
    assert abs(math.hypot(*result.normal) - 1.0) < 1e-12
    assert all(p.distance < 0 for p in result.points)


def test_epa_warning_below_the_limit():
    # Warns from iteration 20 on, without hitting the cap.
    a = ngon(body_at(0, 0), 32, 1.0)
    b = ngon(body_at(0.01, 0.02, 0.2), 32, 1.0)
    cached(a, b)
    _, messages = collide_recording(a, b)
    assert messages == ["High EPA iterations: 26"]


def test_gjk_iteration_limit_warns():
    poly = parabola_poly(body_at(0, 0))
    assert len(poly.get_vertices()) == 60
    point = tamias2d.Circle(body_at(1.5 ** -48, -0.1), 0.0)
    cached(poly, point)
    result, messages = collide_recording(point, poly)
    assert messages == ["High GJK iterations: 31"]
    assert result.points == ()            # 0.1 apart, no radius: no contact
    # With a radius the capped GJK answer becomes a contact.
    big = tamias2d.Circle(point.body, 0.2)
    cached(big)
    result, messages = collide_recording(big, poly)
    assert messages == ["High GJK iterations: 31"]
    assert len(result.points) == 1


def test_no_warning_for_ordinary_pairs():
    a = ngon(body_at(0, 0), 6, 1.0)
    b = ngon(body_at(0.5, 0.3, 0.1), 6, 1.0)
    cached(a, b)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(shapes_collide(a, b).points) >= 1


# -- impulse helpers ----------------------------------------------------------------------------------

def test_relative_velocity_hand_computed():
    a = tamias2d.Body(1, 1)
    b = tamias2d.Body(1, 1)
    a.velocity = (1, 2)
    a.angular_velocity = 3
    b.velocity = (-1, 0.5)
    b.angular_velocity = -2
    # v_a at r1 = (1, 0): (1, 2) + 3 * perp(1, 0) = (1, 2) + (0, 3) = (1, 5)
    # v_b at r2 = (0, 2): (-1, 0.5) - 2 * perp(0, 2) = (-1, 0.5) - 2 * (-2, 0) = (3, 0.5)
    v = relative_velocity(a, b, (1, 0), (0, 2))
    assert tuple(v) == (2.0, -4.5)
    assert normal_relative_velocity(a, b, (1, 0), (0, 2), (0, 1)) == -4.5
    assert normal_relative_velocity(a, b, (1, 0), (0, 2), (0.5, 0.5)) == -1.25


def test_apply_impulse_hand_computed():
    b = tamias2d.Body(4, 8)
    b.velocity = (1, 1)
    b.angular_velocity = 0.5
    # v += j / m = (2, -4) / 4; w += cross(r, j) / I = (1*-4 - 3*2) / 8 = -1.25
    apply_impulse(b, (2, -4), (1, 3))
    assert tuple(b.velocity) == (1.5, 0.0)
    assert b.angular_velocity == -0.75


def test_apply_impulses_opposite():
    a = tamias2d.Body(2, 2)
    b = tamias2d.Body(4, 4)
    # a gets -j at r1: v = (-1, 0), w = cross((0, 1), (-2, 0)) / 2 = (0*0 - 1*-2)/2 = 1
    # b gets  j at r2: v = (0.5, 0), w = cross((0, -1), (2, 0)) / 4 = (0 - -1*2)/4 = 0.5
    apply_impulses(a, b, (0, 1), (0, -1), (2, 0))
    assert tuple(a.velocity) == (-1.0, 0.0) and a.angular_velocity == 1.0
    assert tuple(b.velocity) == (0.5, 0.0) and b.angular_velocity == 0.5


def test_bias_impulses_touch_only_bias_velocities():
    a = tamias2d.Body(2, 2)
    b = tamias2d.Body(4, 4)
    apply_bias_impulses(a, b, (0, 1), (0, -1), (2, 0))
    assert tuple(a.velocity) == (0.0, 0.0) and a.angular_velocity == 0.0
    va, wa = _testing._bias_velocity(a)
    vb, wb = _testing._bias_velocity(b)
    assert tuple(va) == (-1.0, 0.0) and wa == 1.0
    assert tuple(vb) == (0.5, 0.0) and wb == 0.5
    apply_bias_impulse(a, (2, 0), (0, 1))      # undoes a's part
    va, wa = _testing._bias_velocity(a)
    assert tuple(va) == (0.0, 0.0) and wa == 0.0


def test_k_scalar_hand_computed():
    a = tamias2d.Body(2, 4)     # m_inv 0.5, i_inv 0.25
    b = tamias2d.Body(4, 2)     # m_inv 0.25, i_inv 0.5
    # k_a = 0.5 + 0.25 * cross((1, 2), (0, 1))**2 = 0.5 + 0.25 * 1 = 0.75
    # k_b = 0.25 + 0.5 * cross((-2, 0), (0, 1))**2 = 0.25 + 0.5 * 4 = 2.25
    assert k_scalar_body(a, (1, 2), (0, 1)) == 0.75
    assert k_scalar_body(b, (-2, 0), (0, 1)) == 2.25
    assert k_scalar(a, b, (1, 2), (-2, 0), (0, 1)) == 3.0


def test_k_scalar_unsolvable():
    # Two bodies of infinite mass and moment: nothing can move them.
    a = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
    b = tamias2d.Body(body_type=tamias2d.Body.STATIC)
    assert k_scalar_body(a, (1, 1), (0, 1)) == 0.0
    with pytest.raises(UnsolvableCollision):
        k_scalar(a, b, (1, 1), (2, 0), (0, 1))
    assert issubclass(UnsolvableCollision, ArithmeticError)


# -- Python classes ----------------------------------------------------------------------------------

def test_contact_point_classes():
    p = ContactPoint(tamias2d.Vec2d(1.0, 2.0), tamias2d.Vec2d(3.0, 4.0), -0.5)
    assert repr(p) == "ContactPoint(point_a=Vec2d(1.0, 2.0), point_b=Vec2d(3.0, 4.0), distance=-0.5)"
    s = ContactPointSet(tamias2d.Vec2d(0.0, 1.0), (p,))
    assert repr(s).startswith("ContactPointSet(normal=Vec2d(0.0, 1.0), points=(ContactPoint(")
    p.distance = -1.0                         # mutable, as in pymunk
    assert s.points[0].distance == -1.0
    s2 = pickle.loads(pickle.dumps(s))
    assert s2.normal == s.normal and s2.points[0].point_b == p.point_b
    assert tamias2d.ContactPoint is ContactPoint
    assert tamias2d.ContactPointSet is ContactPointSet


def test_collide_loop_helper():
    a, b = cached(tamias2d.Circle(body_at(0, 0), 1), tamias2d.Circle(body_at(1, 0), 1))
    assert _testing._collide_loop([(a, b), (b, a)], 5) == 10


# -- doctests ------------------------------------------------------------------------------------------

def test_doctests():
    import doctest
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    n = 0
    for name, obj in sorted(vars(collision).items()):
        doc = getattr(obj, "__doc__", None)
        if callable(obj) and doc and ">>>" in doc and getattr(obj, "__module__", None) == collision.__name__:
            runner.run(parser.get_doctest(doc, dict(vars(collision)), "tamias2d.collision." + name, None, 0))
            n += 1
    # The narrow-phase test hooks live in tamias2d._testing.
    for name in ("_bias_velocity", "_collide", "_collision_table_call", "_collide_loop"):
        doc = getattr(_testing, name).__doc__
        runner.run(parser.get_doctest(doc, dict(vars(_testing)), "tamias2d._testing." + name, None, 0))
        n += 1
    assert runner.summarize(verbose=False).failed == 0
    assert n >= 15


def test_every_public_function_has_an_example():
    for name in collision.__all__:
        assert ">>>" in (getattr(collision, name).__doc__ or ""), name


# -- the soft solver's polygon pairs: separating axes instead of GJK and EPA -------------

def _random_polygon(rng, centre, radius, sides, angle):
    points = [(centre[0] + radius * (1 + 0.3 * rng.random()) * math.cos(angle + 2 * math.pi * k / sides),
               centre[1] + radius * (1 + 0.3 * rng.random()) * math.sin(angle + 2 * math.pi * k / sides))
              for k in range(sides)]
    body = tamias2d.Body(1, 1)
    poly = tamias2d.Poly(body, points)
    poly.cache_bb()
    return poly


def _soft_finds_what_munk2d_finds(a, b, margin, trial):
    """The soft solver's narrow phase against Munk2D's on one pair: the same
    features, and the normal and points up to EPA's tolerance. Returns both
    first results and whether there were contacts."""
    first, _, n, contacts = _testing._collide(a, b, margin=margin)
    first_s, _, n_s, contacts_s = _testing._collide(a, b, margin=margin, soft=True)
    assert [c[2] for c in contacts] == [c[2] for c in contacts_s], trial
    if contacts:
        assert abs(n.x - n_s.x) < 1e-6 and abs(n.y - n_s.y) < 1e-6, trial
        for (p1, p2, _), (q1, q2, _) in zip(contacts, contacts_s):
            assert (p1 - q1).length < 1e-6 and (p2 - q2).length < 1e-6, trial
    return first, first_s, bool(contacts)


@pytest.mark.parametrize("seed", range(4))
def test_separating_axes_find_what_epa_finds(seed):
    # Where the polygons overlap, the soft solver's narrow phase must find
    # the contacts Munk2D's GJK and EPA find (same features, same normal and
    # points up to EPA's tolerance); apart, see the next test.
    import random
    rng = random.Random(seed)
    overlapping = 0
    for trial in range(300):
        a = _random_polygon(rng, (0, 0), 1.0, rng.randint(3, 8), rng.random() * 7)
        offset = 1.0 + 2.0 * rng.random()
        direction = rng.random() * 7
        b = _random_polygon(rng, (offset * math.cos(direction), offset * math.sin(direction)),
                            1.0, rng.randint(3, 8), rng.random() * 7)
        for margin in (0.0, 0.1):
            first, first_s, touching = _soft_finds_what_munk2d_finds(a, b, margin, trial)
            assert first == first_s
            overlapping += touching and margin == 0.0
    assert overlapping > 50          # the test saw the new path at work


@pytest.mark.parametrize("seed", range(4))
def test_polygons_apart_find_what_gjk_finds(seed):
    # Cores apart but within the margin (speculative contacts): the soft
    # solver's narrow phase takes the reference face and the face most
    # against it, corner to corner where both nearest points are corners,
    # where Munk2D runs GJK: the same features, normal and points. Boxes
    # corner to corner and random polygons, at margins up to half a size.
    import random
    rng = random.Random(100 + seed)
    apart = corners = 0
    for trial in range(400):
        if trial % 2:
            a = _random_polygon(rng, (0, 0), 1.0, rng.randint(3, 8), rng.random() * 7)
            direction = rng.random() * 7
            offset = 2.0 + 1.0 * rng.random()
            b = _random_polygon(rng, (offset * math.cos(direction), offset * math.sin(direction)),
                                1.0, rng.randint(3, 8), rng.random() * 7)
        else:
            # Two unit boxes, the second turned, about a corner's reach apart.
            a = tamias2d.Poly.create_box(tamias2d.Body(1, 1), (1, 1))
            body = tamias2d.Body(1, 1)
            body.angle = rng.uniform(-math.pi, math.pi)
            if trial % 4 == 0:
                # Along a diagonal of the first, a corner's reach off: corners meet.
                body.angle = rng.uniform(0.15, 0.6)
                direction = math.pi / 4 + math.pi / 2 * rng.randint(0, 3) + rng.uniform(-0.1, 0.1)
                offset = rng.uniform(1.42, 1.8)
            else:
                direction = rng.uniform(-math.pi, math.pi)
                offset = rng.uniform(1.0, 1.6)
            body.position = (offset * math.cos(direction), offset * math.sin(direction))
            b = tamias2d.Poly.create_box(body, (1, 1))
            a.cache_bb()
            b.cache_bb()
        for margin in (0.05, 0.2, 0.5):
            first, first_s, touching = _soft_finds_what_munk2d_finds(a, b, margin, trial)
            assert first == first_s
            _, _, n, contacts = _testing._collide(a, b, margin=margin, soft=True)
            if touching and all((p2 - p1).dot(n) > 1e-9 for p1, p2, _ in contacts):
                apart += 1
                # Corner to corner: the normal is along no face of either box.
                rot = b.body.rotation_vector
                if trial % 2 == 0 and min(abs(n.x), abs(n.y), abs(n.cross(rot)),
                                          abs(n.dot(rot))) > 1e-6:
                    corners += 1
    assert apart > 100 and corners > 10, (apart, corners)   # the new path, and its corners


@pytest.mark.parametrize("seed", range(4))
def test_circle_inside_a_polygon_finds_what_epa_finds(seed):
    # A circle whose centre is inside a polygon: the soft solver's narrow
    # phase takes the nearest face where Munk2D runs GJK and EPA; the same
    # normal and points up to EPA's tolerance. Outside, it is Munk2D's code.
    import random
    rng = random.Random(seed)
    inside = 0
    for trial in range(300):
        poly = _random_polygon(rng, (0, 0), 1.0, rng.randint(3, 8), rng.random() * 7)
        body = tamias2d.Body(1, 1)
        body.position = (rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5))
        circle = tamias2d.Circle(body, rng.uniform(0.05, 0.5))
        circle.cache_bb()
        centre_inside = poly.point_query(body.position).distance < 0
        for margin in (0.0, 0.1):
            _, _, touching = _soft_finds_what_munk2d_finds(circle, poly, margin, trial)
            inside += touching and centre_inside and margin == 0.0
    assert inside > 50               # the test saw the new path at work


def test_a_circle_created_at_a_boxs_centre_gets_a_normal():
    # GJK and EPA find none (the chipmunk solver leaves such a pair stuck,
    # as pymunk does); the soft solver's narrow phase takes a face's.
    box = tamias2d.Poly.create_box(tamias2d.Body(1, 1), (20, 20))
    box.cache_bb()
    circle = tamias2d.Circle(tamias2d.Body(1, 1), 10)
    circle.cache_bb()
    _, _, n, contacts = _testing._collide(circle, box, soft=True)
    assert len(contacts) == 1 and abs(n.length - 1.0) < 1e-12
    p1, p2, _ = contacts[0]
    assert (p2 - p1).dot(n) == pytest.approx(-20.0)   # the way out: 10 + 10 deep
