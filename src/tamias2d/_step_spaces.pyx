"""Many spaces stepped in one call, on a pool of native threads.

``step_spaces(spaces, dt, threads=None, steps=1)``: the calling thread
prepares every space for its first step with the GIL (the checks of
``Space.step``); then it and the pool's workers take spaces one at a time
from a shared counter, and each runs all `steps` steps of the space it took
before taking the next, without the GIL; then the calling thread finishes the
last step of every space with the GIL (errors, deferred adds and removes,
post-step callbacks). A space is stepped by one thread at a time and its step
shares nothing with the others, so each space ends bit for bit where stepping
it alone ends, whatever the number of threads.

Between two steps of a space its worker asks the space whether finishing the
step and beginning the next would do anything but unlock and lock it again
(``Space._quiet_between_steps``, no GIL needed); only when it would (a
callback deferred work or raised, a check would fail, another thread waits
for the space) does the worker take the GIL and run them. So a space without
Python callbacks costs no GIL at all within the call, the pool meets once per
call rather than once per step, and a space's data stays in one core's cache
for all its steps.

The workers are daemon threads started on first use and kept for later
calls; after a call they poll for the next one for 0.2 ms, then sleep on a
lock. The caller works through the spaces too and never waits for a worker
that has not started (on a busy machine a woken thread may get a core late):
once every space is taken it waits only for the workers still stepping one.
"""
import os

from cpython.object cimport PyObject
from cpython.pythread cimport (PyThread_type_lock, PyThread_allocate_lock,
    PyThread_acquire_lock, PyThread_release_lock, WAIT_LOCK, NOWAIT_LOCK)
from libc.math cimport isfinite
from libc.stdlib cimport malloc, calloc, free

from tamias2d._structs cimport cpSpace, cpBody
from tamias2d._containers cimport cpTakeOutOfMemory, cpSetOutOfMemory
from tamias2d.collision cimport (CollisionDiagnostics, cpCollisionTakeDiagnostics,
    cpCollisionPutDiagnostics)
from tamias2d.space cimport Space, tamias_space_step
from tamias2d._threads cimport (tamias_take_next, tamias_load, tamias_store, tamias_add,
    tamias_now_ns, tamias_cpu_relax, tamias_thread_ident)

import threading

from tamias2d.errors import SpaceLocked

cdef enum:
    MAX_WORKERS = 256

# How long a thread polls a lock before it blocks on it: a worker after its
# job (the next call of an RL loop usually comes sooner, and waking a
# sleeping thread costs tens of microseconds), the caller waiting for the
# workers at the end of a call.
cdef long long WORKER_SPIN_NS = 200000
cdef long long CALLER_SPIN_NS = 100000


def _set_spin(worker_ns, caller_ns):
    """Set the two polling times in nanoseconds (for benchmarks); returns
    the old ones. 0 blocks at once."""
    global WORKER_SPIN_NS, CALLER_SPIN_NS
    old = (WORKER_SPIN_NS, CALLER_SPIN_NS)
    if worker_ns < 0 or caller_ns < 0:
        raise ValueError("polling times must be >= 0")
    WORKER_SPIN_NS, CALLER_SPIN_NS = worker_ns, caller_ns
    return old


cdef void _take_lock(PyThread_type_lock lock, long long spin_ns) noexcept nogil:
    # Taking a free lock without blocking costs no system call.
    cdef long long until
    if PyThread_acquire_lock(lock, NOWAIT_LOCK):
        return
    until = tamias_now_ns() + spin_ns
    while tamias_now_ns() < until:
        for _ in range(32):
            tamias_cpu_relax()
        if PyThread_acquire_lock(lock, NOWAIT_LOCK):
            return
    PyThread_acquire_lock(lock, WAIT_LOCK)

# What one space's steps left for the calling thread. Slots of neighbouring
# spaces are written by different threads: the padding keeps them on
# different cache lines.
cdef struct Slot:
    cpBody *bad                  # the first body the last step made non-finite, or NULL
    long done                    # steps run
    bint ended                   # the space stopped on its worker (errors[i] says why)
    bint out_of_memory           # the C diagnostics of the last step, taken from
    CollisionDiagnostics diag    #   the thread that ran it (they are per thread)
    char pad[64]

# One call: what every thread works through.
cdef struct Job:
    cpSpace **spaces
    PyObject **owners            # the Python spaces (the caller's list holds them)
    Slot *slots
    PyObject *errors             # a list: the exception that stopped space i on a worker
    double dt
    long count
    long steps
    long next                    # the next space to take (atomic)

cdef Job *_job = NULL                          # the pool's call (its Job lives in _step_all)
cdef int _started = 0                          # workers running
cdef PyThread_type_lock _go[MAX_WORKERS]       # released to wake worker k
cdef PyThread_type_lock _finished = NULL       # released by the last worker out, if asked
cdef volatile long _open = 0                   # 1 while *_job may be worked on
cdef volatile long _in_flight = 0              # workers between their check of _open and leaving
cdef volatile long _caller_waits = 0           # the caller sleeps on _finished
cdef volatile long _seats = 0                  # workers the open call may still take
cdef object _pool_lock = threading.Lock()      # held by the call the pool serves
cdef long _pool_pid = -1                       # the process whose workers these are


cdef bint _between_steps(Job *job, long i, cpBody *bad) noexcept with gil:
    # Finish the step just run and begin the next, as Space.step would
    # between two calls; on an exception the space stops here (both leave it
    # consistent and not stepping).
    cdef Space sp = <Space>job.owners[i]
    try:
        sp._step_finish(bad, job.dt)
        sp._step_begin()
    except BaseException as exc:
        (<list>job.errors)[i] = exc
        job.slots[i].ended = True
        return False
    return True


cdef void _work(Job *job) noexcept nogil:
    cdef long i, s
    cdef cpSpace *space
    cdef Slot *slot
    cdef cpBody *bad
    while True:
        i = tamias_take_next(&job.next)
        if i >= job.count:
            return
        space = job.spaces[i]
        slot = &job.slots[i]
        # The space is this thread's now: its callbacks (which run here)
        # pass the thread guard, other threads still wait (stepThread stays
        # non-zero; a word written whole, read under the GIL by waiters).
        space.stepThread = tamias_thread_ident()
        bad = NULL
        for s in range(job.steps):
            if s > 0 and not (<Space>job.owners[i])._quiet_between_steps(bad):
                if not _between_steps(job, i, bad):
                    break
            bad = tamias_space_step(space, job.dt)
            slot.done = s + 1
        slot.bad = bad
        slot.out_of_memory = cpTakeOutOfMemory()
        slot.diag = cpCollisionTakeDiagnostics()


def _worker_main(int k):
    with nogil:
        while True:
            _take_lock(_go[k], WORKER_SPIN_NS)
            _join_job()


cdef void _join_job() noexcept nogil:
    # A worker woken late (the machine is busy) may find the call over, or
    # may find the next call: it works on whatever call is open, or on none.
    # The caller closes a call before it waits for _in_flight to fall to 0,
    # and a worker counts itself in before it looks at _open, so either the
    # caller waits for the worker or the worker sees the call closed. A call
    # takes no more workers than it asked for (threads - 1).
    tamias_add(&_in_flight, 1)
    if tamias_load(&_open) and tamias_add(&_seats, -1) >= 0:
        _work(_job)
    if tamias_add(&_in_flight, -1) == 0 and tamias_load(&_caller_waits):
        PyThread_release_lock(_finished)


cdef int _ensure_workers(int n) except -1:
    global _started, _pool_pid, _finished, _open, _in_flight, _caller_waits, _seats
    if _pool_pid != os.getpid():
        # A fork keeps the counters but not the threads: start afresh (the
        # parent's locks are left as they are).
        _started = 0
        _open = 0
        _in_flight = 0
        _caller_waits = 0
        _seats = 0
        _finished = PyThread_allocate_lock()
        if _finished == NULL:
            raise MemoryError("cannot allocate the lock of the step_spaces pool")
        PyThread_acquire_lock(_finished, WAIT_LOCK)
        _pool_pid = os.getpid()
    while _started < n:
        k = _started
        _go[k] = PyThread_allocate_lock()
        if _go[k] == NULL:
            raise MemoryError("cannot allocate the lock of a step_spaces worker")
        PyThread_acquire_lock(_go[k], WAIT_LOCK)   # taken: the worker waits on it
        threading.Thread(target=_worker_main, args=(k,), daemon=True,
                         name=f"tamias2d-step-{k}").start()
        _started += 1
    return 0


cdef int _run_job(Job *job, int helpers) except -1:
    # The caller works too, so `helpers` workers make helpers + 1 threads.
    # It never waits for a worker that has not started: once every space is
    # taken it closes the call and waits only for the workers inside it.
    cdef int k
    cdef long long until
    global _job
    _job = job
    with nogil:
        tamias_store(&_seats, helpers)
        tamias_store(&_open, 1)
        for k in range(helpers):
            PyThread_release_lock(_go[k])
        _work(job)
        tamias_store(&_open, 0)
        if tamias_load(&_in_flight) != 0:
            until = tamias_now_ns() + CALLER_SPIN_NS
            while tamias_load(&_in_flight) != 0 and tamias_now_ns() < until:
                for k in range(32):
                    tamias_cpu_relax()
        if tamias_load(&_in_flight) != 0:
            tamias_store(&_caller_waits, 1)
            while tamias_load(&_in_flight) != 0:
                # Woken by the last worker out (or by a stale wake-up of an
                # earlier call: then look again).
                PyThread_acquire_lock(_finished, WAIT_LOCK)
            tamias_store(&_caller_waits, 0)
    return 0


cdef int _default_threads():
    try:
        return len(os.sched_getaffinity(0)) or 1   # the cores this process may use
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def step_spaces(spaces, dt, *, threads=None, steps=1):
    """Step every space of `spaces` `steps` times by `dt`, spread over
    `threads` native threads (default: the cores this process may run on)
    without the GIL.

    Each space ends exactly (bit for bit) where ``space.step(dt)`` called
    `steps` times ends, for any number of threads. A thread takes one space
    and runs all its steps, then takes the next, so the threads meet once
    per call and ``steps=k`` costs less than k calls.

    The worker threads serve one call at a time: a call made while they
    serve another (from another thread, or from a callback of a space being
    stepped) runs on its calling thread alone.

    Python callbacks (collision handlers, body or joint functions, post-step
    callbacks) work and run on the thread stepping their space, which may not
    be the calling thread. Each takes the GIL, so callbacks of different
    spaces run one at a time while the C steps go on in parallel; a space
    whose step spends much of its time in Python gains little, and between
    two of its steps its thread takes the GIL again to run what the callbacks
    deferred. A callback must not touch another space of the same call: that
    space is being stepped, so the callback waits for its steps to end, and
    if a callback of that space waits likewise for this one, both wait for
    ever (a deadlock). A callback may touch its own space and its bodies.

    Before anything steps, bad input raises: a non-Space, a space listed
    twice, a space that is locked or being stepped by another thread, a
    non-finite or negative `dt`, `steps` < 0, `threads` < 1, and whatever
    ``Space.step`` would refuse. An exception raised while stepping (in a
    callback, or an overflow) stops its space after that step, consistent;
    the other spaces still run all their steps. Then the exception of the
    first space (by position) that raised one is raised, carrying the space
    and its position in ``exc.space`` and ``exc.space_index`` and the steps
    that space ran in ``exc.steps_done`` (and a note saying so).

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
        nthreads = _default_threads()
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
    cdef PyObject **owners = <PyObject **>malloc(n * sizeof(PyObject *))
    cdef Slot *slots = <Slot *>calloc(n, sizeof(Slot))
    if cspaces == NULL or owners == NULL or slots == NULL:
        free(cspaces)
        free(owners)
        free(slots)
        raise MemoryError("not enough memory for step_spaces")
    try:
        for i in range(n):
            cspaces[i] = &(<Space>spaces[i])._space
            owners[i] = <PyObject *>spaces[i]
        # While the pool serves one call, another (from another thread, or
        # from a callback of a space being stepped, which must not wait for
        # the call it is part of) runs on its own thread alone.
        if helpers > 0 and _pool_lock.acquire(blocking=False):
            try:
                _ensure_workers(helpers)
                _step_all(spaces, cspaces, owners, slots, n, cdt, nsteps, helpers)
            finally:
                _pool_lock.release()
        else:
            _step_all(spaces, cspaces, owners, slots, n, cdt, nsteps, 0)
    finally:
        free(cspaces)
        free(owners)
        free(slots)
    return None


cdef int _step_all(list spaces, cpSpace **cspaces, PyObject **owners, Slot *slots,
                   Py_ssize_t n, double dt, long steps, int helpers) except -1:
    cdef Py_ssize_t i, j
    cdef Slot *slot
    # Prepare every space first; if one refuses, undo the others.
    for i in range(n):
        try:
            (<Space>spaces[i])._step_begin()
        except BaseException as exc:
            for j in range(i):
                (<Space>spaces[j])._step_abort()
            _name_space(exc, spaces[i], i, 0, "before any space stepped")
            raise
    cdef list errors = [None] * n
    cdef Job job
    job.spaces = cspaces
    job.owners = owners
    job.slots = slots
    job.errors = <PyObject *>errors
    job.dt = dt
    job.count = n
    job.steps = steps
    job.next = 0
    if helpers > 0:
        _run_job(&job, helpers)
    else:
        with nogil:
            _work(&job)
    failed = []
    for i in range(n):
        slot = &slots[i]
        if not slot.ended:
            # The last step's C diagnostics belong to this thread now, so
            # that _step_finish reports them for this space.
            if slot.out_of_memory:
                cpSetOutOfMemory()
            cpCollisionPutDiagnostics(slot.diag)
            try:
                (<Space>spaces[i])._step_finish(slot.bad, dt)
            except BaseException as exc:
                errors[i] = exc
        if errors[i] is not None:
            failed.append(i)
    if failed:
        i = failed[0]
        first = _name_space(errors[i], spaces[i], i, slots[i].done,
                            f"which stopped after {slots[i].done} of its {steps} steps")
        if len(failed) > 1 and hasattr(first, "add_note"):
            others = ", ".join(f"spaces[{k}] ({type(errors[k]).__name__})" for k in failed[1:])
            first.add_note(f"(these spaces raised too and stopped early: {others})")
        raise first
    return 0


cdef object _name_space(exc, space, Py_ssize_t index, long done, str when):
    try:
        exc.space = space
        exc.space_index = index
        exc.steps_done = done
        if hasattr(exc, "add_note"):
            exc.add_note(f"(raised by spaces[{index}] in tamias2d.step_spaces, {when})")
    except AttributeError:  # an exception type that takes no attributes
        pass
    return exc
