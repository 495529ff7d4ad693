"""Snapshots that lie: mutation fuzzing of copy / pickle states.

A pickled space carries its C state as one ``bytes`` snapshot (see
``tamias2d._snapshot``) inside a pymunk-layout state dict, next to the
bodies, shapes and constraints it describes. A restore must refuse every
state that breaks a rule the step, the sleeping code, the broad phase or
the destructors rely on, with a clean Python exception; whatever it accepts
must step, copy and be freed without a crash, a hang or a NaN.

This file is both the pytest test and the fuzz driver. Each trial takes the
pickle of one scene (sleeping bodies, joints asleep and awake, the spatial
hash, fresh contacts, bodies outside the space) and mutates either

* the snapshot bytes: bit flips, byte overwrites, truncations, swapped
  ranges, records copied over or swapped with others of their section, and
  typed writes (an int32 field set to -1, an out-of-range or another
  record's index; a double set to NaN, inf, 0, -1, 1e308, ...), aimed by
  the section map of ``tamias2d._snapshot.snapshot_sections``;
* or the parsed state, as the pickler sees it (a custom ``Pickler`` changes
  the reduce values of the space, its bodies, shapes and constraints):
  numbers set to NaN / inf / 0 / -1 / huge, lists reordered, duplicated,
  truncated or given foreign objects, wrong types;
* or the pickle stream itself (bit flips).

The mutated pickle is made in the test process; the trial runs in a forked
child (``tests/isolated.py``) with a timeout: unpickle, then 60 steps,
checking after each that every body is finite, then the contact graph
(``Space._contact_graph_problem``, also right after the restore), every
body woken, queries, 5 more steps, then a copy and a pickle of the result,
stepped again, then everything freed. A trial passes when the restore
raises a clean exception (CopyError for a corrupt snapshot), or when the
restored space does all of that; a step may also refuse the state the way
it refuses the same state made through the API (IllegalBody for a massless
dynamic body, or for an overflow of a huge but finite value, ...), which is
counted apart. A crash, a hang, a NaN, another exception, or a copy refused
after clean steps fails the trial, with the command that replays it.

CI runs 5 scenes x 150 trials (about 10 s); TAMIAS2D_FULL=1 runs 5 x 1,200 (about 75 s).
TAMIAS2D_SEED=S picks the seed. The driver:

    python tests/test_snapshot_fuzz.py --trials 2000 [--seed S] [--scene NAME]
    python tests/test_snapshot_fuzz.py --replay FILE     # one saved trial, in-process

prints the figures (trials, refused, restored and ran, refused by a step,
failures) and saves each failing trial's pickle for --replay.
"""
import argparse
import collections
import copy
import gc
import io
import math
import os
import pickle
import random
import struct
import sys
import tempfile
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
if os.path.join(os.path.dirname(HERE), "src") not in sys.path:
    sys.path.insert(0, os.path.join(os.path.dirname(HERE), "src"))

import tamias2d  # noqa: E402
from tamias2d import errors  # noqa: E402
from tamias2d import _snapshot  # noqa: E402
from tamias2d._snapshot import snapshot_sections  # noqa: E402

import isolated  # noqa: E402

FULL = os.environ.get("TAMIAS2D_FULL", "") not in ("", "0")
SEED0 = int(os.environ.get("TAMIAS2D_SEED", "7100"))
TRIALS = 1200 if FULL else 150
STEPS = 60
DT = 1.0 / 60.0
TIMEOUT = 30.0


# -- scenes ------------------------------------------------------------------------------------

def _count_begin(arbiter, space, data):
    # A collision callback that pickles (module level) and uses its data.
    if data is not None:
        data["begins"] = data.get("begins", 0) + 1


def _box(space, mass, w, h, pos, angle=0.0):
    body = tamias2d.Body(mass, tamias2d.moment_for_box(mass, (w, h)))
    body.position = pos
    body.angle = angle
    shape = tamias2d.Poly.create_box(body, (w, h), 0.5)
    shape.friction = 0.7
    space.add(body, shape)
    return body


def _ball(space, mass, r, pos):
    body = tamias2d.Body(mass, tamias2d.moment_for_circle(mass, 0, r))
    body.position = pos
    shape = tamias2d.Circle(body, r)
    shape.friction = 0.7
    shape.elasticity = 0.2
    space.add(body, shape)
    return body


def _floor(space, half=400.0):
    floor = tamias2d.Segment(space.static_body, (-half, 0), (half, 0), 2.0)
    floor.friction = 1.0
    space.add(floor)
    return floor


def _run(space, steps):
    for _ in range(steps):
        space.step(DT)


def sleeping_pile():
    """Boxes and balls at rest and asleep in two groups, one more ball still
    falling onto them (an awake body over sleeping ones), two more awake on
    the floor."""
    space = tamias2d.Space()
    space.gravity = 0, -600
    space.sleep_time_threshold = 0.4
    _floor(space)
    for i in range(12):
        _box(space, 1 + i % 3, 16, 12, (-150 + 18 * (i % 4), 8 + 14 * (i // 4)))
        _ball(space, 1, 7, (80 + 15 * (i % 4), 8 + 15 * (i // 4)))
    _run(space, 240)
    # Awake beside them: a ball falling onto the pile (it will wake it) and
    # two resting on the floor (this step's arbiters).
    _ball(space, 2, 8, (-130, 120))
    _ball(space, 1, 8, (300, 30))
    _ball(space, 1, 8, (330, 30))
    _run(space, 25)
    return space


def joints():
    """Every joint kind; a ragdoll-like chain asleep (its joints out of the
    solver's array), a motor and a spring awake, a bare body outside the
    space held by a pivot."""
    space = tamias2d.Space()
    space.gravity = 0, -400
    space.sleep_time_threshold = 0.3
    space.idle_speed_threshold = 15.0
    space.damping = 0.4
    _floor(space)
    prev = space.static_body
    chain = []
    for i in range(5):
        body = _box(space, 1, 10, 6, (-100 + 12 * i, 40))
        anchor = (-106 + 12 * i, 40)
        space.add(tamias2d.PivotJoint(prev, body, anchor))
        chain.append(body)
        prev = body
    a, b, c, d = (_ball(space, 1, 6, (60 + 20 * i, 10)) for i in range(4))
    space.add(tamias2d.PinJoint(a, b), tamias2d.SlideJoint(b, c, (0, 0), (0, 0), 5, 30),
              tamias2d.GrooveJoint(space.static_body, d, (100, 5), (200, 5), (0, 0)),
              tamias2d.DampedSpring(a, c, (0, 0), (0, 0), 30, 50, 2),
              tamias2d.DampedRotarySpring(b, d, 0.2, 400, 5),
              tamias2d.RotaryLimitJoint(a, d, -0.5, 0.5),
              tamias2d.RatchetJoint(c, d, 0.0, 0.3),
              tamias2d.GearJoint(chain[0], chain[1], 0.0, 2.0))
    wheel = _ball(space, 3, 10, (250, 12))
    space.add(tamias2d.SimpleMotor(space.static_body, wheel, 2.0))
    bare = tamias2d.Body(1, 10)          # never added: a joint's body outside the space
    bare.position = 255, 30
    space.add(tamias2d.PivotJoint(wheel, bare, (255, 20)))
    _run(space, 300)
    return space


def spatial_hash():
    """The spatial hash with sleeping bodies (their shapes in the static
    hash), a kinematic paddle keeping some awake, removed shapes whose
    handles are still in the cells."""
    space = tamias2d.Space()
    space.gravity = 0, -500
    space.sleep_time_threshold = 0.4
    space.use_spatial_hash(25.0, 997)
    _floor(space, 300)
    balls = [_ball(space, 1, 8, (-200 + 20 * (i % 10), 10 + 18 * (i // 10))) for i in range(30)]
    paddle = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
    paddle.position = 150, 20
    paddle.angular_velocity = 1.5
    space.add(paddle, tamias2d.Segment(paddle, (-30, 0), (30, 0), 4))
    _run(space, 150)
    for body in balls[25:]:
        space.remove(body, *body.shapes)
    _run(space, 150)
    return space


def fresh_contacts():
    """Shapes touching for the first time in the step before the snapshot
    (contacts in the head buffer, begin callbacks, warm starts to come),
    polygons of 8 vertices (planes on the heap), a sensor, handlers with
    data, no sleeping."""
    space = tamias2d.Space()
    space.gravity = 0, -900
    space.collision_persistence = 2
    _floor(space)
    octagon = [(10 * math.cos(2 * math.pi * k / 8), 10 * math.sin(2 * math.pi * k / 8))
               for k in range(8)]
    for i in range(10):
        body = tamias2d.Body(2, 400)
        body.position = -120 + 25 * i, 11 + (i % 3) * 0.5
        body.velocity = 0, -60
        shape = tamias2d.Poly(body, octagon, None, 0.5)
        shape.friction = 0.6
        shape.collision_type = 1 + i % 2
        space.add(body, shape)
    sensor = tamias2d.Circle(space.static_body, 30, (0, 30))
    sensor.sensor = True
    space.add(sensor)
    space.on_collision(1, None, begin=_count_begin, data={"name": "ones"})
    space.on_collision(1, 2, begin=_count_begin)
    _run(space, 1)
    return space


def outside_bodies():
    """Bodies outside the space: one removed while its shapes stay (an
    orphan), a static body of its own with shapes, kinematic bodies, a
    dynamic body jointed to a bare one."""
    space = tamias2d.Space()
    space.gravity = 0, -300
    space.sleep_time_threshold = 0.5
    _floor(space)
    ground2 = tamias2d.Body(body_type=tamias2d.Body.STATIC)
    ground2.position = 200, 0
    space.add(ground2, tamias2d.Poly.create_box(ground2, (80, 20)))
    bodies = [_box(space, 1, 12, 12, (150 + 14 * i, 20 + 13 * (i % 2))) for i in range(8)]
    bodies += [_ball(space, 1, 6, (-60 + 13 * i, 8)) for i in range(6)]
    orphan = bodies[3]
    space.remove(orphan)                  # its shape stays in the space
    kin = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
    kin.velocity = 10, 0
    kin.position = -150, 10
    space.add(kin, tamias2d.Circle(kin, 10))
    _run(space, 200)
    return space


def soft_pile():
    """The soft solver: a stack asleep; a pyramid settled, its contacts'
    loads learnt; a pinned pair swinging and a bullet in flight."""
    space = tamias2d.Space(solver="soft")
    space.gravity = 0, -600
    space.sleep_time_threshold = 0.3
    _floor(space)
    for i in range(3):
        _box(space, 2, 14, 10, (200, 5 + 10 * i))
    _run(space, 100)
    space.sleep_time_threshold = 5.0
    for row in range(5):
        for j in range(5 - row):
            _box(space, 1, 12, 12, (-150 + 13 * j + 6.5 * row, 6 + 12 * row))
    a = _ball(space, 1, 5, (60, 80))
    b = _ball(space, 1, 5, (90, 80))
    space.add(tamias2d.PivotJoint(space.static_body, a, (60, 80)), tamias2d.PinJoint(a, b))
    _run(space, 80)
    bullet = _ball(space, 0.2, 2, (-300, 100))
    bullet.is_bullet = True
    bullet.velocity = 900, 0
    _run(space, 5)
    return space


def soft_threaded():
    """A soft pyramid stepped on two threads, every step on the pool: its
    contacts lie where the threaded narrow phase places them, two places
    a pair, some left empty (SoftPlaceContacts)."""
    from tamias2d import _soft_step
    space = tamias2d.Space(solver="soft", threaded=True)
    space.threads = 2
    space.gravity = 0, -600
    _floor(space)
    for row in range(6):
        for j in range(6 - row):
            _box(space, 1, 12, 12, (-150 + 13 * j + 6.5 * row, 6 + 12 * row))
    before = _soft_step._threaded_min_contacts_set()
    _soft_step._threaded_min_contacts_set(0)
    try:
        _run(space, 60)
    finally:
        _soft_step._threaded_min_contacts_set(before)
    return space


SCENES = {
    "soft_pile": soft_pile,
    "soft_threaded": soft_threaded,
    "sleeping_pile": sleeping_pile,
    "joints": joints,
    "spatial_hash": spatial_hash,
    "fresh_contacts": fresh_contacts,
    "outside_bodies": outside_bodies,
}


class Base:
    """One scene, pickled, with the map of its snapshot."""

    def __init__(self, name):
        self.name = name
        self.space = SCENES[name]()
        self.pickle = pickle.dumps(self.space, protocol=4)
        state = self.space.__getstate__()
        self.blob = dict(state["special"])["tamias2d_snapshot"][1]
        self.sections = [s for s in snapshot_sections(self.blob) if s[3] > 0]
        self.names = sorted({s[0] for s in self.sections})
        # Small numbers worth writing into an index: the counts of every
        # section, each +-1.
        self.ints = sorted({c + d for _, _, _, c in self.sections for d in (-1, 0, 1)}
                           | {-2, -1, 0, 1, 2, 3, 0x7FFFFFFF, -0x80000000})


# -- mutations -------------------------------------------------------------------------------------

DOUBLES = [math.nan, -math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 1.0, 1e308, -1e308,
           5e-324, 1e9, -1e9, 1e150]
VALUES = DOUBLES + [None, "x", (1, 2), [1], -1, 0, 2 ** 40, True]
# Sections holding only int32 fields (links, arrays, cells).
INT_SECTIONS = {"body links", "Body.shapes orders", "shape links", "shape kinds",
                "constraint links", "solver constraint array", "dynamic bodies", "static bodies",
                "sleeping roots", "step arbiter array", "arbiter cache", "pair count", "pairs",
                "handles", "hash cell", "hash cell handles", "contact buffers"}


def _int32_at(r, base, offset):
    v = r.choice(base.ints)
    if r.random() < 0.3:
        v = r.randrange(-3, max(4, max(c for *_, c in base.sections) + 2))
    return struct.pack("<i", v)


def mutate_blob(r, base):
    """A mutated copy of the snapshot bytes and what was done."""
    b = bytearray(base.blob)
    kind = r.choice(["typed", "typed", "typed", "typed", "bits", "bytes", "truncate",
                     "swap-records", "copy-record", "swap-ranges"])
    # A section by name first (one per shape is one name), then a record.
    name = r.choice(base.names)
    name, off, size, count = r.choice([x for x in base.sections if x[0] == name])
    rec = r.randrange(count)
    start = off + rec * size
    if kind == "typed":
        if name in INT_SECTIONS or size < 8 or r.random() < 0.4:
            field = 4 * r.randrange(max(1, size // 4))
            b[start + field:start + field + 4] = _int32_at(r, base, field)
            what = f"int32 at {name}[{rec}]+{field}"
        else:
            field = 8 * r.randrange(size // 8)
            v = r.choice(DOUBLES)
            b[start + field:start + field + 8] = struct.pack("<d", v)
            what = f"double {v!r} at {name}[{rec}]+{field}"
    elif kind == "bits":
        where = []
        for _ in range(r.randint(1, 4)):
            pos = start + r.randrange(size) if r.random() < 0.7 else r.randrange(len(b))
            bit = r.randrange(8)
            b[pos] ^= 1 << bit
            where.append(f"{pos}.{bit}")
        what = f"bit flips at {', '.join(where)} (in {name})"
    elif kind == "bytes":
        n = r.randint(1, 8)
        pos = start + r.randrange(size)
        b[pos:pos + n] = bytes(r.randrange(256) for _ in range(n))[:len(b) - pos]
        what = f"{n} random bytes at {pos} (in {name})"
    elif kind == "truncate":
        cut = r.choice([r.randrange(len(b)), start, start + size])
        del b[cut:]
        what = f"truncated at {cut} (in {name})"
    elif kind in ("swap-records", "copy-record"):
        other = r.randrange(count)
        o = off + other * size
        a, c = bytes(b[start:start + size]), bytes(b[o:o + size])
        if kind == "swap-records":
            b[start:start + size], b[o:o + size] = c, a
        else:
            b[o:o + size] = a
        what = f"{kind} {name}[{rec}] and [{other}]"
    else:
        n = r.randint(1, 64)
        p1, p2 = r.randrange(len(b) - n), r.randrange(len(b) - n)
        x, y = bytes(b[p1:p1 + n]), bytes(b[p2:p2 + n])
        b[p1:p1 + n], b[p2:p2 + n] = y, x
        what = f"swapped {n} bytes at {p1} and {p2}"
    return bytes(b), f"snapshot bytes: {what}"


def _mutate_list(r, lst, pool):
    lst = list(lst)
    op = r.choice(["shuffle", "duplicate", "truncate", "drop", "foreign", "swap"])
    if not lst and op != "foreign":
        op = "foreign"
    if op == "shuffle":
        r.shuffle(lst)
    elif op == "duplicate":
        lst.insert(r.randrange(len(lst) + 1), r.choice(lst))
    elif op == "truncate":
        del lst[r.randrange(len(lst)):]
    elif op == "drop":
        del lst[r.randrange(len(lst))]
    elif op == "swap":
        i, j = r.randrange(len(lst)), r.randrange(len(lst))
        lst[i], lst[j] = lst[j], lst[i]
    else:
        lst.insert(r.randrange(len(lst) + 1), r.choice(pool))
    return lst, op


def _mutate_struct_bytes(r, data):
    # A double field of a struct (8-byte aligned) set to a special value.
    if not data or len(data) < 8:
        return data, "empty"
    b = bytearray(data)
    field = 8 * r.randrange(len(b) // 8)
    v = r.choice(DOUBLES)
    b[field:field + 8] = struct.pack("<d", v)
    return bytes(b), f"+{field} = {v!r}"


class StatePickler(pickle.Pickler):
    """Pickles a space with one change to the reduce value of the space or
    of one of its bodies, shapes or constraints."""

    def __init__(self, file, r, target, index, pool):
        super().__init__(file, protocol=4)
        self.r = r
        self.target = target
        self.index = index
        self.pool = pool
        self.seen = collections.Counter()
        self.what = None

    def reducer_override(self, obj):
        if isinstance(obj, tamias2d.Space):
            kind = "space"
        elif isinstance(obj, tamias2d.Body):
            kind = "body"
        elif isinstance(obj, tamias2d.Shape):
            kind = "shape"
        elif isinstance(obj, tamias2d.Constraint):
            kind = "constraint"
        else:
            return NotImplemented
        n = self.seen[kind]
        self.seen[kind] += 1
        if kind != self.target or n != self.index or self.what is not None:
            return NotImplemented
        rv = obj.__reduce_ex__(4)
        func, args, state = rv[0], rv[1], rv[2]
        state, self.what = getattr(self, "_" + kind)(state, obj)
        return (func, args, state) + tuple(rv[3:])

    def _space(self, state, space):
        r = self.r
        state = {k: list(v) for k, v in state.items()}
        part = r.choice(["general", "special", "special", "special", "layout"])
        if part == "layout":
            key = r.choice(list(state))
            op = r.choice(["delete", "not-a-list", "bad-entry"])
            if op == "delete":
                del state[key]
            elif op == "not-a-list":
                state[key] = r.choice(VALUES)
            else:
                state[key].append(r.choice(VALUES))
            return state, f"space state: {op} {key!r}"
        if part == "general":
            i = r.randrange(len(state["general"]))
            k, _ = state["general"][i]
            v = r.choice(VALUES)
            state["general"][i] = (k, v)
            return state, f"space state: general {k} = {v!r}"
        special = state["special"]
        i = r.randrange(len(special))
        k, v = special[i]
        if k == "tamias2d_snapshot":
            extra, blob, funcs = v
            sub = r.choice(["extra", "funcs", "tuple", "blob-type"])
            if sub == "extra":
                extra, op = _mutate_list(r, extra, self.pool)
                v = (extra, blob, funcs)
            elif sub == "funcs":
                funcs, op = _mutate_list(r, funcs or [(0, _count_begin)],
                                         [(-1, _count_begin), (10 ** 6, print), (0, None),
                                          ("x", _count_begin), (0, _count_begin)])
                v = (extra, blob, funcs)
            elif sub == "tuple":
                v, op = (extra, blob), "two items"
            else:
                v, op = (extra, bytearray(blob), funcs), "bytearray"
            special[i] = (k, v)
            return state, f"space state: snapshot {sub} {op}"
        if isinstance(v, list):
            v, op = _mutate_list(r, v, self.pool)
        else:
            v, op = r.choice(VALUES + self.pool), "replaced"
        special[i] = (k, v)
        return state, f"space state: special {k} {op}"

    def _body(self, state, body):
        r = self.r
        if not (isinstance(state, tuple) and len(state) == 5):
            return state, "body state (pymunk layout) untouched"
        tag, data, custom, vf, pf = state
        if r.random() < 0.8:
            data, what = _mutate_struct_bytes(r, data)
            return (tag, data, custom, vf, pf), f"body {self.index} struct {what}"
        which = r.randrange(5)
        new = list(state)
        new[which] = r.choice(VALUES + self.pool)
        return tuple(new), f"body {self.index} state item {which} = {new[which]!r}"

    def _shape(self, state, shape):
        r = self.r
        if not (isinstance(state, tuple) and len(state) == 6):
            return state, "shape state (pymunk layout) untouched"
        tag, kind, body, data, planes, custom = state
        roll = r.random()
        if roll < 0.6:
            data, what = _mutate_struct_bytes(r, data)
            return (tag, kind, body, data, planes, custom), f"shape {self.index} struct {what}"
        if roll < 0.75:
            kind = r.choice([0, 1, 2, 3, -1, "x"])
            return (tag, kind, body, data, planes, custom), f"shape {self.index} kind {kind!r}"
        if roll < 0.9:
            body = r.choice(self.pool + [None])
            return (tag, kind, body, data, planes, custom), f"shape {self.index} body {body!r}"
        planes, what = _mutate_struct_bytes(r, planes) if planes else (b"\0" * 7, "junk")
        return (tag, kind, body, data, planes, custom), f"shape {self.index} planes {what}"

    def _constraint(self, state, constraint):
        r = self.r
        state = {k: list(v) for k, v in state.items()}
        part = r.choice([p for p in ("init", "general") if state[p]])
        i = r.randrange(len(state[part]))
        k, _ = state[part][i]
        v = r.choice(VALUES + self.pool)
        state[part][i] = (k, v)
        return state, f"constraint {self.index} {part} {k} = {v!r}"


def mutate_state(r, base):
    space = base.space
    counts = {"space": 1, "body": len(space.bodies) + 2, "shape": len(space.shapes),
              "constraint": len(space.constraints)}
    target = r.choice(["space", "space", "space", "body", "shape", "constraint"])
    if counts[target] == 0:
        target = "space"
    index = r.randrange(counts[target])
    pool = list(space.bodies)[:3] + list(space.shapes)[:2] + [tamias2d.Body(1, 1), None]
    buf = io.BytesIO()
    p = StatePickler(buf, r, target, index, pool)
    try:
        p.dump(space)
    except Exception as exc:             # the mutation itself cannot be pickled
        return None, f"unpicklable mutation ({exc!r})"
    return buf.getvalue(), p.what or f"{target} {index}: not reached"


def mutate_pickle(r, base):
    b = bytearray(base.pickle)
    for _ in range(r.randint(1, 3)):
        b[r.randrange(len(b))] ^= 1 << r.randrange(8)
    return bytes(b), STREAM


STREAM = "pickle stream bit flips"


def make_trial(base, seed, k):
    """The mutated pickle of trial k (deterministic within one process:
    the snapshot's arbiter order follows addresses)."""
    r = random.Random(f"{seed}/{base.name}/{k}")
    roll = r.random()
    if roll < 0.6:
        blob, what = mutate_blob(r, base)
        if r.random() < 0.15:
            # Two or three changes at once.
            for _ in range(r.randint(1, 2)):
                if len(blob) != len(base.blob):
                    break                # truncated: the section map no longer fits
                later = Base.__new__(Base)
                later.__dict__.update(base.__dict__, blob=blob)
                blob, more = mutate_blob(r, later)
                what += "; " + more
        state = base.space.__getstate__()
        state["special"] = [(key, (v[0], blob, v[2]) if key == "tamias2d_snapshot" else v)
                            for key, v in state["special"]]
        return pickle.dumps((state,), protocol=4), what
    if roll < 0.93:
        return mutate_state(r, base)
    return mutate_pickle(r, base)


# -- one trial --------------------------------------------------------------------------------

# What a restore may raise for a state that is refused.
CLEAN = (errors.Tamias2DError, ValueError, TypeError, AssertionError, pickle.UnpicklingError,
         EOFError, KeyError, IndexError, AttributeError, OverflowError)
# What a step may raise for a state it refuses (as for the same state made
# through the API).
STEP_REFUSALS = (errors.IllegalBody, errors.UnsolvableCollision, ValueError)


class TrialFailure(AssertionError):
    pass


def _load(data):
    obj = pickle.loads(data)
    if isinstance(obj, tuple):
        # A state dict with a mutated snapshot, restored as unpickling would.
        space = tamias2d.Space.__new__(tamias2d.Space)
        space.__setstate__(obj[0])
        return space
    return obj


def _outside_bodies(space):
    # Bodies of the space's joints and shapes that are not in the space (a
    # joint's bare body, an orphan): joints still move them.
    inside = set(space.bodies)
    out = {b for c in space.constraints for b in (c.a, c.b)} | {s.body for s in space.shapes}
    return [b for b in out if b not in inside and b is not space.static_body]


def _finite(space, extra=()):
    for body in list(space.bodies) + list(extra) + [space.static_body]:
        for v in (*body.position, *body.velocity, body.angle, body.angular_velocity):
            if not math.isfinite(v):
                return body
    return None


def _step(space, n, note):
    """n steps; returns False when a step refused the state."""
    extra = _outside_bodies(space)
    for i in range(n):
        try:
            space.step(DT)
        except STEP_REFUSALS as exc:
            note.append(f"step {i}: {type(exc).__name__}: {str(exc)[:120]}")
            return False
        bad = _finite(space, extra)
        if bad is not None:
            raise TrialFailure(f"step {i} left {bad!r} non-finite")
    return True


def run_trial(data, stream=False):
    """Unpickle, step, copy, free. Returns (outcome, detail). `stream`: the
    pickle stream itself was mutated, and pickle may also fail to find a
    class or to allocate a corrupt length."""
    try:
        space = _load(data)
    except CLEAN + ((ImportError, MemoryError) if stream else ()) as exc:
        return "refused", f"{type(exc).__name__}: {str(exc)[:200]}"
    if not isinstance(space, tamias2d.Space):
        return "refused", f"not a space: {type(space).__name__}"
    problem = space._contact_graph_problem()
    if problem:
        raise TrialFailure(f"contact graph right after the restore: {problem}")
    note = []
    clean = _step(space, STEPS, note)
    if clean:
        problem = space._contact_graph_problem()
        if problem:
            raise TrialFailure(f"contact graph after {STEPS} steps: {problem}")
        # Wake everything (sleeping contacts go back to the buffers, shapes
        # to the dynamic index), query, step on.
        for body in space.bodies:
            body.activate()
        space.bb_query(tamias2d.BB(-1000, -1000, 1000, 1000), tamias2d.ShapeFilter())
        space.segment_query((-500, 50), (500, 60), 1.0, tamias2d.ShapeFilter())
        clean = _step(space, 5, note)
    copies = []
    for how in ("copy", "pickle"):
        try:
            copies.append(space.copy() if how == "copy" else pickle.loads(pickle.dumps(space)))
        except CLEAN as exc:
            # A space whose step refused it (an overflow left NaN bodies) may
            # be refused a copy; one that stepped cleanly may not, unless its
            # numbers grew past the magnitudes a restore accepts (a huge but
            # accepted value in, a larger one out: finite, counted apart).
            if clean and isinstance(exc, errors.CopyError) and _grew(str(exc)):
                clean = None
                note.append(f"{how} refused, numbers grew: {str(exc)[:120]}")
                continue
            if clean:
                raise TrialFailure(f"the restored space stepped cleanly but its {how} is "
                                   f"refused: {type(exc).__name__}: {exc}")
            note.append(f"{how} refused: {str(exc)[:100]}")
    for c in copies:
        _step(c, 3, note)
    del space, copies
    gc.collect()
    if clean:
        return "ran", ""
    if clean is None:
        return "grew", "; ".join(note)
    return "step-refused", "; ".join(note)


def _grew(message):
    return any(m in message for m in ("beyond 1e150", "would overflow", "1e150 away"))


def _child_trial(data, stream):
    outcome, detail = run_trial(data, stream)
    return outcome, detail


# -- driving many trials -------------------------------------------------------------------------

class Figures:
    def __init__(self):
        self.counts = collections.Counter()
        self.by_scene = collections.defaultdict(collections.Counter)
        self.messages = collections.Counter()
        self.failures = []

    def add(self, scene, outcome, detail):
        self.counts[outcome] += 1
        self.by_scene[scene][outcome] += 1
        if outcome in ("refused", "step-refused", "grew"):
            self.messages[(outcome, _gist(detail))] += 1

    def summary(self):
        total = sum(self.counts.values())
        c = self.counts
        return (f"{total} trials: {c['refused']} refused at restore, {c['ran']} restored and "
                f"ran {STEPS} steps + copies, {c['step-refused']} restored then refused by a "
                f"step, {c['grew']} ran but grew past the magnitudes a copy accepts, "
                f"{c['skipped']} mutations not picklable, {len(self.failures)} failures")


def _gist(detail):
    # The message without numbers, to count refusals by rule.
    out = []
    for word in detail.split():
        out.append("N" if any(ch.isdigit() for ch in word) else word)
    return " ".join(out)[:110]


def fuzz(scenes, seed, trials, fork=True, save_dir=None, progress=None):
    figures = Figures()
    for name in scenes:
        base = Base(name)
        for k in range(trials):
            data, what = make_trial(base, seed, k)
            if data is None:
                figures.add(name, "skipped", what)
                continue
            if fork:
                kind, info = isolated.run_in_child(_child_trial, (data, what == STREAM),
                                                   timeout=TIMEOUT)
            else:
                try:
                    kind, info = "ok", run_trial(data, what == STREAM)
                except Exception:
                    kind, info = "error", ("", "", traceback.format_exc())
            if kind == "ok":
                figures.add(name, *info)
                continue
            problem = {"signal": lambda: f"crash: killed by {info}",
                       "timeout": lambda: f"hang: still running after {info} s",
                       "error": lambda: f"failure:\n{info[2]}"}.get(kind, lambda: str(info))()
            path = None
            if save_dir is not None:
                path = os.path.join(save_dir, f"snapshot-fuzz-{name}-{seed}-{k}.pickle")
                with open(path, "wb") as f:
                    f.write(data)
            replay = (f"python tests/test_snapshot_fuzz.py --replay {path}" if path else
                      f"python tests/test_snapshot_fuzz.py --scene {name} --seed {seed} "
                      f"--trial {k}")
            figures.failures.append(f"{name} trial {k} ({what}): {problem}\nreplay: {replay}")
            figures.counts["failed"] += 1
        if progress:
            progress(name, figures)
    return figures


def main(argv=None):
    ap = argparse.ArgumentParser(description="tamias2d snapshot mutation fuzzer")
    ap.add_argument("--seed", type=int, default=SEED0)
    ap.add_argument("--trials", type=int, default=200, help="trials per scene")
    ap.add_argument("--scene", action="append", choices=list(SCENES))
    ap.add_argument("--no-fork", action="store_true", help="run the trials in this process")
    ap.add_argument("--replay", help="run one saved trial pickle in this process")
    ap.add_argument("--trial", type=int,
                    help="run trial K of --scene in this process and print it (a snapshot "
                         "mutation may aim elsewhere than in the run that found it: the "
                         "arbiter order follows addresses; --replay is exact)")
    ap.add_argument("--save", default=tempfile.gettempdir(),
                    help="directory for the pickles of failing trials")
    ap.add_argument("--messages", action="store_true", help="list the refusals by rule")
    args = ap.parse_args(argv)
    if args.replay:
        with open(args.replay, "rb") as f:
            data = f.read()
        print(run_trial(data, stream=True))
        return 0
    scenes = args.scene or list(SCENES)
    if args.trial is not None:
        base = Base(scenes[0])
        data, what = make_trial(base, args.seed, args.trial)
        print(what)
        print(run_trial(data, what == STREAM) if data is not None else "not picklable")
        return 0

    def progress(name, figures):
        print(f"{name}: {dict(figures.by_scene[name])}", flush=True)

    figures = fuzz(scenes, args.seed, args.trials, fork=not args.no_fork, save_dir=args.save,
                   progress=progress)
    print(figures.summary())
    if args.messages:
        for (outcome, msg), n in figures.messages.most_common():
            print(f"{n:6d} {outcome}: {msg}")
    for f in figures.failures:
        print("FAILED", f)
    return 1 if figures.failures else 0


# -- the pytest side -----------------------------------------------------------------------------

import pytest  # noqa: E402

# Field offsets of a few records, mirroring the structs of tamias2d/_snapshot.pyx
# and _structs.pxd (the record sizes are checked against the snapshot's own).
BODY_LINK = {"in_space": 0, "shapeList": 4, "arbiterList": 8, "root": 12, "next": 16,
             "constraintList": 24, "size": 32}
BODY = {"m": 16, "m_inv": 24, "idleTime": 264, "size": 280}
ARB = {"a": 48, "b": 52, "body_a": 56, "body_b": 60, "handlerAB": 96, "size": 128}
SHAPE_BB = {"l": 64, "b": 72, "r": 80, "t": 88}
INDEX = {"reach": 8, "size": 64}


class Snap:
    """A space's snapshot bytes, edited field by field, restored into a new space."""

    def __init__(self, space):
        self.state = space.__getstate__()
        self.blob = bytearray(dict(self.state["special"])["tamias2d_snapshot"][1])
        self.sections = snapshot_sections(bytes(self.blob))
        assert self.section("body links")[1] == BODY_LINK["size"]
        assert self.section("body structs")[1] == BODY["size"]
        assert self.section("arbiters", allow_empty=True)[1] == ARB["size"]

    def section(self, name, nth=0, allow_empty=False):
        found = [s[1:] for s in self.sections if s[0] == name]
        if not found:
            assert allow_empty, name
            return 0, ARB["size"], 0
        return found[nth]

    def at(self, name, index, field=0):
        # Per-shape sections (circle, segment, polygon) come one per shape.
        found = [s[1:] for s in self.sections if s[0] == name]
        if len(found) > 1:
            off, size, count = found[index]
            return off + field
        off, size, count = found[0]
        assert 0 <= index < count, (name, index, count)
        return off + index * size + field

    def i32(self, name, index, field=0):
        return struct.unpack_from("<i", self.blob, self.at(name, index, field))[0]

    def set_i32(self, name, index, field, value):
        struct.pack_into("<i", self.blob, self.at(name, index, field), value)

    def f64(self, name, index, field):
        return struct.unpack_from("<d", self.blob, self.at(name, index, field))[0]

    def set_f64(self, name, index, field, value):
        struct.pack_into("<d", self.blob, self.at(name, index, field), value)

    def count(self, name):
        return self.section(name, allow_empty=True)[2]

    def shape_section(self, shape):
        # The struct section of shape number `shape` (kinds in shape order).
        kinds = [self.i32("shape kinds", k) for k in range(self.count("shape kinds"))]
        kind = kinds[shape]
        name = ("circle", "segment", "polygon")[kind]
        return name, sum(1 for k in kinds[:shape] if k == kind)

    def restore(self):
        state = copy.deepcopy(self.state)
        state["special"] = [(k, (v[0], bytes(self.blob), v[2]) if k == "tamias2d_snapshot"
                             else v) for k, v in state["special"]]
        space = tamias2d.Space.__new__(tamias2d.Space)
        space.__setstate__(state)
        return space

    def chain(self, root):
        members = []
        cur = root
        while cur >= 0:
            members.append(cur)
            cur = self.i32("body links", cur, BODY_LINK["next"])
        return members

    def sleeping_arbiter(self):
        for k in range(self.count("sleeping roots")):
            for body in self.chain(self.i32("sleeping roots", k)):
                arb = self.i32("body links", body, BODY_LINK["arbiterList"])
                if arb >= 0:
                    return arb
        raise AssertionError("no sleeping arbiter")


def _refused(snap, pattern):
    # The refusal must be a CopyError naming the rule; run in a child so
    # that a regression (a crash, a hang) fails only this test.
    import re

    def attempt():
        try:
            space = snap.restore()
        except errors.CopyError as exc:
            if not re.search(pattern, str(exc)):
                raise AssertionError(f"refused, but not for {pattern!r}: {exc}")
            return "refused"
        for _ in range(STEPS):
            space.step(DT)
        raise AssertionError(f"not refused (expected {pattern!r})")
    kind, info = isolated.run_in_child(attempt, timeout=TIMEOUT)
    assert kind == "ok", (kind, info[2] if kind == "error" else info)


def _two_sleeping_groups():
    space = sleeping_pile()
    assert sum(b.is_sleeping for b in space.bodies) > 4
    return space


def test_unmutated_snapshots_restore_and_continue_bitwise():
    for name, build in SCENES.items():
        space = build()
        twins = [space.copy(), pickle.loads(pickle.dumps(space))]
        for _ in range(30):
            for s in [space] + twins:
                s.step(DT)
        ref = [(tuple(b.position), tuple(b.velocity), b.angle) for b in space.bodies]
        for t in twins:
            assert [(tuple(b.position), tuple(b.velocity), b.angle) for b in t.bodies] == ref, name


# The classes of lying snapshots that crashed or hung before the restore checked them.

def test_arbiter_without_collision_handler_is_refused():
    snap = Snap(fresh_contacts())
    snap.set_i32("arbiters", 0, ARB["handlerAB"], -2)
    _refused(snap, "arbiter 0 has no collision handler")


def test_sleeping_body_whose_idle_time_reads_static_is_refused():
    snap = Snap(_two_sleeping_groups())
    root = snap.i32("sleeping roots", 0)
    snap.set_f64("body structs", root, BODY["idleTime"], math.inf)
    _refused(snap, f"body {root} .*idle time is infinite")
    # Made static all through (an infinite mass too): it still sleeps.
    snap.set_f64("body structs", root, BODY["m"], math.inf)
    snap.set_f64("body structs", root, BODY["m_inv"], 0.0)
    _refused(snap, f"body {root} sleeps but reads as static")


def test_sleeping_chain_linked_into_another_is_refused():
    snap = Snap(_two_sleeping_groups())
    assert snap.count("sleeping roots") >= 2
    first, second = snap.i32("sleeping roots", 0), snap.i32("sleeping roots", 1)
    last = snap.chain(first)[-1]
    snap.set_i32("body links", last, BODY_LINK["next"], second)
    _refused(snap, "runs into body")


def test_step_arbiter_array_naming_a_sleeping_arbiter_or_one_twice_is_refused():
    space = _two_sleeping_groups()
    snap = Snap(space)
    assert snap.count("step arbiter array") >= 2
    snap.set_i32("step arbiter array", 0, 0, snap.sleeping_arbiter())
    _refused(snap, "this step's arbiter array names arbiter [0-9]+, whose bodies sleep")
    snap = Snap(space)
    snap.set_i32("step arbiter array", 1, 0, snap.i32("step arbiter array", 0))
    _refused(snap, "this step's arbiter array names arbiter [0-9]+ twice")


def test_constraint_array_naming_a_joint_twice_is_refused():
    snap = Snap(joints())
    assert snap.count("solver constraint array") >= 2
    snap.set_i32("solver constraint array", 1, 0, snap.i32("solver constraint array", 0))
    _refused(snap, "the solver's constraint array names constraint [0-9]+ twice")


@pytest.mark.parametrize("section,offset", [("slide joint", 56), ("ratchet joint", 112),
                                            ("gear joint", 56)])
def test_joint_parameter_its_setter_refuses_is_refused(section, offset):
    # A copy rebuilds the joints through their setters, which refuse a
    # parameter beyond 1e100 (constraints.PARAMETER_LIMIT): a snapshot with
    # one (an error_bias at +56, the ratchet's phase at +112) restored and
    # stepped, but its copy was refused (this fuzzer's seed 4040).
    snap = Snap(joints())
    snap.set_f64(section, 0, offset, 1e150)
    _refused(snap, rf"constraint [0-9]+ (\({section}\) has a parameter|has max_force)")


def test_joint_ranges_the_setters_accept_copy():
    # The other way round: what the setters accept, a snapshot accepts (a
    # slide joint with min > max, a limit far below -1e150), and the copy
    # steps as the original does.
    assert _snapshot.JOINT_PARAMETER_LIMIT == tamias2d.constraints.PARAMETER_LIMIT
    space = tamias2d.Space()
    space.gravity = 0, -100
    a, b = _ball(space, 1, 1, (0, 0)), _ball(space, 1, 1, (7, 0))
    space.add(tamias2d.SlideJoint(a, b, (0, 0), (0, 0), 10, 5),
              tamias2d.RotaryLimitJoint(a, b, -1e300, 1e300),
              tamias2d.DampedSpring(a, b, (0, 0), (0, 0), 7, 10, 0))
    twins = [space.copy(), pickle.loads(pickle.dumps(space))]
    for _ in range(20):
        for s in [space] + twins:
            s.step(DT)
    ref = [(tuple(b.position), b.angle) for b in space.bodies]
    for t in twins:
        assert [(tuple(b.position), b.angle) for b in t.bodies] == ref


def test_awake_body_claiming_to_be_a_sleeping_root_is_refused():
    snap = Snap(_two_sleeping_groups())
    awake = snap.i32("dynamic bodies", 0)
    snap.set_i32("body links", awake, BODY_LINK["root"], awake)
    _refused(snap, f"body {awake} is awake .* claims to be in a sleeping component")


def test_spatial_hash_sleeping_shape_with_inverted_box_is_refused():
    snap = Snap(spatial_hash())
    root = snap.i32("sleeping roots", 0)
    shape = snap.i32("body links", root, BODY_LINK["shapeList"])
    name, nth = snap.shape_section(shape)
    right = snap.f64(name, nth, SHAPE_BB["r"])
    snap.set_f64(name, nth, SHAPE_BB["l"], right + 1e6)
    _refused(snap, f"shape {shape}'s cached bounding box .* inverted")


def test_sleeping_body_with_nan_or_zero_mass_is_refused():
    space = _two_sleeping_groups()
    snap = Snap(space)
    root = snap.i32("sleeping roots", 0)
    snap.set_f64("body structs", root, BODY["m"], math.nan)
    _refused(snap, f"body {root} has mass nan")
    snap = Snap(space)
    snap.set_f64("body structs", root, BODY["m"], 0.0)
    snap.set_f64("body structs", root, BODY["m_inv"], math.inf)
    _refused(snap, f"sleeping body {root} has mass 0.0")


def test_tree_reaching_nan_or_negative_into_the_static_tree_is_refused():
    # The soft solver's static reach is kept in the snapshot (a copy finds
    # the same pairs next step); a lying one is refused, not used.
    space = fresh_contacts()
    space.solver = "soft"
    for _ in range(3):
        space.step(DT)
    snap = Snap(space)
    assert snap.section("dynamic index")[1] == INDEX["size"]
    assert snap.f64("dynamic index", 0, INDEX["reach"]) > 0.0
    for bad in (math.nan, -1.0, math.inf):
        snap.set_f64("dynamic index", 0, INDEX["reach"], bad)
        _refused(snap, "the dynamic index reaches .* into the static tree")


def test_legit_states_of_the_operation_fuzzer_are_never_refused():
    # Random operation sequences (tests/test_fuzz.py) make the odd states
    # the API allows (orphan shapes, kinematic and static bodies, joints,
    # forced sleep, the spatial hash); every copy taken after a step must
    # restore.
    import test_fuzz

    refused = []

    def run(seed):
        fz = test_fuzz.Fuzzer(tamias2d, seed, io.StringIO())

        def after(i, name):
            if name == "step":
                try:
                    fz.space.copy()
                except errors.CopyError as exc:
                    if "internal error" not in str(exc):   # a capture refusal, not a restore's
                        refused.append(f"seed {seed}, operation {i}: {exc}")
        fz.run(1500, after_op=after)
        return refused

    for seed in (SEED0, SEED0 + 1):
        kind, info = isolated.run_in_child(run, (seed,), timeout=300)
        assert kind == "ok", info
        assert not info, info[:3]



def test_snapshot_mutation_fuzz(tmp_path):
    figures = fuzz(list(SCENES), SEED0, TRIALS, save_dir=str(tmp_path))
    assert not figures.failures, (figures.summary() + "\n" + "\n\n".join(figures.failures[:5]))
    # The fuzzer reaches both sides: refusals and restores that run.
    assert figures.counts["refused"] > 0 and figures.counts["ran"] > 0, figures.summary()


if __name__ == "__main__":
    sys.exit(main())
