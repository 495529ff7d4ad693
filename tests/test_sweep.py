"""tamias2d.sweep: a function of a scene over a parameter grid, on a process
pool, serially, on Dask or on Ray, with the same results in grid order.

The scene is a box on an incline; the sweep varies friction, mass and the
step. Every backend must return what the serial run returns, bit for bit
(body positions after the steps), since each point unpickles the same scene
and runs the same code.
"""
import math
import pickle

import pytest

import tamias2d
from tamias2d.sweeps import grid_points


def incline():
    """A box resting at the top of a 20 degree slope."""
    space = tamias2d.Space()
    space.gravity = 0, -9.81
    a = math.radians(20)
    d = (math.cos(a), -math.sin(a))
    slope = tamias2d.Segment(space.static_body, (0, 0), (20 * d[0], 20 * d[1]), 0.05)
    slope.friction = 1.0
    box = tamias2d.Body(1, tamias2d.moment_for_box(1, (1, 0.5)))
    box.position = 1.0 * d[0] - 0.3 * d[1], 1.0 * d[1] + 0.3 * d[0]
    box.angle = -a
    shape = tamias2d.Poly.create_box(box, (1, 0.5))
    space.add(slope, box, shape)
    for _ in range(30):
        space.step(1 / 120)       # settled on the slope (with contacts cached)
    return space


def slide(space, friction, mass=1.0, dt=1 / 120, steps=240):
    box = next(b for b in space.bodies if b.body_type == tamias2d.Body.DYNAMIC)
    box.mass = mass
    for shape in box.shapes:
        shape.friction = friction
    for _ in range(steps):
        space.step(dt)
    return (tuple(box.position), box.angle, tuple(box.velocity))


def no_scene(x, y):
    return x * 10 + y


def fails_at_three(space, friction):
    if friction == 3:
        raise ArithmeticError(f"friction {friction}")
    return friction


GRID = {"friction": [0.0, 0.2, 0.35, 0.6], "mass": [0.5, 2.0]}


def test_grid_points_order_and_forms():
    assert grid_points({"a": [1, 2], "b": ["x", "y"]}) == [
        {"a": 1, "b": "x"}, {"a": 1, "b": "y"}, {"a": 2, "b": "x"}, {"a": 2, "b": "y"}]
    assert grid_points({}) == [{}]
    assert grid_points([{"a": 1}, {"b": 2}]) == [{"a": 1}, {"b": 2}]
    assert grid_points([]) == []
    assert grid_points({"a": range(3)}) == [{"a": 0}, {"a": 1}, {"a": 2}]


def test_serial_equals_stepping_by_hand_and_friction_matters():
    scene = incline()
    got = tamias2d.sweep(slide, GRID, scene=scene, backend="serial")
    by_hand = [slide(incline(), **p) for p in grid_points(GRID)]
    assert got == by_hand
    # Without friction it slides down; with 0.6 (> tan 20 degrees) it stops.
    assert got[0][0][0] > got[-1][0][0] + 5 and abs(got[-1][2][0]) < 1e-6
    # The scene passed in is not touched (each point steps its own copy).
    assert scene.current_time_step == 1 / 120
    assert pickle.dumps(scene) == pickle.dumps(incline())


def test_process_pool_equals_serial_bit_for_bit():
    serial = tamias2d.sweep(slide, GRID, scene=incline(), backend="serial")
    pooled = tamias2d.sweep(slide, GRID, scene=incline(), workers=2)
    assert pooled == serial
    points = [{"friction": 0.1, "dt": 1 / 60, "steps": 120}, {"friction": 0.1}]
    assert (tamias2d.sweep(slide, points, scene=incline(), workers=2, chunksize=1)
            == tamias2d.sweep(slide, points, scene=incline(), backend="serial"))
    assert tamias2d.sweep(no_scene, {"x": [1, 2], "y": [3, 4]}, workers=2) == [13, 14, 23, 24]


def test_an_error_names_its_grid_point():
    for backend in ("serial", "process"):
        with pytest.raises(ArithmeticError, match="friction 3") as info:
            tamias2d.sweep(fails_at_three, {"friction": [1, 2, 3, 4]}, scene=incline(),
                           backend=backend, workers=2 if backend == "process" else None)
        if hasattr(info.value, "__notes__"):
            assert any("grid point 2" in n and "'friction': 3" in n
                       for n in info.value.__notes__)


def test_bad_input_is_refused_clearly():
    with pytest.raises(ValueError, match="unknown backend 'threads'.*'process'"):
        tamias2d.sweep(no_scene, {"x": [1]}, backend="threads")
    with pytest.raises(TypeError, match="callable"):
        tamias2d.sweep(42, {"x": [1]})
    with pytest.raises(TypeError, match=r"grid\['x'\] must be a sequence"):
        tamias2d.sweep(no_scene, {"x": 1})
    with pytest.raises(TypeError, match=r"grid\['x'\] must be a sequence"):
        tamias2d.sweep(no_scene, {"x": "abc"})
    with pytest.raises(ValueError, match="no values"):
        tamias2d.sweep(no_scene, {"x": []})
    with pytest.raises(TypeError, match=r"grid\[1\] must be a dict"):
        tamias2d.sweep(no_scene, [{"x": 1}, 5])
    with pytest.raises(TypeError, match="grid must be"):
        tamias2d.sweep(no_scene, 17)
    with pytest.raises(ValueError, match="workers"):
        tamias2d.sweep(no_scene, {"x": [1]}, workers=0)
    with pytest.raises(ValueError, match="client"):
        tamias2d.sweep(no_scene, {"x": [1]}, client=object())
    with pytest.raises(ValueError, match="chunksize"):
        tamias2d.sweep(no_scene, {"x": [1]}, backend="serial", chunksize=2)
    with pytest.raises(TypeError, match="does not pickle"):
        tamias2d.sweep(lambda x: x, {"x": [1]}, backend="process")
    with pytest.raises(TypeError, match="scene must pickle"):
        tamias2d.sweep(no_scene, {"x": [1]}, scene=lambda: 0, backend="serial")


def test_a_missing_backend_names_the_extra(monkeypatch):
    import builtins
    real_import = builtins.__import__

    def no_dask_or_ray(name, *args, **kwargs):
        if name.split(".")[0] in ("dask", "distributed", "ray"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask_or_ray)
    with pytest.raises(ImportError, match=r"tamias2d\[dask\]"):
        tamias2d.sweep(no_scene, {"x": [1]}, backend="dask")
    with pytest.raises(ImportError, match=r"tamias2d\[ray\]"):
        tamias2d.sweep(no_scene, {"x": [1]}, backend="ray")


def test_dask_local_cluster_equals_serial():
    distributed = pytest.importorskip("dask.distributed")
    serial = tamias2d.sweep(slide, GRID, scene=incline(), backend="serial")
    # Worker threads in this process (a cluster of processes takes seconds
    # more to start): the scene still travels pickled, as sweep pickles it.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        got = tamias2d.sweep(slide, GRID, scene=incline(), backend="dask", client=client)
        assert got == serial
        # Dask pickles lambdas (cloudpickle), and errors name their point.
        assert tamias2d.sweep(lambda x: x + 1, {"x": [1, 2]}, backend="dask",
                              client=client) == [2, 3]
        with pytest.raises(ArithmeticError, match="friction 3"):
            tamias2d.sweep(fails_at_three, {"friction": [1, 2, 3, 4]}, scene=incline(),
                           backend="dask", client=client)


def test_ray_equals_serial():
    ray = pytest.importorskip("ray")
    serial = tamias2d.sweep(slide, GRID, scene=incline(), backend="serial")
    got = tamias2d.sweep(slide, GRID, scene=incline(), backend="ray", workers=2)
    assert got == serial
    assert not ray.is_initialized()     # the sweep's own local Ray was shut down
