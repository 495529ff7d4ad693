"""Many static shapes: why adding them in a row is quadratic, and the bulk path.

Munk2D's bounding-box tree (and so pymunk's) inserts a leaf by walking down
from the root, choosing at each node by a cost heuristic. Shapes added in
spatial order (a row of segments) always pair with the last one added, at
the bottom of a single branch: the tree becomes a list n deep and adding n
shapes takes O(n^2) (docs/stability.md has the figures). The heuristic is
what makes the broad phase's pair and query order match pymunk's, so it is
kept; Space.add_static_bulk adds in bisection order instead, which pymunk
reproduces with ``space.add(*bisection_order(shapes))``.
"""
import struct
import time

import pytest

import tamias2d
from tamias2d._testing import _TestTree
from tamias2d.space import bisection_order

pymunk = pytest.importorskip("pymunk")


def tree_depth(structure):
    depth, stack = 0, [(structure, 0)]
    while stack:
        node, d = stack.pop()
        if isinstance(node, tuple):
            stack.append((node[0], d + 1))
            stack.append((node[1], d + 1))
        else:
            depth = max(depth, d)
    return depth


def row_depth(order):
    tree = _TestTree(capacity=len(order) + 1, fatten=False)
    for i in order:
        tree.add((i - 0.5, -0.5, i + 1.5, 0.5), static=True)
    return tree_depth(tree.structure(True))


def test_bisection_order_is_a_permutation():
    for n in (0, 1, 2, 3, 10, 1000, 1023, 1024, 1025):
        order = bisection_order(range(n))
        assert sorted(order) == list(range(n))
    assert bisection_order([]) == []
    assert bisection_order("abc") == ["b", "a", "c"]


def test_the_cause_a_row_makes_a_list_shaped_tree():
    n = 1000
    assert row_depth(range(n)) == n - 1                 # one branch: O(n) per insert
    assert row_depth(bisection_order(range(n))) <= 2 * n.bit_length()


def test_bulk_add_is_fast():
    s = tamias2d.Space()
    row = [tamias2d.Segment(s.static_body, (i, 0), (i + 1, 0), 0.5) for i in range(50_000)]
    t = time.perf_counter()
    s.add_static_bulk(*row)
    elapsed = time.perf_counter() - t
    assert len(s.shapes) == 50_000
    # ~0.05 s on the reference machine; add(*row) takes ~13 s.
    assert elapsed < 3.0, elapsed


def _build(mod, n=3000, balls=40):
    s = mod.Space()
    s.gravity = (0, -100)
    row = [mod.Segment(s.static_body, (i * 2.0, 0), (i * 2.0 + 2.0, 0.5 * (i % 3)), 0.5)
           for i in range(n)]
    for seg in row:
        seg.friction = 0.7
    if mod is tamias2d:
        s.add_static_bulk(*row)
    else:
        s.add(*bisection_order(row))
    bodies = []
    for k in range(balls):
        b = mod.Body(1, mod.moment_for_circle(1, 0, 1.5))
        b.position = (37.0 * k + 5.0, 4.0 + (k % 5))
        b.velocity = ((k % 7) - 3.0, 0)
        c = mod.Circle(b, 1.5)
        c.friction = 0.5
        s.add(b, c)
        bodies.append(b)
    return s, row, bodies


def _bits(bodies):
    return b"".join(struct.pack("<6d", *b.position, *b.velocity, b.angle, b.angular_velocity)
                    for b in bodies)


def test_bulk_scene_steps_bit_for_bit_like_pymunk():
    ts, trow, tbodies = _build(tamias2d)
    ps, prow, pbodies = _build(pymunk)
    for step in range(240):
        ts.step(1 / 60)
        ps.step(1 / 60)
        assert _bits(tbodies) == _bits(pbodies), step
    # Query results come in the tree's order: the same in both engines.
    tindex = {id(x): i for i, x in enumerate(trow)}
    pindex = {id(x): i for i, x in enumerate(prow)}
    bb = (100, -5, 900, 5)
    assert ([tindex[id(x)] for x in ts.bb_query(tamias2d.BB(*bb), tamias2d.ShapeFilter())
             if id(x) in tindex]
            == [pindex[id(x)] for x in ps.bb_query(pymunk.BB(*bb), pymunk.ShapeFilter())
                if id(x) in pindex])
    tq = ts.segment_query((0, 10), (5000, -3), 1, tamias2d.ShapeFilter())
    pq = ps.segment_query((0, 10), (5000, -3), 1, pymunk.ShapeFilter())
    assert ([(tindex.get(id(q.shape)), q.alpha) for q in tq]
            == [(pindex.get(id(q.shape)), q.alpha) for q in pq])
    assert len(tq) > 10
