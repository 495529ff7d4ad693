"""Step time of whole scenes in both engines (the scene table), and step time
against body count (scaling).

Each scene is built in both engines, warmed up, then timed in blocks of
steps, the engines taking turns (which one goes first alternates), and the
median time per step of each is kept. The engines run the same simulation
(tamias2d is a bitwise port), which the runner checks after timing
(``same_motion``), so each pair of timings covers the same motion.
"""
import math

import more_scenes
from harness import ENGINES, alternate, median, ratio, same_state, step_block


def scene_specs(scenes, quick):
    """(name, size, size unit, build(mod) -> Space, dt) of the scene table."""
    dt = 1.0 / 60.0
    if quick:
        sizes = {"pyramid": [4], "stack": [4], "rain": [40], "drum": [30],
                 "static field": [100], "sparse field": [50], "sleeping wall": [50],
                 "callback rain": [40]}
    else:
        sizes = {"pyramid": [10, 20, 40], "stack": [10, 20, 40], "rain": [250, 1000, 2000],
                 "drum": [250, 1000], "static field": [1000, 5000],
                 "sparse field": [1000, 5000], "sleeping wall": [1000, 10000],
                 "callback rain": [250, 1000]}

    def drum(n):
        # a drum just big enough for n boxes of 10 (14 per 100 px of radius squared)
        radius = max(120.0, 30.0 + 12.6 * math.sqrt(n))
        return lambda mod: scenes.drum(mod, count=n, box=10.0, radius=radius, wall=10.0)

    specs = []
    for n in sizes["pyramid"]:
        specs.append(("pyramid", n, "rows", lambda mod, n=n: scenes.pyramid(mod, rows=n), dt))
    for n in sizes["stack"]:
        specs.append(("stack", n, "boxes", lambda mod, n=n: scenes.vertical_stack(mod, count=n), dt))
    for n in sizes["rain"]:
        specs.append(("rain", n, "circles", lambda mod, n=n: scenes.rain(mod, count=n), dt))
    for n in sizes["drum"]:
        specs.append(("drum", n, "boxes", drum(n), dt))
    for n in sizes["static field"]:
        balls = 5 if quick else 30
        specs.append(("static field", n, "static pegs",
                      lambda mod, n=n, b=balls: more_scenes.static_field(mod, pegs=n, balls=b), dt))
    for n in sizes["sparse field"]:
        specs.append(("sparse field", n, "circles",
                      lambda mod, n=n: more_scenes.sparse_field(mod, count=n), dt))
    for n in sizes["sleeping wall"]:
        specs.append(("sleeping wall", n, "boxes",
                      lambda mod, n=n: more_scenes.sleeping_wall(mod, count=n), dt))
    for n in sizes["callback rain"]:
        specs.append(("callback rain", n, "circles",
                      lambda mod, n=n: more_scenes.callback_rain(mod, count=n, scenes=scenes), dt))
    return specs


SCENE_NOTES = {
    "pyramid": "box2d-style pyramid of 20x20 boxes, friction 1 (tests/scenes.py)",
    "stack": "one column of boxes on the ground (tests/scenes.py)",
    "rain": "circles of 5 radii falling into an open box (tests/scenes.py)",
    "drum": "boxes tumbling in a turning kinematic octagonal drum (tests/scenes.py)",
    "static field": "Galton board: static circle pegs, 30 balls falling through",
    "sparse field": "circles far apart drifting together without gravity: no contacts",
    "sleeping wall": "the box wall with sleeping on, timed once every box sleeps",
    "callback rain": "rain with a Python post_solve callback on every contact",
}

# Warm-up steps of scenes that need more than the default 60 (the sleeping
# wall: until every box has fallen asleep).
WARMUP = {"sleeping wall": 240}


def time_pair(mods, build, dt, warmup, repeat, block_s, min_steps, max_steps):
    """Build a scene in both engines and time it; a result dict."""
    spaces = {e: build(mods[e]) for e in ENGINES}
    for space in spaces.values():
        for _ in range(warmup):
            space.step(dt)
    # one probe step each (the same step in both, so the motions stay equal)
    probe = max(step_block(spaces[e], dt, 1) for e in ENGINES)
    steps = int(min(max_steps, max(min_steps, math.ceil(block_s / max(probe, 1e-9)))))
    funcs = {e: (lambda e=e: step_block(spaces[e], dt, steps)) for e in ENGINES}
    times = alternate(funcs, repeat)
    tspace = spaces["tamias2d"]
    contacts = len(mods["tamias2d"].batch.get_arbiters(tspace, ["count"]))
    row = {
        "bodies": len(tspace.bodies),
        "shapes": len(tspace.shapes),
        "contacts": contacts,
        "dt": dt,
        "warmup": warmup,
        "steps": steps,
        "repeat": repeat,
        "same_motion": same_state(spaces["pymunk"], tspace),
    }
    for e in ENGINES:
        row[f"{e}_ms"] = median(times[e]) * 1e3
        row[f"{e}_times_ms"] = [t * 1e3 for t in times[e]]
    row["ratio"] = ratio(row["tamias2d_ms"], row["pymunk_ms"])
    counter = getattr(tspace, "bench_counter", None)
    if counter is not None:
        pc = spaces["pymunk"].bench_counter
        total_steps = warmup + 1 + steps * repeat
        row["callbacks_per_step"] = counter[0] / total_steps
        row["same_callbacks"] = counter == pc
    return row


def run_scenes(mods, scenes, quick, progress, repeat=None):
    specs = scene_specs(scenes, quick)
    rows = []
    for name, size, unit, build, dt in specs:
        progress.start(f"scenes: {name} {size} {unit}")
        row = time_pair(mods, build, dt,
                        warmup=3 if quick else WARMUP.get(name, 60),
                        repeat=repeat or (1 if quick else 7),
                        block_s=0.0 if quick else 0.05,
                        min_steps=2 if quick else 5,
                        max_steps=3 if quick else 1000)
        row = {"scene": name, "size": size, "unit": unit, **row}
        rows.append(row)
        progress.advance()
        progress.note(f"  {name:<14} {size:>6} {unit:<12} pymunk {row['pymunk_ms']:8.3f} ms  "
                      f"tamias2d {row['tamias2d_ms']:8.3f} ms  ratio {row['ratio']:.3f}")
    return rows


# -- scaling ---------------------------------------------------------------------------

SCALING_SCENES = {
    "box wall": ("columns of 5 boxes side by side on the ground: one contact per box",
                 lambda mod, n: more_scenes.box_wall(mod, count=n)),
    "sparse field": ("circles far apart drifting together, no gravity, no contacts",
                     lambda mod, n: more_scenes.sparse_field(mod, count=n)),
}


def scaling_sizes(quick):
    return [100, 300] if quick else [100, 300, 1000, 3000, 10000, 30000]


def scaling_count(quick):
    return len(scaling_sizes(quick)) * 2


def run_scaling(mods, scenes, quick, progress, repeat=None):
    rows = []
    for name in ("box wall", "sparse field"):
        note, build = SCALING_SCENES[name]
        for n in scaling_sizes(quick):
            progress.start(f"scaling: {name} {n} bodies")
            row = time_pair(mods, lambda mod, n=n, b=build: b(mod, n), 1.0 / 60.0,
                            warmup=2 if quick else 10,
                            repeat=repeat or (1 if quick else (7 if n <= 3000 else 3)),
                            block_s=0.0 if quick else 0.1,
                            min_steps=2 if quick else 3,
                            max_steps=3 if quick else 50)
            row = {"scene": name, "size": n, **row}
            row["pymunk_us_per_body"] = row["pymunk_ms"] * 1e3 / n
            row["tamias2d_us_per_body"] = row["tamias2d_ms"] * 1e3 / n
            rows.append(row)
            progress.advance()
            progress.note(f"  {name:<14} {n:>6} bodies  pymunk {row['pymunk_ms']:9.3f} ms  "
                          f"tamias2d {row['tamias2d_ms']:9.3f} ms  ratio {row['ratio']:.3f}")
    return rows
