"""Threads and one space: a thread that reaches a space while another thread
steps it waits for the step to end (see ``_threadguard.pxd``)."""
from cpython.pythread cimport (PyThread_type_lock, PyThread_allocate_lock,
    PyThread_free_lock, PyThread_acquire_lock, PyThread_release_lock,
    PyThread_get_thread_ident, WAIT_LOCK, NOWAIT_LOCK)
from libc.stdint cimport uintptr_t
from posix.unistd cimport usleep

from tamias2d._structs cimport cpSpace


cdef int tamias_wait_for_step_slow(cpSpace *space) except -1:
    if space.stepThread == PyThread_get_thread_ident():
        return 0  # a callback of the step itself
    # space.userData is the Python Space; holding a reference keeps the
    # space (and its lock) alive while this thread waits without the GIL.
    cdef object owner = <object>space.userData if space.userData != NULL else None
    cdef PyThread_type_lock lock = <PyThread_type_lock>space.stepLock
    space.stepWaiters += 1
    try:
        while space.stepThread != 0:
            with nogil:
                # The stepping thread holds the lock for the whole step.
                PyThread_acquire_lock(lock, WAIT_LOCK)
                PyThread_release_lock(lock)
    finally:
        space.stepWaiters -= 1
    del owner
    return 0


cdef int tamias_begin_step(cpSpace *space) except -1:
    cdef unsigned long me = PyThread_get_thread_ident()
    # Another thread stepping the same space: wait for it, as any other
    # access would.
    if space.stepThread != 0:
        tamias_wait_for_step_slow(space)
    # Threads that waited for the last step get the GIL before this one
    # starts (they only need the GIL now; the lock is free).
    while space.stepWaiters > 0 and space.stepThread == 0:
        with nogil:
            usleep(50)
    if space.stepThread != 0:
        # Someone else started a step meanwhile; wait for that one too.
        return tamias_begin_step(space)
    space.stepThread = me
    # Free unless a waiter is between its acquire and release (it holds the
    # lock for an instant without the GIL, so waiting cannot deadlock). Try
    # first without letting the GIL go: that is the usual case, and dropping
    # the GIL for every space costs step_spaces a lot on small scenes.
    if not PyThread_acquire_lock(<PyThread_type_lock>space.stepLock, NOWAIT_LOCK):
        with nogil:
            PyThread_acquire_lock(<PyThread_type_lock>space.stepLock, WAIT_LOCK)
    return 0


cdef void tamias_end_step(cpSpace *space) noexcept:
    space.stepThread = 0
    PyThread_release_lock(<PyThread_type_lock>space.stepLock)


cdef int tamias_step_lock_new(cpSpace *space) except -1:
    space.stepLock = <void *>PyThread_allocate_lock()
    if space.stepLock == NULL:
        raise MemoryError("cannot allocate the space's step lock")
    return 0


cdef void tamias_step_lock_free(cpSpace *space) noexcept:
    if space.stepLock != NULL:
        PyThread_free_lock(<PyThread_type_lock>space.stepLock)
        space.stepLock = NULL
