# Broad phase: the bounding box tree of Munk2D (cpBBTree.c as of Munk2D
# 47b0e6b, the version inside pymunk 7.3), the default implementation of the
# spatial index interface of _spatialindex.pxd.
#
# The space uses two trees: a static one (exact boxes) and a dynamic one
# linked to it (fattened boxes, pair cache). Every call to the space goes
# through the cpSpatialIndex* dispatchers of _spatialindex.pxd, so the spatial
# hash (_spacehash) can replace the trees.
#
# Out of memory: the class functions have no return path, so a failed
# allocation raises the sticky flag of _containers (cpTakeOutOfMemory) and the
# operation is left undone or incomplete (see docs/architecture.md). A tree
# never crashes on it.
from tamias2d._config cimport cpFloat, cpHashValue, cpCollisionID, cpBool, cpTimestamp
from tamias2d.vector cimport cpVect, cpBB
from tamias2d._structs cimport (cpArray, cpHashSet, cpSpatialIndex, cpSpatialIndexClass,
    cpSpatialIndexBBFunc, cpSpatialIndexIteratorFunc, cpSpatialIndexQueryFunc,
    cpSpatialIndexSegmentQueryFunc)

# -- the tree's own types ---------------------------------------------------------
ctypedef cpVect (*cpBBTreeVelocityFunc)(void *obj) noexcept nogil
# Not Munk2D's: fetches into cache what the tree's box function will read
# of an object beyond the object itself (cpBBTreeSetFetchFunc).
ctypedef void (*cpBBTreeFetchFunc)(void *obj) noexcept nogil
# Not Munk2D's: told each leaf's box whenever the tree sets it (a new leaf,
# or one refattened as it left its box), so that the object can keep a copy
# (cpBBTreeSetFatFunc).
ctypedef void (*cpBBTreeFatFunc)(void *obj, cpBB fat) noexcept nogil

cdef struct Node
cdef struct Pair

cdef struct cpBBTree:
    cpSpatialIndex spatialIndex      # base, must stay first
    cpBBTreeVelocityFunc velocityFunc
    cpHashSet *leaves                # Node* keyed by the object's hashid
    Node *root
    Node *pooledNodes
    Pair *pooledPairs
    cpArray *allocatedBuffers
    cpTimestamp stamp
    # Not Munk2D's: counts every change of the tree's shape or of its pairs
    # (kept in the dynamic tree for both), so that a caller can tell that a
    # walk over the pairs would report the same ones in the same order.
    unsigned long long version
    # Not Munk2D's: how far around a dynamic leaf's box its pairs with the
    # static tree are looked for (the soft solver's reach for continuous
    # collision, cpBBTreeSetStaticReach; 0, as in Munk2D, otherwise).
    cpFloat staticReach
    # Not Munk2D's: the leaves listed in the leaf set's order for their
    # refresh (RefreshLeaves), and the object fetch function.
    Node **refreshList
    int refreshCap
    cpBBTreeFetchFunc fetchFunc
    # Not Munk2D's: the fat-box function, and whether every leaf's box has
    # been told to it since (0 after a snapshot's tree is linked:
    # cpBBTreeSyncFat tells them all).
    cpBBTreeFatFunc fatFunc
    bint fatSynced

cdef struct NodeChildren:
    Node *a
    Node *b

cdef struct NodeLeaf:
    cpTimestamp stamp
    Pair *pairs

cdef union NodeUnion:
    NodeChildren children
    NodeLeaf leaf

cdef struct Node:
    void *obj                        # NULL for internal nodes
    cpBB bb
    Node *parent
    NodeUnion node

# One side of a pair: the links of the pair list of one leaf.
cdef struct Thread:
    Pair *prev
    Node *leaf
    Pair *next

# What a pair of leaves remembers for the narrow phase between steps.
cdef struct cpPairSlot:
    cpCollisionID id                 # narrow-phase cache, handed back on replay
    # The soft solver's guess at the pair's cached arbiter, checked before
    # use (saves it the arbiter cache's lookup); unused by the chipmunk path.
    void *arbiter

cdef struct Pair:
    Thread a
    Thread b
    cpPairSlot slot

# A pair the soft solver's walk collects (cpBBTreeReindexCollect): its two
# objects, as cpBBTreeReindexQuery would report them, and where the tree
# keeps the pair's slot (NULL for a pair new this walk: not kept).
cdef struct cpCollectedPair:
    void *a
    void *b
    cpPairSlot *slot

# Where that walk writes its pairs, in order: `pairs` has room for `cap`.
# The walk calls `grow` as soon as the array is full (it may enlarge it,
# updating pairs and cap; while it stays full, further pairs are dropped).
# `complete` is cleared when a pair has no slot or is dropped: such a walk
# cannot stand for the next steps' (see `known` below).
cdef struct cpPairCollector:
    cpCollectedPair *pairs
    int count
    int cap
    bint complete
    void (*grow)(cpPairCollector *collector) noexcept nogil
    void *data                       # the caller's (for grow)

# -- cpBBTree.c -----------------------------------------------------------------------
cdef cpBBTree *cpBBTreeAlloc() noexcept nogil
# NULL when out of memory (the tree is then not allocated / left zeroed).
cdef cpSpatialIndex *cpBBTreeInit(cpBBTree *tree, cpSpatialIndexBBFunc bbfunc,
                                  cpSpatialIndex *staticIndex) noexcept nogil
cdef cpSpatialIndex *cpBBTreeNew(cpSpatialIndexBBFunc bbfunc, cpSpatialIndex *staticIndex) noexcept nogil
cdef void cpBBTreeOptimize(cpSpatialIndex *index) noexcept nogil
cdef void cpBBTreeSetVelocityFunc(cpSpatialIndex *index, cpBBTreeVelocityFunc func) noexcept nogil
cdef void cpBBTreeSetFetchFunc(cpSpatialIndex *index, cpBBTreeFetchFunc func) noexcept nogil
cdef void cpBBTreeSetFatFunc(cpSpatialIndex *index, cpBBTreeFatFunc func) noexcept nogil
cdef bint cpBBTreeSyncFat(cpSpatialIndex *index) noexcept nogil
# The soft solver's broad phase: cpBBTreeReindexQuery's pairs written into
# `collector` with where each pair's id lives, or nothing when the tree is
# still at the version in `known` (then the caller's record of the last walk
# holds); false (nothing done) unless the index and its static index are
# trees. `inside`: the caller has checked that no leaf left its box (through
# the fat-box function's copies), so the leaves' refresh is skipped.
cdef bint cpBBTreeReindexCollect(cpSpatialIndex *index, cpPairCollector *collector,
                                 unsigned long long *known, bint inside) noexcept nogil
# Sets how far around each dynamic leaf's box the static tree is searched
# (kept in the dynamic tree). Made larger, every leaf looks for its pairs
# afresh in the next walk, so the cached pairs are those of the new reach.
cdef void cpBBTreeSetStaticReach(cpSpatialIndex *index, cpFloat reach) noexcept nogil
cdef cpFloat cpBBTreeGetStaticReach(cpSpatialIndex *index) noexcept nogil
# The tree class table (what GetTree compares klass against).
cdef cpSpatialIndexClass *cpBBTreeClass() noexcept nogil
