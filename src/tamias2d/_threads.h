/* What the thread pools (_step_spaces: many spaces; _soft_step: one soft
 * step on several threads) need below Python's thread API: atomics, a
 * monotonic clock, a pause for spin loops and a yield. */
#ifndef TAMIAS_THREADS_H
#define TAMIAS_THREADS_H

/* Sequentially consistent, except tamias_take_next (its only job is to
 * hand each index out once). */
#if defined(_MSC_VER)
#include <intrin.h>
static long tamias_take_next(volatile long *counter) { return _InterlockedExchangeAdd(counter, 1); }
static long tamias_load(volatile long *p) { return _InterlockedCompareExchange(p, 0, 0); }
static void tamias_store(volatile long *p, long v) { _InterlockedExchange(p, v); }
static long tamias_add(volatile long *p, long v) { return _InterlockedExchangeAdd(p, v) + v; }
static long tamias_exchange(volatile long *p, long v) { return _InterlockedExchange(p, v); }
#else
static long tamias_take_next(volatile long *counter) {
    return __atomic_fetch_add(counter, 1, __ATOMIC_RELAXED);
}
static long tamias_load(volatile long *p) { return __atomic_load_n(p, __ATOMIC_SEQ_CST); }
static void tamias_store(volatile long *p, long v) { __atomic_store_n(p, v, __ATOMIC_SEQ_CST); }
static long tamias_add(volatile long *p, long v) { return __atomic_add_fetch(p, v, __ATOMIC_SEQ_CST); }
static long tamias_exchange(volatile long *p, long v) {
    return __atomic_exchange_n(p, v, __ATOMIC_SEQ_CST);
}
#endif

#if defined(_WIN32)
#include <windows.h>
static long long tamias_now_ns(void) {
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return (long long)((double)c.QuadPart * 1e9 / (double)f.QuadPart);
}
#define tamias_cpu_relax() YieldProcessor()
#define tamias_yield() ((void)SwitchToThread())
#else
#include <time.h>
#include <sched.h>
static long long tamias_now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}
#if defined(__x86_64__) || defined(__i386__)
#define tamias_cpu_relax() __builtin_ia32_pause()
#elif defined(__aarch64__)
#define tamias_cpu_relax() __asm__ __volatile__("yield")
#else
#define tamias_cpu_relax() ((void)0)
#endif
#define tamias_yield() ((void)sched_yield())
#endif

#endif /* TAMIAS_THREADS_H */
