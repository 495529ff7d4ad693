"""tamias2d's soft solver against Box2D v3 (pyb2d3) and pymunk 7.3 on
Box2D's own benchmark scenes.

The same scenes are built in each engine (sleeping off, gravity -10, dt
1/60): Box2D at 4 substeps, tamias2d ``Space(solver="soft")`` at its 4
substeps, pymunk's solver at its 10 iterations. Lengths are in metres, so
tamias2d and pymunk get Box2D's linear slop (``collision_slop = 0.005``, as
docs/coming-from-box2d.md advises); masses and moments are density times
area as Box2D computes them; the contact friction is 0.6 in every engine
(Box2D mixes sqrt(a b) of 0.6 and 0.6, tamias2d and pymunk multiply a
ground's 1.0 by a box's 0.6).

  large_pyramid  Box2D's: a pyramid of base 100 (5,050 boxes 1x1), 500 steps
  many_pyramids  Box2D's: 20 x 20 pyramids of base 10 on 20 ground segments
                 (22,000 boxes), 200 steps
  tumbler        Box2D's: a hollow box 20x20 (density 50) turned at 25 deg/s
                 by a motor (max torque 1e8) holding 45 x 45 boxes of 0.25,
                 750 steps
  pyramid_20     a pyramid of base 20 (210 boxes), 300 steps
  rain_1000      1,000 circles of radius 0.25-0.5 (seed 1) dropped into an
                 open box 30 wide, 300 steps

Timing: every engine builds the scene once and takes a few warm-up steps;
then the engines are advanced in turn, a chunk of steps each (the order
turned each round), every chunk timed with time.perf_counter, so that a
noisy shared machine slows all of them alike. The figure is the median
ms/step over the chunks. Beside them, the same scene in a threaded tamias2d
space at ``threads = 1`` and ``threads = 2`` and in Box2D with a thread pool
of 2 workers, for the two-thread speedups (t1 / t2).

"Stands" (pyramids): at the end no box moved more than 0.25 box sideways
and no pyramid's top box sank 0.25 box. Tumbler and rain: "ok" when no body
left the container and nothing is NaN.

    PYTHONPATH=src python benchmarks/against_box2d.py [--quick] [--json [PATH]]
        [--plot PATH] [--scenes a,b] [--skip-pymunk a,b] [--no-threads]
"""
import argparse
import importlib.metadata
import json
import math
import os
import random
import statistics
import sys
import time

try:
    import tamias2d
except ImportError:  # run from a checkout that is not installed
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src"))
    import tamias2d
import pymunk

# pyb2d3 imports numpy, whose OpenBLAS starts a thread per core that spins
# for a while (3% of a tumbler run's samples under `perf record`): on a
# two-core machine that takes time from the engines measured, most of all
# from the two-thread rows. Nothing here calls BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import pyb2d3 as b2  # noqa: E402

from harness import box2d_shape_def

DT = 1.0 / 60.0
GRAVITY = -10.0
FRICTION = 0.6
SLOP = 0.005  # Box2D's linear slop, metres
COMPARED = ("box2d", "tamias2d", "pymunk")


class Box2DEngine:
    name = "box2d"

    def __init__(self, workers=1):
        pool = b2.ThreadPool(workers) if workers > 1 else None
        self.w = b2.World(thread_pool=pool, gravity=(0, GRAVITY))
        self.w.sleeping_enabled = False
        self.ground = self.w.create_static_body(position=(0, 0))

    @staticmethod
    def _sdef(density):
        return box2d_shape_def(b2, density, FRICTION)

    def static_box(self, cx, cy, hw, hh):
        self.ground.create_polygon_shape(self._sdef(1.0), b2.box(hw, hh, center=(cx, cy)))

    def static_segment(self, a, b):
        self.ground.create_segment_shape(self._sdef(1.0), b2.segment(a, b))

    def box(self, x, y, hw, hh, density=1.0):
        body = self.w.create_dynamic_body(position=(x, y))
        body.create_polygon_shape(self._sdef(density), b2.box(hw, hh))
        return body

    def circle(self, x, y, r, density=1.0):
        body = self.w.create_dynamic_body(position=(x, y))
        body.create_circle_shape(self._sdef(density), b2.circle(radius=r))
        return body

    def tumbler(self, x, y, walls, density, speed, torque):
        body = self.w.create_dynamic_body(position=(x, y))
        for cx, cy, hw, hh in walls:
            body.create_polygon_shape(self._sdef(density), b2.box(hw, hh, center=(cx, cy)))
        self.w.create_revolute_joint(body_a=self.ground, body_b=body, local_anchor_a=(x, y),
                                     local_anchor_b=(0, 0), enable_motor=True,
                                     motor_speed=speed, max_motor_torque=torque)
        return body

    def step(self, n):
        for _ in range(n):
            self.w.step(DT, 4)

    @staticmethod
    def pose(body):
        p = body.position
        return p[0], p[1], body.angle


class ChipmunkEngine:
    """tamias2d and pymunk share pymunk's API; ``mod`` is either module."""

    def __init__(self, mod, name, **space_kw):
        self.mod, self.name = mod, name
        self.s = mod.Space(**space_kw)
        self.s.gravity = 0, GRAVITY
        self.s.collision_slop = SLOP

    def _add(self, body, shape, friction=FRICTION):
        shape.friction = friction
        self.s.add(body, shape) if body is not None else self.s.add(shape)

    def static_box(self, cx, cy, hw, hh):
        verts = [(cx - hw, cy - hh), (cx + hw, cy - hh), (cx + hw, cy + hh), (cx - hw, cy + hh)]
        self._add(None, self.mod.Poly(self.s.static_body, verts), 1.0)

    def static_segment(self, a, b):
        self._add(None, self.mod.Segment(self.s.static_body, a, b, 0.0), 1.0)

    def box(self, x, y, hw, hh, density=1.0):
        m = density * 4 * hw * hh
        body = self.mod.Body(m, self.mod.moment_for_box(m, (2 * hw, 2 * hh)))
        body.position = x, y
        self._add(body, self.mod.Poly.create_box(body, (2 * hw, 2 * hh)))
        return body

    def circle(self, x, y, r, density=1.0):
        m = density * math.pi * r * r
        body = self.mod.Body(m, self.mod.moment_for_circle(m, 0, r))
        body.position = x, y
        self._add(body, self.mod.Circle(body, r))
        return body

    def tumbler(self, x, y, walls, density, speed, torque):
        # mass and moment as Box2D sums them over the shapes (corners overlap twice)
        mass = moment = 0.0
        for cx, cy, hw, hh in walls:
            m = density * 4 * hw * hh
            mass += m
            moment += m * ((2 * hw) ** 2 + (2 * hh) ** 2) / 12 + m * (cx * cx + cy * cy)
        body = self.mod.Body(mass, moment)
        body.position = x, y
        self.s.add(body)
        for cx, cy, hw, hh in walls:
            verts = [(cx - hw, cy - hh), (cx + hw, cy - hh), (cx + hw, cy + hh), (cx - hw, cy + hh)]
            self._add(None, self.mod.Poly(body, verts), 1.0)
        static = self.s.static_body
        motor = self.mod.SimpleMotor(static, body, -speed)  # Chipmunk drives w_b - w_a = -rate
        motor.max_force = torque
        self.s.add(self.mod.PivotJoint(static, body, (x, y)), motor)
        return body

    def step(self, n):
        for _ in range(n):
            self.s.step(DT)

    @staticmethod
    def pose(body):
        p = body.position
        return p.x, p.y, body.angle


# -- scenes: each builds into an engine and returns what the checks need -----------------

def pyramid_rows(base, half, x0, y0):
    """Box centres of a pyramid of ``base`` boxes of half size ``half``, row by
    row from the bottom, its base's left end at x0 and its bottom at y0."""
    return [(x0 + (i + 1) * half + 2 * (j - i) * half, y0 + (2 * i + 1) * half)
            for i in range(base) for j in range(i, base)]


def build_pyramid(e, base):
    e.static_box(0.0, -1.0, 100.0, 1.0)
    bodies = [e.box(x, y, 0.5, 0.5) for x, y in pyramid_rows(base, 0.5, -0.5 * base, 0.0)]
    return {"bodies": bodies, "tops": [len(bodies) - 1], "size": 1.0}


def build_many_pyramids(e, rows, columns, base=10, half=0.5):
    # Box2D's layout: ground segments 2 half (base + 1) apart, the pyramids of a
    # row one box apart from each other, the first one box in from the left end
    dy = 2 * half * (base + 1)
    width = 2 * half * columns * (base + 1)
    for i in range(rows):
        e.static_segment((-0.5 * width, i * dy), (0.5 * width, i * dy))
    bodies, tops = [], []
    for i in range(rows):
        for j in range(columns):
            centre = -0.5 * width + j * (2 * half * base + 2 * half) + 2 * half
            bodies += [e.box(x, y, half, half)
                       for x, y in pyramid_rows(base, half, centre - 0.5, i * dy)]
            tops.append(len(bodies) - 1)
    return {"bodies": bodies, "tops": tops, "size": 2 * half}


def build_tumbler(e, grid):
    walls = ((10.0, 0.0, 0.5, 10.0), (-10.0, 0.0, 0.5, 10.0),
             (0.0, 10.0, 10.0, 0.5), (0.0, -10.0, 10.0, 0.5))
    drum = e.tumbler(0.0, 10.0, walls, 50.0, math.radians(25.0), 1e8)
    bodies = [e.box(-0.2 * grid + 0.4 * j, 10.0 - 0.2 * grid + 0.4 * i, 0.125, 0.125)
              for i in range(grid) for j in range(grid)]
    return {"bodies": bodies + [drum], "drum": drum}


def build_rain(e, count, seed=1):
    e.static_box(0.0, -1.0, 16.0, 1.0)
    e.static_box(-16.0, 30.0, 1.0, 30.0)
    e.static_box(16.0, 30.0, 1.0, 30.0)
    rng = random.Random(seed)
    per_row = 25
    bodies = [e.circle(-13.2 + 1.1 * (k % per_row), 1.0 + 1.1 * (k // per_row),
                       rng.uniform(0.25, 0.5)) for k in range(count)]
    return {"bodies": bodies, "box": (-15.0, 15.0, 0.0, 60.0)}


# name: (builder, full arguments, quick arguments, full steps, quick steps)
SCENES = {
    "large_pyramid": (build_pyramid, (100,), (20,), 500, 40),
    "many_pyramids": (build_many_pyramids, (20, 20), (3, 3), 200, 30),
    "tumbler": (build_tumbler, (45,), (12,), 750, 40),
    "pyramid_20": (build_pyramid, (20,), (10,), 300, 40),
    "rain_1000": (build_rain, (1000,), (150,), 300, 40),
}


def judge(e, scene, home):
    """(verdict, detail) at the end of the run: True/False and the largest
    sideways move and top sink in boxes (pyramids), or "ok"/"FAIL" (tumbler,
    rain: every body still in the container, nothing NaN)."""
    poses = [e.pose(b) for b in scene["bodies"]]
    if any(not all(map(math.isfinite, p)) for p in poses):
        return (False if "tops" in scene else "FAIL"), {"nan": True}
    if "tops" in scene:
        size = scene["size"]
        side = max(abs(p[0] - h[0]) for p, h in zip(poses, home)) / size
        sink = max(home[t][1] - poses[t][1] for t in scene["tops"]) / size
        return side < 0.25 and sink < 0.25, {"sideways": side, "sink": sink}
    if "drum" in scene:  # every box still inside the drum, in the drum's frame
        dx, dy, a = e.pose(scene["drum"])
        c, s = math.cos(a), math.sin(a)
        inside = all(abs(c * (x - dx) + s * (y - dy)) < 9.7 and abs(-s * (x - dx) + c * (y - dy)) < 9.7
                     for x, y, _ in poses[:-1])
    else:
        x0, x1, y0, y1 = scene["box"]
        inside = all(x0 < x < x1 and y0 < y < y1 for x, y, _ in poses)
    return ("ok" if inside else "FAIL"), {}


def make_engines(pymunk_too, threads_too):
    """(label, constructor): the compared three, then the two-thread pairs."""
    made = [("box2d", Box2DEngine),
            ("tamias2d", lambda: ChipmunkEngine(tamias2d, "tamias2d", solver="soft"))]
    if pymunk_too:
        made.append(("pymunk", lambda: ChipmunkEngine(pymunk, "pymunk")))
    if threads_too:
        def threaded(n):
            e = ChipmunkEngine(tamias2d, f"tamias2d_t{n}", threaded=True, solver="soft")
            e.s.threads = n
            return e
        made += [("tamias2d_t1", lambda: threaded(1)), ("tamias2d_t2", lambda: threaded(2)),
                 ("box2d_w2", lambda: Box2DEngine(workers=2))]
    return made


def run_scene(name, quick, pymunk_too, threads_too, log):
    build, full_args, quick_args, full_steps, quick_steps = SCENES[name]
    args, steps = (quick_args, quick_steps) if quick else (full_args, full_steps)
    warm, chunk = (5, 5) if quick else (20, 10)
    engines, scenes, homes = {}, {}, {}
    for label, make in make_engines(pymunk_too, threads_too):
        t0 = time.perf_counter()
        engines[label] = e = make()
        scenes[label] = build(e, *args)
        homes[label] = [e.pose(b) for b in scenes[label]["bodies"]]
        e.step(warm)
        log(f"{name}: {label} built and warmed up in {time.perf_counter() - t0:.1f} s")
    times = {label: [] for label in engines}
    labels = list(engines)
    done, rnd = 0, 0
    while done < steps:
        n = min(chunk, steps - done)
        for label in labels[rnd % len(labels):] + labels[:rnd % len(labels)]:
            t0 = time.perf_counter()
            engines[label].step(n)
            times[label].append((time.perf_counter() - t0) * 1000.0 / n)
        done += n
        rnd += 1
        if rnd % 10 == 0:
            log(f"{name}: {done}/{steps} steps")
    ms = {label: statistics.median(t) for label, t in times.items()}
    judged = {label: judge(engines[label], scenes[label], homes[label])
              for label in COMPARED if label in engines}
    row = {"scene": name, "bodies": len(scenes["box2d"]["bodies"]), "steps": steps,
           "warmup_steps": warm, "chunk_steps": chunk,
           "box2d_ms": ms["box2d"], "tamias2d_ms": ms["tamias2d"], "pymunk_ms": ms.get("pymunk"),
           "tamias2d_vs_box2d": ms["tamias2d"] / ms["box2d"],
           "pymunk_vs_box2d": ms["pymunk"] / ms["box2d"] if "pymunk" in ms else None,
           "stands": {k: v[0] for k, v in judged.items()},
           "stands_detail": {k: v[1] for k, v in judged.items()}}
    if threads_too:
        row.update({"tamias2d_1thread_ms": ms["tamias2d_t1"], "tamias2d_2threads_ms": ms["tamias2d_t2"],
                    "tamias2d_2thread_speedup": ms["tamias2d_t1"] / ms["tamias2d_t2"],
                    "box2d_2workers_ms": ms["box2d_w2"],
                    "box2d_2thread_speedup": ms["box2d"] / ms["box2d_w2"]})
    else:
        row.update(tamias2d_2thread_speedup=None, box2d_2thread_speedup=None)
    return row


def fmt(x, spec=".2f", none="-"):
    return none if x is None else format(x, spec)


def stand_cell(v):
    return "yes" if v is True else "NO" if v is False else v


def table(rows):
    lines = ["| scene | bodies | Box2D ms/step | tamias2d soft ms/step | pymunk ms/step "
             "| tamias2d / Box2D | pymunk / Box2D | stands (Box2D, tamias2d, pymunk) "
             "| tamias2d 2-thread speedup | Box2D 2-thread speedup |",
             "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
    for r in rows:
        st = r["stands"]
        stands = ", ".join(stand_cell(st[k]) if k in st else "-" for k in COMPARED)
        lines.append(f"| {r['scene']} | {r['bodies']:,} | {fmt(r['box2d_ms'])} | {fmt(r['tamias2d_ms'])} "
                     f"| {fmt(r['pymunk_ms'])} | {fmt(r['tamias2d_vs_box2d'], '.1f')}x "
                     f"| {fmt(r['pymunk_vs_box2d'], '.1f')}{'x' if r['pymunk_vs_box2d'] else ''} "
                     f"| {stands} | {fmt(r['tamias2d_2thread_speedup'])} "
                     f"| {fmt(r['box2d_2thread_speedup'])} |")
    lines += ["", "| pyramid scene | largest sideways move, boxes (Box2D, tamias2d, pymunk) "
              "| largest top sink, boxes (Box2D, tamias2d, pymunk) |", "|---|---|---|"]
    for r in rows:
        d = r["stands_detail"]
        if "sink" not in d.get("box2d", {}):
            continue
        cell = [", ".join(fmt(d[k].get(q), ".3f") if k in d else "-" for k in COMPARED)
                for q in ("sideways", "sink")]
        lines.append(f"| {r['scene']} | {cell[0]} | {cell[1]} |")
    return "\n".join(lines)


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return None


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4.2))
    for shift, key, label in ((-0.2, "tamias2d_vs_box2d", "tamias2d soft / Box2D"),
                              (0.2, "pymunk_vs_box2d", "pymunk 7.3 / Box2D")):
        xs = [i + shift for i, r in enumerate(rows) if r[key] is not None]
        ys = [r[key] for r in rows if r[key] is not None]
        bars = ax.bar(xs, ys, 0.4, label=label)
        ax.bar_label(bars, fmt="%.1fx", fontsize=8)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(range(len(rows)), [f"{r['scene']}\n{r['bodies']:,} bodies" for r in rows])
    ax.set_ylabel("time per step / Box2D v3's (1 thread)")
    ax.set_title("Against Box2D v3: median time per step relative to Box2D (lower is faster)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small scenes, few steps (a smoke test)")
    ap.add_argument("--json", nargs="?", const="-", metavar="PATH",
                    help="write the results as JSON to PATH (without PATH: to stdout, no table)")
    ap.add_argument("--plot", metavar="PATH", help="save a bar chart of the ratios (PNG)")
    ap.add_argument("--scenes", help="comma-separated subset of " + ", ".join(SCENES))
    ap.add_argument("--skip-pymunk", default="", metavar="SCENES",
                    help="comma-separated scenes to run without pymunk (too slow there)")
    ap.add_argument("--no-threads", action="store_true", help="skip the two-thread comparisons")
    args = ap.parse_args(argv)
    names = args.scenes.split(",") if args.scenes else list(SCENES)
    skip = set(filter(None, args.skip_pymunk.split(",")))
    unknown = [n for n in names + sorted(skip) if n not in SCENES]
    if unknown:
        ap.error(f"unknown scene(s): {', '.join(unknown)}")

    def log(msg):
        print(f"[{time.perf_counter() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)
    start = time.perf_counter()
    load = os.getloadavg if hasattr(os, "getloadavg") else (lambda: (None,))
    load_start = load()[0]
    rows = [run_scene(n, args.quick, n not in skip, not args.no_threads, log) for n in names]
    result = {"meta": {"quick": args.quick, "dt": DT, "box2d_substeps": 4,
                       "tamias2d_substeps": 4, "pymunk_iterations": 10, "collision_slop": SLOP,
                       "tamias2d": tamias2d.version, "pymunk": pymunk.version,
                       "pyb2d3": importlib.metadata.version("pyb2d3"), "cpu": cpu_name(),
                       "logical_cpus": os.cpu_count(), "load_1min_start_end": [load_start, load()[0]],
                       "duration_s": time.perf_counter() - start},
              "scenes": rows}
    if args.json != "-":
        print(table(rows))
    if args.json:
        text = json.dumps(result, indent=1)
        if args.json == "-":
            print(text)
        else:
            with open(args.json, "w") as f:
                f.write(text + "\n")
    if args.plot:
        plot(rows, args.plot)


if __name__ == "__main__":
    main()
