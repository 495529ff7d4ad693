"""Narrow-phase throughput: tamias2d against pymunk in the same process.

Times ``shape_a.shapes_collide(shape_b)`` over a fixed set of shape pairs
(every kind pair; touching, overlapping and separated) in both engines, and
tamias2d's C-level loop over the same pairs (cpCollide without the GIL, no
Python objects), then prints calls per second and the ratios.

pymunk's shapes_collide raises AssertionError for a pair that does not touch,
so the Python-level comparison uses touching pairs only; the C-level loop
also runs over the separated ones.

    python benchmarks/bench_collision.py [--pairs N] [--repeat R]
"""
import argparse
import math
import random
import time

import pymunk
import tamias2d
from tamias2d import _testing, collision


def make_pairs(mod, n, seed=1):
    """n pairs of shapes with cached world data; the same pairs for any engine."""
    rng = random.Random(seed)
    pairs = []
    kinds = ("circle", "segment", "box", "poly")
    for i in range(n):
        specs = []
        for _ in range(2):
            kind = kinds[rng.randrange(4)]
            body = mod.Body(1, 1)
            body.angle = rng.uniform(-math.pi, math.pi)
            body.position = (rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5))
            if kind == "circle":
                shape = mod.Circle(body, rng.uniform(0.3, 1.0))
            elif kind == "segment":
                shape = mod.Segment(body, (-1, 0), (1, 0), rng.uniform(0.0, 0.2))
            elif kind == "box":
                shape = mod.Poly.create_box(body, (rng.uniform(0.5, 2), rng.uniform(0.5, 2)),
                                            rng.choice((0.0, 0.1)))
            else:
                k = rng.randint(3, 8)
                shape = mod.Poly(body, [(math.cos(2 * math.pi * j / k), math.sin(2 * math.pi * j / k))
                                        for j in range(k)])
            shape.cache_bb()
            specs.append(shape)
        pairs.append(tuple(specs))
    return pairs


def touching(pairs):
    return [i for i, (a, b) in enumerate(pairs) if len(collision.shapes_collide(a, b).points) > 0]


def time_python(pairs, repeat):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for a, b in pairs:
            a.shapes_collide(b)
        best = min(best, time.perf_counter() - t0)
    return len(pairs) / best


def time_c_loop(pairs, rounds, repeat):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        _testing._collide_loop(pairs, rounds)
        best = min(best, time.perf_counter() - t0)
    return len(pairs) * rounds / best


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    t_pairs = make_pairs(tamias2d, args.pairs)
    p_pairs = make_pairs(pymunk, args.pairs)
    hit = touching(t_pairs)
    t_hit = [t_pairs[i] for i in hit]
    p_hit = [p_pairs[i] for i in hit]
    print("pairs: %d, touching: %d" % (len(t_pairs), len(hit)))

    t_rate = time_python(t_hit, args.repeat)
    p_rate = time_python(p_hit, args.repeat)
    c_rate = time_c_loop(t_pairs, 50, args.repeat)
    c_rate_hit = time_c_loop(t_hit, 50, args.repeat)
    print("shapes_collide, touching pairs (calls/s):")
    print("  pymunk    %12.0f" % p_rate)
    print("  tamias2d  %12.0f   ratio tamias2d/pymunk = %.2f" % (t_rate, t_rate / p_rate))
    print("cpCollide C loop, tamias2d (calls/s):")
    print("  all pairs      %12.0f   ratio to pymunk shapes_collide = %.1f" % (c_rate, c_rate / p_rate))
    print("  touching pairs %12.0f   ratio to pymunk shapes_collide = %.1f" % (c_rate_hit, c_rate_hit / p_rate))


if __name__ == "__main__":
    main()
