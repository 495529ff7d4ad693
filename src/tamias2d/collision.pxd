# Collision Solver module (MIS section 10): the narrow phase of Munk2D
# (cpCollision.c, cpRobust.c) and the contact impulse helpers that the solver
# shares with the joints (chipmunk_private.h).
#
# C level: cpCollide is what the space calls for every candidate pair in its
# step; cpShapesCollide is the one-shot query. Both run without the GIL and
# never call into Python. Anything that Munk2D would assert about (an
# internal error, a GJK/EPA run that needed many iterations) is recorded in
# per-thread flags; the caller turns them into Python exceptions or warnings
# after the C call has returned, with collision_check_flags().
from tamias2d._config cimport cpFloat, cpHashValue, cpCollisionID, cpBool
from tamias2d._structs cimport (cpBody, cpShape, cpContact, cpCollisionInfo,
    cpContactPointSet, CP_NUM_SHAPES)
from tamias2d.vector cimport (cpVect, cpv, cpvadd, cpvsub, cpvneg, cpvmult,
    cpvdot, cpvcross, cpvperp)

# -- contact impulse helpers (chipmunk_private.h) ------------------------------
# MIS section 10 names them in this module; the one copy is in _private.pxd
# (beneath body, which applies impulses too). Re-exported here.
from tamias2d._private cimport (relative_velocity, normal_relative_velocity,
    apply_impulse, apply_impulses, apply_bias_impulse, apply_bias_impulses,
    k_scalar_body, k_scalar)

# -- narrow phase ----------------------------------------------------------------
# The collision of two shapes with cached world data (cpShapeCacheBB).
# `id` is the GJK warm-start id cached by the broad phase (0: none); the
# updated id is returned in the info. Contacts (at most 2) are written to
# `contacts` with absolute positions r1 (on info.a) and r2 (on info.b);
# info.a/info.b may be the arguments swapped (shape types sorted). Points are
# kept up to a separation of `margin` (0: touching only, as Munk2D; the soft
# solver's speculative distance otherwise).
cdef cpCollisionInfo cpCollide(const cpShape *a, const cpShape *b, cpCollisionID id,
                               cpContact *contacts, cpFloat margin) noexcept nogil

# cpCollide as the soft solver runs it: the same but for polygon pairs whose
# cores overlap, which take the separating-axis test instead of GJK and EPA
# (the same axis, found faster; not Munk2D's bits).
cdef cpCollisionInfo cpCollideSoft(const cpShape *a, const cpShape *b, cpCollisionID id,
                                   cpContact *contacts, cpFloat margin) noexcept nogil

# Contact points of two shapes oriented a -> b, as the query API reports them.
cdef cpContactPointSet cpShapesCollide(const cpShape *a, const cpShape *b) noexcept nogil

# The collision table, indexed by a.type + b.type*CP_NUM_SHAPES; only the slots
# with a.type <= b.type collide, the others raise the UNSORTED flag. cpCollide
# sorts the pair before indexing it; the table is exported for the tests of
# the unsorted slots (_testing._collision_table_call).
ctypedef void (*CollisionFunc)(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil
cdef CollisionFunc CollisionFuncs[9]

# The soft solver's table (cpCollideSoft's), and the slots no sorted pair
# reaches (they raise the UNSORTED flag).
cdef CollisionFunc SoftCollisionFuncs[9]
cdef void CollisionError_(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil

# The collision of a pair by a table, written into *info: cpCollide and
# cpCollideSoft, and inline in the soft step's narrow phase
# (cpCollideSoftInto), which runs it for every pair its rejection lets
# through: there the call and the copy of a returned struct cost about as
# much as a pair of circles' collision.
cdef inline void CollideInto(const CollisionFunc *funcs, const cpShape *a, const cpShape *b,
                             cpCollisionID id, cpContact *contacts, cpFloat margin,
                             cpCollisionInfo *info) noexcept nogil:
    cdef const cpShape *swap
    cdef unsigned int index
    # The table holds one function per unordered pair of types. (Sorted in
    # locals first: through *info each would be read back after a store.)
    if a.klass.type > b.klass.type:
        swap = a
        a = b
        b = swap
    index = <unsigned int>a.klass.type + <unsigned int>b.klass.type * CP_NUM_SHAPES
    info.margin = margin
    info.a = a
    info.b = b
    info.id = id
    info.n = cpv(0.0, 0.0)
    info.count = 0
    info.arr = contacts
    if index < 9:
        funcs[index](a, b, info)
    else:
        CollisionError_(a, b, info)

cdef inline void cpCollideSoftInto(const cpShape *a, const cpShape *b, cpCollisionID id,
                                   cpContact *contacts, cpFloat margin,
                                   cpCollisionInfo *info) noexcept nogil:
    CollideInto(SoftCollisionFuncs, a, b, id, contacts, margin, info)

# The C shape of a Python Circle/Segment/Poly; TypeError/ValueError (and NULL)
# for anything else, a bare Shape or a polygon without vertices.
cdef const cpShape *shape_pointer(object shape, str what) except NULL

# -- diagnostics: flags recorded by the C code, read by the Python layer -----------
cdef enum:
    CP_COLLISION_FLAG_GJK_WARN = 1        # GJK reached WARN_GJK_ITERATIONS
    CP_COLLISION_FLAG_EPA_WARN = 2        # EPA reached WARN_EPA_ITERATIONS
    CP_COLLISION_FLAG_UNSORTED = 4        # the table was called with unsorted types
    CP_COLLISION_FLAG_OVERFLOW = 8        # more than CP_MAX_CONTACTS_PER_ARBITER pushed
    CP_COLLISION_FLAG_SAME_VERTICES = 16  # EPA's closest hull edge had equal ends

# Read and clear this thread's flags (no GIL needed).
cdef unsigned int cpCollisionTakeFlags() noexcept nogil
# Read this thread's flags, leaving them set.
cdef unsigned int cpCollisionPeekFlags() noexcept nogil

# A thread's flags with the iteration counts of its warnings. step_spaces
# takes them from the worker thread that stepped a space and puts them into
# the thread that checks that space's step (the flags are per thread).
cdef struct CollisionDiagnostics:
    unsigned int flags
    int gjk_iter
    int epa_iter

# Read and clear all of this thread's diagnostics.
cdef CollisionDiagnostics cpCollisionTakeDiagnostics() noexcept nogil
# Merge `d` into this thread's diagnostics.
cdef void cpCollisionPutDiagnostics(CollisionDiagnostics d) noexcept nogil
# Read and clear the flags, then raise CollisionError / CollisionContactOverflow
# or warn HighIterWarning as they say. Returns 0, or -1 with an exception set.
cdef int collision_check_flags() except -1

# -- Python-level contact point sets (pymunk.ContactPoint / ContactPointSet) --------
cdef class ContactPoint:
    cdef public object point_a
    """The contact point on the surface of the first shape (a Vec2d, world
    coordinates)."""
    cdef public object point_b
    """The contact point on the surface of the second shape (a Vec2d, world
    coordinates)."""
    cdef public object distance
    """Signed distance of the two points along the normal: negative when the
    shapes overlap (the depth of the overlap), positive for a speculative
    contact of the soft solver that has not closed yet."""

cdef class ContactPointSet:
    cdef public object normal
    """The collision normal (a unit Vec2d), pointing from the first shape
    towards the second."""
    cdef public object points
    """A tuple of the contacts: zero, one or two :class:`ContactPoint`."""

# A ContactPointSet holding the first `count` points of a C set.
cdef ContactPointSet contact_point_set_from_cp(const cpContactPointSet *cps)
