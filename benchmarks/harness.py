"""Shared pieces of the benchmark runner: finding the engines, timing,
progress display, machine description.

The runner is started as ``python benchmarks/run.py`` from anywhere. tamias2d
is imported as installed; only when that fails is the checkout that holds
this file put on ``sys.path`` (an installed package must win over a source
folder without compiled modules). ``tests/scenes.py`` of the same checkout
provides the scenes shared with the cross-validation tests.
"""
import importlib
import math
import os
import platform
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def import_engines():
    """(tamias2d, pymunk), importing tamias2d from the checkout if it is not
    installed."""
    try:
        import tamias2d
    except ImportError:
        sys.path.insert(0, os.path.join(ROOT, "src"))
        for name in [m for m in sys.modules if m == "tamias2d" or m.startswith("tamias2d.")]:
            del sys.modules[name]
        import tamias2d
    import tamias2d.batch  # noqa: F401
    import pymunk
    import pymunk.batch  # noqa: F401
    return tamias2d, pymunk


def import_scenes():
    """tests/scenes.py of this checkout (the scene builders both engines share)."""
    tests = os.path.join(ROOT, "tests")
    if tests not in sys.path:
        sys.path.insert(0, tests)
    return importlib.import_module("scenes")


ENGINES = ("pymunk", "tamias2d")

# The clock of every timing. "wall" is elapsed real time; "cpu" is the CPU
# time of this process, which for this single-threaded work equals the wall
# time on an idle machine and leaves out the time the process waits while
# other programs run (on a shared machine the wall clock adds their load).
CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
_clock = [time.perf_counter]


def set_clock(name):
    _clock[0] = CLOCKS[name]


def now():
    """The current reading of the chosen clock, in seconds."""
    return _clock[0]()


def median(xs):
    return statistics.median(xs)


def ratio(t_tamias, t_pymunk):
    """tamias2d time / pymunk time (below 1: tamias2d is faster)."""
    if t_tamias is None or t_pymunk is None or not t_pymunk > 0:
        return None
    return t_tamias / t_pymunk


def alternate(funcs, repeat):
    """Call every function of `funcs` (engine -> f() returning seconds)
    `repeat` times, switching which engine goes first at every round;
    engine -> list of times."""
    times = {name: [] for name in funcs}
    order = list(funcs)
    for r in range(repeat):
        for name in (order if r % 2 == 0 else order[::-1]):
            times[name].append(funcs[name]())
    return times


def timed(func, number=1):
    """Seconds per call of func() over `number` calls."""
    t0 = now()
    for _ in range(number):
        func()
    return (now() - t0) / number


def step_block(space, dt, steps):
    """Seconds per step over `steps` steps."""
    step = space.step
    t0 = now()
    for _ in range(steps):
        step(dt)
    return (now() - t0) / steps


def same_state(a, b):
    """True when two spaces' bodies have bitwise equal positions, angles and
    velocities (the two engines ran the same simulation)."""
    sa = [(tuple(x.position), x.angle, tuple(x.velocity), x.angular_velocity) for x in a.bodies]
    sb = [(tuple(x.position), x.angle, tuple(x.velocity), x.angular_velocity) for x in b.bodies]
    return sa == sb


def box2d_hard_case_world(b2, scale, friction):
    """A pyb2d3 world for a tests/hard_cases.py scene scaled by `scale`:
    its gravity (900 down), sleeping off, and its ground (a static segment
    of radius 5 whose top is at y 0) as a box of that friction."""
    world = b2.World(gravity=(0.0, -900.0 * scale))
    world.sleeping_enabled = False
    ground = world.create_static_body(position=(0.0, 0.0))
    ground.create_polygon_shape(box2d_shape_def(b2, 1.0, friction),
                                b2.box(2000.0 * scale, 5.0 * scale, center=(0.0, -5.0 * scale)))
    return world


def body_pose(body):
    """((x, y), angle) of a tamias2d or pyb2d3 body."""
    p = body.position
    return (p[0], p[1]), body.angle


def largest_motion(step, bodies, scale, steps, give_up):
    """Call `step` `steps` times; every 10 steps note the largest move (in
    the scene's units: divided by `scale`) and turn of any of `bodies` since
    the start. Stops early once a move passes `give_up` (fallen).
    Returns (largest move, largest turn)."""
    home = [body_pose(b) for b in bodies]
    moved = turned = 0.0
    for i in range(steps):
        step()
        if i % 10 == 9:
            for b, (p, a) in zip(bodies, home):
                q, ang = body_pose(b)
                moved = max(moved, math.dist(q, p) / scale)
                turned = max(turned, abs(ang - a))
            if moved > give_up:
                break
    return moved, turned


def box2d_shape_def(b2, density=1.0, friction=None, restitution=None, group_index=None):
    """A pyb2d3 ``ShapeDef``. pyb2d3 hands out copies of a definition's
    material and filter, so each is changed and then set back."""
    d = b2.ShapeDef()
    d.density = density
    if friction is not None or restitution is not None:
        m = d.material
        if friction is not None:
            m.friction = friction
        if restitution is not None:
            m.restitution = restitution
        d.material = m
    if group_index is not None:
        f = d.filter
        f.group_index = group_index
        d.filter = f
    return d


def finite(x):
    return isinstance(x, (int, float)) and math.isfinite(x)


class Progress:
    """One status line on stderr: rewritten in place on a terminal, printed
    as plain lines otherwise (logs, CI)."""

    def __init__(self, total, stream=None, enabled=True):
        self.stream = stream if stream is not None else sys.stderr
        self.total = total
        self.done = 0
        self.enabled = enabled
        self.tty = enabled and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.t0 = time.perf_counter()
        self._width = 0

    def _line(self, text):
        elapsed = time.perf_counter() - self.t0
        return f"[{self.done}/{self.total} {elapsed:5.0f}s] {text}"

    def start(self, text):
        """Show what runs now."""
        if not self.enabled:
            return
        line = self._line(text)
        if self.tty:
            cols = _terminal_columns(self.stream)
            line = line[:cols - 1]
            self.stream.write("\r" + line + "\x1b[K")
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def advance(self, n=1):
        self.done += n

    def note(self, text):
        """A line that stays (a finished item's result)."""
        if not self.enabled:
            return
        if self.tty:
            self.stream.write("\r\x1b[K" + text + "\n")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def finish(self):
        if self.enabled and self.tty:
            self.stream.write("\r\x1b[K")
            self.stream.flush()


def _terminal_columns(stream):
    try:
        cols = os.get_terminal_size(stream.fileno()).columns
    except (OSError, AttributeError, ValueError):
        cols = 0
    return cols if cols >= 20 else 100   # a terminal that reports no size


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_info(tamias2d, pymunk):
    import numpy
    info = {
        "cpu": cpu_model(),
        "logical_cpus": os.cpu_count(),
        "python": sys.version.split()[0],
        "python_implementation": platform.python_implementation(),
        "platform": platform.platform(),
        "tamias2d": tamias2d.version,
        "pymunk": pymunk.version,
        "chipmunk_of_pymunk": getattr(pymunk, "chipmunk_version", "?"),
        "numpy": numpy.__version__,
    }
    try:
        import Cython
        info["cython"] = Cython.__version__
    except ImportError:
        pass
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal"):
                    info["memory_kb"] = int(line.split()[1])
                    break
    except OSError:
        pass
    return info
