"""benchmarks/against_box2d.py --quick --json in a subprocess.

Started from a temporary directory with the environment as it is (as
tests/test_benchmarks.py starts run.py). Only the shape and sanity of the
results are checked (every scene, positive finite times and ratios, a
stands verdict per engine), never how fast anything is.
"""
import json
import math
import os
import subprocess
import sys

import pytest

pytest.importorskip("pyb2d3")
pytest.importorskip("pymunk")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "benchmarks", "against_box2d.py")
SCENES = {"large_pyramid", "many_pyramids", "tumbler", "pyramid_20", "rain_1000"}
PYRAMIDS = {"large_pyramid", "many_pyramids", "pyramid_20"}


def positive(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > 0


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("against_box2d")
    res = subprocess.run([sys.executable, SCRIPT, "--quick", "--json"], cwd=tmp,
                         env=dict(os.environ), capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, f"against_box2d.py failed:\n{res.stderr[-4000:]}"
    return json.loads(res.stdout)


def test_meta(quick):
    assert quick["meta"]["quick"] is True
    assert positive(quick["meta"]["duration_s"])


def test_every_scene_timed(quick):
    rows = quick["scenes"]
    assert {r["scene"] for r in rows} == SCENES and len(rows) == len(SCENES)
    for r in rows:
        name = r["scene"]
        assert r["bodies"] > 0 and r["steps"] > 0, name
        for key in ("box2d_ms", "tamias2d_ms", "pymunk_ms", "tamias2d_vs_box2d", "pymunk_vs_box2d",
                    "tamias2d_2thread_speedup", "box2d_2thread_speedup"):
            assert positive(r[key]), (name, key)
        assert math.isclose(r["tamias2d_vs_box2d"], r["tamias2d_ms"] / r["box2d_ms"]), name
        assert math.isclose(r["pymunk_vs_box2d"], r["pymunk_ms"] / r["box2d_ms"]), name


def test_stands_verdicts(quick):
    for r in quick["scenes"]:
        assert set(r["stands"]) == {"box2d", "tamias2d", "pymunk"}, r["scene"]
        for engine, verdict in r["stands"].items():
            if r["scene"] in PYRAMIDS:
                assert isinstance(verdict, bool), (r["scene"], engine)
            else:
                assert verdict in ("ok", "FAIL", "n/a"), (r["scene"], engine)


def test_bad_scene_name(tmp_path):
    res = subprocess.run([sys.executable, SCRIPT, "--scenes", "large_pyramid,nonsense"],
                         cwd=tmp_path, env=dict(os.environ), capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2 and "nonsense" in res.stderr
