"""The benchmark runner: ``benchmarks/run.py --quick --json`` in a subprocess.

The runner is started from a temporary directory with the path of this
checkout's benchmarks folder (it must not depend on the working directory:
in CI tamias2d is installed and the source folder has no compiled modules).
Only the shape and sanity of the results are checked (every scene present,
positive times, finite ratios), never how fast anything is.
"""
import json
import math
import os
import subprocess
import sys

import pytest

pytest.importorskip("numpy")
pytest.importorskip("pymunk")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BENCH = os.path.join(ROOT, "benchmarks")
RUN = os.path.join(BENCH, "run.py")

SCENES = {"pyramid", "stack", "rain", "drum", "static field", "sparse field", "sleeping wall",
          "callback rain"}
ACCURACY = {
    "IM1 free flight": {"position"}, "IM2 spin": {"angle"}, "IM3 head-on": {"velocity"},
    "incline": {"acceleration", "distance"}, "stack": {"penetration", "drift"},
    "pyramid": {"penetration", "drift"}, "chaotic pile": {"divergence"},
}
OPERATIONS = {
    "read position, angle, velocity: one by one", "read position, angle, velocity: batch",
    "write position, angle, velocity: one by one", "write position, angle, velocity: batch",
    "step with a Python velocity_func on every body",
    "step with a Python post_solve on every contact", "space.copy()", "pickle.dumps + pickle.loads",
}


def _env():
    # The environment as it is: an installed tamias2d (CI) is found as such;
    # without one the runner falls back to the checkout holding run.py.
    return dict(os.environ)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bench")
    out = tmp / "results.json"
    res = subprocess.run([sys.executable, RUN, "--quick", "--json", str(out)],
                         cwd=tmp, env=_env(), capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, f"run.py failed:\n{res.stderr[-4000:]}"
    with open(out) as f:
        data = json.load(f)
    return data, res, tmp, out


def positive(x):
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def test_meta(quick_run):
    data, res, _, _ = quick_run
    meta = data["meta"]
    assert meta["quick"] is True
    assert meta["sections"] == ["scenes", "scaling", "accuracy", "operations"]
    for key in ("cpu", "logical_cpus", "python", "tamias2d", "pymunk", "numpy"):
        assert meta["machine"][key], key
    assert positive(meta["duration_s"])


def test_progress_on_stderr_tables_on_stdout(quick_run):
    _, res, _, _ = quick_run
    # not a terminal: progress comes as plain lines "[done/total  seconds] what"
    assert "[0/" in res.stderr and "scenes: pyramid" in res.stderr
    assert "\r" not in res.stderr
    for heading in ("### Machine", "### Scenes", "### Scaling", "### Speed against error",
                    "### Operations"):
        assert heading in res.stdout


def test_scenes(quick_run):
    rows = quick_run[0]["scenes"]
    assert {r["scene"] for r in rows} == SCENES
    for r in rows:
        where = f"{r['scene']} {r['size']}"
        assert positive(r["pymunk_ms"]) and positive(r["tamias2d_ms"]), where
        assert positive(r["ratio"]), where
        assert math.isclose(r["ratio"], r["tamias2d_ms"] / r["pymunk_ms"]), where
        assert r["bodies"] > 0 and r["steps"] > 0 and r["repeat"] == 1, where
        assert len(r["pymunk_times_ms"]) == len(r["tamias2d_times_ms"]) == r["repeat"]
        # the two engines must have run the same motion, or the timing compares different work
        assert r["same_motion"] is True, f"{where}: tamias2d and pymunk diverged"
    cb = [r for r in rows if r["scene"] == "callback rain"]
    assert all(r["same_callbacks"] for r in cb)


def test_scaling(quick_run):
    rows = quick_run[0]["scaling"]
    assert {r["scene"] for r in rows} == {"box wall", "sparse field"}
    for scene in ("box wall", "sparse field"):
        sizes = [r["bodies"] for r in rows if r["scene"] == scene]
        assert sizes == sorted(sizes) and len(sizes) >= 2
    for r in rows:
        assert positive(r["pymunk_ms"]) and positive(r["tamias2d_ms"]) and positive(r["ratio"])
        assert positive(r["tamias2d_us_per_body"]) and positive(r["pymunk_us_per_body"])


def test_accuracy(quick_run):
    acc = quick_run[0]["accuracy"]
    rows = acc["rows"]
    dts, its = acc["meta"]["dts"], acc["meta"]["iterations"]
    assert positive(acc["meta"]["chaos_reference_dt"]) and acc["meta"]["chaos_reference_dt"] < min(dts)
    seen = {}
    for r in rows:
        seen.setdefault(r["case"], set()).add(r["metric"])
        assert positive(r["cost"]) and positive(r["wall_s"]) and positive(r["sim_seconds"])
        assert isinstance(r["error"], float) and math.isfinite(r["error"]) and r["error"] >= 0
        assert r["engine"] in ("pymunk", "tamias2d")
    assert seen == ACCURACY
    # every case, metric, engine and setting once
    keys = {(r["case"], r["metric"], r["engine"], r["dt"], r["iterations"]) for r in rows}
    assert len(keys) == len(rows) == sum(len(m) for m in ACCURACY.values()) * 2 * len(dts) * len(its)
    assert set(acc["front"]) == {f"{c} / {m}" for c, ms in ACCURACY.items() for m in ms}
    for key, front in acc["front"].items():
        assert front, key
        costs = [f["cost"] for f in front]
        errors = [f["error"] for f in front]
        assert costs == sorted(costs), key
        # along the front, paying more buys a smaller error
        assert all(b < a for a, b in zip(errors, errors[1:])), key


def test_accuracy_errors_are_physical(quick_run):
    """Known answers: errors shrink with the time step where the method is
    first order, and the head-on collision converges with iterations."""
    rows = quick_run[0]["accuracy"]["rows"]
    dts = sorted({r["dt"] for r in rows}, reverse=True)

    def err(case, metric, dt, it, engine="tamias2d"):
        return next(r["error"] for r in rows if (r["case"], r["metric"], r["dt"], r["iterations"],
                                                  r["engine"]) == (case, metric, dt, it, engine))
    its = sorted({r["iterations"] for r in rows})
    for case, metric in (("IM1 free flight", "position"), ("IM2 spin", "angle"),
                         ("incline", "distance")):
        assert err(case, metric, dts[-1], its[0]) < err(case, metric, dts[0], its[0]), case
    assert err("IM3 head-on", "velocity", dts[0], its[-1]) < err("IM3 head-on", "velocity", dts[0], its[0])
    # bitwise port: the same errors in both engines
    assert all(r["same_error_both_engines"] for r in rows)


def test_operations(quick_run):
    rows = quick_run[0]["operations"]
    names = {r["operation"] for r in rows}
    assert OPERATIONS <= names
    for r in rows:
        assert r["status"] in ("ok", "not yet available"), r
        assert positive(r["pymunk_ms"]), r["operation"]
        if r["status"] == "ok":
            assert positive(r["tamias2d_ms"]) and positive(r["ratio"]), r["operation"]
            if "same_result" in r:
                assert r["same_result"] is True, r["operation"]
        else:
            # an operation tamias2d cannot do yet is reported as such, never timed
            assert r["tamias2d_ms"] is None and r["ratio"] is None
            assert "tamias2d:" in r["note"]


def test_report_and_plots_from_json(quick_run):
    _, _, tmp, out = quick_run
    res = subprocess.run([sys.executable, os.path.join(BENCH, "report.py"), str(out)],
                         cwd=tmp, env=_env(), capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert "### Scenes" in res.stdout and "| pyramid |" in res.stdout
    pytest.importorskip("matplotlib")
    res = subprocess.run([sys.executable, os.path.join(BENCH, "report.py"), str(out),
                          "--plots", str(tmp / "plots")],
                         cwd=tmp, env=_env(), capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    for name in ("scene-ratios.png", "scaling.png", "speed-vs-error.png"):
        with open(tmp / "plots" / name, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", name


def test_bad_arguments(tmp_path):
    res = subprocess.run([sys.executable, RUN, "--only", "scenes,nonsense"], cwd=tmp_path,
                         env=_env(), capture_output=True, text=True, timeout=300)
    assert res.returncode == 2 and "nonsense" in res.stderr
    res = subprocess.run([sys.executable, RUN, "--repeat", "0"], cwd=tmp_path,
                         env=_env(), capture_output=True, text=True, timeout=300)
    assert res.returncode == 2


def test_only_one_section(tmp_path):
    out = tmp_path / "r.json"
    res = subprocess.run([sys.executable, RUN, "--quick", "--only", "scaling", "--no-progress",
                          "--json", str(out)], cwd=tmp_path, env=_env(), capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "[0/" not in res.stderr
    data = json.loads(out.read_text())
    assert "scaling" in data and "scenes" not in data and "operations" not in data
