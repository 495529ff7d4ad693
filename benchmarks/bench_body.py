"""Per-body Python access: tamias2d against pymunk in the same process.

Cases, each over N bodies (1,000 by default):
  * read       ``t += b.position.x + b.position.y + b.angle`` (pymunk's own
               get benchmark, benchmarks/pymunk-get.py);
  * read-vec   ``p = b.position`` only (Vec2d construction);
  * read-float ``a = b.angle`` only (no Vec2d);
  * write      ``b.position = (x, y)``;
  * create     ``Body(1, 10)`` N times;
  * create+shape  ``Body(1, 10)`` plus ``Circle(body, 1)`` N times (when the
               shape module is built).

With ``--in-space`` the bodies (with a circle each) are in a space, the case
that pays the thread guard's check (src/tamias2d/_threadguard.pxd: a thread
that touches a body while another thread steps its space waits for the
step); run it against two builds to see that check's cost.

Every case is timed ``--repeat`` times (each a ``--number``-loop); the median
per-loop time of each engine and the ratio tamias2d/pymunk are printed.
Lower is better; a ratio of 0.5 means tamias2d takes half of pymunk's time.

    PYTHONPATH=src:. python benchmarks/bench_body.py [--bodies N] [--repeat R] [--number K]
        [--in-space]
"""
import argparse
import statistics
import time

import pymunk
import tamias2d


def make_bodies(mod, n, in_space=False):
    bodies = []
    space = mod.Space() if in_space else None
    for i in range(n):
        b = mod.Body(1, 10)
        b.position = (i * 0.5, -i * 0.25)
        b.angle = i * 0.001
        if space is not None:
            space.add(b, mod.Circle(b, 0.1))
        bodies.append(b)
    if space is not None:
        _spaces.append(space)   # the spaces live as long as the run
    return bodies


_spaces = []


def case_read(bodies):
    t = 0.0
    for b in bodies:
        t += b.position.x + b.position.y + b.angle
    return t


def case_read_vec(bodies):
    for b in bodies:
        p = b.position
    return p


def case_read_float(bodies):
    for b in bodies:
        a = b.angle
    return a


def make_case_write(n):
    points = [(i * 0.5, i * 0.25) for i in range(n)]

    def case_write(bodies):
        for b, p in zip(bodies, points):
            b.position = p
    return case_write


def make_case_create(mod, n):
    Body = mod.Body

    def case_create(_):
        for _i in range(n):
            Body(1, 10)
    return case_create


def _circle_class(mod):
    if hasattr(mod, "Circle"):
        return mod.Circle
    try:
        from tamias2d.shape import Circle
    except ImportError:
        return None
    return Circle


def make_case_create_shape(mod, n):
    Body, Circle = mod.Body, _circle_class(mod)

    def case_create_shape(_):
        for _i in range(n):
            Circle(Body(1, 10), 1)
    return case_create_shape


def timeit(func, arg, repeat, number):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            func(arg)
        times.append((time.perf_counter() - t0) / number)
    return statistics.median(times)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--number", type=int, default=20)
    parser.add_argument("--in-space", action="store_true",
                        help="put the bodies (with a circle each) in a space")
    args = parser.parse_args(argv)
    n = args.bodies

    engines = {"tamias2d": tamias2d, "pymunk": pymunk}
    bodies = {name: make_bodies(mod, n, args.in_space) for name, mod in engines.items()}
    cases = [
        ("read (pos.x+pos.y+angle)", lambda mod: case_read),
        ("read position only", lambda mod: case_read_vec),
        ("read angle only", lambda mod: case_read_float),
        ("write position", lambda mod: make_case_write(n)),
        ("create Body", lambda mod: make_case_create(mod, n)),
    ]
    if _circle_class(tamias2d) is not None:
        cases.append(("create Body+Circle", lambda mod: make_case_create_shape(mod, n)))
    else:
        print("(tamias2d.Circle not available: skipping create Body+Circle)")

    # Same results first, so the timing compares equal work.
    assert case_read(bodies["tamias2d"]) == case_read(bodies["pymunk"])

    print("%d bodies%s, median of %d repeats x %d loops" % (n, " in a space" if args.in_space else "",
                                                   args.repeat, args.number))
    print("%-28s %14s %14s %8s" % ("case", "tamias2d us", "pymunk us", "ratio"))
    for label, make in cases:
        result = {}
        for name, mod in engines.items():
            result[name] = timeit(make(mod), bodies[name], args.repeat, args.number)
        ratio = result["tamias2d"] / result["pymunk"]
        print("%-28s %14.1f %14.1f %8.3f" % (label, result["tamias2d"] * 1e6,
                                            result["pymunk"] * 1e6, ratio))


if __name__ == "__main__":
    main()
