# Scalar types and the constants of the engine, as Munk2D's chipmunk_types.h
# and chipmunk.h define them (double precision, 64-bit hash values).
from libc.stdint cimport uintptr_t, uint32_t

ctypedef double cpFloat
ctypedef uintptr_t cpHashValue
ctypedef uint32_t cpCollisionID
ctypedef unsigned char cpBool
ctypedef void *cpDataPointer
ctypedef uintptr_t cpCollisionType
ctypedef uintptr_t cpGroup
ctypedef unsigned int cpBitmask
ctypedef unsigned int cpTimestamp

cdef extern from *:
    """
    /* The C compiler rounds these float literals exactly as Munk2D's sources do:
       0.1f is 0.10000000149011612 once stored in a double. */
    #define TAMIAS_FLOAT_0_1F ((double)0.1f)
    #define TAMIAS_FLOAT_0_9F ((double)(1.0f - 0.1f))
    """
    const double TAMIAS_FLOAT_0_1F
    const double TAMIAS_FLOAT_0_9F

cdef extern from *:
    """
    /* A hint to fetch a cache line that is about to be read (walks of the
       broad phase's pairs and the arbiter cache); nothing where the compiler
       has no such builtin. */
    #if defined(__GNUC__) || defined(__clang__)
    #define tamias_prefetch(p) __builtin_prefetch(p)
    #define tamias_prefetch_write(p) __builtin_prefetch((p), 1)
    #else
    #define tamias_prefetch(p) ((void)(p))
    #define tamias_prefetch_write(p) ((void)(p))
    #endif
    """
    void tamias_prefetch(const void *p) nogil
    # The same for a line about to be written.
    void tamias_prefetch_write(const void *p) nogil

cdef extern from *:
    """
    /* The index of the lowest set bit of a non-zero word. */
    #if defined(__GNUC__) || defined(__clang__)
    #define tamias_lowest_bit(x) __builtin_ctz(x)
    #elif defined(_MSC_VER)
    #include <intrin.h>
    static __inline int tamias_lowest_bit(unsigned int x) {
        unsigned long i; _BitScanForward(&i, x); return (int)i;
    }
    #else
    static inline int tamias_lowest_bit(unsigned int x) {
        int i = 0; while (!(x & 1u)) { x >>= 1; i++; } return i;
    }
    #endif
    """
    int tamias_lowest_bit(unsigned int x) nogil

# chipmunk.h / chipmunk_private.h
cdef enum:
    CP_MAX_CONTACTS_PER_ARBITER = 2
    CP_BUFFER_BYTES = 32 * 1024
    CP_POLY_SHAPE_INLINE_ALLOC = 6
    MAX_GJK_ITERATIONS = 30
    MAX_EPA_ITERATIONS = 30
    WARN_GJK_ITERATIONS = 20
    WARN_EPA_ITERATIONS = 20

cdef const cpHashValue CP_HASH_COEF = <cpHashValue>3344921057UL
cdef const cpHashValue CP_HASH_COEF_ORDERED = <cpHashValue>1566083941UL
cdef const cpBitmask CP_ALL_CATEGORIES = <cpBitmask>0xFFFFFFFFU
cdef const cpGroup CP_NO_GROUP = 0
cdef const cpCollisionType CP_WILDCARD_COLLISION_TYPE = <cpCollisionType>(-1)
cdef const cpFloat MAGIC_EPSILON = 1e-5

# CP_HASH_PAIR(A, B): symmetric, wraps modulo 2**64 as uintptr_t arithmetic does.
cdef inline cpHashValue CP_HASH_PAIR(cpHashValue a, cpHashValue b) noexcept nogil:
    return (a * CP_HASH_COEF) ^ (b * CP_HASH_COEF)

# Munk2D's ordered variant, used for collision handler keys.
cdef inline cpHashValue CP_HASH_PAIR_ORDERED(cpHashValue a, cpHashValue b) noexcept nogil:
    return (a * CP_HASH_COEF) ^ (b * CP_HASH_COEF_ORDERED)
