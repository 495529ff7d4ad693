"""No leaks: creating and destroying spaces, bodies and shapes in a long loop
keeps memory flat.

Each scenario runs in a fresh subprocess (this file is also the driver:
``python tests/test_leaks.py SCENARIO CYCLES``). After a warm-up, memory is
read three times, ``CYCLES`` cycles apart: Python objects with tracemalloc
and the whole process (the C structs: spaces, arrays, hash sets, trees,
contact buffers) as the resident set size from /proc/self/statm. The first
window may still grow (allocator high-water marks); the second must not grow
by more than the thresholds below, which are generous (a few hundred bytes
of Python objects and 2 MiB of RSS over hundreds of cycles, where a cycle
allocates megabytes), but still catch anything leaked every cycle: a body
(a few hundred bytes) times the bodies of a cycle, a contact buffer (32 KiB)
or a Python object per body. test_the_checker_catches_a_leak shows that.

TAMIAS2D_FULL=1 runs four times as many cycles.
"""
import gc
import json
import math
import os
import subprocess
import sys
import time
import tracemalloc

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
FULL = os.environ.get("TAMIAS2D_FULL", "") not in ("", "0")

PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096

# second-window growth allowed (bytes)
RSS_LIMIT = 2 * 1024 * 1024
PY_LIMIT_PER_CYCLE = 64


def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE


# -- scenarios (each is one cycle) ----------------------------------------------------------

def _world(t, count=24, hashing=False):
    s = t.Space()
    s.gravity = 0, -500
    if hashing:
        s.use_spatial_hash(20.0, 500)
    floor = t.Segment(s.static_body, (-300, 0), (300, 0), 3)
    floor.friction = 0.6
    s.add(floor)
    bodies = []
    for i in range(count):
        b = t.Body(1, 100)
        b.position = -100 + 17 * (i % 12), 20 + 25 * (i // 12)
        kind = i % 4
        if kind == 0:
            shape = t.Circle(b, 7)
        elif kind == 1:
            shape = t.Poly.create_box(b, (14, 12), 0.5)
        elif kind == 2:
            # more vertices than the inline buffer: a heap allocation
            shape = t.Poly(b, [(8 * math.cos(k / 2), 8 * math.sin(k / 2)) for k in range(12)])
        else:
            shape = t.Segment(b, (-8, 0), (8, 2), 2)
        shape.friction = 0.5
        s.add(b, shape)
        bodies.append(b)
    return s, bodies


def cycle_space(t, state):
    """A whole space: build, step (arbiters, contact buffers), query,
    remove half, step again, drop."""
    s, bodies = _world(t)
    for _ in range(12):
        s.step(1 / 60)
    flt = t.ShapeFilter()
    s.point_query((0, 10), 20, flt)
    s.point_query_nearest((0, 10), 20, flt)
    s.segment_query((-200, 10), (200, 30), 2, flt)
    s.segment_query_first((-200, 10), (200, 30), 2, flt)
    s.bb_query(t.BB(-50, 0, 50, 50), flt)
    s.shape_query(t.Circle(None, 30, (0, 20)))
    for b in bodies[::2]:
        s.remove(b, *b.shapes)
    for _ in range(5):
        s.step(1 / 60)


def cycle_sleeping(t, state):
    """A space dropped while most of its bodies sleep (their arbiters keep
    their contacts on the heap until woken), in both solvers."""
    for solver in ("chipmunk", "soft"):
        s, bodies = _world(t)
        s.solver = solver
        s.sleep_time_threshold = 0.05
        for _ in range(40):
            s.step(1 / 60)


def cycle_spatial_hash(t, state):
    s, bodies = _world(t, hashing=True)
    for _ in range(10):
        s.step(1 / 60)
    s.bb_query(t.BB(-50, 0, 50, 50), t.ShapeFilter())


def cycle_callbacks(t, state):
    """Handlers, post-step and integrator callbacks that close over the
    space (reference cycles through C-held callbacks), arbiter views kept."""
    s, bodies = _world(t, count=12)
    kept = []

    def begin(arb, space, data):
        kept.append((arb.contact_point_set, arb.normal, space, data))

    def post_solve(arb, space, data):
        arb.total_impulse
        if len(kept) < 50:
            space.add_post_step_callback(lambda sp, key: kept.append(key), len(kept))

    def separate(arb, space, data):
        kept.append(arb.shapes)

    s.on_collision(None, None, begin=begin, post_solve=post_solve, separate=separate, data=bodies)

    def vel(body, gravity, damping, dt):
        t.Body.update_velocity(body, gravity, damping, dt)
    bodies[0].velocity_func = vel
    for _ in range(12):
        s.step(1 / 60)
    for b in bodies[:4]:
        s.remove(*b.shapes)  # separate callbacks from the removal
    for b in bodies:
        b.each_arbiter(lambda arb: kept.append(arb.total_ke))


def cycle_churn(t, state):
    """One long-lived space; bodies and shapes come and go every cycle."""
    if "space" not in state:
        state["space"], _ = _world(t, count=8)
    s = state["space"]
    new = []
    for i in range(16):
        b = t.Body(1, 50)
        b.position = -60 + 9 * i, 80
        c = t.Circle(b, 4) if i % 2 else t.Poly.create_box(b, (8, 8))
        s.add(b, c)
        new.append((b, c))
    for _ in range(6):
        s.step(1 / 60)
    for b, c in new:
        s.remove(c, b)
    s.step(1 / 60)


def cycle_loose_objects(t, state):
    """Bodies and shapes never added to a space, their geometry, copies of
    values; shapes_collide between them."""
    b1, b2 = t.Body(1, 10), t.Body(2, 20)
    b2.position = 5, 0
    shapes = [t.Circle(b1, 5), t.Poly(b2, [(0, 0), (10, 0), (5, 8), (1, 7)], radius=1),
              t.Segment(b1, (0, 0), (9, 9), 1), t.Poly.create_box_bb(b2, t.BB(0, 0, 4, 4))]
    for s in shapes:
        s.cache_bb()
        s.area, s.moment, s.center_of_gravity, s.bb
        s.point_query((1, 1))
        s.segment_query((-10, 0), (10, 1), 0.5)
    for a in shapes:
        for b in shapes:
            if a.body is not b.body:
                a.shapes_collide(b)
    t.moment_for_poly(1, [(0, 0), (1, 0), (0, 1)])


def cycle_errors(t, state):
    """Refused input: the exceptions (and their tracebacks) go away."""
    s, (b, *_) = _world(t, count=2)
    for bad in (lambda: setattr(b, "mass", -1), lambda: setattr(b, "position", (math.nan, 0)),
                lambda: t.Circle(b, -1), lambda: t.Poly(b, []), lambda: s.step(math.nan),
                lambda: s.remove(t.Body(1, 1)), lambda: s.add(b),
                lambda: setattr(next(iter(b.shapes)), "friction", math.inf)):
        try:
            bad()
        except Exception:
            pass

    def boom(arb, space, data):
        raise KeyError("boom")
    s.on_collision(None, None, pre_solve=boom)
    for _ in range(5):
        try:
            s.step(1 / 60)
        except KeyError:
            pass


def cycle_autogeometry(t, state):
    """Marching squares and the polyline functions, with their error paths
    (a sample function that raises midway, refused polylines)."""
    from tamias2d import autogeometry as ag
    img = [[((i * 7 + j * 13) % 10) / 10 for i in range(40)] for j in range(40)]
    lines = ag.march_soft((0, 0, 39, 39), 40, 40, 0.45, lambda p: img[int(p[1])][int(p[0])])
    ag.march_hard((0, 0, 39, 39), 40, 40, 0.45, lambda p: img[int(p[1])][int(p[0])])
    for line in lines:
        ag.simplify_curves(line, 0.5)
        ag.simplify_vertexes(line, 0.2)
        ag.to_convex_hull(line, 0.1)
        if ag.is_closed(line) and t.area_for_poly(line) >= 0:
            ag.convex_decomposition(line, 0.1)

    def failing(p):
        # fails on the second row, with a 40 KB row buffer and the first
        # row's polylines allocated
        if p[1] > 0:
            raise KeyError(p)
        return (p[0] * 0.37) % 1.0
    for call in (lambda: ag.march_soft((0, 0, 4999, 99), 5000, 100, 0.45, failing),
                 lambda: ag.convex_decomposition([(0, 0), (1, 1), (1, 0), (0, 0)], 0.1),
                 lambda: ag.simplify_curves([(0, 0), (1, 0)], float("nan"))):
        try:
            call()
        except (KeyError, ValueError):
            pass


def cycle_leaky(t, state):
    """A deliberate leak, to show the checker finds one: a Python object
    and 16 KiB of C memory per cycle."""
    import ctypes
    state.setdefault("py", []).append(bytearray(512))
    libc = ctypes.CDLL(None)
    libc.malloc.restype = ctypes.c_void_p
    p = libc.malloc(16384)
    ctypes.memset(p, 1, 16384)  # touch it so it is resident


SCENARIOS = {name[len("cycle_"):]: fn for name, fn in globals().items()
             if name.startswith("cycle_")}


def measure(name, cycles, warmup):
    sys.path.insert(0, ROOT)
    import tamias2d as t
    fn = SCENARIOS[name]
    state = {}
    tracemalloc.start()
    for _ in range(warmup):
        fn(t, state)
    points = []
    t0 = time.perf_counter()
    for window in range(3):
        if window:
            for _ in range(cycles):
                fn(t, state)
        gc.collect()
        points.append((rss(), tracemalloc.get_traced_memory()[0]))
    return {"scenario": name, "cycles": cycles, "warmup": warmup, "rss": [p[0] for p in points],
            "py": [p[1] for p in points], "seconds": time.perf_counter() - t0}


# -- pytest side -----------------------------------------------------------------------------

CYCLES = {"space": 300, "spatial_hash": 300, "callbacks": 300, "churn": 600,
          "loose_objects": 1500, "errors": 600, "autogeometry": 150, "sleeping": 300, "leaky": 300}


def _run(name, cycles=None, warmup=None):
    cycles = cycles or CYCLES[name] * (4 if FULL else 1)
    warmup = warmup or max(20, cycles // 5)
    proc = subprocess.run([sys.executable, "-X", "faulthandler", os.path.abspath(__file__),
                           name, str(cycles), str(warmup)], capture_output=True, text=True,
                          timeout=600, cwd=ROOT)
    assert proc.returncode == 0, f"{name}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _verdict(m):
    """(ok, text): growth over the second window within the limits."""
    rss_growth = m["rss"][2] - m["rss"][1]
    py_growth = m["py"][2] - m["py"][1]
    n = m["cycles"]
    text = (f"{m['scenario']}: {n} cycles per window; RSS {m['rss'][0] / 2**20:.1f} -> "
            f"{m['rss'][1] / 2**20:.1f} -> {m['rss'][2] / 2**20:.1f} MiB; Python objects "
            f"{m['py'][0] / 1024:.0f} -> {m['py'][1] / 1024:.0f} -> {m['py'][2] / 1024:.0f} KiB; "
            f"second window: RSS {rss_growth / n:+.0f} B/cycle, Python {py_growth / n:+.1f} B/cycle")
    ok = rss_growth <= RSS_LIMIT and py_growth <= PY_LIMIT_PER_CYCLE * n
    return ok, text


def _scenarios():
    return [n for n in SCENARIOS if n != "leaky"]


def _parametrize():
    import pytest
    return pytest.mark.parametrize("name", _scenarios())


@_parametrize()
def test_memory_stays_flat(name):
    m = _run(name)
    ok, text = _verdict(m)
    print(text)
    assert ok, text


def test_the_checker_catches_a_leak():
    m = _run("leaky")
    ok, text = _verdict(m)
    assert not ok, "a deliberate leak went unnoticed: " + text
    # both halves: the Python object and the C block
    assert m["py"][2] - m["py"][1] > PY_LIMIT_PER_CYCLE * m["cycles"], text
    assert m["rss"][2] - m["rss"][1] > RSS_LIMIT, text


if __name__ == "__main__":
    name, cycles, warmup = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    print(json.dumps(measure(name, cycles, warmup)))
