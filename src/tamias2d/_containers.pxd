# Containers of the engine: the growable pointer array and the chained hash
# set of Munk2D (cpArray.c, cpHashSet.c, prime.h), plus the allocation helpers
# every C-level module uses. The structs live in _structs.pxd.
#
# Out of memory. Munk2D assumes calloc/realloc never fail. Here every
# allocation goes through cpcalloc/cprealloc, and a failure never aborts:
#   * constructors (cpArrayNew, cpHashSetNew) return NULL; callers check it;
#   * cpArrayPush returns 0 and leaves the array as it was;
#   * cpHashSetInsert returns NULL and leaves the set as it was;
#   * in every case a process-wide sticky flag is raised. Code that runs
#     without a return path (the broad phase inside a step) only raises the
#     flag; the Python layer reads it with cpTakeOutOfMemory() after such a
#     call and turns it into MemoryError.
from libc.stddef cimport size_t
from tamias2d._config cimport cpHashValue, cpBool, CP_BUFFER_BYTES
from tamias2d._structs cimport (cpArray, cpHashSet, cpHashSetBin, cpHashSetEqlFunc,
    cpHashSetTransFunc, cpHashSetIteratorFunc, cpHashSetFilterFunc)

# -- allocation ----------------------------------------------------------------
cdef void *cpcalloc(size_t count, size_t size) noexcept nogil
cdef void *cprealloc(void *ptr, size_t size) noexcept nogil
cdef void cpfree(void *ptr) noexcept nogil
# The sticky out-of-memory flag: raised by any failed allocation.
cdef void cpSetOutOfMemory() noexcept nogil
cdef bint cpOutOfMemory() noexcept nogil
# Returns the flag and lowers it.
cdef bint cpTakeOutOfMemory() noexcept nogil

# -- cpArray ---------------------------------------------------------------------
ctypedef void (*cpArrayFreeFunc)(void *ptr) noexcept nogil

cdef cpArray *cpArrayNew(int size) noexcept nogil
cdef void cpArrayFree(cpArray *arr) noexcept nogil
# 1 on success, 0 when the array could not grow (element not added).
cdef cpBool cpArrayPush(cpArray *arr, void *object) noexcept nogil
cdef void *cpArrayPop(cpArray *arr) noexcept nogil
# Swap-with-last removal of the first slot holding obj; no-op when absent.
cdef void cpArrayDeleteObj(cpArray *arr, void *obj) noexcept nogil
cdef void cpArrayFreeEach(cpArray *arr, cpArrayFreeFunc freeFunc) noexcept nogil
cdef cpBool cpArrayContains(cpArray *arr, void *ptr) noexcept nogil

# -- prime.h ---------------------------------------------------------------------
# Smallest table prime >= n, or 0 past the end of the table.
cdef int next_prime(int n) noexcept nogil

# -- cpHashSet -------------------------------------------------------------------
cdef void cpHashSetFree(cpHashSet *set) noexcept nogil
cdef cpHashSet *cpHashSetNew(int size, cpHashSetEqlFunc eqlFunc) noexcept nogil
cdef void cpHashSetSetDefaultValue(cpHashSet *set, void *default_value) noexcept nogil
cdef int cpHashSetCount(cpHashSet *set) noexcept nogil
cdef const void *cpHashSetInsert(cpHashSet *set, cpHashValue hash, const void *ptr,
                                 cpHashSetTransFunc trans, void *data) noexcept nogil
cdef const void *cpHashSetRemove(cpHashSet *set, cpHashValue hash, const void *ptr) noexcept nogil
cdef const void *cpHashSetFind(cpHashSet *set, cpHashValue hash, const void *ptr) noexcept nogil
cdef void cpHashSetEach(cpHashSet *set, cpHashSetIteratorFunc func, void *data) noexcept nogil
cdef void cpHashSetFilter(cpHashSet *set, cpHashSetFilterFunc func, void *data) noexcept nogil
