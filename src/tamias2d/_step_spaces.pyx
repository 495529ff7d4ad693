"""Many spaces stepped in one call, on a pool of native threads.

``step_spaces(spaces, dt, threads=None, steps=1)``: every step, the calling
thread prepares each space with the GIL (the checks of ``Space.step``), then
it and the pool's workers take spaces one at a time from a shared counter and
run their C steps without the GIL, then the calling thread finishes each
space with the GIL (errors, deferred adds and removes, post-step callbacks).
A space is stepped by one thread at a time and its step shares nothing with
the others, so each space ends bit for bit where stepping it alone ends,
whatever the number of threads.

The workers are daemon threads started on first use and kept for later
calls; between calls they sleep on a lock.
"""
import os

from cpython.pythread cimport (PyThread_type_lock, PyThread_allocate_lock,
    PyThread_acquire_lock, PyThread_release_lock, WAIT_LOCK)
from libc.math cimport isfinite
from libc.stdlib cimport malloc, free

from tamias2d._structs cimport cpSpace, cpBody
from tamias2d.space cimport Space, tamias_space_step

import threading

from tamias2d.errors import SpaceLocked

cdef extern from "pythread.h":
    # Safe without the GIL (Cython's declaration lacks nogil).
    unsigned long tamias_thread_ident "PyThread_get_thread_ident"() nogil

cdef extern from *:
    """
    #if defined(_MSC_VER)
    #include <intrin.h>
    static long tamias_take_next(volatile long *counter) {
        return _InterlockedExchangeAdd(counter, 1);
    }
    #else
    static long tamias_take_next(volatile long *counter) {
        return __atomic_fetch_add(counter, 1, __ATOMIC_RELAXED);
    }
    #endif
    """
    long tamias_take_next(volatile long *counter) nogil

cdef enum:
    MAX_WORKERS = 256

# One step of many spaces: what every thread works through.
cdef struct Job:
    cpSpace **spaces
    cpBody **bad          # per space: the first body its step made non-finite
    double dt
    long count
    long next             # the next space to take (atomic)

cdef Job _job
cdef int _started = 0                          # workers running
cdef PyThread_type_lock _go[MAX_WORKERS]       # released to start worker k
cdef PyThread_type_lock _done[MAX_WORKERS]     # released by worker k when it ends
cdef object _pool_lock = threading.Lock()      # one step_spaces call at a time
cdef long _pool_pid = -1                       # the process whose workers these are


cdef void _work(Job *job) noexcept nogil:
    cdef long i
    while True:
        i = tamias_take_next(&job.next)
        if i >= job.count:
            return
        # The space is this thread's now: its callbacks (which run here)
        # pass the thread guard, other threads still wait (stepThread stays
        # non-zero; a word written whole, read under the GIL by waiters).
        job.spaces[i].stepThread = tamias_thread_ident()
        job.bad[i] = tamias_space_step(job.spaces[i], job.dt)


def _worker_main(int k):
    with nogil:
        while True:
            PyThread_acquire_lock(_go[k], WAIT_LOCK)
            _work(&_job)
            PyThread_release_lock(_done[k])


cdef int _ensure_workers(int n) except -1:
    global _started, _pool_pid
    if _pool_pid != os.getpid():
        # A fork keeps the counters but not the threads: start afresh (the
        # parent's locks are left as they are).
        _started = 0
        _pool_pid = os.getpid()
    while _started < n:
        k = _started
        _go[k] = PyThread_allocate_lock()
        _done[k] = PyThread_allocate_lock()
        if _go[k] == NULL or _done[k] == NULL:
            raise MemoryError("cannot allocate the locks of a step_spaces worker")
        # Both start taken: the worker waits on _go, the caller on _done.
        PyThread_acquire_lock(_go[k], WAIT_LOCK)
        PyThread_acquire_lock(_done[k], WAIT_LOCK)
        threading.Thread(target=_worker_main, args=(k,), daemon=True,
                         name=f"tamias2d-step-{k}").start()
        _started += 1
    return 0


cdef int _run_job(int helpers) except -1:
    # The caller works too, so `helpers` workers make helpers + 1 threads.
    cdef int k
    with nogil:
        for k in range(helpers):
            PyThread_release_lock(_go[k])
        _work(&_job)
        for k in range(helpers):
            PyThread_acquire_lock(_done[k], WAIT_LOCK)
    return 0


def step_spaces(spaces, dt, *, threads=None, steps=1):
    """Step every space of `spaces` `steps` times by `dt`, spread over
    `threads` native threads (default: the machine's cores) without the GIL.

    Each space ends exactly (bit for bit) where ``space.step(dt)`` called
    `steps` times ends, for any number of threads. Spaces with Python
    callbacks work: a callback takes the GIL, so callbacks of different
    spaces run one at a time while the C steps go on in parallel (a scene
    that spends most of its step in Python gains little).

    Before anything steps, bad input raises: a non-Space, a space listed
    twice, a space that is locked or being stepped by another thread, a
    non-finite or negative `dt`, `steps` < 0, `threads` < 1. An exception
    raised while stepping (in a callback, or an overflow) is raised after
    every space finished that step and was left consistent; it carries the
    failing space and its position in ``exc.space`` and ``exc.space_index``
    (and a note saying which). Later steps are not run then.

    >>> import tamias2d
    >>> spaces = [tamias2d.Space() for _ in range(4)]
    >>> for i, s in enumerate(spaces):
    ...     s.gravity = 0, -10 * (i + 1)
    ...     b = tamias2d.Body(1, 1)
    ...     s.add(b, tamias2d.Circle(b, 1))
    >>> tamias2d.step_spaces(spaces, 0.1, threads=2, steps=3)
    >>> [round(next(iter(s.bodies)).position.y, 6) for s in spaces]
    [-0.3, -0.6, -0.9, -1.2]
    """
    cdef double cdt = dt
    cdef long nsteps = steps
    cdef Py_ssize_t n, i
    cdef long step
    cdef int nthreads, helpers
    cdef Space sp
    if not (isfinite(cdt) and cdt >= 0.0):
        raise ValueError(f"dt must be a finite number >= 0, not {dt!r}")
    if nsteps < 0:
        raise ValueError(f"steps must be >= 0, not {steps!r}")
    spaces = list(spaces)
    seen = set()
    for i, s in enumerate(spaces):
        if not isinstance(s, Space):
            raise TypeError(f"spaces[{i}] is a {type(s).__name__}, not a tamias2d.Space")
        if id(s) in seen:
            raise ValueError(f"spaces[{i}] is listed twice; each space may be stepped once per step")
        seen.add(id(s))
        sp = <Space>s
        if sp._space.stepThread != 0 or sp._locked:
            raise SpaceLocked(f"spaces[{i}] is being stepped (by another thread or from a callback)")
    n = len(spaces)
    if threads is None:
        nthreads = os.cpu_count() or 1
    else:
        nthreads = threads
        if nthreads < 1:
            raise ValueError(f"threads must be >= 1, not {threads!r}")
    if nthreads > MAX_WORKERS:
        nthreads = MAX_WORKERS
    if nthreads > n:
        nthreads = <int>n
    helpers = nthreads - 1 if nthreads > 0 else 0
    if n == 0 or nsteps == 0:
        return None

    cdef cpSpace **cspaces = <cpSpace **>malloc(n * sizeof(cpSpace *))
    cdef cpBody **bad = <cpBody **>malloc(n * sizeof(cpBody *))
    if cspaces == NULL or bad == NULL:
        free(cspaces)
        free(bad)
        raise MemoryError("not enough memory for step_spaces")
    try:
        for i in range(n):
            cspaces[i] = &(<Space>spaces[i])._space
        with _pool_lock:
            _ensure_workers(helpers)
            for step in range(nsteps):
                _step_all(spaces, cspaces, bad, n, cdt, helpers)
    finally:
        free(cspaces)
        free(bad)
    return None


cdef int _step_all(list spaces, cpSpace **cspaces, cpBody **bad, Py_ssize_t n, double dt,
                   int helpers) except -1:
    cdef Py_ssize_t i, j
    cdef Space sp
    # Prepare every space first; if one refuses, undo the others.
    for i in range(n):
        try:
            (<Space>spaces[i])._step_begin()
        except BaseException as exc:
            for j in range(i):
                (<Space>spaces[j])._step_abort()
            _name_space(exc, spaces[i], i)
            raise
        bad[i] = NULL
    _job.spaces = cspaces
    _job.bad = bad
    _job.dt = dt
    _job.count = n
    _job.next = 0
    _run_job(helpers)
    first = None
    for i in range(n):
        try:
            (<Space>spaces[i])._step_finish(bad[i], dt)
        except BaseException as exc:
            if first is None:
                first = _name_space(exc, spaces[i], i)
    if first is not None:
        raise first
    return 0


cdef object _name_space(exc, space, Py_ssize_t index):
    try:
        exc.space = space
        exc.space_index = index
        if hasattr(exc, "add_note"):
            exc.add_note(f"(raised while stepping spaces[{index}] in tamias2d.step_spaces)")
    except AttributeError:  # an exception type that takes no attributes
        pass
    return exc
