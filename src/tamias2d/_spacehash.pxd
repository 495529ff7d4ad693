# The spatial hash of Munk2D (cpSpaceHash.c): the broad phase that
# Space.use_spatial_hash(dim, count) puts in place of the two BB trees.
# Objects are hashed into square cells of side `celldim` in a table of
# next_prime(count) buckets; it plugs into the same cpSpatialIndex interface
# as the tree (_spatialindex.pxd).
from tamias2d._config cimport cpFloat, cpTimestamp
from tamias2d._structs cimport (cpArray, cpHashSet, cpSpatialIndex, cpSpatialIndexClass,
    cpSpatialIndexBBFunc)

cdef struct cpHandle:
    void *obj
    int retain
    cpTimestamp stamp

cdef struct cpSpaceHashBin:
    cpHandle *handle
    cpSpaceHashBin *next

cdef struct cpSpaceHash:
    cpSpatialIndex spatialIndex      # base, must stay first
    int numcells
    cpFloat celldim
    cpSpaceHashBin **table
    cpHashSet *handleSet
    cpSpaceHashBin *pooledBins
    cpArray *pooledHandles
    cpArray *allocatedBuffers
    cpTimestamp stamp

cdef cpSpaceHash *cpSpaceHashAlloc() noexcept nogil
# NULL when out of memory, when numcells is past the prime table, or when the
# static index already has a dynamic partner.
cdef cpSpatialIndex *cpSpaceHashInit(cpSpaceHash *hash, cpFloat celldim, int numcells,
                                     cpSpatialIndexBBFunc bbfunc,
                                     cpSpatialIndex *staticIndex) noexcept nogil
cdef cpSpatialIndex *cpSpaceHashNew(cpFloat celldim, int cells, cpSpatialIndexBBFunc bbfunc,
                                    cpSpatialIndex *staticIndex) noexcept nogil
cdef void cpSpaceHashResize(cpSpaceHash *hash, cpFloat celldim, int numcells) noexcept nogil
# The hash's class table.
cdef cpSpatialIndexClass *cpSpaceHashClass() noexcept nogil
