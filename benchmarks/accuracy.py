"""Speed against error: scenes with known answers, swept over the time step
and the solver iterations, in both engines.

For every case, engine, time step and iteration count the scene is built
fresh and simulated for a fixed time; the cost is the time (wall or CPU,
as run.py's --clock says) per simulated second (the Python loop calling
``step`` included, and the
per-step force or torque writes of IM1 and IM2, which are the same calls in
both engines), the error is measured against the known answer:

* IM1 free flight: 20 bodies under gravity plus a constant force; relative
  position error at T against p0 + v0 t + a t^2 / 2 (max over bodies).
* IM2 spin: 20 bodies under a constant torque; relative angle error at T
  against a0 + w0 t + (tau / I) t^2 / 2.
* IM3 head-on: two boxes meeting face to face, restitution 0.8, no friction;
  error of the velocities after the impact against the closed form (any
  spin or sideways velocity counts as error), relative to the closing speed.
* incline: a box released on a 30 degree slope with friction 0.2; relative
  error of the acceleration measured between 0.5 s and 1.5 s against
  g (sin a - mu cos a), and of the distance slid in 1.5 s against a t^2 / 2.
* stack (10 boxes) and pyramid (20 rows): the deepest penetration at the end
  (px, from the contact distances; Chipmunk lets shapes overlap by its 0.1 px
  slop on purpose) and the drift (px, the largest move of a body between
  1 s and the end, when everything should stand still).
* chaotic pile: 150 circles raining into a box; RMS distance (px) at 1 s
  from a reference run of the same engine at a 16 times smaller step than
  the smallest swept one, with 100 iterations.

Both engines compute the same numbers (tamias2d is a bitwise port), so their
errors coincide and the comparison is of cost; the runner records whether
the errors were equal.
"""
import math

import more_scenes
from harness import ENGINES, median, now


def sweep(quick):
    if quick:
        return [1 / 30, 1 / 60], [5, 10]
    return [1 / 30, 1 / 60, 1 / 120, 1 / 240], [2, 5, 10, 20]


def _steps(t, dt):
    return int(round(t / dt))


def _timed_steps(space, dt, n, before=None):
    step = space.step
    t0 = now()
    if before is None:
        for _ in range(n):
            step(dt)
    else:
        for _ in range(n):
            before()
            step(dt)
    return now() - t0


def _dist(a, b):
    return math.hypot(a[0] - b[0], a[1] - b[1])


# -- the cases: each returns (wall seconds, simulated seconds, {metric: error}) -------

def case_free_flight(mod, dt, iterations, quick, ctx):
    T = 0.5 if quick else 2.0
    space, bodies, apply, exact = more_scenes.free_flight(mod)
    space.iterations = iterations
    n = _steps(T, dt)
    wall = _timed_steps(space, dt, n, apply)
    t = n * dt
    p0, pe = exact(0.0), exact(t)
    err = max(_dist(tuple(b.position), e) / _dist(e, s) for b, e, s in zip(bodies, pe, p0))
    return wall, t, {"position": err}


def case_spin(mod, dt, iterations, quick, ctx):
    T = 0.5 if quick else 2.0
    space, bodies, apply, exact = more_scenes.spin(mod)
    space.iterations = iterations
    n = _steps(T, dt)
    wall = _timed_steps(space, dt, n, apply)
    t = n * dt
    a0, ae = exact(0.0), exact(t)
    err = max(abs(b.angle - e) / abs(e - s) for b, e, s in zip(bodies, ae, a0))
    return wall, t, {"angle": err}


def case_head_on(mod, dt, iterations, quick, ctx):
    T = 1.0
    space, a, b, (u1, u2) = more_scenes.head_on(mod, kind="box")
    space.iterations = iterations
    closing = abs(a.velocity.x - b.velocity.x)
    n = _steps(T, dt)
    wall = _timed_steps(space, dt, n)
    half = 10.0
    err = (abs(a.velocity.x - u1) + abs(b.velocity.x - u2) + abs(a.velocity.y) + abs(b.velocity.y)
           + half * (abs(a.angular_velocity) + abs(b.angular_velocity))) / closing
    return wall, n * dt, {"velocity": err}


def case_incline(mod, dt, iterations, quick, ctx):
    t1, t2 = 0.5, 1.5
    space, box, d, exact = more_scenes.incline(mod)
    space.iterations = iterations
    start = tuple(box.position)
    n1, n2 = _steps(t1, dt), _steps(t2, dt)
    wall = _timed_steps(space, dt, n1)
    v1 = box.velocity.x * d[0] + box.velocity.y * d[1]
    wall += _timed_steps(space, dt, n2 - n1)
    v2 = box.velocity.x * d[0] + box.velocity.y * d[1]
    acc = (v2 - v1) / ((n2 - n1) * dt)
    t = n2 * dt
    moved = (box.position.x - start[0]) * d[0] + (box.position.y - start[1]) * d[1]
    return wall, t, {"acceleration": abs(acc - exact) / exact,
                     "distance": abs(moved - 0.5 * exact * t * t) / (0.5 * exact * t * t)}


def _penetration(space):
    """Deepest overlap (px) over the contacts of the last step, read through
    Body.each_arbiter (the same calls in both engines, outside the timing)."""
    deepest = [0.0]

    def visit(arb):
        for p in arb.contact_point_set.points:
            if -p.distance > deepest[0]:
                deepest[0] = -p.distance

    for body in space.bodies:
        body.each_arbiter(visit)
    return deepest[0]


def _resting(build):
    def case(mod, dt, iterations, quick, ctx):
        t1, T = (0.5, 1.0) if quick else (1.0, 5.0)
        space = build(mod)
        space.iterations = iterations
        n1, n = _steps(t1, dt), _steps(T, dt)
        wall = _timed_steps(space, dt, n1)
        before = [tuple(b.position) for b in space.bodies]
        wall += _timed_steps(space, dt, n - n1)
        drift = max(_dist(tuple(b.position), p) for b, p in zip(space.bodies, before))
        return wall, n * dt, {"penetration": _penetration(space), "drift": drift}
    return case


def _chaos_reference(mod, dts, quick, scenes):
    dt_ref = min(dts) / 16.0
    T = 0.5 if quick else 1.0
    space = scenes.rain(mod, count=40 if quick else 150)
    space.iterations = 100
    _timed_steps(space, dt_ref, _steps(T, dt_ref))
    return [tuple(b.position) for b in space.bodies], dt_ref


def case_chaos(mod, dt, iterations, quick, ctx):
    scenes = ctx["scenes"]
    T = 0.5 if quick else 1.0
    space = scenes.rain(mod, count=40 if quick else 150)
    space.iterations = iterations
    n = _steps(T, dt)
    wall = _timed_steps(space, dt, n)
    ref = ctx["reference"][ctx["engine"]]
    sq = [_dist(tuple(b.position), r) ** 2 for b, r in zip(space.bodies, ref)]
    return wall, n * dt, {"divergence": math.sqrt(sum(sq) / len(sq))}


def cases(scenes):
    """(name, function, {metric: unit})."""
    return [
        ("IM1 free flight", case_free_flight, {"position": "relative"}),
        ("IM2 spin", case_spin, {"angle": "relative"}),
        ("IM3 head-on", case_head_on, {"velocity": "relative"}),
        ("incline", case_incline, {"acceleration": "relative", "distance": "relative"}),
        ("stack", _resting(lambda mod: scenes.vertical_stack(mod, count=10)),
         {"penetration": "px", "drift": "px"}),
        ("pyramid", _resting(lambda mod: scenes.pyramid(mod, rows=20)),
         {"penetration": "px", "drift": "px"}),
        ("chaotic pile", case_chaos, {"divergence": "px"}),
    ]


def task_count(quick):
    dts, its = sweep(quick)
    return 7 * len(dts) * len(its) + 1


def run_accuracy(mods, scenes, quick, progress, repeat=None):
    dts, its = sweep(quick)
    ctx = {"scenes": scenes, "reference": {}}
    progress.start("accuracy: chaotic pile reference runs")
    dt_ref = None
    for e in ENGINES:
        ctx["reference"][e], dt_ref = _chaos_reference(mods[e], dts, quick, scenes)
    progress.advance()
    rows = []
    for name, func, metrics in cases(scenes):
        for dt in dts:
            for it in its:
                progress.start(f"accuracy: {name} dt=1/{round(1 / dt)} iterations={it}")
                results = {}
                reps = 1 if quick else (repeat or 5)
                for r in range(reps):
                    order = ENGINES if r % 2 == 0 else ENGINES[::-1]
                    for e in order:
                        ctx["engine"] = e
                        wall, sim, errs = func(mods[e], dt, it, quick, ctx)
                        res = results.setdefault(e, {"walls": [], "sim": sim, "errors": errs})
                        res["walls"].append(wall)
                        if errs != res["errors"]:
                            res["deterministic"] = False
                same = results["pymunk"]["errors"] == results["tamias2d"]["errors"]
                for e in ENGINES:
                    res = results[e]
                    for metric, unit in metrics.items():
                        rows.append({
                            "case": name, "metric": metric, "unit": unit, "engine": e,
                            "dt": dt, "iterations": it, "sim_seconds": res["sim"],
                            "wall_s": median(res["walls"]), "repeats": len(res["walls"]),
                            "cost": median(res["walls"]) / res["sim"],
                            "error": res["errors"][metric],
                            "same_error_both_engines": same,
                        })
                progress.advance()
    front = pareto_fronts(rows)
    meta = {"dts": dts, "iterations": its, "chaos_reference_dt": dt_ref,
            "chaos_reference_iterations": 100}
    return rows, front, meta


def pareto_fronts(rows):
    """(case, metric) -> the settings no other setting beats on both cost
    and error, cheapest first."""
    groups = {}
    for r in rows:
        groups.setdefault(f"{r['case']} / {r['metric']}", []).append(r)
    fronts = {}
    for key, pts in groups.items():
        front = []
        for p in pts:
            dominated = any(
                q["cost"] <= p["cost"] and q["error"] <= p["error"]
                and (q["cost"] < p["cost"] or q["error"] < p["error"])
                for q in pts)
            if not dominated:
                front.append({k: p[k] for k in ("engine", "dt", "iterations", "cost", "error")})
        front.sort(key=lambda q: q["cost"])
        fronts[key] = front
    return fronts
