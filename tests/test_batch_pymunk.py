"""pymunk's batch API in tamias2d.batch (BodyFields, ArbiterFields, Buffer,
get_space_bodies, set_space_bodies, get_space_arbiters) against pymunk 7.3's
pymunk.batch, bit for bit.

The scenes are built in both engines the same way and stepped side by side
(tests/scenes.py); they have sleeping components, static bodies (the
space's own and an added one), a kinematic body, free-falling bodies with
forces, and arbiters with two, one and no contacts (pairs that separated
but are still cached). Then:

- get_space_bodies: for several field combinations the float buffer is
  byte-equal to pymunk's and the int buffer (body ids, mapped to the index
  of the body in ``space.bodies`` since ids differ between engines) is
  equal: the same bodies in the same order (Munk2D's cpSpaceEachBody).
- get_space_arbiters: per arbiter, the records (ints with ids mapped,
  float bytes) are the same multiset as pymunk's. The order is that of
  Munk2D's arbiter cache, a hash set keyed by shape addresses, which differs
  between processes; within tamias2d, every field combination lists the
  arbiters in one order and lays out the fields as the full record does.
- set_space_bodies: the same values written in both engines give the same
  bodies (also the quirk that writing to a sleeping component wakes it
  mid-visit) and the same motion after, step by step.
- Buffer: appending, clear(), set_float_buf/set_int_buf used in place, the
  buffer protocol of float_buf()/int_buf(); bad input raises, never
  crashes; the thread guard.
"""
import array
import math
import threading
import time

import pytest

np = pytest.importorskip("numpy")
pymunk = pytest.importorskip("pymunk")
import pymunk.batch  # noqa: E402

import tamias2d  # noqa: E402
import tamias2d.batch  # noqa: E402
from tamias2d.errors import IllegalBody  # noqa: E402

import scenes  # noqa: E402
from isolated import isolated  # noqa: E402

ENGINES = ((pymunk, pymunk.batch), (tamias2d, tamias2d.batch))

# Arbiter fields: the int ones in order, and the doubles of the float ones.
ARB_INT_BITS = (1, 2, 16, 64)
ARB_FLOAT_WIDTH = {4: 2, 8: 1, 32: 2, 128: 2, 256: 2, 512: 1, 1024: 2, 2048: 2, 4096: 1}
BODY_FLOAT_WIDTH = {2: 2, 4: 1, 8: 2, 16: 1, 32: 2, 64: 1}

BODY_COMBOS = [0xFFFF, 1 | 2, 4 | 64, 8 | 16 | 32, 1, 2 | 4 | 8 | 16 | 32 | 64, 0, 1 | 64]
ARBITER_COMBOS = [0xFFFF, 1 | 2, 4 | 8 | 16, 32 | 64 | 1024 | 4096, 256 | 512 | 2048,
                  128 | 64, 4 | 32, 1 | 16 | 128 | 256 | 512 | 1024 | 2048 | 4096]


# -- scenes -------------------------------------------------------------------------------

def sleepy(mod):
    """Stacks that fall asleep (boxes: two contacts, circles: one), an added
    static wall, a kinematic paddle, a bouncing ball (its pair separates and
    stays cached) and free fallers that get forces before each step."""
    space = mod.Space()
    space.gravity = 0, -500
    space.sleep_time_threshold = 0.3
    ground = mod.Segment(space.static_body, (-300, 0), (300, 0), 1)
    ground.friction = 1
    space.add(ground)
    wall_body = mod.Body(body_type=mod.Body.STATIC)
    wall_body.position = 320, 0
    wall = mod.Segment(wall_body, (0, 0), (0, 200), 2)
    space.add(wall_body, wall)
    for col in range(4):
        for row in range(3):
            body = mod.Body(1, scenes.box_moment(1, 10, 10))
            body.position = -200 + 40 * col, 6 + 11 * row
            box = mod.Poly.create_box(body, (10, 10))
            box.friction = 1
            space.add(body, box)
        ball = mod.Body(1, scenes.circle_moment(1, 5))
        ball.position = -200 + 40 * col, 50
        circle = mod.Circle(ball, 5)
        circle.friction = 1
        space.add(ball, circle)
    lone = mod.Body(1, scenes.circle_moment(1, 4))
    lone.position = 100, 4.5
    lone_shape = mod.Circle(lone, 4)
    lone_shape.friction = 1
    space.add(lone, lone_shape)
    bouncer = mod.Body(1, scenes.circle_moment(1, 6))
    bouncer.position = 250, 80
    bouncer_shape = mod.Circle(bouncer, 6)
    bouncer_shape.elasticity = 0.95
    ground.elasticity = 0.95
    space.add(bouncer, bouncer_shape)
    paddle = mod.Body(body_type=mod.Body.KINEMATIC)
    paddle.position = 0, 300
    paddle.angular_velocity = 1.5
    space.add(paddle, mod.Poly.create_box(paddle, (40, 4)))
    fallers = []
    for k in range(3):
        body = mod.Body(2, scenes.box_moment(2, 8, 8))
        body.position = 600 + 30 * k, 1000
        space.add(body, mod.Poly.create_box(body, (8, 8)))
        fallers.append(body)

    def hook(i):
        for k, body in enumerate(fallers):
            body.force = 10.0 * (k + 1), -3.0 * i
            body.torque = 0.25 * i - k

    space.scene_hook = hook
    return space


SCENES = {
    "sleepy": (sleepy, 1 / 60),
    "mixed": (scenes.mixed, 1 / 60),
    "pyramid": (lambda mod: scenes.pyramid(mod, rows=8), 1 / 60),
}


def stepped(name, steps):
    """The scene in both engines after `steps` steps: [pymunk, tamias2d]."""
    build, dt = SCENES[name]
    spaces = []
    for mod, _ in ENGINES:
        space = build(mod)
        scenes.run(space, dt, steps)
        spaces.append(space)
    return spaces


def step_both(spaces, name, first, steps):
    build, dt = SCENES[name]
    for space in spaces:
        hook = getattr(space, "scene_hook", None)
        for i in range(first, first + steps):
            if hook is not None:
                hook(i)
            space.step(dt)


# -- reading buffers ----------------------------------------------------------------------

def labels(space):
    """Body id -> the body's index in space.bodies ("static" for space.static_body)."""
    out = {b.id: i for i, b in enumerate(space.bodies)}
    out[space.static_body.id] = "static"
    return out


def ints_of(buf):
    return list(memoryview(buf.int_buf()).cast("P"))


def floats_of(buf):
    return bytes(buf.float_buf())


def body_data(batch, space, value, buf=None):
    """(float bytes, ints with ids as labels) of get_space_bodies."""
    buf = batch.Buffer() if buf is None else buf
    batch.get_space_bodies(space, batch.BodyFields(value), buf)
    ids = labels(space)
    ints = ints_of(buf)
    if value & 1:
        ints = [ids[i] for i in ints]
    return floats_of(buf), ints


def arbiter_records(batch, space, value):
    """The records of get_space_arbiters, in its order: (ints with the ids
    as labels, float bytes) per arbiter."""
    buf = batch.Buffer()
    batch.get_space_arbiters(space, batch.ArbiterFields(value), buf)
    ints, floats = ints_of(buf), floats_of(buf)
    iw = sum(1 for bit in ARB_INT_BITS if value & bit)
    fw = sum(w for bit, w in ARB_FLOAT_WIDTH.items() if value & bit)
    assert iw or fw
    n = len(ints) // iw if iw else len(floats) // (8 * fw)
    assert len(ints) == n * iw and len(floats) == n * fw * 8
    nids = (value & 1 != 0) + (value & 2 != 0)
    ids = labels(space)
    recs = []
    for k in range(n):
        ri = ints[k * iw:(k + 1) * iw]
        ri = [ids[x] for x in ri[:nids]] + ri[nids:]
        recs.append((tuple(ri), floats[k * fw * 8:(k + 1) * fw * 8]))
    return recs


def project(record, value):
    """The record of field combination `value` taken from a full (ALL) record."""
    ints, floats = record
    full_ints = dict(zip(ARB_INT_BITS, ints))
    out_ints = tuple(full_ints[bit] for bit in ARB_INT_BITS if value & bit)
    out_floats, pos = b"", 0
    for bit, w in ARB_FLOAT_WIDTH.items():
        if value & bit:
            out_floats += floats[pos:pos + 8 * w]
        pos += 8 * w
    return out_ints, out_floats


def multiset(records):
    return sorted(records, key=repr)


def state(space):
    """Every body's full state, as exact reprs."""
    bodies = list(space.bodies) + [space.static_body]
    return [(repr(tuple(b.position)), repr(b.angle), repr(tuple(b.velocity)),
             repr(b.angular_velocity), repr(tuple(b.force)), repr(b.torque), b.is_sleeping)
            for b in bodies]


def each_body_order(space):
    return body_data(tamias2d.batch if isinstance(space, tamias2d.Space) else pymunk.batch,
                     space, 1)[1]


# -- the enums and the Buffer -----------------------------------------------------------------

def test_flags_have_pymunks_names_and_values():
    for name in ("BodyFields", "ArbiterFields"):
        ours, theirs = getattr(tamias2d.batch, name), getattr(pymunk.batch, name)
        assert issubclass(ours, __import__("enum").Flag)
        assert [(m.name, m.value) for m in ours] == [(m.name, m.value) for m in theirs]
        assert ours.ALL.value == theirs.ALL.value == 0xFFFF
        assert ours.__module__ == "tamias2d.batch"
    F = tamias2d.batch.BodyFields
    assert repr(F.POSITION | F.ANGLE) == "<BodyFields.POSITION|ANGLE: 6>"
    assert (F.POSITION | F.VELOCITY).value == 10
    assert set(pymunk.batch.__all__) <= set(tamias2d.batch.__all__)


def test_empty_buffer():
    buf = tamias2d.batch.Buffer()
    assert len(buf.float_buf()) == 0 and len(buf.int_buf()) == 0
    assert list(memoryview(buf.float_buf()).cast("d")) == []
    assert np.frombuffer(buf.int_buf(), dtype=np.uintp).size == 0
    with pytest.raises(TypeError):
        tamias2d.batch.Buffer(1)


# -- get_space_bodies -----------------------------------------------------------------------

@pytest.mark.parametrize("name,steps", [("sleepy", 0), ("sleepy", 1), ("sleepy", 150),
                                        ("sleepy", 400), ("mixed", 90), ("pyramid", 200)])
def test_get_space_bodies_equals_pymunk(name, steps):
    spaces = stepped(name, steps)
    for value in BODY_COMBOS:
        got = [body_data(batch, space, value) for (_, batch), space in zip(ENGINES, spaces)]
        assert got[0] == got[1], f"BodyFields({value:#x})"
    # The order of cpSpaceEachBody: not that of space.bodies once bodies sleep.
    order = each_body_order(spaces[1])
    assert sorted(order, key=repr) == sorted(list(range(len(spaces[1].bodies))) + ["static"],
                                             key=repr)
    if name == "sleepy" and steps == 400:
        sleeping = [b.is_sleeping for b in spaces[1].bodies]
        assert any(sleeping) and not all(sleeping)
        assert order != list(range(len(spaces[1].bodies))) + ["static"]


def test_get_space_bodies_layout():
    # Field by field, against the properties, in BodyFields member order.
    (space,) = stepped("sleepy", 30)[1:]
    F = tamias2d.batch.BodyFields
    buf = tamias2d.batch.Buffer()
    tamias2d.batch.get_space_bodies(space, F.ALL, buf)
    ids = ints_of(buf)
    by_id = {b.id: b for b in list(space.bodies) + [space.static_body]}
    floats = list(memoryview(buf.float_buf()).cast("d"))
    assert len(floats) == 9 * len(ids) == 9 * (len(space.bodies) + 1)
    for k, i in enumerate(ids):
        b = by_id[i]
        expect = [*b.position, b.angle, *b.velocity, b.angular_velocity, *b.force, b.torque]
        assert floats[9 * k:9 * k + 9] == expect


def test_buffers_append_and_clear():
    spaces = stepped("sleepy", 100)
    results = []
    for (mod, batch), space in zip(ENGINES, spaces):
        buf = batch.Buffer()
        batch.get_space_bodies(space, batch.BodyFields.ALL, buf)
        batch.get_space_bodies(space, batch.BodyFields.BODY_ID | batch.BodyFields.ANGLE, buf)
        once = body_data(batch, space, 0xFFFF)
        angles = body_data(batch, space, 1 | 4)
        ids = labels(space)
        got = (floats_of(buf), [ids[i] for i in ints_of(buf)])
        assert got == (once[0] + angles[0], once[1] + angles[1])
        buf.clear()
        assert floats_of(buf) == b"" and ints_of(buf) == []
        batch.get_space_bodies(space, batch.BodyFields.POSITION, buf)
        assert floats_of(buf) == body_data(batch, space, 2)[0]
        results.append(got)
    assert results[0] == results[1]
    # Arbiters append after bodies in the same buffer.
    space = spaces[1]
    batch = tamias2d.batch
    buf = batch.Buffer()
    batch.get_space_bodies(space, batch.BodyFields.ALL, buf)
    n_float, n_int = len(buf.float_buf()), len(buf.int_buf())
    batch.get_space_arbiters(space, batch.ArbiterFields.ALL, buf)
    alone = batch.Buffer()
    batch.get_space_arbiters(space, batch.ArbiterFields.ALL, alone)
    assert bytes(buf.float_buf())[n_float:] == floats_of(alone)
    assert bytes(buf.int_buf())[n_int:] == bytes(alone.int_buf())


def test_a_view_outlives_the_growth_of_its_buffer():
    (space,) = stepped("mixed", 10)[1:]
    batch = tamias2d.batch
    buf = batch.Buffer()
    batch.get_space_bodies(space, batch.BodyFields.POSITION, buf)
    view = buf.float_buf()
    arr = np.frombuffer(view)
    before = bytes(view)
    for _ in range(50):                      # grows far beyond the first memory
        batch.get_space_bodies(space, batch.BodyFields.ALL, buf)
    assert bytes(view) == before and arr.tobytes() == before
    n = len(space.bodies) + 1
    assert len(buf.float_buf()) == 8 * (2 * n + 50 * 9 * n)


# -- get_space_arbiters ------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["sleepy", "mixed", "pyramid"])
def test_get_space_arbiters_equals_pymunk(name):
    build, dt = SCENES[name]
    spaces = [build(mod) for mod, _ in ENGINES]
    counts = set()
    first_contacts = set()
    samples = 0
    for i in range(420 if name == "sleepy" else 150):
        step_both(spaces, name, i, 1)
        if i % 7 and i < 410:
            continue
        samples += 1
        full = [arbiter_records(batch, space, 0xFFFF) for (_, batch), space in zip(ENGINES, spaces)]
        assert multiset(full[0]) == multiset(full[1]), f"step {i}: ArbiterFields.ALL"
        for ints, floats in full[1]:
            a, b, first, count = ints
            counts.add(count)
            first_contacts.add(first)
            assert first in (0, 1) and count in (0, 1, 2)
            d = list(memoryview(floats).cast("d"))
            # no such contact: zeros (pymunk's values)
            # impulse (0, 1), ke (2), normal (3, 4), contact 1 (5-9), contact 2 (10-14)
            assert len(d) == 15
            if count < 2:
                assert d[10:] == [0.0] * 5
            if count == 0:
                assert d[0:3] == [0.0] * 3 and d[5:10] == [0.0] * 5
        for value in ARBITER_COMBOS[1:]:
            part = [arbiter_records(batch, space, value) for (_, batch), space in zip(ENGINES, spaces)]
            assert multiset(part[0]) == multiset(part[1]), f"step {i}: ArbiterFields({value:#x})"
            # tamias2d: one order for every combination, the full record's layout
            assert part[1] == [project(r, value) for r in full[1]], f"step {i}: {value:#x}"
    assert samples > 10
    if name == "sleepy":
        # two-contact, one-contact and separated (still cached) pairs were seen
        assert counts == {0, 1, 2} and first_contacts == {0, 1}
        assert any(b.is_sleeping for b in spaces[1].bodies)


def test_arbiter_ids_and_contacts_match_the_arbiter_objects():
    # tamias2d alone: the records of the arbiters the step solved, as the
    # post-solve callbacks see them (the same arbiters, in any order).
    space = scenes.mixed(tamias2d)
    seen = []

    def post_solve(arbiter, space, data):
        a, b = arbiter.bodies
        ps = arbiter.contact_point_set
        seen.append((a.id, b.id, int(arbiter.is_first_contact), len(ps.points)))

    space.on_collision(post_solve=post_solve)
    for _ in range(60):
        seen.clear()
        space.step(1 / 60)
    buf = tamias2d.batch.Buffer()
    F = tamias2d.batch.ArbiterFields
    tamias2d.batch.get_space_arbiters(
        space, F.BODY_A_ID | F.BODY_B_ID | F.IS_FIRST_CONTACT | F.CONTACT_COUNT, buf)
    ints = ints_of(buf)
    recs = [tuple(ints[k:k + 4]) for k in range(0, len(ints), 4)]
    touching = [r for r in recs if r[3] > 0]
    assert seen and sorted(touching) == sorted(seen)


# -- set_space_bodies ----------------------------------------------------------------------------

def set_both(spaces, value, data, kind="numpy"):
    """set_space_bodies(value) in both engines from the same doubles."""
    for (_, batch), space in zip(ENGINES, spaces):
        buf = batch.Buffer()
        arr = np.array(data, dtype=np.float64)
        if kind == "numpy":
            buf.set_float_buf(arr)
        elif kind == "bytes":
            buf.set_float_buf(arr.tobytes())
        else:
            buf.set_float_buf(array.array("d", arr.tolist()))
        batch.set_space_bodies(space, batch.BodyFields(value), buf)


def assert_same_motion(spaces, name, first, steps):
    assert state(spaces[0]) == state(spaces[1])
    for i in range(first, first + steps):
        step_both(spaces, name, i, 1)
        assert state(spaces[0]) == state(spaces[1]), f"step {i}"
        if i % 10 == 0:
            full = [arbiter_records(batch, space, 0xFFFF)
                    for (_, batch), space in zip(ENGINES, spaces)]
            assert multiset(full[0]) == multiset(full[1]), f"step {i}"


@pytest.mark.parametrize("name,steps", [("sleepy", 1), ("mixed", 60), ("sleepy", 150),
                                        ("sleepy", 400)])
def test_set_space_bodies_round_trip(name, steps):
    # Everything read and written back: with every body awake no value
    # changes; with sleeping components the writes wake them during the
    # visit and the values go astray, exactly as in pymunk. Both engines
    # then move on alike.
    spaces = stepped(name, steps)
    data = [body_data(batch, space, 0xFFFF) for (_, batch), space in zip(ENGINES, spaces)]
    assert data[0] == data[1]
    before = [state(s) for s in spaces]
    was_sleeping = [b.is_sleeping for b in spaces[1].bodies]
    for (_, batch), space in zip(ENGINES, spaces):
        buf = batch.Buffer()
        batch.get_space_bodies(space, batch.BodyFields.ALL, buf)
        batch.set_space_bodies(space, batch.BodyFields.ALL, buf)
    after = [state(s) for s in spaces]
    assert after[0] == after[1]
    values = [[row[:6] for row in st] for st in before + after]
    assert values[0] == values[1]
    if not any(was_sleeping):
        assert values[0] == values[2] == values[3]
        assert not any(b.is_sleeping for b in spaces[1].bodies)
    else:
        assert values[2] != values[0]
        # the visited components woke, some others were passed over
        now = [b.is_sleeping for b in spaces[1].bodies]
        assert now != was_sleeping and any(now)
    if steps == 400:
        assert any(was_sleeping)
    assert_same_motion(spaces, name, steps, 120)


def test_set_space_bodies_after_waking_writes_every_body():
    # The way to write every body of a sleeping scene: wake them, read, write.
    spaces = stepped("sleepy", 400)
    assert any(b.is_sleeping for b in spaces[1].bodies)
    for (_, batch), space in zip(ENGINES, spaces):
        for b in space.bodies:
            b.activate()
        buf = batch.Buffer()
        batch.get_space_bodies(space, batch.BodyFields.ALL, buf)
        before = [row[:6] for row in state(space)]
        batch.set_space_bodies(space, batch.BodyFields.ALL, buf)
        assert [row[:6] for row in state(space)] == before
    assert_same_motion(spaces, "sleepy", 400, 60)


@pytest.mark.parametrize("value", [8 | 16, 2 | 4, 32 | 64, 1 | 8, 2 | 4 | 8 | 16 | 32 | 64, 0, 1])
@pytest.mark.parametrize("kind", ["numpy", "bytes", "array"])
def test_set_space_bodies_new_values_equal_pymunk(value, kind):
    spaces = stepped("sleepy", 400)
    floats, _ = body_data(pymunk.batch, spaces[0], value)
    assert floats == body_data(tamias2d.batch, spaces[1], value)[0]
    d = np.frombuffer(floats).copy()
    width = sum(w for bit, w in BODY_FLOAT_WIDTH.items() if value & bit)
    if width:
        rows = d.reshape(-1, width)
        rows += np.linspace(0.25, 1.5, rows.size).reshape(rows.shape)
    # a longer buffer: the extra values are not read
    set_both(spaces, value, list(d) + [123.0, 456.0], kind)
    assert_same_motion(spaces, "sleepy", 400, 90)


def test_set_space_bodies_reads_from_the_start_and_ignores_body_id():
    spaces = stepped("mixed", 30)
    results = []
    for (_, batch), space in zip(ENGINES, spaces):
        n = len(space.bodies) + 1
        buf = batch.Buffer()
        batch.get_space_bodies(space, batch.BodyFields.BODY_ID | batch.BodyFields.VELOCITY, buf)
        batch.get_space_bodies(space, batch.BodyFields.BODY_ID | batch.BodyFields.VELOCITY, buf)
        assert len(buf.float_buf()) == 2 * n * 2 * 8
        velocities = np.frombuffer(buf.float_buf())
        velocities *= 2.0                # writes through the view into the Buffer
        ids_before = ints_of(buf)
        buf.set_int_buf(np.zeros(3, dtype=np.uint64))   # not read, whatever it holds
        batch.set_space_bodies(space, batch.BodyFields.BODY_ID | batch.BodyFields.VELOCITY, buf)
        assert len(ids_before) == 2 * n
        results.append(state(space))
    assert results[0] == results[1]
    assert_same_motion(spaces, "mixed", 30, 60)


def test_set_float_buf_is_used_in_place():
    # As pymunk: the object given to set_float_buf is not copied, so later
    # changes to it are what set_space_bodies reads.
    spaces = stepped("mixed", 5)
    for (_, batch), space in zip(ENGINES, spaces):
        n = len(space.bodies) + 1
        arr = np.zeros(2 * n)
        buf = batch.Buffer()
        buf.set_float_buf(arr)
        arr[0::2] = np.arange(n)
        arr[1::2] = 7.0
        batch.set_space_bodies(space, batch.BodyFields.VELOCITY, buf)
        assert np.frombuffer(buf.float_buf()).tolist() == arr.tolist()
    assert state(spaces[0]) == state(spaces[1])
    space = spaces[1]
    bodies = list(space.bodies) + [space.static_body]
    for k, label in enumerate(each_body_order(space)):
        body = bodies[-1 if label == "static" else label]
        assert body.velocity == (k, 7.0)


def test_appending_to_a_set_buffer_copies_it():
    (space,) = stepped("mixed", 5)[1:]
    batch = tamias2d.batch
    original = np.arange(6, dtype=np.float64).tobytes()
    buf = batch.Buffer()
    buf.set_float_buf(original)
    batch.get_space_bodies(space, batch.BodyFields.ANGLE, buf)
    assert floats_of(buf) == original + body_data(batch, space, 4)[0]
    arr = np.arange(4, dtype=np.float64)
    buf.set_float_buf(arr)
    buf.set_int_buf(array.array("Q", [5, 6]))
    assert ints_of(buf) == [5, 6]
    buf.clear()                            # the arrays given are not written to
    batch.get_space_bodies(space, batch.BodyFields.ALL, buf)
    assert arr.tolist() == [0.0, 1.0, 2.0, 3.0]
    assert floats_of(buf) == body_data(batch, space, 0xFFFF)[0]
    # 2-D C-contiguous arrays and raw bytes are accepted
    buf.set_float_buf(np.zeros((3, 2)))
    assert len(buf.float_buf()) == 48
    buf.set_int_buf(bytes(16))
    assert ints_of(buf) == [0, 0]


# -- bad input ---------------------------------------------------------------------------------

def test_bad_arguments_raise():
    (space,) = stepped("mixed", 2)[1:]
    batch = tamias2d.batch
    buf = batch.Buffer()
    F, A = batch.BodyFields, batch.ArbiterFields
    for call in (lambda: batch.get_space_bodies(space, 2, buf),
                 lambda: batch.get_space_bodies(space, A.ALL, buf),
                 lambda: batch.get_space_bodies(space, "POSITION", buf),
                 lambda: batch.set_space_bodies(space, 8, buf),
                 lambda: batch.get_space_arbiters(space, F.ALL, buf),
                 lambda: batch.get_space_bodies(pymunk.Space(), F.ALL, buf),
                 lambda: batch.get_space_bodies(None, F.ALL, buf),
                 lambda: batch.get_space_bodies(space, F.ALL, pymunk.batch.Buffer()),
                 lambda: batch.set_space_bodies(space, F.ALL, None),
                 lambda: batch.get_space_arbiters(space, A.ALL, [])):
        with pytest.raises(TypeError):
            call()
    assert floats_of(buf) == b"" and ints_of(buf) == []


@pytest.mark.parametrize("bad,error", [
    (object(), TypeError), (1.5, TypeError), ([1.0, 2.0], TypeError),
    (np.zeros(4, dtype=np.float32), TypeError), (np.zeros(4, dtype=np.int64), TypeError),
    (array.array("i", [1, 2]), TypeError), (bytes(12), ValueError),
    (np.zeros(8)[::2], ValueError), (np.zeros((4, 4)).T, ValueError),
])
def test_set_float_buf_rejects(bad, error):
    buf = tamias2d.batch.Buffer()
    with pytest.raises(error):
        buf.set_float_buf(bad)
    assert floats_of(buf) == b""


@pytest.mark.parametrize("bad,error", [
    (object(), TypeError), (np.zeros(4, dtype=np.int32), TypeError),
    (np.zeros(4), TypeError), (bytes(7), ValueError), (np.zeros(8, dtype=np.uint64)[::2], ValueError),
])
def test_set_int_buf_rejects(bad, error):
    buf = tamias2d.batch.Buffer()
    with pytest.raises(error):
        buf.set_int_buf(bad)
    for ok in (np.zeros(2, dtype=np.uint64), np.zeros(2, dtype=np.int64),
               np.zeros(2, dtype=np.uintp), array.array("Q", [1, 2])):
        buf.set_int_buf(ok)
        assert len(buf.int_buf()) == 16


@isolated(timeout=120)
def test_set_space_bodies_short_or_non_finite_buffers_raise_and_change_nothing():
    (space,) = stepped("sleepy", 400)[1:]
    batch = tamias2d.batch
    F = batch.BodyFields
    n = len(space.bodies) + 1
    before = state(space)
    buf = batch.Buffer()
    for fields, width in ((F.POSITION | F.ANGLE, 3), (F.ALL, 9), (F.TORQUE, 1)):
        for count in (0, 1, n * width - 1):
            buf.set_float_buf(np.ones(count))
            with pytest.raises(ValueError, match="need"):
                batch.set_space_bodies(space, fields, buf)
        buf.clear()
        with pytest.raises(ValueError):
            batch.set_space_bodies(space, fields, buf)
        for bad in (math.nan, math.inf, -math.inf):
            for where in (0, n * width // 2, n * width - 1):
                values = np.ones(n * width)
                values[where] = bad
                buf.set_float_buf(values)
                with pytest.raises(IllegalBody, match="finite"):
                    batch.set_space_bodies(space, fields, buf)
        assert state(space) == before
    # a non-finite value past the part that is read is not looked at
    values = np.ones(n + 1)
    values[n] = math.nan
    buf.set_float_buf(values)
    batch.set_space_bodies(space, F.ANGULAR_VELOCITY, buf)
    # only BODY_ID or nothing: no float is needed
    buf.clear()
    batch.set_space_bodies(space, F.BODY_ID, buf)
    batch.set_space_bodies(space, F(0), buf)


# -- the thread guard --------------------------------------------------------------------------

def busy_pile():
    s = tamias2d.Space()
    s.gravity = 0, -900
    s.sleep_time_threshold = 0.05
    s.iterations = 40
    s.add(tamias2d.Segment(s.static_body, (-1000, 0), (1000, 0), 2))
    for col in range(30):
        for row in range(8):
            b = tamias2d.Body(1, tamias2d.moment_for_box(1, (10, 10)))
            b.position = -800 + col * 40, 6 + row * 11
            box = tamias2d.Poly.create_box(b, (10, 10))
            box.friction = 1
            s.add(b, box)
    for _ in range(60):
        s.step(1 / 60)
    return s


@isolated(timeout=120)
def test_batch_calls_from_a_second_thread_while_stepping():
    s = busy_pile()
    batch = tamias2d.batch
    stop = threading.Event()
    errors = []
    calls = [0]

    def work():
        buf = batch.Buffer()
        try:
            while not stop.is_set():
                buf.clear()
                batch.get_space_bodies(s, batch.BodyFields.ALL, buf)
                batch.get_space_arbiters(s, batch.ArbiterFields.ALL, buf)
                buf.clear()
                batch.get_space_bodies(s, batch.BodyFields.VELOCITY, buf)
                batch.set_space_bodies(s, batch.BodyFields.VELOCITY, buf)
                calls[0] += 1
        except BaseException as exc:  # reported below
            errors.append(exc)

    t = threading.Thread(target=work)
    t.start()
    steps = 0
    deadline = time.monotonic() + 1.0
    try:
        while time.monotonic() < deadline and t.is_alive():
            s.step(1 / 60)
            steps += 1
    finally:
        stop.set()
        t.join()
    assert not errors, errors
    assert steps > 0 and calls[0] > 0
    assert s._contact_graph_problem() is None
    for _ in range(20):
        s.step(1 / 60)
    assert s._contact_graph_problem() is None


@isolated(timeout=60)
def test_a_second_thread_waits_for_the_step_to_end():
    s = tamias2d.Space()
    s.gravity = 0, -100
    ball = tamias2d.Body(1, 10)
    ball.position = 0, 4
    s.add(ball, tamias2d.Circle(ball, 5), tamias2d.Segment(s.static_body, (-50, 0), (50, 0), 1))
    batch = tamias2d.batch
    inside = threading.Event()
    in_callback = [False]
    seen = []
    own = batch.Buffer()

    def pre_solve(arbiter, space, data):
        in_callback[0] = True
        batch.get_space_bodies(space, batch.BodyFields.POSITION, own)   # the stepping thread
        inside.set()
        time.sleep(0.3)                # releases the GIL
        in_callback[0] = False

    s.on_collision(pre_solve=pre_solve)

    def other():
        inside.wait(10)
        buf = batch.Buffer()
        buf.set_float_buf(np.array([1.0, 0.0, 0.0, 0.0]))
        batch.set_space_bodies(s, batch.BodyFields.VELOCITY, buf)     # waits for the step
        seen.append(in_callback[0])
        batch.get_space_arbiters(s, batch.ArbiterFields.ALL, buf)
        seen.append(in_callback[0])

    t = threading.Thread(target=other)
    t.start()
    s.step(1 / 60)
    t.join()
    assert seen == [False, False]
    assert ball.velocity == (1, 0)
    assert len(own.float_buf()) == 2 * 2 * 8
