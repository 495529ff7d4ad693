"""The operations users of pymunk complain about, timed in both engines.

* reading position, angle and velocity of every body, one property at a
  time from Python and through the batch call (tamias2d.batch.get_bodies;
  pymunk.batch.get_space_bodies into a Buffer viewed as a NumPy array);
* writing the same fields, one by one and through the batch call
  (tamias2d.batch.set_bodies; pymunk.batch.set_space_bodies);
* a step with a Python ``velocity_func`` on every body;
* a step with a Python ``post_solve`` callback on every contact;
* ``space.copy()`` and a pickle round trip of a 1,000-body space.

Every operation is timed in blocks (enough calls for ~20 ms), the engines
taking turns, and the median per call is kept. Results that should be equal
in both engines (the values read, the state after a write or a step) are
checked, so no row times different work.
"""
import math
import pickle

import more_scenes
from harness import ENGINES, alternate, median, now, ratio, same_state

FIELDS = ("position", "angle", "velocity")


def _calls_for(func, budget):
    t0 = now()
    func()
    once = now() - t0
    return max(1, min(1000, int(math.ceil(budget / max(once, 1e-7)))))


def _time_ops(funcs, repeat, budget):
    """Median seconds per call of each function of `funcs` (any keys), all
    timed in the same rounds with the order reversed every other round."""
    number = min(_calls_for(f, budget) for f in funcs.values())

    def block(f):
        def run():
            t0 = now()
            for _ in range(number):
                f()
            return (now() - t0) / number
        return run

    times = alternate({k: block(f) for k, f in funcs.items()}, repeat)
    medians = {k: median(v) for k, v in times.items()}
    medians["_raw"] = times
    return medians, number


def _added_cost(t, engine, suffix, count):
    """Median over rounds of (time with the Python function - time without)
    per call, in microseconds: paired by round, so that the motion and the
    machine's load at that moment cancel out."""
    raw = t["_raw"]
    diffs = [(a - b) / max(count, 1) * 1e6 for a, b in zip(raw[engine + suffix], raw[engine])]
    return median(diffs)


def _pymunk_batch(np, pymunk):
    F = pymunk.batch.BodyFields
    return F.POSITION | F.ANGLE | F.VELOCITY


def _row(name, n, t, number, note="", status="ok", **extra):
    row = {"operation": name, "n": n, "status": status, "note": note, "calls_per_block": number,
           "repeats": len(next(iter(t["_raw"].values()))) if "_raw" in t else None}
    for e in ENGINES:
        row[f"{e}_ms"] = None if t.get(e) is None else t[e] * 1e3
    row["ratio"] = ratio(t.get("tamias2d"), t.get("pymunk"))
    row.update(extra)
    return row


def task_count():
    return 7


def run_operations(mods, scenes, quick, progress, repeat=None):
    import numpy as np
    tamias2d, pymunk = mods["tamias2d"], mods["pymunk"]
    repeat = repeat or (1 if quick else 7)
    budget = 0.0 if quick else 0.02
    n = 200 if quick else 10000
    rows = []

    # -- reads and writes of every body -------------------------------------------------
    spaces = {e: more_scenes.sparse_field(mods[e], count=n) for e in ENGINES}
    for _ in range(3):
        for s in spaces.values():
            s.step(1 / 60)

    def read_one_by_one(space):
        def f():
            for b in space.bodies:
                p = b.position
                a = b.angle
                v = b.velocity
            return p, a, v
        return f

    flags = _pymunk_batch(np, pymunk)
    buf = pymunk.batch.Buffer()

    def p_read_batch():
        buf.clear()
        pymunk.batch.get_space_bodies(spaces["pymunk"], flags, buf)
        return np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(n, 5)

    def t_read_batch():
        return tamias2d.batch.get_bodies(spaces["tamias2d"], FIELDS)

    same_values = bool((p_read_batch() == t_read_batch()).all())
    progress.start(f"operations: read {n} bodies one by one")
    t, k = _time_ops({e: read_one_by_one(spaces[e]) for e in ENGINES}, repeat, budget)
    rows.append(_row("read position, angle, velocity: one by one", n, t, k,
                     "for b in space.bodies: b.position; b.angle; b.velocity"))
    progress.advance()
    progress.start(f"operations: read {n} bodies, batch")
    t, k = _time_ops({"pymunk": p_read_batch, "tamias2d": t_read_batch}, repeat, budget)
    rows.append(_row("read position, angle, velocity: batch", n, t, k,
                     "tamias2d.batch.get_bodies / pymunk.batch.get_space_bodies + np.frombuffer",
                     same_result=same_values))
    progress.advance()

    values = np.column_stack([np.linspace(0, 1000, n), np.linspace(-500, 500, n),
                              np.linspace(-3, 3, n), np.linspace(5, -5, n), np.linspace(-2, 2, n)])
    rows_list = [((r[0], r[1]), r[2], (r[3], r[4])) for r in values.tolist()]

    def write_one_by_one(space):
        def f():
            for b, (p, a, v) in zip(space.bodies, rows_list):
                b.position = p
                b.angle = a
                b.velocity = v
        return f

    wbuf = pymunk.batch.Buffer()

    def p_write_batch():
        wbuf.set_float_buf(values)
        pymunk.batch.set_space_bodies(spaces["pymunk"], flags, wbuf)

    def t_write_batch():
        tamias2d.batch.set_bodies(spaces["tamias2d"], values, FIELDS)

    progress.start(f"operations: write {n} bodies one by one")
    t, k = _time_ops({e: write_one_by_one(spaces[e]) for e in ENGINES}, repeat, budget)
    same = same_state(spaces["pymunk"], spaces["tamias2d"])
    rows.append(_row("write position, angle, velocity: one by one", n, t, k,
                     "b.position = p; b.angle = a; b.velocity = v", same_result=same))
    progress.advance()
    progress.start(f"operations: write {n} bodies, batch")
    t, k = _time_ops({"pymunk": p_write_batch, "tamias2d": t_write_batch}, repeat, budget)
    same = same_state(spaces["pymunk"], spaces["tamias2d"])
    rows.append(_row("write position, angle, velocity: batch", n, t, k,
                     "tamias2d.batch.set_bodies / pymunk.batch.set_space_bodies", same_result=same))
    progress.advance()
    del spaces

    # -- a Python velocity_func on every body ---------------------------------------------
    nv = 100 if quick else 1000
    progress.start(f"operations: step with a Python velocity_func on {nv} bodies")
    plain, custom = {}, {}
    for e in ENGINES:
        mod = mods[e]
        plain[e] = more_scenes.sparse_field(mod, count=nv)
        custom[e] = more_scenes.sparse_field(mod, count=nv)
        update = mod.Body.update_velocity

        def vf(body, gravity, damping, dt, update=update):
            update(body, (0.0, -100.0), damping, dt)
        for b in custom[e].bodies:
            b.velocity_func = vf
    funcs = {}
    for e in ENGINES:
        funcs[e] = lambda s=plain[e]: s.step(1 / 60)
        funcs[e + "+vf"] = lambda s=custom[e]: s.step(1 / 60)
    t, k = _time_ops(funcs, 2 * repeat + 1, 5 * budget)
    rows.append(_row("step, sparse field (no callbacks)", nv, t, k,
                     "the scene of the next row without the Python function"))
    rows.append(_row("step with a Python velocity_func on every body", nv,
                     {**{e: t[e + "+vf"] for e in ENGINES}, "_raw": t["_raw"]}, k,
                     "sparse field (no contacts); the function calls Body.update_velocity",
                     pymunk_us_per_callback=_added_cost(t, "pymunk", "+vf", nv),
                     tamias2d_us_per_callback=_added_cost(t, "tamias2d", "+vf", nv),
                     same_result=same_state(custom["pymunk"], custom["tamias2d"])))
    progress.advance()
    del plain, custom

    # -- a Python post_solve callback on every contact ------------------------------------
    nc = 100 if quick else 1000
    progress.start(f"operations: step with a post_solve callback, {nc}-box wall")
    plain = {e: more_scenes.box_wall(mods[e], count=nc) for e in ENGINES}
    counters = {e: [0, 0] for e in ENGINES}
    with_cb = {e: more_scenes.with_post_solve(more_scenes.box_wall(mods[e], count=nc), counters[e])
               for e in ENGINES}
    for _ in range(5 if quick else 200):   # past the first settling of the wall
        for e in ENGINES:
            plain[e].step(1 / 60)
            with_cb[e].step(1 / 60)
    funcs = {}
    steps = [0]

    def counted(space):
        def f():
            steps[0] += 1
            space.step(1 / 60)
        return f
    for e in ENGINES:
        funcs[e] = lambda s=plain[e]: s.step(1 / 60)
        funcs[e + "+cb"] = counted(with_cb[e]) if e == "tamias2d" else (lambda s=with_cb[e]: s.step(1 / 60))
    before = counters["tamias2d"][0]
    t, k = _time_ops(funcs, 2 * repeat + 1, 5 * budget)
    calls = round((counters["tamias2d"][0] - before) / max(steps[0], 1))
    rows.append(_row("step, box wall (no callbacks)", nc, t, k,
                     f"{nc} boxes in 5 layers, {calls} contact pairs per step on average"))
    rows.append(_row("step with a Python post_solve on every contact", nc,
                     {**{e: t[e + "+cb"] for e in ENGINES}, "_raw": t["_raw"]}, k,
                     f"{calls} callbacks per step on average; each reads arbiter.total_impulse",
                     callbacks_per_step=calls,
                     pymunk_us_per_callback=_added_cost(t, "pymunk", "+cb", calls),
                     tamias2d_us_per_callback=_added_cost(t, "tamias2d", "+cb", calls),
                     same_result=(counters["pymunk"] == counters["tamias2d"]
                                  and same_state(with_cb["pymunk"], with_cb["tamias2d"]))))
    progress.advance()
    del plain, with_cb

    # -- copy and pickle ------------------------------------------------------------------
    nb = 100 if quick else 1000
    progress.start(f"operations: space.copy() and pickle, {nb} bodies")
    spaces = {}
    for e in ENGINES:
        s = scenes.rain(mods[e], count=nb)
        for _ in range(30):
            s.step(1 / 60)
        spaces[e] = s
    rows.append(_copy_row("space.copy()", nb, spaces, repeat, budget,
                          lambda s: s.copy()))
    rows.append(_copy_row("pickle.dumps + pickle.loads", nb, spaces, repeat, budget,
                          lambda s: pickle.loads(pickle.dumps(s, pickle.HIGHEST_PROTOCOL))))
    progress.advance()
    return rows


def _diverges(op, space, steps=10):
    """Copy `space` with `op`, step the copy and the original side by side;
    the first step after which they differ, 0 if the copy differs at once,
    None if they stay bitwise equal. (The original is stepped too.)"""
    copy = op(space)
    if not same_state(copy, space):
        return 0
    for i in range(steps):
        copy.step(1 / 60)
        space.step(1 / 60)
        if not same_state(copy, space):
            return i + 1
    return None


def _copy_row(name, n, spaces, repeat, budget, op):
    """Time `op` on both spaces; a tamias2d space that cannot do it yet gets a
    'not yet available' row (pymunk's time is still given)."""
    note = "rain of %d circles after 30 steps (contacts cached)" % n
    try:
        op(spaces["tamias2d"])
    except (AttributeError, NotImplementedError, TypeError, pickle.PicklingError) as exc:
        f = lambda: op(spaces["pymunk"])  # noqa: E731
        k = _calls_for(f, budget)
        times = []
        for _ in range(repeat):
            t0 = now()
            for _ in range(k):
                f()
            times.append((now() - t0) / k)
        return _row(name, n, {"pymunk": median(times), "tamias2d": None}, k,
                    f"{note}; tamias2d: {type(exc).__name__}: {exc}",
                    status="not yet available")
    # Does the copy go on exactly as the original does? (Both originals are
    # stepped 10 times by the check, so they stay in the same state.)
    diverge = {e: _diverges(op, spaces[e]) for e in ENGINES}
    if diverge["tamias2d"] == 0:
        return _row(name, n, {"pymunk": None, "tamias2d": None}, 0,
                    f"{note}; tamias2d's copy differs from the original", status="wrong result")
    t, k = _time_ops({e: (lambda s=spaces[e]: op(s)) for e in ENGINES}, repeat, budget)
    said = "; ".join(f"{e}'s copy " + ("steps exactly like the original (10 steps checked)"
                                       if diverge[e] is None else
                                       f"parts from the original after step {diverge[e]}")
                     for e in ENGINES)
    return _row(name, n, t, k, f"{note}; {said}",
                **{f"{e}_copy_diverges_at_step": diverge[e] for e in ENGINES})
