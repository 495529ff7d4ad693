# Atomics, a clock and spin-loop helpers for the thread pools (_threads.h).
cdef extern from "_threads.h" nogil:
    long tamias_take_next(volatile long *counter)
    long tamias_load(volatile long *p)
    void tamias_store(volatile long *p, long v)
    long tamias_add(volatile long *p, long v)
    long tamias_exchange(volatile long *p, long v)
    long long tamias_now_ns()
    void tamias_cpu_relax()
    void tamias_yield()

cdef extern from "pythread.h":
    # Safe without the GIL (Cython's declaration lacks nogil).
    unsigned long tamias_thread_ident "PyThread_get_thread_ident"() nogil
