"""Parameter sweeps: one function over a grid of parameters, on a local
process pool (the default), serially, on a Dask cluster or on Ray.

A space pickles and goes on bit for bit where it was, so a sweep is a map
of a function over pickled scenes: the scene is pickled once here, and every
grid point gets a fresh copy of it in whatever process runs that point. The
results come back in grid order and are the same, bit for bit, whichever
backend ran them (the same code on the same numbers; only where it runs
changes).

>>> import tamias2d
>>> def slide(space, friction):
...     box = next(b for b in space.bodies if b.body_type == tamias2d.Body.DYNAMIC)
...     for shape in box.shapes:
...         shape.friction = friction
...     for _ in range(60):
...         space.step(1 / 60)
...     return round(box.position.x, 3)
>>> space = tamias2d.Space()
>>> space.gravity = 3, -10          # pulled sideways along the floor
>>> floor = tamias2d.Segment(space.static_body, (-100, 0), (100, 0), 0)
>>> floor.friction = 1.0
>>> box = tamias2d.Body(1, 1)
>>> box.position = 0, 0.5
>>> space.add(floor, box, tamias2d.Poly.create_box(box, (1, 1)))
>>> tamias2d.sweep(slide, {"friction": [0.0, 0.1, 0.5]}, scene=space, backend="serial")
[1.475, 0.984, 0.0]
"""
import itertools
import os
import pickle
import sys
from collections.abc import Mapping

__all__ = ["sweep", "grid_points", "BACKENDS"]

BACKENDS = ("process", "serial", "dask", "ray")
"""The places a sweep can run, as ``backend=`` names them."""

_EXTRAS = {"dask": ("dask.distributed", "tamias2d[dask]", "dask[distributed]"),
           "ray": ("ray", "tamias2d[ray]", "ray")}


def grid_points(grid):
    """The points of `grid` as a list of dicts, in the order a sweep runs
    them and returns their results.

    `grid` is a dict of sequences (every combination of the values: the
    cartesian product, the last key varying fastest; ``{}`` is one point with
    no parameters) or a sequence of dicts (those points, as they are).

    >>> grid_points({"mass": [1, 2], "friction": [0.1, 0.5]})
    [{'mass': 1, 'friction': 0.1}, {'mass': 1, 'friction': 0.5}, {'mass': 2, 'friction': 0.1}, {'mass': 2, 'friction': 0.5}]
    >>> grid_points([{"dt": 0.01}, {"dt": 0.02, "steps": 50}])
    [{'dt': 0.01}, {'dt': 0.02, 'steps': 50}]
    """
    if isinstance(grid, Mapping):
        keys = list(grid)
        columns = []
        for key in keys:
            if not isinstance(key, str):
                raise TypeError(f"grid keys are parameter names (str), not {key!r}")
            values = grid[key]
            if isinstance(values, (str, bytes, Mapping)) or not _iterable(values):
                raise TypeError(f"grid[{key!r}] must be a sequence of values, not {values!r}")
            values = list(values)
            if not values:
                raise ValueError(f"grid[{key!r}] has no values")
            columns.append(values)
        return [dict(zip(keys, combo)) for combo in itertools.product(*columns)]
    if isinstance(grid, (str, bytes)) or not _iterable(grid):
        raise TypeError(f"grid must be a dict of value lists or a list of dicts, not {grid!r}")
    points = []
    for i, point in enumerate(grid):
        if not isinstance(point, Mapping):
            raise TypeError(f"grid[{i}] must be a dict of parameters, not {point!r}")
        for key in point:
            if not isinstance(key, str):
                raise TypeError(f"grid[{i}] has a parameter name that is not a str: {key!r}")
        points.append(dict(point))
    return points


def _iterable(x):
    try:
        iter(x)
    except TypeError:
        return False
    return True


# -- what runs in the worker ------------------------------------------------------------

# The pickled scene of the process pool's current sweep, set by its initializer.
_worker_scene = None


def _set_worker_scene(data):
    global _worker_scene
    _worker_scene = data


def _run_point(params, fn, scene):
    # `scene`: the pickled scene, or None. Each point unpickles its own copy.
    if scene is None:
        return fn(**params)
    return fn(pickle.loads(scene), **params)


def _run_pool_point(fn, params):
    return _run_point(params, fn, _worker_scene)


def _name_point(exc, index, params):
    try:
        exc.add_note(f"(raised by tamias2d.sweep for grid point {index}: {params!r})")
    except AttributeError:   # Python < 3.11
        pass
    return exc


# -- the backends -------------------------------------------------------------------------

def _serial(fn, points, scene):
    out = []
    for i, params in enumerate(points):
        try:
            out.append(_run_point(params, fn, scene))
        except BaseException as exc:
            raise _name_point(exc, i, params)
    return out


def _process(fn, points, scene, workers, chunksize, mp_context):
    from concurrent.futures import ProcessPoolExecutor
    try:
        pickle.dumps(fn)
    except Exception as exc:
        raise TypeError(
            f"backend='process' sends fn to other processes with pickle, and {fn!r} does not "
            f"pickle ({exc}); use a function defined at the top level of a module, or "
            f"backend='serial' (dask and ray pickle lambdas and local functions too)") from None
    workers = workers or _cores()
    workers = max(1, min(workers, len(points)))
    if chunksize is None:
        chunksize = max(1, len(points) // (4 * workers))
    if isinstance(mp_context, str):
        import multiprocessing
        mp_context = multiprocessing.get_context(mp_context)
    out = []
    with ProcessPoolExecutor(max_workers=workers, mp_context=mp_context,
                             initializer=_set_worker_scene, initargs=(scene,)) as pool:
        results = pool.map(_run_pool_point, itertools.repeat(fn), points, chunksize=chunksize)
        try:
            for value in results:
                out.append(value)
        except BaseException as exc:
            # map yields in order: the failing point is the one after the last result.
            raise _name_point(exc, len(out), points[len(out)])
    return out


def _dask(fn, points, scene, workers, client):
    dd = _need("dask")
    own = client is None
    if own:
        client = dd.Client(n_workers=workers or _cores(), threads_per_worker=1,
                           processes=True, dashboard_address=None)
    try:
        shared = client.scatter(scene, broadcast=True) if scene is not None else None
        futures = client.map(_run_point, points, fn=fn, scene=shared, pure=False)
        dd.wait(futures)
        for i, future in enumerate(futures):
            if future.status == "error":
                raise _name_point(future.exception(), i, points[i])
        return client.gather(futures)
    finally:
        if own:
            client.close()


def _ray(fn, points, scene, workers):
    ray = _need("ray")
    own = not ray.is_initialized()
    if own:
        # Workers of a local Ray start afresh: give them this process's
        # import path, so that they find fn's module as it does.
        path = os.pathsep.join(p for p in sys.path if p)
        ray.init(num_cpus=workers or _cores(), include_dashboard=False,
                 log_to_driver=False, configure_logging=False,
                 runtime_env={"env_vars": {"PYTHONPATH": path}})
    try:
        task = ray.remote(num_cpus=1)(_run_point)
        shared = ray.put(scene) if scene is not None else None
        refs = [task.remote(params, fn=fn, scene=shared) for params in points]
        out = []
        for i, ref in enumerate(refs):
            try:
                out.append(ray.get(ref))
            except ray.exceptions.RayTaskError as err:
                cause = err.as_instanceof_cause()
                raise _name_point(cause, i, points[i]) from None
        return out
    finally:
        if own:
            ray.shutdown()


def _need(backend):
    module, extra, package = _EXTRAS[backend]
    try:
        return __import__(module, fromlist=["_"])
    except ImportError as exc:
        raise ImportError(
            f"backend={backend!r} needs {module}, which is not installed ({exc}): "
            f"pip install '{extra}' (or pip install '{package}')") from None


def _cores():
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def sweep(fn, grid, *, scene=None, backend="process", workers=None, client=None,
          chunksize=None, mp_context=None):
    """Call `fn` once for every point of `grid` and return the results, a
    list in grid order (see :func:`grid_points`), the same whichever
    `backend` runs them.

    :param fn: called as ``fn(**point)``, or ``fn(scene_copy, **point)``
        when `scene` is given; its result must pickle (except with
        ``"serial"``). With ``"process"`` `fn` itself must pickle: a function
        defined at the top level of a module.
    :param grid: a dict of value lists (their cartesian product) or a list
        of dicts.
    :param scene: any object that pickles, such as a :class:`Space` or a
        tuple of them: it is pickled once and every point gets a fresh copy,
        which goes on bit for bit as the original would.
    :param backend: ``"process"`` (a local pool of `workers` processes,
        :class:`concurrent.futures.ProcessPoolExecutor`), ``"serial"`` (this
        process, one point after the other), ``"dask"`` (the
        ``dask.distributed`` `client` given, or a local cluster of `workers`
        processes started and closed for the sweep) or ``"ray"`` (the Ray
        cluster this process is connected to with ``ray.init``, or a local
        one of `workers` CPUs started and shut down for the sweep).
    :param workers: processes (or CPUs) to start; default: the cores this
        process may run on.
    :param client: a ``dask.distributed.Client`` (``backend="dask"`` only).
    :param chunksize: points sent to a pool process at a time
        (``"process"`` only; default: about a quarter of the points a process
        gets).
    :param mp_context: a multiprocessing context or its name ("spawn",
        "fork", "forkserver") for the pool (``"process"`` only).

    An exception raised by `fn` is raised here (the first, in grid order),
    with a note naming its grid point.
    """
    if not callable(fn):
        raise TypeError(f"fn must be callable, not {fn!r}")
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; the backends are "
                         + ", ".join(repr(b) for b in BACKENDS))
    if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool)
                                or workers < 1):
        raise ValueError(f"workers must be an int >= 1 or None, not {workers!r}")
    if client is not None and backend != "dask":
        raise ValueError(f"client is a dask.distributed.Client, for backend='dask' "
                         f"(not {backend!r})")
    if chunksize is not None and backend != "process":
        raise ValueError(f"chunksize is for backend='process' (not {backend!r})")
    if chunksize is not None and (not isinstance(chunksize, int) or chunksize < 1):
        raise ValueError(f"chunksize must be an int >= 1 or None, not {chunksize!r}")
    if mp_context is not None and backend != "process":
        raise ValueError(f"mp_context is for backend='process' (not {backend!r})")
    points = grid_points(grid)
    data = None
    if scene is not None:
        try:
            data = pickle.dumps(scene, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:
            raise TypeError(f"scene must pickle: {exc}") from exc
    if backend in _EXTRAS:
        _need(backend)        # before anything starts
    if not points:
        return []
    if backend == "serial":
        return _serial(fn, points, data)
    if backend == "process":
        return _process(fn, points, data, workers, chunksize, mp_context)
    if backend == "dask":
        return _dask(fn, points, data, workers, client)
    return _ray(fn, points, data, workers)
