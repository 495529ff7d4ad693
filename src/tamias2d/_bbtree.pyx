"""The broad phase: Munk2D's AABB tree, an implementation of the spatial index.

A faithful port of cpBBTree.c at Munk2D 47b0e6b (the tree pymunk 7.3 runs:
explicit stacks instead of recursion, segment-query pruning when children are
pushed). The order in which pairs are reported is what fixes the solver order
of the whole engine, so every traversal keeps Munk2D's order: insertion by
area cost (ties by proximity, then child A), new leaf at child A, depth-first
A before B, pair lists head-inserted, leaves updated in hash-set order.

The tree plugs into the interface of ``_spatialindex`` (cpSpatialIndex.c/.h),
through which the space calls it; the engine uses the C functions of
``_bbtree.pxd``. The test-only wrapper over a pair of trees, ``_TestTree``, is
in ``_testing``.
"""
from libc.stdlib cimport free, qsort
from libc.string cimport memcpy
from libc.stdint cimport uintptr_t
from tamias2d._config cimport tamias_prefetch, TAMIAS_FLOAT_0_1F, CP_BUFFER_BYTES
from tamias2d.vector cimport (cpvmult, cpfmin, cpfmax, cpfabs, cpBBNew, cpBBMerge,
    cpBBArea, cpBBMergedArea, cpBBIntersects, cpBBContainsBB, cpBBSegmentQuery)
from tamias2d._containers cimport (cpcalloc, cprealloc, cpSetOutOfMemory,
    cpArrayNew, cpArrayFree, cpArrayPush, cpHashSetNew, cpHashSetFree, cpHashSetInsert,
    cpHashSetRemove, cpHashSetFind, cpHashSetCount, cpHashSetEach)
from tamias2d._spatialindex cimport cpSpatialIndexInit, cpSpatialIndexCollideStatic
from tamias2d._structs cimport (cpHashSetEqlFunc, cpHashSetTransFunc, cpHashSetIteratorFunc,
    cpSpatialIndexDestroyImpl, cpSpatialIndexCountImpl, cpSpatialIndexEachImpl,
    cpSpatialIndexContainsImpl, cpSpatialIndexInsertImpl, cpSpatialIndexRemoveImpl,
    cpSpatialIndexReindexImpl, cpSpatialIndexReindexObjectImpl,
    cpSpatialIndexReindexQueryImpl, cpSpatialIndexQueryImpl, cpSpatialIndexSegmentQueryImpl)


# -- explicit traversal stack (47b0e6b) -----------------------------------------------
# 64 slots on the C stack, then a heap buffer that doubles. Only the LIFO order
# matters for fidelity. If growing fails, the push is dropped and the
# out-of-memory flag raised: the traversal is then incomplete, never unsafe.
cdef enum:
    STACK_INIT_SIZE = 64

cdef struct NodeStack:
    Node **items
    int top
    int cap
    Node *local[STACK_INIT_SIZE]


cdef inline void StackInit(NodeStack *s) noexcept nogil:
    s.items = s.local
    s.top = 0
    s.cap = STACK_INIT_SIZE


cdef bint StackGrow(NodeStack *s) noexcept nogil:
    cdef int new_cap = s.cap * 2
    cdef Node **grown
    if s.items == s.local:
        grown = <Node **>cpcalloc(new_cap, sizeof(Node *))
        if grown == NULL:
            return False
        memcpy(grown, s.local, s.cap * sizeof(Node *))
    else:
        grown = <Node **>cprealloc(s.items, new_cap * sizeof(Node *))
        if grown == NULL:
            return False
    s.items = grown
    s.cap = new_cap
    return True


cdef inline void StackPush(NodeStack *s, Node *node) noexcept nogil:
    if s.top >= s.cap and not StackGrow(s):
        return
    s.items[s.top] = node
    s.top += 1


cdef inline Node *StackPop(NodeStack *s) noexcept nogil:
    s.top -= 1
    return s.items[s.top]


cdef inline void StackFree(NodeStack *s) noexcept nogil:
    if s.items != s.local:
        free(s.items)


# -- misc -------------------------------------------------------------------------------
cdef cpSpatialIndexClass klass


cdef cpSpatialIndexClass *cpBBTreeClass() noexcept nogil:
    return &klass


cdef inline cpBB GetBB(cpBBTree *tree, void *obj) noexcept nogil:
    cdef cpBB bb = tree.spatialIndex.bbfunc(obj)
    cdef cpBBTreeVelocityFunc velocityFunc = tree.velocityFunc
    cdef cpFloat coef, x, y
    cdef cpVect v
    if velocityFunc != NULL:
        # Fattened box: 10% margin per side (the float literal 0.1f), grown
        # further toward where the velocity points.
        coef = TAMIAS_FLOAT_0_1F
        x = (bb.r - bb.l) * coef
        y = (bb.t - bb.b) * coef
        v = cpvmult(velocityFunc(obj), TAMIAS_FLOAT_0_1F)
        return cpBBNew(bb.l + cpfmin(-x, v.x), bb.b + cpfmin(-y, v.y),
                       bb.r + cpfmax(x, v.x), bb.t + cpfmax(y, v.y))
    return bb


cdef inline cpBBTree *GetTree(cpSpatialIndex *index) noexcept nogil:
    if index != NULL and index.klass == &klass:
        return <cpBBTree *>index
    return NULL


cdef inline Node *GetRootIfTree(cpSpatialIndex *index) noexcept nogil:
    if index != NULL and index.klass == &klass:
        return (<cpBBTree *>index).root
    return NULL


cdef inline cpBBTree *GetMasterTree(cpBBTree *tree) noexcept nogil:
    # The dynamic tree owns the stamp and the pair pool shared with its static tree.
    cdef cpBBTree *dynamicTree = GetTree(tree.spatialIndex.dynamicIndex)
    return dynamicTree if dynamicTree != NULL else tree


cdef inline void TreeChanged(cpBBTree *tree) noexcept nogil:
    GetMasterTree(tree).version += 1


cdef inline void IncrementStamp(cpBBTree *tree) noexcept nogil:
    cdef cpBBTree *dynamicTree = GetTree(tree.spatialIndex.dynamicIndex)
    if dynamicTree != NULL:
        dynamicTree.stamp += 1
    else:
        tree.stamp += 1


# -- pairs and threads ------------------------------------------------------------------
cdef void PairRecycle(cpBBTree *tree, Pair *pair) noexcept nogil:
    tree = GetMasterTree(tree)
    pair.a.next = tree.pooledPairs
    tree.pooledPairs = pair


cdef Pair *PairFromPool(cpBBTree *tree) noexcept nogil:
    tree = GetMasterTree(tree)
    cdef Pair *pair = tree.pooledPairs
    cdef int count, i
    cdef Pair *block
    if pair != NULL:
        tree.pooledPairs = pair.a.next
        return pair
    count = CP_BUFFER_BYTES // sizeof(Pair)
    block = <Pair *>cpcalloc(1, CP_BUFFER_BYTES)
    if block == NULL:
        return NULL
    if not cpArrayPush(tree.allocatedBuffers, block):
        free(block)
        return NULL
    for i in range(1, count):
        PairRecycle(tree, block + i)
    return block


cdef inline void ThreadUnlink(Thread thread) noexcept nogil:
    cdef Pair *next_pair = thread.next
    cdef Pair *prev_pair = thread.prev
    if next_pair != NULL:
        if next_pair.a.leaf == thread.leaf:
            next_pair.a.prev = prev_pair
        else:
            next_pair.b.prev = prev_pair
    if prev_pair != NULL:
        if prev_pair.a.leaf == thread.leaf:
            prev_pair.a.next = next_pair
        else:
            prev_pair.b.next = next_pair
    else:
        thread.leaf.node.leaf.pairs = next_pair


cdef void PairsClear(Node *leaf, cpBBTree *tree) noexcept nogil:
    cdef Pair *pair = leaf.node.leaf.pairs
    cdef Pair *next_pair
    if pair != NULL:
        TreeChanged(tree)
    leaf.node.leaf.pairs = NULL
    while pair != NULL:
        if pair.a.leaf == leaf:
            next_pair = pair.a.next
            ThreadUnlink(pair.b)
        else:
            next_pair = pair.b.next
            ThreadUnlink(pair.a)
        PairRecycle(tree, pair)
        pair = next_pair


cdef void PairInsert(Node *a, Node *b, cpBBTree *tree) noexcept nogil:
    cdef Pair *nextA = a.node.leaf.pairs
    cdef Pair *nextB = b.node.leaf.pairs
    cdef Pair *pair = PairFromPool(tree)
    if pair == NULL:
        return      # out of memory: the pair is lost, the flag is raised
    TreeChanged(tree)
    # The new pair goes at the head of both leaves' lists, id 0 (no cache yet).
    pair.a.prev = NULL
    pair.a.leaf = a
    pair.a.next = nextA
    pair.b.prev = NULL
    pair.b.leaf = b
    pair.b.next = nextB
    pair.slot.id = 0
    pair.slot.arbiter = NULL
    a.node.leaf.pairs = pair
    b.node.leaf.pairs = pair
    if nextA != NULL:
        if nextA.a.leaf == a:
            nextA.a.prev = pair
        else:
            nextA.b.prev = pair
    if nextB != NULL:
        if nextB.a.leaf == b:
            nextB.a.prev = pair
        else:
            nextB.b.prev = pair


# -- nodes --------------------------------------------------------------------------------
cdef inline void NodeRecycle(cpBBTree *tree, Node *node) noexcept nogil:
    node.parent = tree.pooledNodes
    tree.pooledNodes = node


cdef bint NodePoolAddBlock(cpBBTree *tree) noexcept nogil:
    cdef int count = CP_BUFFER_BYTES // sizeof(Node)
    cdef int i
    cdef Node *block = <Node *>cpcalloc(1, CP_BUFFER_BYTES)
    if block == NULL:
        return False
    if not cpArrayPush(tree.allocatedBuffers, block):
        free(block)
        return False
    for i in range(count - 1, -1, -1):
        NodeRecycle(tree, block + i)
    return True


cdef Node *NodeFromPool(cpBBTree *tree) noexcept nogil:
    cdef Node *node = tree.pooledNodes
    if node == NULL:
        if not NodePoolAddBlock(tree):
            return NULL
        node = tree.pooledNodes
    tree.pooledNodes = node.parent
    return node


cdef bint NodePoolReserve(cpBBTree *tree, int n) noexcept nogil:
    # Makes sure n nodes can be taken without allocating, so an insertion
    # never fails half way through the tree surgery.
    cdef Node *node = tree.pooledNodes
    cdef int have = 0
    while node != NULL and have < n:
        have += 1
        node = node.parent
    return have >= n or NodePoolAddBlock(tree)


cdef inline void NodeSetA(Node *node, Node *value) noexcept nogil:
    node.node.children.a = value
    value.parent = node


cdef inline void NodeSetB(Node *node, Node *value) noexcept nogil:
    node.node.children.b = value
    value.parent = node


cdef Node *NodeNew(cpBBTree *tree, Node *a, Node *b) noexcept nogil:
    cdef Node *node = NodeFromPool(tree)
    if node == NULL:
        return NULL
    node.obj = NULL
    node.bb = cpBBMerge(a.bb, b.bb)
    node.parent = NULL
    NodeSetA(node, a)
    NodeSetB(node, b)
    return node


cdef inline bint NodeIsLeaf(Node *node) noexcept nogil:
    return node.obj != NULL


cdef inline Node *NodeOther(Node *node, Node *child) noexcept nogil:
    return node.node.children.b if node.node.children.a == child else node.node.children.a


cdef inline void NodeReplaceChild(Node *parent, Node *child, Node *value,
                                  cpBBTree *tree) noexcept nogil:
    cdef Node *node
    if parent.node.children.a == child:
        NodeRecycle(tree, parent.node.children.a)
        NodeSetA(parent, value)
    else:
        NodeRecycle(tree, parent.node.children.b)
        NodeSetB(parent, value)
    node = parent
    while node != NULL:
        node.bb = cpBBMerge(node.node.children.a.bb, node.node.children.b.bb)
        node = node.parent


# -- subtrees ------------------------------------------------------------------------------
cdef inline cpFloat cpBBProximity(cpBB a, cpBB b) noexcept nogil:
    return cpfabs(a.l + a.r - b.l - b.r) + cpfabs(a.b + a.t - b.b - b.t)


cdef Node *SubtreeInsert(Node *subtree, Node *leaf, cpBBTree *tree) noexcept nogil:
    # Callers reserve the one internal node this may need (NodePoolReserve).
    cdef Node *node
    cdef Node *parent
    cdef Node *newNode
    cdef cpFloat cost_a, cost_b
    if subtree == NULL:
        return leaf
    if NodeIsLeaf(subtree):
        return NodeNew(tree, leaf, subtree)
    node = subtree
    while not NodeIsLeaf(node):
        # Cost of descending into a child: its growth plus the sibling's area.
        cost_a = cpBBArea(node.node.children.b.bb) + cpBBMergedArea(node.node.children.a.bb, leaf.bb)
        cost_b = cpBBArea(node.node.children.a.bb) + cpBBMergedArea(node.node.children.b.bb, leaf.bb)
        if cost_a == cost_b:
            cost_a = cpBBProximity(node.node.children.a.bb, leaf.bb)
            cost_b = cpBBProximity(node.node.children.b.bb, leaf.bb)
        if cost_b < cost_a:
            node = node.node.children.b
        else:
            node = node.node.children.a
    # Pair the leaf found with the new one (new leaf at A) in its place.
    parent = node.parent
    newNode = NodeNew(tree, leaf, node)
    if parent.node.children.a == node:
        NodeSetA(parent, newNode)
    else:
        NodeSetB(parent, newNode)
    while parent != NULL:
        parent.bb = cpBBMerge(parent.bb, leaf.bb)
        parent = parent.parent
    return subtree


cdef void SubtreeQuery(Node *subtree, void *obj, cpBB bb, cpSpatialIndexQueryFunc func,
                       void *data) noexcept nogil:
    cdef NodeStack stack
    cdef Node *node
    StackInit(&stack)
    StackPush(&stack, subtree)
    while stack.top > 0:
        node = StackPop(&stack)
        if cpBBIntersects(node.bb, bb):
            if NodeIsLeaf(node):
                func(obj, node.obj, 0, data)
            else:
                # B pushed first so that A is visited first.
                StackPush(&stack, node.node.children.b)
                StackPush(&stack, node.node.children.a)
    StackFree(&stack)


cdef cpFloat SubtreeSegmentQuery(Node *subtree, void *obj, cpVect a, cpVect b, cpFloat t_exit,
                                 cpSpatialIndexSegmentQueryFunc func, void *data) noexcept nogil:
    cdef NodeStack stack
    cdef Node *node
    cdef cpFloat t_a, t_b
    StackInit(&stack)
    StackPush(&stack, subtree)
    while stack.top > 0:
        node = StackPop(&stack)
        if NodeIsLeaf(node):
            t_exit = cpfmin(t_exit, func(obj, node.obj, data))
        else:
            t_a = cpBBSegmentQuery(node.node.children.a.bb, a, b)
            t_b = cpBBSegmentQuery(node.node.children.b.bb, a, b)
            # Children are tested against t_exit now, when pushed (47b0e6b);
            # the nearer one is pushed last so it is visited first, B on a tie.
            if t_a < t_b:
                if t_b < t_exit:
                    StackPush(&stack, node.node.children.b)
                if t_a < t_exit:
                    StackPush(&stack, node.node.children.a)
            else:
                if t_a < t_exit:
                    StackPush(&stack, node.node.children.a)
                if t_b < t_exit:
                    StackPush(&stack, node.node.children.b)
    StackFree(&stack)
    return t_exit


cdef void SubtreeRecycle(cpBBTree *tree, Node *root, Node **leaves, int count) noexcept nogil:
    # Returns every internal node under root to the pool. Munk2D walks the
    # subtree with a stack; walking up from each leaf needs no memory and
    # recycles the same nodes (only the pool order differs, which nothing
    # observes). An internal node is marked visited by clearing child A.
    cdef int i
    cdef Node *node
    cdef Node *up
    if NodeIsLeaf(root):
        return
    for i in range(count):
        node = leaves[i].parent
        leaves[i].parent = NULL
        while node != NULL and node.node.children.a != NULL:
            up = node.parent
            node.node.children.a = NULL
            NodeRecycle(tree, node)
            node = up


cdef inline Node *SubtreeRemove(Node *subtree, Node *leaf, cpBBTree *tree) noexcept nogil:
    cdef Node *parent
    cdef Node *other
    if leaf == subtree:
        return NULL
    parent = leaf.parent
    if parent == subtree:
        other = NodeOther(subtree, leaf)
        other.parent = subtree.parent
        NodeRecycle(tree, subtree)
        return other
    NodeReplaceChild(parent.parent, parent, NodeOther(parent, leaf), tree)
    return subtree


# -- marking: pair generation ----------------------------------------------------------------
cdef struct MarkContext:
    cpBBTree *tree
    Node *staticRoot
    cpSpatialIndexQueryFunc func
    void *data
    # Set by cpBBTreeReindexCollect instead of func: pairs are written there
    # with where their id lives, for the caller to store it later.
    cpPairCollector *collector


cdef inline cpBB GrownBB(cpBB bb, cpFloat reach) noexcept nogil:
    if reach == 0.0:
        return bb
    return cpBBNew(bb.l - reach, bb.b - reach, bb.r + reach, bb.t + reach)


cdef inline void CollectPair(cpPairCollector *c, void *a, void *b,
                             cpPairSlot *slot) noexcept nogil:
    # A pair into the collector (inline: the walk writes every pair, and a
    # call through a pointer for each cost more than the writing).
    cdef int n = c.count
    cdef cpCollectedPair *p
    if slot == NULL or n >= c.cap:
        c.complete = 0
        if n >= c.cap:
            return
    p = &c.pairs[n]
    p.a = a
    p.b = b
    p.slot = slot
    c.count = n + 1
    if n + 1 == c.cap:
        c.grow(c)


cdef void MarkLeafQuery(Node *subtree, Node *leaf, cpBB bb, bint left,
                        MarkContext *context) noexcept nogil:
    # The leaves of `subtree` whose boxes meet `bb` (the box of `leaf`, or
    # more around it against the static tree) are paired with `leaf`.
    cdef NodeStack stack
    cdef Node *node
    StackInit(&stack)
    StackPush(&stack, subtree)
    while stack.top > 0:
        node = StackPop(&stack)
        if cpBBIntersects(bb, node.bb):
            if NodeIsLeaf(node):
                if left:
                    PairInsert(leaf, node, context.tree)
                else:
                    if node.node.leaf.stamp < leaf.node.leaf.stamp:
                        PairInsert(node, leaf, context.tree)
                    if context.collector != NULL:
                        CollectPair(context.collector, leaf.obj, node.obj, NULL)
                    else:
                        context.func(leaf.obj, node.obj, 0, context.data)
            else:
                StackPush(&stack, node.node.children.b)
                StackPush(&stack, node.node.children.a)
    StackFree(&stack)


cdef void MarkLeaf(Node *leaf, MarkContext *context) noexcept nogil:
    cdef cpBBTree *tree = context.tree
    cdef Node *node
    cdef Pair *pair
    if leaf.node.leaf.stamp == GetMasterTree(tree).stamp:
        # Moved (or new) this stamp: find its pairs afresh. Against the static
        # tree, and against each ancestor's other subtree: a right sibling only
        # records pairs, a left sibling also reports them.
        if context.staticRoot != NULL:
            MarkLeafQuery(context.staticRoot, leaf, GrownBB(leaf.bb, tree.staticReach),
                          False, context)
        node = leaf
        while node.parent != NULL:
            if node == node.parent.node.children.a:
                MarkLeafQuery(node.parent.node.children.b, leaf, leaf.bb, True, context)
            else:
                MarkLeafQuery(node.parent.node.children.a, leaf, leaf.bb, False, context)
            node = node.parent
    else:
        # Unchanged: replay the cached pairs where this leaf is side b, storing
        # the narrow phase's id back into the pair.
        pair = leaf.node.leaf.pairs
        while pair != NULL:
            if leaf == pair.b.leaf:
                # The narrow phase takes long: fetch the next pair meanwhile
                # (walking the pairs is otherwise a cache miss per pair).
                tamias_prefetch(pair.b.next)
                if context.collector != NULL:
                    CollectPair(context.collector, pair.a.leaf.obj, leaf.obj, &pair.slot)
                else:
                    pair.slot.id = context.func(pair.a.leaf.obj, leaf.obj, pair.slot.id, context.data)
                pair = pair.b.next
            else:
                pair = pair.a.next


# Unchanged leaves whose pair lists are walked together before they are
# replayed (MarkSubtree, when pairs are only collected).
cdef enum:
    MARK_BATCH = 32
    # Below this many leaves the tree and its pairs stay in cache, and the
    # second walk of each pair list would only add instructions (the rain of
    # 520 circles: 0.13 M a step, 3% of it).
    MARK_BATCH_MIN_LEAVES = 1024


cdef void FetchPairLists(Node **leaves, int count) noexcept nogil:
    # Walk the pair lists of `count` leaves side by side, reading each pair
    # once, so that MarkLeaf then finds them in cache. A list is a chain of
    # pairs scattered in memory, each read waiting for the one before;
    # walked side by side, the chains' reads overlap. (Only reads: the
    # replay that follows reports the same pairs in the same order.)
    cdef Pair *cursor[MARK_BATCH]
    cdef Pair *pair
    cdef int i, active = count
    for i in range(count):
        cursor[i] = leaves[i].node.leaf.pairs
    while active > 0:
        active = 0
        for i in range(count):
            pair = cursor[i]
            if pair != NULL:
                cursor[i] = pair.b.next if pair.b.leaf == leaves[i] else pair.a.next
                active += 1


cdef void MarkBatch(Node **batch, int count, MarkContext *context) noexcept nogil:
    # Leaves of a batch (MarkSubtree): their pair lists fetched, then marked.
    cdef int i
    FetchPairLists(batch, count)
    for i in range(count):
        MarkLeaf(batch[i], context)


cdef void MarkSubtree(Node *subtree, MarkContext *context) noexcept nogil:
    # The leaves in depth-first order. When pairs are only collected
    # (collector; no narrow phase runs between them to hide the misses),
    # unchanged leaves are held back in batches and their pair lists
    # fetched together first; a leaf that moved flushes the batch before
    # its own query, so the order is the same. (In small trees, no batches.)
    cdef NodeStack stack
    cdef Node *node
    cdef Node *batch[MARK_BATCH]
    cdef int held = 0
    cdef bint batching = (context.collector != NULL
                          and cpHashSetCount(context.tree.leaves) >= MARK_BATCH_MIN_LEAVES)
    cdef cpTimestamp stamp = GetMasterTree(context.tree).stamp
    StackInit(&stack)
    StackPush(&stack, subtree)
    while stack.top > 0:
        node = StackPop(&stack)
        if NodeIsLeaf(node):
            if not batching:
                MarkLeaf(node, context)
                continue
            if node.node.leaf.stamp != stamp:
                batch[held] = node
                held += 1
                if held == MARK_BATCH:
                    MarkBatch(batch, held, context)
                    held = 0
            else:
                MarkBatch(batch, held, context)
                held = 0
                MarkLeaf(node, context)
        else:
            StackPush(&stack, node.node.children.b)
            StackPush(&stack, node.node.children.a)
    MarkBatch(batch, held, context)
    StackFree(&stack)


# -- leaves ----------------------------------------------------------------------------------
cdef Node *LeafNew(cpBBTree *tree, void *obj) noexcept nogil:
    cdef Node *node = NodeFromPool(tree)
    if node == NULL:
        return NULL
    node.obj = obj
    node.bb = GetBB(tree, obj)
    if tree.fatFunc != NULL:
        tree.fatFunc(obj, node.bb)
    node.parent = NULL
    node.node.leaf.stamp = 0
    node.node.leaf.pairs = NULL
    return node


cdef bint LeafUpdate(Node *leaf, cpBBTree *tree) noexcept nogil:
    cdef Node *root = tree.root
    cdef cpBB bb = tree.spatialIndex.bbfunc(leaf.obj)
    if not cpBBContainsBB(leaf.bb, bb):
        # Left its fat box: refatten and reinsert. The removal frees the one
        # internal node the insertion takes, so this cannot run out of memory.
        leaf.bb = GetBB(tree, leaf.obj)
        if tree.fatFunc != NULL:
            tree.fatFunc(leaf.obj, leaf.bb)
        TreeChanged(tree)
        root = SubtreeRemove(root, leaf, tree)
        tree.root = SubtreeInsert(root, leaf, tree)
        PairsClear(leaf, tree)
        leaf.node.leaf.stamp = GetMasterTree(tree).stamp
        return True
    return False


cdef cpCollisionID VoidQueryFunc(void *obj1, void *obj2, cpCollisionID id, void *data) noexcept nogil:
    return id


cdef void LeafAddPairs(Node *leaf, cpBBTree *tree) noexcept nogil:
    cdef cpSpatialIndex *dynamicIndex = tree.spatialIndex.dynamicIndex
    cdef Node *dynamicRoot
    cdef MarkContext context
    if dynamicIndex != NULL:
        # A static leaf: record pairs with the dynamic tree, report nothing.
        dynamicRoot = GetRootIfTree(dynamicIndex)
        if dynamicRoot != NULL:
            context.tree = GetTree(dynamicIndex)
            context.staticRoot = NULL
            context.func = NULL
            context.data = NULL
            context.collector = NULL
            MarkLeafQuery(dynamicRoot, leaf, GrownBB(leaf.bb, context.tree.staticReach),
                          True, &context)
    else:
        context.tree = tree
        context.staticRoot = GetRootIfTree(tree.spatialIndex.staticIndex)
        context.func = VoidQueryFunc
        context.data = NULL
        context.collector = NULL
        MarkLeaf(leaf, &context)


# -- memory management ------------------------------------------------------------------------
cdef cpBBTree *cpBBTreeAlloc() noexcept nogil:
    return <cpBBTree *>cpcalloc(1, sizeof(cpBBTree))


cdef cpBool leafSetEql(const void *obj, const void *elt) noexcept nogil:
    return obj == (<Node *>elt).obj


cdef void *leafSetTrans(const void *obj, void *data) noexcept nogil:
    return LeafNew(<cpBBTree *>data, <void *>obj)


cdef cpSpatialIndex *cpBBTreeInit(cpBBTree *tree, cpSpatialIndexBBFunc bbfunc,
                                  cpSpatialIndex *staticIndex) noexcept nogil:
    if tree == NULL:
        return NULL
    if cpSpatialIndexInit(<cpSpatialIndex *>tree, &klass, bbfunc, staticIndex) == NULL:
        return NULL
    tree.velocityFunc = NULL
    tree.fatFunc = NULL
    tree.fatSynced = 0
    tree.staticReach = 0.0
    tree.leaves = cpHashSetNew(0, leafSetEql)
    tree.root = NULL
    tree.pooledNodes = NULL
    tree.pooledPairs = NULL
    tree.allocatedBuffers = cpArrayNew(0)
    tree.stamp = 0
    if tree.leaves == NULL or tree.allocatedBuffers == NULL:
        cpHashSetFree(tree.leaves)
        cpArrayFree(tree.allocatedBuffers)
        tree.leaves = NULL
        tree.allocatedBuffers = NULL
        if staticIndex != NULL:
            staticIndex.dynamicIndex = NULL
        tree.spatialIndex.klass = NULL
        return NULL
    return <cpSpatialIndex *>tree


cdef void cpBBTreeSetVelocityFunc(cpSpatialIndex *index, cpBBTreeVelocityFunc func) noexcept nogil:
    if index.klass != &klass:
        return      # not a tree: ignored, as Munk2D does (its warning is compiled out)
    (<cpBBTree *>index).velocityFunc = func


cdef void cpBBTreeSetFetchFunc(cpSpatialIndex *index, cpBBTreeFetchFunc func) noexcept nogil:
    if index.klass != &klass:
        return
    (<cpBBTree *>index).fetchFunc = func


cdef void cpBBTreeSetFatFunc(cpSpatialIndex *index, cpBBTreeFatFunc func) noexcept nogil:
    cdef cpBBTree *tree = GetTree(index)
    if tree != NULL:
        tree.fatFunc = func
        # (Leaves already there were not told their boxes.)
        tree.fatSynced = cpHashSetCount(tree.leaves) == 0


cdef void TellLeafFat(void *elt, void *data) noexcept nogil:
    cdef Node *leaf = <Node *>elt
    (<cpBBTree *>data).fatFunc(leaf.obj, leaf.bb)


cdef bint cpBBTreeSyncFat(cpSpatialIndex *index) noexcept nogil:
    # Every leaf's box told to the fat-box function, unless they all have
    # been since it was set. False without a function.
    cdef cpBBTree *tree = GetTree(index)
    if tree == NULL or tree.fatFunc == NULL:
        return 0
    if not tree.fatSynced:
        cpHashSetEach(tree.leaves, TellLeafFat, tree)
        tree.fatSynced = 1
    return 1


cdef void RequeryLeaf(void *elt, void *data) noexcept nogil:
    cdef Node *leaf = <Node *>elt
    cdef cpBBTree *tree = <cpBBTree *>data
    PairsClear(leaf, tree)
    leaf.node.leaf.stamp = tree.stamp


cdef void cpBBTreeSetStaticReach(cpSpatialIndex *index, cpFloat reach) noexcept nogil:
    cdef cpBBTree *tree = GetTree(index)
    if tree == NULL or reach == tree.staticReach:
        return
    if reach > tree.staticReach:
        # The cached pairs were looked for less far: each leaf drops them and
        # finds its pairs again in the next walk (as if it had moved).
        cpHashSetEach(tree.leaves, RequeryLeaf, tree)
    tree.staticReach = reach
    TreeChanged(tree)


cdef cpFloat cpBBTreeGetStaticReach(cpSpatialIndex *index) noexcept nogil:
    cdef cpBBTree *tree = GetTree(index)
    return tree.staticReach if tree != NULL else 0.0


cdef cpSpatialIndex *cpBBTreeNew(cpSpatialIndexBBFunc bbfunc, cpSpatialIndex *staticIndex) noexcept nogil:
    cdef cpBBTree *tree = cpBBTreeAlloc()
    if tree == NULL:
        return NULL
    if cpBBTreeInit(tree, bbfunc, staticIndex) == NULL:
        free(tree)
        return NULL
    return <cpSpatialIndex *>tree


cdef void cpBBTreeDestroy(cpSpatialIndex *index) noexcept nogil:
    cdef cpBBTree *tree = <cpBBTree *>index
    cdef int i
    cpHashSetFree(tree.leaves)
    free(tree.refreshList)
    tree.refreshList = NULL
    tree.refreshCap = 0
    if tree.allocatedBuffers != NULL:
        for i in range(tree.allocatedBuffers.num):
            free(tree.allocatedBuffers.arr[i])
    cpArrayFree(tree.allocatedBuffers)


# -- insert / remove ---------------------------------------------------------------------------
cdef void cpBBTreeInsert(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    cdef cpBBTree *tree = <cpBBTree *>index
    # The leaf and the internal node that joins it to the tree.
    if not NodePoolReserve(tree, 2):
        return
    cdef Node *leaf = <Node *>cpHashSetInsert(tree.leaves, hashid, obj, leafSetTrans, tree)
    if leaf == NULL:
        return
    TreeChanged(tree)
    tree.root = SubtreeInsert(tree.root, leaf, tree)
    leaf.node.leaf.stamp = GetMasterTree(tree).stamp
    LeafAddPairs(leaf, tree)
    IncrementStamp(tree)


cdef void cpBBTreeRemove(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    cdef cpBBTree *tree = <cpBBTree *>index
    cdef Node *leaf = <Node *>cpHashSetRemove(tree.leaves, hashid, obj)
    if leaf == NULL:
        return      # not in this tree (Munk2D would crash)
    TreeChanged(tree)
    tree.root = SubtreeRemove(tree.root, leaf, tree)
    PairsClear(leaf, tree)
    NodeRecycle(tree, leaf)


cdef cpBool cpBBTreeContains(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    return cpHashSetFind((<cpBBTree *>index).leaves, hashid, obj) != NULL


# -- reindex ------------------------------------------------------------------------------------
cdef void LeafUpdateWrap(void *elt, void *data) noexcept nogil:
    LeafUpdate(<Node *>elt, <cpBBTree *>data)


cdef struct LeafList:
    Node **items
    int count


cdef void ListLeaf(void *elt, void *data) noexcept nogil:
    cdef LeafList *list = <LeafList *>data
    list.items[list.count] = <Node *>elt
    list.count += 1


cdef void RefreshLeaves(cpBBTree *tree) noexcept nogil:
    # LeafUpdate on every leaf in the leaf set's order (Munk2D's), from a
    # list of them, so that each leaf's node, object and what its box
    # function reads (fetchFunc) are fetched a few leaves ahead: the set's
    # order is not the order they lie in memory, and the refresh was a cache
    # miss or more per leaf. (Without memory for the list: unfetched.)
    cdef int n = cpHashSetCount(tree.leaves)
    cdef Node **grown
    cdef LeafList list
    cdef int i
    if n > tree.refreshCap:
        grown = <Node **>cprealloc(tree.refreshList, n * sizeof(Node *))
        if grown == NULL:
            cpHashSetEach(tree.leaves, LeafUpdateWrap, tree)
            return
        tree.refreshList = grown
        tree.refreshCap = n
    list.items = tree.refreshList
    list.count = 0
    cpHashSetEach(tree.leaves, ListLeaf, &list)
    for i in range(list.count):
        if i + 16 < list.count:
            tamias_prefetch(list.items[i + 16])
        if i + 8 < list.count:
            tamias_prefetch(list.items[i + 8].obj)
            tamias_prefetch(<char *>list.items[i + 8].obj + 64)
        if i + 4 < list.count and tree.fetchFunc != NULL:
            tree.fetchFunc(list.items[i + 4].obj)
        LeafUpdate(list.items[i], tree)


cdef void ReindexQuery(cpBBTree *tree, cpSpatialIndexQueryFunc func, cpPairCollector *collector,
                       void *data, unsigned long long *known, bint inside) noexcept nogil:
    # Pairs go to func (the id it returns is kept) or, with a collector,
    # into it with where the id lives. Given `known`, a version of the tree
    # whose walk the caller has kept: the walk is skipped if the leaves'
    # refresh left the tree at that version (the same pairs, in the same
    # order, would be reported); otherwise set to the version after it.
    # `inside`: the caller knows that every leaf is still inside its box, so
    # the refresh would change nothing (cpBBTreeReindexCollect).
    cdef cpSpatialIndex *staticIndex
    cdef Node *staticRoot = NULL
    cdef MarkContext context
    if tree.root == NULL:
        if known != NULL:
            known[0] = 0
        return
    # Leaves are refreshed in hash-set order; LeafUpdate may change the root.
    if not inside:
        RefreshLeaves(tree)
    if known != NULL and known[0] != 0 and known[0] == tree.version:
        IncrementStamp(tree)
        return
    staticIndex = tree.spatialIndex.staticIndex
    if staticIndex != NULL and staticIndex.klass == &klass:
        staticRoot = (<cpBBTree *>staticIndex).root
    context.tree = tree
    context.staticRoot = staticRoot
    context.func = func
    context.data = data
    context.collector = collector
    MarkSubtree(tree.root, &context)
    if staticIndex != NULL and staticRoot == NULL and func != NULL:
        cpSpatialIndexCollideStatic(<cpSpatialIndex *>tree, staticIndex, func, data)
    IncrementStamp(tree)
    if known != NULL:
        known[0] = tree.version


cdef void cpBBTreeReindexQuery(cpSpatialIndex *index, cpSpatialIndexQueryFunc func,
                               void *data) noexcept nogil:
    ReindexQuery(<cpBBTree *>index, func, NULL, data, NULL, 0)


cdef bint cpBBTreeReindexCollect(cpSpatialIndex *index, cpPairCollector *collector,
                                 unsigned long long *known, bint inside) noexcept nogil:
    # cpBBTreeReindexQuery, but each pair is written into the collector with
    # a pointer to the id the tree keeps for it (NULL for a pair new this
    # step, whose id is not kept), so that the caller can run the narrow
    # phase later, and in parallel, and store the ids then. Same pairs in
    # the same order, unless `known` says that the caller has them already
    # (see ReindexQuery). False (nothing done) unless this index and its
    # static index are trees.
    cdef cpSpatialIndex *staticIndex
    if index.klass != &klass:
        return 0
    staticIndex = (<cpBBTree *>index).spatialIndex.staticIndex
    if staticIndex != NULL and staticIndex.klass != &klass:
        return 0
    ReindexQuery(<cpBBTree *>index, NULL, collector, NULL, known, inside)
    return 1


cdef void cpBBTreeReindex(cpSpatialIndex *index) noexcept nogil:
    cpBBTreeReindexQuery(index, VoidQueryFunc, NULL)


cdef void cpBBTreeReindexObject(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    cdef cpBBTree *tree = <cpBBTree *>index
    cdef Node *leaf = <Node *>cpHashSetFind(tree.leaves, hashid, obj)
    if leaf != NULL:
        if LeafUpdate(leaf, tree):
            LeafAddPairs(leaf, tree)
        IncrementStamp(tree)


# -- queries ------------------------------------------------------------------------------------
cdef void cpBBTreeSegmentQuery(cpSpatialIndex *index, void *obj, cpVect a, cpVect b, cpFloat t_exit,
                               cpSpatialIndexSegmentQueryFunc func, void *data) noexcept nogil:
    cdef Node *root = (<cpBBTree *>index).root
    if root != NULL:
        SubtreeSegmentQuery(root, obj, a, b, t_exit, func, data)


cdef void cpBBTreeQuery(cpSpatialIndex *index, void *obj, cpBB bb, cpSpatialIndexQueryFunc func,
                        void *data) noexcept nogil:
    cdef Node *root = (<cpBBTree *>index).root
    if root != NULL:
        SubtreeQuery(root, obj, bb, func, data)


cdef int cpBBTreeCount(cpSpatialIndex *index) noexcept nogil:
    return cpHashSetCount((<cpBBTree *>index).leaves)


cdef struct EachContext:
    cpSpatialIndexIteratorFunc func
    void *data


cdef void each_helper(void *elt, void *data) noexcept nogil:
    cdef EachContext *context = <EachContext *>data
    context.func((<Node *>elt).obj, context.data)


cdef void cpBBTreeEach(cpSpatialIndex *index, cpSpatialIndexIteratorFunc func, void *data) noexcept nogil:
    cdef EachContext context
    context.func = func
    context.data = data
    cpHashSetEach((<cpBBTree *>index).leaves, each_helper, &context)


klass.destroy = cpBBTreeDestroy
klass.count = cpBBTreeCount
klass.each = cpBBTreeEach
klass.contains = cpBBTreeContains
klass.insert = cpBBTreeInsert
klass.remove = cpBBTreeRemove
klass.reindex = cpBBTreeReindex
klass.reindexObject = cpBBTreeReindexObject
klass.reindexQuery = cpBBTreeReindexQuery
klass.query = cpBBTreeQuery
klass.segmentQuery = cpBBTreeSegmentQuery


# -- optimization (top-down rebuild; pymunk never calls it) --------------------------------------
cdef int cpfcompare(const void *a, const void *b) noexcept nogil:
    cdef cpFloat fa = (<const cpFloat *>a)[0]
    cdef cpFloat fb = (<const cpFloat *>b)[0]
    return -1 if fa < fb else (1 if fb < fa else 0)


cdef struct FillCursor:
    Node **cursor


cdef void fillNodeArray(void *elt, void *data) noexcept nogil:
    cdef FillCursor *c = <FillCursor *>data
    c.cursor[0] = <Node *>elt
    c.cursor += 1


cdef Node *partitionNodes(cpBBTree *tree, Node **nodes, int count, cpFloat *bounds) noexcept nogil:
    # `bounds` is scratch space for 2*count values, allocated once by the caller
    # (Munk2D allocates it per call; the values and the split are the same).
    cdef int i, left, right
    cdef cpBB bb, a, b
    cdef bint splitWidth
    cdef cpFloat split
    cdef Node *node
    if count == 1:
        return nodes[0]
    elif count == 2:
        return NodeNew(tree, nodes[0], nodes[1])
    bb = nodes[0].bb
    for i in range(1, count):
        bb = cpBBMerge(bb, nodes[i].bb)
    # Split the longer axis at the median of the boxes' bounds.
    splitWidth = (bb.r - bb.l) > (bb.t - bb.b)
    if splitWidth:
        for i in range(count):
            bounds[2 * i + 0] = nodes[i].bb.l
            bounds[2 * i + 1] = nodes[i].bb.r
    else:
        for i in range(count):
            bounds[2 * i + 0] = nodes[i].bb.b
            bounds[2 * i + 1] = nodes[i].bb.t
    qsort(bounds, count * 2, sizeof(cpFloat), cpfcompare)
    split = (bounds[count - 1] + bounds[count]) * 0.5
    a = bb
    b = bb
    if splitWidth:
        a.r = split
        b.l = split
    else:
        a.t = split
        b.b = split
    right = count
    left = 0
    while left < right:
        node = nodes[left]
        if cpBBMergedArea(node.bb, b) < cpBBMergedArea(node.bb, a):
            right -= 1
            nodes[left] = nodes[right]
            nodes[right] = node
        else:
            left += 1
    if right == count or right == 0:
        # No useful split: insert one by one. (Munk2D tests right == count
        # only; right == 0 would make it read past the array.)
        node = NULL
        for i in range(count):
            node = SubtreeInsert(node, nodes[i], tree)
        return node
    return NodeNew(tree, partitionNodes(tree, nodes, right, bounds),
                   partitionNodes(tree, nodes + right, count - right, bounds))


cdef void cpBBTreeOptimize(cpSpatialIndex *index) noexcept nogil:
    if index.klass != &klass:
        return
    cdef cpBBTree *tree = <cpBBTree *>index
    cdef Node *root = tree.root
    cdef int count
    cdef Node **nodes
    cdef cpFloat *bounds
    cdef FillCursor cursor
    if root == NULL:
        return
    count = cpBBTreeCount(index)
    nodes = <Node **>cpcalloc(count, sizeof(Node *))
    bounds = <cpFloat *>cpcalloc(2 * count, sizeof(cpFloat))
    if nodes == NULL or bounds == NULL:
        free(nodes)
        free(bounds)
        return      # out of memory: the tree is left as it was
    cursor.cursor = nodes
    cpHashSetEach(tree.leaves, fillNodeArray, &cursor)
    # The rebuild takes exactly as many internal nodes as this returns to the pool.
    TreeChanged(tree)
    SubtreeRecycle(tree, root, nodes, count)
    tree.root = partitionNodes(tree, nodes, count, bounds)
    free(nodes)
    free(bounds)
