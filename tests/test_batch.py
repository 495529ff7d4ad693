"""tamias2d.batch: NumPy reads and writes of all bodies, and the arbiters.

Compared with per-body property access in tamias2d (the same numbers, bit for
bit), with pymunk's batch module and per-arbiter properties for the same
scene (the engines step the same scenes to the same bits), and with the Body
setters for writes (the same state afterwards, and the same motion after).
"""
import math
import os
import subprocess
import sys

import pytest

np = pytest.importorskip("numpy")
pymunk = pytest.importorskip("pymunk")
import pymunk.batch  # noqa: E402

import tamias2d  # noqa: E402
import tamias2d.batch as tb  # noqa: E402
from tamias2d.errors import IllegalBody  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402

ALL = ("position", "angle", "velocity", "angular_velocity", "force", "torque")


def per_body(space, fields):
    """The rows get_bodies should give, read one property at a time."""
    rows = []
    for b in space.bodies:
        row = []
        for f in fields:
            v = getattr(b, f)
            row += [v[0], v[1]] if isinstance(v, tuple) else [v]
        rows.append(row)
    return rows


def stepped(mod, build, steps, dt=1.0 / 60.0, **kw):
    space = build(mod, **kw)
    scenes.run(space, dt, steps)
    return space


def exact(a, b):
    """Elementwise equality that treats NaN == NaN and keeps -0.0 == 0.0."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))


# -- reads -------------------------------------------------------------------------

@pytest.mark.parametrize("fields", [ALL, ("angle",), ("torque", "position"),
                                    ("velocity", "force", "angular_velocity")])
def test_get_bodies_equals_properties(fields):
    space = stepped(tamias2d, scenes.mixed, 90)
    # forces and torques are cleared by the step: give them values to read
    for i, b in enumerate(space.bodies):
        b.force = (i * 0.5, -i)
        b.torque = i * 0.25
    got = tb.get_bodies(space, fields)
    assert got.dtype == np.float64 and got.flags.c_contiguous
    assert got.shape == (len(space.bodies), sum(tb.BODY_FIELDS[f] for f in fields))
    assert got.tolist() == per_body(space, fields)
    assert len(tb.body_columns(fields)) == got.shape[1]


def test_get_bodies_static_and_kinematic_in_add_order():
    space = stepped(tamias2d, scenes.drum, 20, count=30)
    kinds = {b.body_type for b in space.bodies}
    assert kinds == {tamias2d.Body.KINEMATIC, tamias2d.Body.DYNAMIC}
    static = tamias2d.Body(body_type=tamias2d.Body.STATIC)
    static.position = 7, 8
    space.add(static)
    got = tb.get_bodies(space, ALL)
    assert got.tolist() == per_body(space, ALL)
    assert got[-1, :2].tolist() == [7.0, 8.0]
    assert tb.get_body_ids(space).tolist() == [b.id for b in space.bodies]


def test_get_bodies_out_argument():
    space = stepped(tamias2d, scenes.pyramid, 10, rows=6)
    out = np.full((len(space.bodies), 3), np.nan)
    res = tb.get_bodies(space, ("position", "angle"), out=out)
    assert res is out
    assert out.tolist() == per_body(space, ("position", "angle"))
    with pytest.raises(ValueError):
        tb.get_bodies(space, ("position",), out=out)
    with pytest.raises(TypeError):
        tb.get_bodies(space, ("position", "angle"), out=out.astype(np.float32))
    with pytest.raises(ValueError):
        tb.get_bodies(space, ("position", "angle"), out=np.empty((3, len(space.bodies))).T)


def test_empty_space():
    space = tamias2d.Space()
    assert tb.get_bodies(space, ALL).shape == (0, 9)
    assert tb.get_body_ids(space).shape == (0,)
    tb.set_bodies(space, np.empty((0, 2)), "velocity")
    assert len(tb.get_arbiters(space)) == 0
    space.step(0.1)
    assert len(tb.get_arbiters(space)) == 0


def test_reads_after_sleep_and_removal():
    space = tamias2d.Space()
    space.sleep_time_threshold = 0.3
    space.gravity = 0, -100
    space.add(tamias2d.Segment(space.static_body, (-100, 0), (100, 0), 1))
    bodies = []
    for i in range(5):
        b = tamias2d.Body(1, 100)
        b.position = -40 + 20 * i, 6
        space.add(b, tamias2d.Poly.create_box(b, (10, 10)))
        bodies.append(b)
    for _ in range(400):
        space.step(1 / 60)
    assert all(b.is_sleeping for b in bodies)
    assert tb.get_bodies(space, ALL).tolist() == per_body(space, ALL)
    space.remove(*bodies[1].shapes, bodies[1])
    assert tb.get_bodies(space, ALL).tolist() == per_body(space, ALL)
    assert tb.get_body_ids(space).tolist() == [b.id for b in space.bodies]


def pymunk_rows(space, fields):
    """pymunk.batch's rows for `fields`, reordered to space.bodies order.

    pymunk.batch walks Chipmunk's body arrays (dynamic, static, then
    sleeping), which include the space's static_body; the ids tell which
    row is which body."""
    F = pymunk.batch.BodyFields
    flags = F.BODY_ID
    for f in fields:
        flags |= getattr(F, f.upper())
    buf = pymunk.batch.Buffer()
    pymunk.batch.get_space_bodies(space, flags, buf)
    ids = np.frombuffer(buf.int_buf(), dtype=np.uintp)
    floats = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ids), -1)
    # pymunk writes the fields in its flag order, whatever order they are asked in
    flag_order = [f for f in ALL if f in fields]
    cols, c = {}, 0
    for f in flag_order:
        cols[f] = list(range(c, c + tb.BODY_FIELDS[f]))
        c += tb.BODY_FIELDS[f]
    by_id = dict(zip(ids.tolist(), floats))
    rows = [by_id[b.id] for b in space.bodies]
    return np.array([[r[k] for f in fields for k in cols[f]] for r in rows])


@pytest.mark.parametrize("name,build,kw,steps", [
    ("pyramid", scenes.pyramid, {"rows": 12}, 80),
    ("mixed", scenes.mixed, {}, 120),
    ("drum", scenes.drum, {"count": 60}, 60),
])
def test_get_bodies_equals_pymunk_batch(name, build, kw, steps):
    tspace = stepped(tamias2d, build, steps, **kw)
    pspace = stepped(pymunk, build, steps, **kw)
    fields = ("position", "angle", "velocity", "angular_velocity")
    mine = tb.get_bodies(tspace, fields)
    theirs = pymunk_rows(pspace, fields)
    assert mine.shape == theirs.shape
    bad = np.argwhere(mine != theirs)
    assert len(bad) == 0, (f"{name}: first difference at body {bad[0][0]}, column "
                           f"{tb.body_columns(fields)[bad[0][1]]}: "
                           f"{mine[tuple(bad[0])]!r} != {theirs[tuple(bad[0])]!r}")


# -- writes ------------------------------------------------------------------------

def state(space):
    out = []
    for b in space.bodies:
        out.append((tuple(b.position), b.angle, tuple(b.velocity), b.angular_velocity,
                    tuple(b.force), b.torque, b.is_sleeping,
                    tuple(b.local_to_world((1.0, 2.0)))))
    return out


@pytest.mark.parametrize("fields", [ALL, ("angle", "position"), ("position", "angle"),
                                    ("velocity",), ("force", "torque")])
def test_set_bodies_equals_setters(fields, rng):
    # scenes.mixed has a body whose centre of gravity is off its origin, so
    # the order of position and angle writes matters (as with the setters).
    a = stepped(tamias2d, scenes.mixed, 60)
    b = stepped(tamias2d, scenes.mixed, 60)
    assert any(tuple(body.center_of_gravity) != (0.0, 0.0) for body in a.bodies)
    width = sum(tb.BODY_FIELDS[f] for f in fields)
    values = np.array([[rng.uniform(-50, 50) for _ in range(width)] for _ in a.bodies])
    tb.set_bodies(a, values, fields)
    for body, row in zip(b.bodies, values.tolist()):
        c = 0
        for f in fields:
            if tb.BODY_FIELDS[f] == 2:
                setattr(body, f, (row[c], row[c + 1]))
            else:
                setattr(body, f, row[c])
            c += tb.BODY_FIELDS[f]
    assert state(a) == state(b)
    scenes.run(a, 1 / 60, 30)
    scenes.run(b, 1 / 60, 30)
    assert state(a) == state(b)


def test_set_then_get_round_trip_without_cog():
    space = stepped(tamias2d, scenes.pyramid, 5, rows=5)
    values = np.arange(len(space.bodies) * 9, dtype=float).reshape(-1, 9) * 0.5
    tb.set_bodies(space, values, ALL)
    assert tb.get_bodies(space, ALL).tolist() == values.tolist()


def test_set_bodies_matches_pymunk_batch_set():
    tspace = stepped(tamias2d, scenes.pyramid, 30, rows=8)
    pspace = stepped(pymunk, scenes.pyramid, 30, rows=8)
    n = len(tspace.bodies)
    vel = np.column_stack([np.linspace(-20, 20, n), np.linspace(5, 50, n),
                           np.linspace(-1, 1, n)])
    tb.set_bodies(tspace, vel, ("velocity", "angular_velocity"))
    # pymunk's batch writes rows in its own body order: build that buffer
    F = pymunk.batch.BodyFields
    buf = pymunk.batch.Buffer()
    pymunk.batch.get_space_bodies(pspace, F.BODY_ID, buf)
    ids = np.frombuffer(buf.int_buf(), dtype=np.uintp).tolist()
    row_of = {b.id: i for i, b in enumerate(pspace.bodies)}
    pvals = np.array([vel[row_of[i]] if i in row_of else [0.0, 0.0, 0.0] for i in ids])
    wbuf = pymunk.batch.Buffer()
    wbuf.set_float_buf(np.ascontiguousarray(pvals))
    pymunk.batch.set_space_bodies(pspace, F.VELOCITY | F.ANGULAR_VELOCITY, wbuf)
    scenes.run(tspace, 1 / 60, 40)
    scenes.run(pspace, 1 / 60, 40)
    fields = ("position", "angle", "velocity", "angular_velocity")
    assert tb.get_bodies(tspace, fields).tolist() == pymunk_rows(pspace, fields).tolist()


def test_set_bodies_wakes_sleeping_bodies():
    space = tamias2d.Space()
    space.sleep_time_threshold = 0.2
    space.gravity = 0, -100
    space.add(tamias2d.Segment(space.static_body, (-100, 0), (100, 0), 1))
    bodies = []
    for i in range(3):
        b = tamias2d.Body(1, 100)
        b.position = -40 + 40 * i, 6
        space.add(b, tamias2d.Poly.create_box(b, (10, 10)))
        bodies.append(b)
    for _ in range(300):
        space.step(1 / 60)
    assert all(b.is_sleeping for b in bodies)
    tb.set_bodies(space, [[0.0], [0.0], [0.0]], "torque")
    assert not any(b.is_sleeping for b in bodies)


def test_single_column_field_accepts_1d():
    space = stepped(tamias2d, scenes.pyramid, 2, rows=3)
    n = len(space.bodies)
    tb.set_bodies(space, np.linspace(0, 1, n), "angular_velocity")
    assert [b.angular_velocity for b in space.bodies] == np.linspace(0, 1, n).tolist()
    tb.set_bodies(space, list(range(n)), ["angle"])   # ints and lists are fine
    assert [b.angle for b in space.bodies] == [float(i) for i in range(n)]
    with pytest.raises(ValueError):
        tb.set_bodies(space, np.zeros(2 * n), "velocity")


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_set_bodies_rejects_non_finite_and_changes_nothing(bad):
    space = stepped(tamias2d, scenes.pyramid, 10, rows=4)
    before = state(space)
    values = tb.get_bodies(space, ALL)
    values[-1, 4] = bad
    with pytest.raises(IllegalBody, match=r"values\[.*angle|velocity"):
        tb.set_bodies(space, values, ALL)
    assert state(space) == before
    # IllegalBody is a ValueError, as for the Body setters
    with pytest.raises(ValueError):
        tb.set_bodies(space, values, ALL)


def test_argument_errors():
    space = stepped(tamias2d, scenes.pyramid, 1, rows=3)
    n = len(space.bodies)
    with pytest.raises(ValueError, match="unknown body field"):
        tb.get_bodies(space, ("position", "spin"))
    with pytest.raises(ValueError, match="twice"):
        tb.get_bodies(space, ("angle", "angle"))
    with pytest.raises(ValueError, match="empty"):
        tb.get_bodies(space, ())
    with pytest.raises(TypeError):
        tb.get_bodies(space, 3)
    with pytest.raises(TypeError, match="tamias2d.Space"):
        tb.get_bodies(pymunk.Space(), "angle")
    with pytest.raises(TypeError):
        tb.get_bodies(None, "angle")
    with pytest.raises(ValueError, match="shape"):
        tb.set_bodies(space, np.zeros((n + 1, 2)), "position")
    with pytest.raises(ValueError, match="shape"):
        tb.set_bodies(space, np.zeros((n, 3)), "position")
    with pytest.raises(TypeError):
        tb.set_bodies(space, [["a", "b"]] * n, "position")
    with pytest.raises(ValueError, match="unknown arbiter field"):
        tb.get_arbiters(space, ["normal", "depth"])


def test_import_tamias2d_does_not_import_numpy(tmp_path):
    code = ("import sys, tamias2d, tamias2d.batch; "
            "assert 'numpy' not in sys.modules, 'numpy imported'; "
            "s = tamias2d.Space(); tamias2d.batch.get_bodies(s, 'angle'); "
            "assert 'numpy' in sys.modules")
    env = dict(os.environ)
    # the tamias2d this test imported (the installed one, or the checkout)
    where = os.path.dirname(os.path.dirname(os.path.abspath(tamias2d.__file__)))
    env["PYTHONPATH"] = where + os.pathsep + env.get("PYTHONPATH", "")
    res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr


# -- arbiters ----------------------------------------------------------------------

def arbiter_records(arbiter, bodies, shapes):
    """The get_arbiters record of one Arbiter, read through its properties."""
    sa, sb = arbiter.shapes
    cps = arbiter.contact_point_set
    pa = [[math.nan] * 2, [math.nan] * 2]
    pb = [[math.nan] * 2, [math.nan] * 2]
    dist = [math.nan, math.nan]
    for i, p in enumerate(cps.points):
        pa[i] = list(p.point_a)
        pb[i] = list(p.point_b)
        dist[i] = p.distance
    return {
        "body_a": bodies.get(sa.body, -1), "body_b": bodies.get(sb.body, -1),
        "shape_a": shapes[sa], "shape_b": shapes[sb],
        "count": len(cps.points), "first_contact": arbiter.is_first_contact,
        "normal": list(arbiter.normal), "total_impulse": list(arbiter.total_impulse),
        "total_ke": arbiter.total_ke, "point_a": pa, "point_b": pb, "distance": dist,
    }


def post_solve_log(mod, space):
    """Install a global post_solve callback that records each arbiter as
    get_arbiters would (the solver runs arbiters in the order of these calls)."""
    log = []

    def post_solve(arbiter, sp, data):
        bodies = {b: i for i, b in enumerate(sp.bodies)}
        shapes = {s: i for i, s in enumerate(sp.shapes)}
        log.append(arbiter_records(arbiter, bodies, shapes))

    space.on_collision(None, None, post_solve=post_solve)
    return log


def compare_records(got, expected, where):
    assert len(got) == len(expected), f"{where}: {len(got)} arbiters, expected {len(expected)}"
    for i, (g, e) in enumerate(zip(got, expected)):
        for key, value in e.items():
            assert exact(g[key], value), f"{where}: arbiter {i} field {key}: {g[key]!r} != {value!r}"


def typed_rain(mod, count=120):
    """scenes.rain with collision types and handlers keyed (2, 1) and (3, 2),
    so handlers see arbiters in both orders during the step (the swapped flag
    is set back before get_arbiters can read it)."""
    space = scenes.rain(mod, count=count)
    for i, shape in enumerate(space.shapes):
        shape.collision_type = 1 + i % 3
    space.on_collision(2, 1)
    space.on_collision(3, 2)
    return space


@pytest.mark.parametrize("name,build,kw", [
    ("pyramid", scenes.pyramid, {"rows": 10}),
    ("typed rain", typed_rain, {}),
    ("mixed", scenes.mixed, {}),
    ("rain", scenes.rain, {"count": 120}),
])
def test_get_arbiters_equals_post_solve_properties(name, build, kw):
    """Checked against tamias2d's own Arbiter properties (in a twin space
    with a post_solve callback) and against pymunk's for the same scene."""
    plain = build(tamias2d, **kw)
    twin = build(tamias2d, **kw)
    pm = build(pymunk, **kw)
    logs = {"tamias2d": post_solve_log(tamias2d, twin), "pymunk": post_solve_log(pymunk, pm)}
    seen = 0
    for step in range(90):
        for lg in logs.values():
            lg.clear()
        for s in (plain, twin, pm):
            s.step(1 / 60)
        got = tb.get_arbiters(plain)
        ids = {b.id: i for i, b in enumerate(plain.bodies)}
        for rec in got:
            assert ids.get(int(rec["body_a_id"]), -1) == rec["body_a"]
            assert ids.get(int(rec["body_b_id"]), -1) == rec["body_b"]
        for engine, lg in logs.items():
            compare_records(got, lg, f"{name} step {step} vs {engine}")
        seen += len(got)
    assert seen > 100


def test_get_arbiters_static_body_index_and_field_selection():
    space = tamias2d.Space()
    space.gravity = 0, -100
    ground = tamias2d.Segment(space.static_body, (-50, 0), (50, 0), 1)
    space.add(ground)
    box = tamias2d.Body(1, 100)
    box.position = 0, 5.9
    shape = tamias2d.Poly.create_box(box, (10, 10))
    space.add(box, shape)
    space.step(1 / 60)
    arbs = tb.get_arbiters(space)
    assert arbs.dtype == tb.arbiter_dtype()
    assert len(arbs) == 1
    rec = arbs[0]
    assert sorted([int(rec["body_a"]), int(rec["body_b"])]) == [-1, 0]
    assert sorted([int(rec["shape_a"]), int(rec["shape_b"])]) == [0, 1]
    assert {int(rec["body_a_id"]), int(rec["body_b_id"])} == {box.id, space.static_body.id}
    assert rec["count"] == 2 and bool(rec["first_contact"])
    assert (rec["distance"] < 0).all()
    sel = tb.get_arbiters(space, ["normal", "count"])
    assert sel.dtype.names == ("normal", "count")
    assert sel["normal"].tolist() == arbs["normal"].tolist()
    space.step(1 / 60)
    assert not tb.get_arbiters(space, "first_contact")["first_contact"][0]
    # a removed shape takes its arbiter with it
    space.remove(shape)
    assert len(tb.get_arbiters(space)) == 0
