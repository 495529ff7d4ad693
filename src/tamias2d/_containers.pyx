"""Containers under the space and the broad phase: a growable pointer array and
a chained hash set, ported from Munk2D's cpArray.c and cpHashSet.c.

Their iteration orders are part of the engine's behaviour (they decide the
order in which the broad phase updates leaves and thus the solver order), so
they follow Munk2D exactly: swap-with-last removal in the array; in the hash
set, prime table sizes, head insertion into buckets, growth when the entry
count reaches the table size, and traversal bucket by bucket, chain head to
tail.

The engine uses the C functions declared in ``_containers.pxd``; the tests
drive them through ``_TestArray``, ``_TestHashSet`` and ``_next_prime`` of
``_testing``. The allocation-failure hooks ``_set_alloc_failure`` and
``_take_out_of_memory`` stay here, next to the thread-local C state they set
and read (``_testing`` re-exports them).
"""
from libc.stdlib cimport calloc, realloc, free

# -- allocation ----------------------------------------------------------------
# Test hook: when _fail_after >= 0, that many more allocations succeed, then the
# next _fail_count ones fail. Lets the tests reach the out-of-memory paths.
#
# These three are per thread: steps of different spaces run at the same time
# on different threads (without the GIL), and each thread must read back the
# out-of-memory flag its own calls raised. The test hook arms the calling
# thread only.
cdef extern from *:
    """
    #if defined(_MSC_VER)
    #define TAMIAS_CONTAINERS_TLS __declspec(thread)
    #else
    #define TAMIAS_CONTAINERS_TLS __thread
    #endif
    static TAMIAS_CONTAINERS_TLS long tamias_fail_after = -1;
    static TAMIAS_CONTAINERS_TLS long tamias_fail_count = 0;
    static TAMIAS_CONTAINERS_TLS int tamias_out_of_memory = 0;
    """
    long _fail_after "tamias_fail_after"
    long _fail_count "tamias_fail_count"
    bint _out_of_memory "tamias_out_of_memory"


cdef inline bint _should_fail() noexcept nogil:
    global _fail_after, _fail_count
    if _fail_after < 0:
        return False
    if _fail_after > 0:
        _fail_after -= 1
        return False
    if _fail_count > 0:
        _fail_count -= 1
        if _fail_count == 0:
            _fail_after = -1
        return True
    _fail_after = -1
    return False


cdef void *cpcalloc(size_t count, size_t size) noexcept nogil:
    cdef void *ptr = NULL
    if not _should_fail():
        ptr = calloc(count, size)
    if ptr == NULL:
        cpSetOutOfMemory()
    return ptr


cdef void *cprealloc(void *ptr, size_t size) noexcept nogil:
    cdef void *out = NULL
    if not _should_fail():
        out = realloc(ptr, size)
    if out == NULL:
        cpSetOutOfMemory()
    return out


cdef void cpfree(void *ptr) noexcept nogil:
    free(ptr)


cdef void cpSetOutOfMemory() noexcept nogil:
    global _out_of_memory
    _out_of_memory = True


cdef bint cpOutOfMemory() noexcept nogil:
    return _out_of_memory


cdef bint cpTakeOutOfMemory() noexcept nogil:
    global _out_of_memory
    cdef bint flag = _out_of_memory
    _out_of_memory = False
    return flag


def _set_alloc_failure(long after, long count=1):
    """Test hook: let `after` more C allocations succeed, then fail `count`.

    A negative `after` switches the hook off.

    >>> _set_alloc_failure(-1)
    """
    global _fail_after, _fail_count
    if after < 0 or count <= 0:
        _fail_after = -1
        _fail_count = 0
    else:
        _fail_after = after
        _fail_count = count


def _take_out_of_memory():
    """Test hook: read and clear the sticky out-of-memory flag.

    >>> _take_out_of_memory()
    False
    """
    return bool(cpTakeOutOfMemory())


# -- cpArray ---------------------------------------------------------------------
cdef cpArray *cpArrayNew(int size) noexcept nogil:
    cdef cpArray *arr = <cpArray *>cpcalloc(1, sizeof(cpArray))
    if arr == NULL:
        return NULL
    arr.num = 0
    arr.max = size if size else 4
    arr.arr = <void **>cpcalloc(arr.max, sizeof(void *))
    if arr.arr == NULL:
        free(arr)
        return NULL
    return arr


cdef void cpArrayFree(cpArray *arr) noexcept nogil:
    if arr != NULL:
        free(arr.arr)
        arr.arr = NULL
        free(arr)


cdef cpBool cpArrayPush(cpArray *arr, void *object) noexcept nogil:
    cdef int new_max
    cdef void **grown
    if arr.num == arr.max:
        # Same growth rule as Munk2D (about 1.5x), so capacities match.
        new_max = 3 * (arr.max + 1) // 2
        grown = <void **>cprealloc(arr.arr, new_max * sizeof(void *))
        if grown == NULL:
            return 0
        arr.arr = grown
        arr.max = new_max
    arr.arr[arr.num] = object
    arr.num += 1
    return 1


cdef void *cpArrayPop(cpArray *arr) noexcept nogil:
    arr.num -= 1
    cdef void *value = arr.arr[arr.num]
    arr.arr[arr.num] = NULL
    return value


cdef void cpArrayDeleteObj(cpArray *arr, void *obj) noexcept nogil:
    cdef int i
    for i in range(arr.num):
        if arr.arr[i] == obj:
            # The last element takes the freed slot: order changes on purpose.
            arr.num -= 1
            arr.arr[i] = arr.arr[arr.num]
            arr.arr[arr.num] = NULL
            return


cdef void cpArrayFreeEach(cpArray *arr, cpArrayFreeFunc freeFunc) noexcept nogil:
    cdef int i
    for i in range(arr.num):
        freeFunc(arr.arr[i])


cdef cpBool cpArrayContains(cpArray *arr, void *ptr) noexcept nogil:
    cdef int i
    for i in range(arr.num):
        if arr.arr[i] == ptr:
            return 1
    return 0


# -- prime.h ---------------------------------------------------------------------
# Table sizes, each roughly twice the one before.
cdef int[29] _primes = [
    5, 13, 23, 47, 97, 193, 389, 769, 1543, 3079, 6151, 12289, 24593, 49157,
    98317, 196613, 393241, 786433, 1572869, 3145739, 6291469, 12582917,
    25165843, 50331653, 100663319, 201326611, 402653189, 805306457, 1610612741,
]


cdef int next_prime(int n) noexcept nogil:
    cdef int i = 0
    while n > _primes[i]:
        i += 1
        if i == 29:
            return 0
    return _primes[i]


# -- cpHashSet -------------------------------------------------------------------
cdef void cpHashSetFree(cpHashSet *set) noexcept nogil:
    cdef int i
    if set != NULL:
        free(set.table)
        if set.allocatedBuffers != NULL:
            for i in range(set.allocatedBuffers.num):
                free(set.allocatedBuffers.arr[i])
            cpArrayFree(set.allocatedBuffers)
        free(set)


cdef cpHashSet *cpHashSetNew(int size, cpHashSetEqlFunc eqlFunc) noexcept nogil:
    cdef int prime = next_prime(size)
    if prime == 0:
        cpSetOutOfMemory()
        return NULL
    cdef cpHashSet *set = <cpHashSet *>cpcalloc(1, sizeof(cpHashSet))
    if set == NULL:
        return NULL
    set.size = prime
    set.entries = 0
    set.eql = eqlFunc
    set.default_value = NULL
    set.table = <cpHashSetBin **>cpcalloc(set.size, sizeof(cpHashSetBin *))
    set.pooledBins = NULL
    set.allocatedBuffers = cpArrayNew(0)
    if set.table == NULL or set.allocatedBuffers == NULL:
        cpHashSetFree(set)
        return NULL
    return set


cdef void cpHashSetSetDefaultValue(cpHashSet *set, void *default_value) noexcept nogil:
    set.default_value = default_value


cdef void _cpHashSetResize(cpHashSet *set) noexcept nogil:
    cdef unsigned int new_size = next_prime(set.size + 1)
    if new_size == 0:
        # Past the largest prime: keep the table, chains just get longer.
        cpSetOutOfMemory()
        return
    cdef cpHashSetBin **new_table = <cpHashSetBin **>cpcalloc(new_size, sizeof(cpHashSetBin *))
    if new_table == NULL:
        # The old table stays valid; only the order no longer matches Munk2D.
        return
    cdef unsigned int i
    cdef cpHashSetBin *bin
    cdef cpHashSetBin *next_bin
    cdef cpHashValue idx
    # Walk the old buckets in order and push each bin on the head of its new
    # bucket; this reverses relative order inside a bucket, as upstream does.
    for i in range(set.size):
        bin = set.table[i]
        while bin != NULL:
            next_bin = bin.next
            idx = bin.hash % new_size
            bin.next = new_table[idx]
            new_table[idx] = bin
            bin = next_bin
    free(set.table)
    set.table = new_table
    set.size = new_size


cdef inline void _recycleBin(cpHashSet *set, cpHashSetBin *bin) noexcept nogil:
    bin.next = set.pooledBins
    set.pooledBins = bin
    bin.elt = NULL


cdef cpHashSetBin *_getUnusedBin(cpHashSet *set) noexcept nogil:
    cdef cpHashSetBin *bin = set.pooledBins
    cdef int count, i
    cdef cpHashSetBin *block
    if bin != NULL:
        set.pooledBins = bin.next
        return bin
    # Pool empty: carve one 32 KiB block into bins, hand out the first.
    count = CP_BUFFER_BYTES // sizeof(cpHashSetBin)
    block = <cpHashSetBin *>cpcalloc(1, CP_BUFFER_BYTES)
    if block == NULL:
        return NULL
    if not cpArrayPush(set.allocatedBuffers, block):
        free(block)
        return NULL
    for i in range(1, count):
        _recycleBin(set, block + i)
    return block


cdef int cpHashSetCount(cpHashSet *set) noexcept nogil:
    return set.entries


cdef const void *cpHashSetInsert(cpHashSet *set, cpHashValue hash, const void *ptr,
                                 cpHashSetTransFunc trans, void *data) noexcept nogil:
    cdef cpHashValue idx = hash % set.size
    cdef cpHashSetBin *bin = set.table[idx]
    cdef void *elt
    # The stored hash first: a chain's other elements are then not read.
    while bin != NULL and not (bin.hash == hash and set.eql(ptr, bin.elt)):
        bin = bin.next
    if bin == NULL:
        bin = _getUnusedBin(set)
        if bin == NULL:
            return NULL
        elt = trans(ptr, data) if trans != NULL else data
        if elt == NULL and trans != NULL:
            # The element could not be made (out of memory in trans).
            _recycleBin(set, bin)
            return NULL
        bin.hash = hash
        bin.elt = elt
        bin.next = set.table[idx]
        set.table[idx] = bin
        set.entries += 1
        if set.entries >= set.size:
            _cpHashSetResize(set)
    return bin.elt


cdef const void *cpHashSetRemove(cpHashSet *set, cpHashValue hash, const void *ptr) noexcept nogil:
    cdef cpHashValue idx = hash % set.size
    cdef cpHashSetBin **prev_ptr = &set.table[idx]
    cdef cpHashSetBin *bin = set.table[idx]
    cdef const void *elt
    # The stored hash first: a chain's other elements are then not read.
    while bin != NULL and not (bin.hash == hash and set.eql(ptr, bin.elt)):
        prev_ptr = &bin.next
        bin = bin.next
    if bin != NULL:
        prev_ptr[0] = bin.next
        set.entries -= 1
        elt = bin.elt
        _recycleBin(set, bin)
        return elt
    return NULL


cdef const void *cpHashSetFind(cpHashSet *set, cpHashValue hash, const void *ptr) noexcept nogil:
    cdef cpHashValue idx = hash % set.size
    cdef cpHashSetBin *bin = set.table[idx]
    # The stored hash first: a chain's other elements are then not read.
    while bin != NULL and not (bin.hash == hash and set.eql(ptr, bin.elt)):
        bin = bin.next
    return bin.elt if bin != NULL else set.default_value


# Each and Filter walk every bin, and a table never shrinks: a space whose
# bodies have all fallen asleep walks tens of thousands of empty bins per step.
# The empty bins are skipped in a tight pointer loop of their own; with one
# loop around the callback, gcc keeps the bin index on the stack and each
# empty bin costs a store-to-load round trip (1.2x pymunk's step time for a
# sleeping wall of 10,000 boxes). The order of visits is unchanged.
cdef void cpHashSetEach(cpHashSet *set, cpHashSetIteratorFunc func, void *data) noexcept nogil:
    cdef cpHashSetBin **slot = set.table
    cdef cpHashSetBin **end = set.table + set.size
    cdef cpHashSetBin *bin
    cdef cpHashSetBin *next_bin
    while True:
        while slot < end and slot[0] == NULL:
            slot += 1
        if slot == end:
            return
        bin = slot[0]
        while bin != NULL:
            # Read the link first: the callback may remove the current element.
            next_bin = bin.next
            func(bin.elt, data)
            bin = next_bin
        slot += 1


cdef void cpHashSetFilter(cpHashSet *set, cpHashSetFilterFunc func, void *data) noexcept nogil:
    cdef cpHashSetBin **slot = set.table
    cdef cpHashSetBin **end = set.table + set.size
    cdef cpHashSetBin **prev_ptr
    cdef cpHashSetBin *bin
    cdef cpHashSetBin *next_bin
    while True:
        while slot < end and slot[0] == NULL:
            slot += 1
        if slot == end:
            return
        prev_ptr = slot
        bin = slot[0]
        while bin != NULL:
            next_bin = bin.next
            if func(bin.elt, data):
                prev_ptr = &bin.next
            else:
                prev_ptr[0] = next_bin
                set.entries -= 1
                _recycleBin(set, bin)
            bin = next_bin
        slot += 1
