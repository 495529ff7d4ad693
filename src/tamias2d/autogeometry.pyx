# Automatic geometry: Munk2D's marching squares (cpMarch.c) and polyline
# tools (cpPolyline.c) with pymunk 7.3's pymunk.autogeometry API.
#
# The arithmetic follows the C code expression by expression (same lerps,
# same association, same comparison order), so every vertex is bitwise equal
# to pymunk's. Three things are done differently, none visible in a result
# pymunk can produce:
# - recursion (Douglas-Peucker, the concave decomposition) runs on explicit
#   heap stacks in the same visiting order, so a long polyline cannot
#   overflow the C stack;
# - memory comes from malloc with a MemoryError on failure;
# - inputs on which Munk2D reads out of bounds, loops forever or recurses
#   without end raise IllegalPolyline (a ValueError and AssertionError).
"""Geometry from images and polylines: marching squares, simplification,
convex hulls and an approximate convex decomposition (pymunk's
``pymunk.autogeometry``).

:func:`march_soft` and :func:`march_hard` sample a function over a grid and
trace the contour where it crosses a threshold, giving a :class:`PolylineSet`.
Each polyline is a list of :class:`~tamias2d.Vec2d`; a closed one ends on its
first vertex.

>>> from tamias2d import BB
>>> from tamias2d.autogeometry import march_hard, simplify_vertexes
>>> picture = ["......",
...            ".####.",
...            ".####.",
...            "......"]
>>> def solid(point):
...     x, y = point
...     return 1.0 if picture[int(y)][int(x)] == "#" else 0.0
>>> outlines = march_hard(BB(0, 0, 5, 3), 6, 4, 0.5, solid)
>>> len(outlines)
1
>>> simplify_vertexes(outlines[0], 0.1)
[Vec2d(4.5, 2.5), Vec2d(0.5, 2.5), Vec2d(0.5, 0.5), Vec2d(4.5, 0.5), Vec2d(4.5, 2.5)]

The results equal pymunk's point for point. Where pymunk would crash, hang
or read garbage (an empty polyline, zero samples, a negative simplification
tolerance, a sample function that raises) a Python exception is raised
instead; an exception raised by the sample function propagates out of the
march (pymunk prints it and goes on with 0).
"""
from collections.abc import Sequence as _Sequence

from cpython.number cimport PyNumber_Index
from cpython.float cimport PyFloat_CheckExact, PyFloat_AS_DOUBLE
from libc.stdlib cimport malloc, calloc, realloc, free
from libc.string cimport memmove, memcpy
from libc.math cimport cos, fabs, isfinite, INFINITY
from libc.limits cimport INT_MAX, ULONG_MAX

from tamias2d._config cimport cpFloat, cpBool
from tamias2d.vector cimport (cpVect, cpBB, cpv, cpveql, cpvsub, cpvdot, cpvcross,
    cpvperp, cpvrperp, cpvnormalize, cpvdist, cpvnear, cpvlerp, cpflerp,
    vec2d_from_cpv, cpv_from_object, cpbb_from_object)
from tamias2d.shape cimport cpConvexHull, cpLoopIndexes, cpAreaForPoly

from tamias2d.errors import IllegalPolyline
from tamias2d.vector import Vec2d
from tamias2d.shape import area_for_poly

__docformat__ = "reStructuredText"

__all__ = ["is_closed", "simplify_curves", "simplify_vertexes", "to_convex_hull",
           "convex_decomposition", "PolylineSet", "march_soft", "march_hard"]


# -- growable vertex arrays (cpPolyline) -----------------------------------------------

ctypedef struct Polyline:
    Py_ssize_t count
    Py_ssize_t capacity
    cpVect *verts

# Munk2D's smallest polyline capacity; only memory use depends on it.
cdef enum:
    DEFAULT_POLYLINE_CAPACITY = 16

cdef inline Py_ssize_t Next(Py_ssize_t i, Py_ssize_t count) noexcept nogil:
    return (i + 1) % count

cdef int pl_reserve(Polyline *line, Py_ssize_t need) noexcept nogil:
    """Room for `need` vertices; -1 (line unchanged) when out of memory."""
    cdef Py_ssize_t capacity = line.capacity if line.capacity > 0 else DEFAULT_POLYLINE_CAPACITY
    cdef cpVect *verts
    if need <= line.capacity:
        return 0
    while capacity < need:
        if capacity > (<Py_ssize_t>1 << 58):
            return -1
        capacity *= 2
    verts = <cpVect *>realloc(line.verts, capacity * sizeof(cpVect))
    if verts == NULL:
        return -1
    line.verts = verts
    line.capacity = capacity
    return 0

cdef int pl_push(Polyline *line, cpVect v) noexcept nogil:
    # cpPolylinePush: v onto the end.
    if pl_reserve(line, line.count + 1) < 0:
        return -1
    line.verts[line.count] = v
    line.count += 1
    return 0

cdef int pl_enqueue(Polyline *line, cpVect v) noexcept nogil:
    # cpPolylineEnqueue: v onto the beginning.
    if pl_reserve(line, line.count + 1) < 0:
        return -1
    memmove(line.verts + 1, line.verts, line.count * sizeof(cpVect))
    line.verts[0] = v
    line.count += 1
    return 0

cdef inline void pl_free(Polyline *line) noexcept nogil:
    free(line.verts)
    line.verts = NULL
    line.count = 0
    line.capacity = 0

cdef inline cpBool pl_is_closed(const cpVect *verts, Py_ssize_t count) noexcept nogil:
    # cpPolylineIsClosed
    return count > 1 and cpveql(verts[0], verts[count - 1])

cdef list pl_to_list(const cpVect *verts, Py_ssize_t count):
    cdef Py_ssize_t i
    return [vec2d_from_cpv(verts[i]) for i in range(count)]

cdef int _no_memory() except -1:
    raise MemoryError("out of memory in tamias2d.autogeometry")


cdef class _Verts:
    # A C copy of a Python polyline, freed with the object.
    cdef cpVect *verts
    cdef Py_ssize_t count

    def __dealloc__(self):
        free(self.verts)


cdef _Verts _read_polyline(object polyline, Py_ssize_t min_count, str fname):
    """The polyline's vertices as a C array (room for one more vertex)."""
    cdef _Verts buf = _Verts.__new__(_Verts)
    cdef Py_ssize_t n, i
    if isinstance(polyline, (str, bytes)):
        raise TypeError(f"{fname}: polyline must be a sequence of (x, y) pairs, not a string")
    try:
        items = list(polyline)
    except TypeError:
        raise TypeError(f"{fname}: polyline must be a sequence of (x, y) pairs, not "
                        f"{type(polyline).__name__}") from None
    n = len(items)
    if n < min_count:
        raise IllegalPolyline(f"{fname} needs a polyline of at least {min_count} "
                              f"vert{'ex' if min_count == 1 else 'ices'}, got {n}")
    if n > INT_MAX // 4:
        raise IllegalPolyline(f"{fname}: too many vertices ({n})")
    buf.verts = <cpVect *>malloc((n + 1) * sizeof(cpVect))
    if buf.verts == NULL:
        raise MemoryError()
    buf.count = n
    for i in range(n):
        buf.verts[i] = cpv_from_object(items[i])
    return buf


cdef double _tolerance(object tolerance, str fname) except? -1.0:
    cdef double tol
    try:
        tol = tolerance
    except TypeError:
        raise TypeError(f"{fname}: tolerance must be a number, not "
                        f"{type(tolerance).__name__}") from None
    if not isfinite(tol):
        raise IllegalPolyline(f"{fname}: tolerance must be finite, got {tol!r}")
    return tol


# -- is_closed ---------------------------------------------------------------------------

def is_closed(polyline):
    """True if the polyline's first vertex equals its last (and it has at
    least two).

    >>> is_closed([(0, 0), (1, 0), (0, 1), (0, 0)])
    True
    >>> is_closed([(0, 0), (1, 0), (0, 1)])
    False
    """
    cdef _Verts line = _read_polyline(polyline, 0, "is_closed")
    return bool(pl_is_closed(line.verts, line.count))


# -- simplify_vertexes (cpPolylineSimplifyVertexes) ----------------------------------------

cdef inline cpFloat Sharpness(cpVect a, cpVect b, cpVect c) noexcept nogil:
    # Cosine of the angle at b: -1 for a straight line, 1 for a spike.
    return cpvdot(cpvnormalize(cpvsub(a, b)), cpvnormalize(cpvsub(c, b)))

def simplify_vertexes(polyline, tolerance):
    """A copy of the polyline without its "flat" vertices: a vertex goes when
    the path turns by less than ``tolerance`` radians there. Suits
    straight-edged shapes.

    >>> simplify_vertexes([(0, 0), (5, 0.1), (10, 0), (10, 10)], 0.1)
    [Vec2d(0.0, 0.0), Vec2d(10.0, 0.0), Vec2d(10.0, 10.0)]

    :param polyline: at least two (x, y) vertices.
    :param float tolerance: the largest turn (radians) that still counts as flat.
    :rtype: list of Vec2d
    """
    cdef _Verts line = _read_polyline(polyline, 2, "simplify_vertexes")
    cdef cpFloat tol = _tolerance(tolerance, "simplify_vertexes")
    cdef Polyline reduced
    cdef cpFloat minSharp = -cos(tol)
    cdef cpFloat sharp
    cdef cpVect vert
    cdef Py_ssize_t i
    reduced.count = 0
    reduced.capacity = 0
    reduced.verts = NULL
    try:
        if pl_reserve(&reduced, line.count) < 0:
            _no_memory()
        reduced.verts[0] = line.verts[0]
        reduced.verts[1] = line.verts[1]
        reduced.count = 2
        for i in range(2, line.count):
            vert = line.verts[i]
            sharp = Sharpness(reduced.verts[reduced.count - 2], reduced.verts[reduced.count - 1], vert)
            if sharp <= minSharp:
                # flat enough: the new vertex replaces the last one
                reduced.verts[reduced.count - 1] = vert
            elif pl_push(&reduced, vert) < 0:
                _no_memory()
        if (pl_is_closed(line.verts, line.count)
                and Sharpness(reduced.verts[reduced.count - 2], reduced.verts[0],
                              reduced.verts[1]) < minSharp):
            # the seam of a loop is flat too: drop it
            reduced.verts[0] = reduced.verts[reduced.count - 2]
            reduced.count -= 1
        return pl_to_list(reduced.verts, reduced.count)
    finally:
        pl_free(&reduced)


# -- simplify_curves (cpPolylineSimplifyCurves, Douglas-Peucker) --------------------------

cdef cpBool IsShort(const cpVect *points, Py_ssize_t count, Py_ssize_t start, Py_ssize_t end,
                    cpFloat vmin) noexcept nogil:
    # cpPolylineIsShort: is the path start..end (wrapping) at most vmin long?
    cdef cpFloat length = 0.0
    cdef Py_ssize_t i = start
    while i != end:
        length += cpvdist(points[i], points[Next(i, count)])
        if length > vmin:
            return False
        i = Next(i, count)
    return True

ctypedef struct DPTask:
    Py_ssize_t start
    Py_ssize_t end      # -1: emit vertex `start` instead of reducing a range

cdef int DouglasPeucker(const cpVect *verts, Polyline *reduced, Py_ssize_t length,
                        Py_ssize_t start, Py_ssize_t end, cpFloat vmin, cpFloat tol) noexcept nogil:
    # Munk2D's recursion "reduce(start, maxi); push(maxi); reduce(maxi, end)"
    # as a loop over a stack of tasks, pushed in reverse so they pop in the
    # recursion's order. -1 when out of memory.
    cdef DPTask *stack = NULL
    cdef DPTask *grown
    cdef Py_ssize_t size = 0, capacity = 64
    cdef Py_ssize_t i, maxi
    cdef cpVect a, b, n
    cdef cpFloat d, dist, vmax
    cdef DPTask task
    cdef int status = 0
    stack = <DPTask *>malloc(capacity * sizeof(DPTask))
    if stack == NULL:
        return -1
    stack[0].start = start
    stack[0].end = end
    size = 1
    while size > 0:
        size -= 1
        task = stack[size]
        if task.end < 0:
            if pl_push(reduced, verts[task.start]) < 0:
                status = -1
                break
            continue
        start = task.start
        end = task.end
        # adjacent points: nothing in between
        if (end - start + length) % length < 2:
            continue
        a = verts[start]
        b = verts[end]
        # a short stretch between close ends goes as a whole
        if cpvnear(a, b, vmin) and IsShort(verts, length, start, end, vmin):
            continue
        # the vertex farthest from the chord a-b
        vmax = 0.0
        maxi = start
        n = cpvnormalize(cpvperp(cpvsub(b, a)))
        d = cpvdot(n, a)
        i = Next(start, length)
        while i != end:
            dist = fabs(cpvdot(n, verts[i]) - d)
            if dist > vmax:
                vmax = dist
                maxi = i
            i = Next(i, length)
        if vmax > tol:
            if size + 3 > capacity:
                capacity *= 2
                grown = <DPTask *>realloc(stack, capacity * sizeof(DPTask))
                if grown == NULL:
                    status = -1
                    break
                stack = grown
            stack[size].start = maxi
            stack[size].end = end
            stack[size + 1].start = maxi
            stack[size + 1].end = -1
            stack[size + 2].start = start
            stack[size + 2].end = maxi
            size += 3
    free(stack)
    return status

def simplify_curves(polyline, tolerance):
    """A copy of the polyline simplified with the Douglas-Peucker algorithm:
    no point of the original is farther than ``tolerance`` from the result.
    Suits smooth, gently curved shapes.

    >>> simplify_curves([(0, 0), (1, 0.05), (2, 0), (3, 2), (4, 0)], 0.5)
    [Vec2d(0.0, 0.0), Vec2d(2.0, 0.0), Vec2d(3.0, 2.0), Vec2d(4.0, 0.0)]

    :param polyline: at least one (x, y) vertex.
    :param float tolerance: the largest error allowed (>= 0).
    :rtype: list of Vec2d
    """
    cdef _Verts line = _read_polyline(polyline, 1, "simplify_curves")
    cdef cpFloat tol = _tolerance(tolerance, "simplify_curves")
    cdef Polyline reduced
    cdef cpFloat vmin = tol / 2.0
    cdef int start, end
    cdef Py_ssize_t count = line.count
    cdef const cpVect *verts = line.verts
    if tol < 0.0:
        # Munk2D recurses forever on collinear points with tol < 0
        raise IllegalPolyline(f"simplify_curves: tolerance must be >= 0, got {tol!r}")
    reduced.count = 0
    reduced.capacity = 0
    reduced.verts = NULL
    try:
        if pl_reserve(&reduced, count) < 0:
            _no_memory()
        if pl_is_closed(verts, count):
            # a loop is split at its extreme points, each half reduced
            cpLoopIndexes(verts, <int>(count - 1), &start, &end)
            if (pl_push(&reduced, verts[start]) < 0
                    or DouglasPeucker(verts, &reduced, count - 1, start, end, vmin, tol) < 0
                    or pl_push(&reduced, verts[end]) < 0
                    or DouglasPeucker(verts, &reduced, count - 1, end, start, vmin, tol) < 0
                    or pl_push(&reduced, verts[start]) < 0):
                _no_memory()
        else:
            if (pl_push(&reduced, verts[0]) < 0
                    or DouglasPeucker(verts, &reduced, count, 0, count - 1, vmin, tol) < 0
                    or pl_push(&reduced, verts[count - 1]) < 0):
                _no_memory()
        return pl_to_list(reduced.verts, reduced.count)
    finally:
        pl_free(&reduced)


# -- to_convex_hull (cpPolylineToConvexHull) ----------------------------------------------

def to_convex_hull(polyline, tolerance):
    """The convex hull of the polyline's vertices as a closed polyline
    (counter-clockwise, from the lowest-x vertex). Vertices closer than
    ``tolerance`` to a hull edge are left out.

    >>> to_convex_hull([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2)], 0.0)
    [Vec2d(0.0, 0.0), Vec2d(2.0, 0.0), Vec2d(2.0, 2.0), Vec2d(0.0, 2.0), Vec2d(0.0, 0.0)]

    :param polyline: at least one (x, y) vertex.
    :param float tolerance: how far inside a hull edge a vertex may be dropped.
    :rtype: list of Vec2d
    """
    cdef _Verts line = _read_polyline(polyline, 1, "to_convex_hull")
    cdef cpFloat tol = _tolerance(tolerance, "to_convex_hull")
    cdef cpVect *hull = <cpVect *>malloc((line.count + 1) * sizeof(cpVect))
    cdef int n
    if hull == NULL:
        raise MemoryError()
    try:
        n = cpConvexHull(<int>line.count, line.verts, hull, NULL, tol)
        hull[n] = hull[0]
        return pl_to_list(hull, n + 1)
    finally:
        free(hull)


# -- convex_decomposition (cpPolylineConvexDecomposition) ---------------------------------

ctypedef struct Notch:
    Py_ssize_t i
    cpFloat d
    cpVect v
    cpVect n

ctypedef struct Piece:
    # A polygon still to decompose: count vertices, open (no closing copy),
    # with room for one more at verts[count].
    cpVect *verts
    Py_ssize_t count

cdef int DeepestNotch(Py_ssize_t count, const cpVect *verts, int hullCount,
                      const cpVect *hullVerts, Py_ssize_t first, Notch *notch) noexcept nogil:
    # The vertex deepest inside the hull, measured from the hull edge whose
    # chain of polygon vertices it belongs to. -1 if a hull vertex cannot be
    # found among the polygon's (only with NaN, where Munk2D loops forever).
    cdef Py_ssize_t j = Next(first, count)
    cdef Py_ssize_t steps
    cdef int i
    cdef cpVect a, b, n, v
    cdef cpFloat d, depth
    notch.i = 0
    notch.d = 0.0
    notch.v = cpv(0.0, 0.0)
    notch.n = cpv(0.0, 0.0)
    for i in range(hullCount):
        a = hullVerts[i]
        b = hullVerts[(i + 1) % hullCount]
        n = cpvnormalize(cpvrperp(cpvsub(a, b)))
        d = cpvdot(n, a)
        v = verts[j]
        steps = 0
        while not cpveql(v, b):
            depth = cpvdot(n, v) - d
            if depth > notch.d:
                notch.d = depth
                notch.i = j
                notch.v = v
                notch.n = n
            j = Next(j, count)
            v = verts[j]
            steps += 1
            if steps > count:
                return -1
        j = Next(j, count)
    return 0

cdef cpFloat FindSteiner(Py_ssize_t count, const cpVect *verts, Notch notch) noexcept nogil:
    # Where the ray from the notch along its normal first meets the polygon:
    # edge index + fraction along it, or -1.
    cdef cpFloat vmin = INFINITY
    cdef cpFloat feature = -1.0
    cdef Py_ssize_t i, index
    cdef cpVect seg_a, seg_b
    cdef cpFloat thing_a, thing_b, t, dist
    for i in range(1, count - 1):
        index = (notch.i + i) % count
        seg_a = verts[index]
        seg_b = verts[Next(index, count)]
        thing_a = cpvcross(notch.n, cpvsub(seg_a, notch.v))
        thing_b = cpvcross(notch.n, cpvsub(seg_b, notch.v))
        if thing_a * thing_b <= 0.0:
            t = thing_a / (thing_a - thing_b)
            dist = cpvdot(notch.n, cpvsub(cpvlerp(seg_a, seg_b, t), notch.v))
            if dist >= 0.0 and dist <= vmin:
                vmin = dist
                feature = index + t
    return feature

cdef int _push_piece(Piece **stack, Py_ssize_t *size, Py_ssize_t *capacity,
                     cpVect *verts, Py_ssize_t count) noexcept nogil:
    cdef Piece *grown
    if size[0] == capacity[0]:
        grown = <Piece *>realloc(stack[0], 2 * capacity[0] * sizeof(Piece))
        if grown == NULL:
            return -1
        stack[0] = grown
        capacity[0] *= 2
    stack[0][size[0]].verts = verts
    stack[0][size[0]].count = count
    size[0] += 1
    return 0

cdef int _decompose(cpVect *verts, Py_ssize_t count, cpFloat tol, list out) except -1:
    # ApproximateConcaveDecomposition: split at the deepest notch deeper than
    # tol, toward the nearest boundary point along the notch's normal, until
    # every piece is convex within tol. Munk2D recurses into the first piece,
    # then the second; the stack pops them in that order. `verts` (count + 1
    # entries) is taken over and freed.
    cdef Piece *stack = <Piece *>malloc(16 * sizeof(Piece))
    cdef Py_ssize_t size = 0, capacity = 16
    # A simple polygon needs about one split per reflex vertex; many more
    # mean Munk2D's recursion would never end.
    cdef Py_ssize_t splits = 0, max_splits = 8 * count + 256
    cdef Py_ssize_t i, sub1_count, sub2_count, steiner_i, k
    cdef cpVect *hull = NULL
    cdef cpVect *sub1
    cdef cpVect *sub2
    cdef cpVect steiner
    cdef cpFloat steiner_it
    cdef int hullCount, first
    cdef Notch notch
    cdef cpVect *current = NULL     # the piece being worked on (owned)
    cdef bint split
    if stack == NULL:
        free(verts)
        raise MemoryError()
    stack[0].verts = verts
    stack[0].count = count
    size = 1
    try:
        while size > 0:
            size -= 1
            current = verts = stack[size].verts
            count = stack[size].count
            hull = <cpVect *>malloc((count + 1) * sizeof(cpVect))
            if hull == NULL:
                raise MemoryError()
            hullCount = cpConvexHull(<int>count, verts, hull, &first, 0.0)
            split = False
            if hullCount != count:
                if DeepestNotch(count, verts, hullCount, hull, first, &notch) < 0:
                    raise IllegalPolyline(
                        "convex_decomposition: a degenerate polygon (a hull vertex "
                        "not found on the outline)")
                if notch.d > tol:
                    steiner_it = FindSteiner(count, verts, notch)
                    if steiner_it >= 0.0:
                        splits += 1
                        if splits > max_splits:
                            # Munk2D recurses until the C stack overflows
                            raise IllegalPolyline(
                                "convex_decomposition does not converge on this polygon "
                                "(a repeated vertex, or self-intersecting?)")
                        steiner_i = <Py_ssize_t>steiner_it
                        # verts[count] is the closing vertex, a copy of verts[0]
                        steiner = cpvlerp(verts[steiner_i], verts[Next(steiner_i, count)],
                                          steiner_it - steiner_i)
                        # vertex counts not including the steiner point
                        sub1_count = (steiner_i - notch.i + count) % count + 1
                        sub2_count = count - (steiner_i - notch.i + count) % count
                        sub1 = <cpVect *>malloc((sub1_count + 2) * sizeof(cpVect))
                        sub2 = <cpVect *>malloc((sub2_count + 2) * sizeof(cpVect))
                        if sub1 == NULL or sub2 == NULL:
                            free(sub1)
                            free(sub2)
                            raise MemoryError()
                        for k in range(sub1_count):
                            sub1[k] = verts[(notch.i + k) % count]
                        sub1[sub1_count] = steiner
                        sub1[sub1_count + 1] = sub1[0]
                        for k in range(sub2_count):
                            sub2[k] = verts[(steiner_i + 1 + k) % count]
                        sub2[sub2_count] = steiner
                        sub2[sub2_count + 1] = sub2[0]
                        # second piece below the first: the first is done first
                        if _push_piece(&stack, &size, &capacity, sub2, sub2_count + 1) < 0:
                            free(sub1)
                            free(sub2)
                            raise MemoryError()
                        if _push_piece(&stack, &size, &capacity, sub1, sub1_count + 1) < 0:
                            free(sub1)
                            raise MemoryError()
                        split = True
            if not split:
                hull[hullCount] = hull[0]
                out.append(pl_to_list(hull, hullCount + 1))
            free(hull)
            hull = NULL
            free(current)
            current = NULL
    finally:
        free(hull)
        free(current)
        for i in range(size):
            free(stack[i].verts)
        free(stack)
    return 0

def convex_decomposition(polyline, tolerance):
    """An approximate convex decomposition of a closed, counter-clockwise
    polygon: a list of closed convex polylines that cover it to within
    ``tolerance`` (Munk2D's ``cpPolylineConvexDecomposition``).

    >>> notched = [(0, 0), (4, 0), (4, 4), (2, 1), (0, 4), (0, 0)]
    >>> for part in convex_decomposition(notched, 0.1):
    ...     print([tuple(v) for v in part])
    [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 4.0), (0.0, 0.0)]
    [(2.0, 0.0), (4.0, 0.0), (4.0, 4.0), (2.0, 1.0), (2.0, 0.0)]

    A self-intersecting polygon may come out overly simplified.

    :param polyline: a closed polyline (last vertex equal to the first) with
        non-negative area (counter-clockwise).
    :param float tolerance: how deep a notch may stay.
    :rtype: list of lists of Vec2d
    """
    cdef _Verts line = _read_polyline(polyline, 0, "convex_decomposition")
    cdef cpFloat tol = _tolerance(tolerance, "convex_decomposition")
    cdef cpVect *verts
    cdef Py_ssize_t i
    cdef list out = []
    if not pl_is_closed(line.verts, line.count):
        raise IllegalPolyline("Cannot decompose an open polygon.")
    if not cpAreaForPoly(<int>line.count, line.verts, 0.0) >= 0.0:
        raise IllegalPolyline("Winding is backwards. Try to reverse the vertices. "
                              "(Are you passing a hole?)")
    for i in range(line.count):
        if not (isfinite(line.verts[i].x) and isfinite(line.verts[i].y)):
            raise IllegalPolyline(f"convex_decomposition: vertex {i} is not finite")
    # The polygon without its closing vertex, which stays behind it as the
    # wrap-around copy Munk2D reads there.
    verts = <cpVect *>malloc((line.count + 1) * sizeof(cpVect))
    if verts == NULL:
        raise MemoryError()
    memcpy(verts, line.verts, line.count * sizeof(cpVect))
    _decompose(verts, line.count - 1, tol, out)
    return out


# -- PolylineSet (cpPolylineSet) ----------------------------------------------------------

cdef class PolylineSet:
    """A set of polylines, grown one segment at a time by
    :meth:`collect_segment`; :func:`march_soft` and :func:`march_hard` return
    one. It is a read-only sequence of polylines (lists of Vec2d).

    >>> lines = PolylineSet()
    >>> lines.collect_segment((0, 0), (1, 0))
    >>> lines.collect_segment((1, 0), (1, 1))
    >>> lines.collect_segment((5, 5), (6, 6))
    >>> len(lines)
    2
    >>> lines[0]
    [Vec2d(0.0, 0.0), Vec2d(1.0, 0.0), Vec2d(1.0, 1.0)]
    >>> [len(line) for line in lines]
    [3, 2]
    """
    cdef Polyline *lines
    cdef Py_ssize_t n          # number of polylines
    cdef Py_ssize_t capacity

    def __cinit__(self):
        self.lines = <Polyline *>calloc(8, sizeof(Polyline))
        if self.lines == NULL:
            raise MemoryError()
        self.capacity = 8
        self.n = 0

    def __init__(self):
        pass

    def __dealloc__(self):
        cdef Py_ssize_t i
        if self.lines != NULL:
            for i in range(self.n):
                free(self.lines[i].verts)
            free(self.lines)

    cdef Py_ssize_t find_ends(self, cpVect v) noexcept nogil:
        # first polyline ending at v, or -1
        cdef Py_ssize_t i
        cdef Polyline *line
        for i in range(self.n):
            line = &self.lines[i]
            if cpveql(line.verts[line.count - 1], v):
                return i
        return -1

    cdef Py_ssize_t find_starts(self, cpVect v) noexcept nogil:
        # first polyline starting at v, or -1
        cdef Py_ssize_t i
        for i in range(self.n):
            if cpveql(self.lines[i].verts[0], v):
                return i
        return -1

    cdef int add(self, cpVect v0, cpVect v1) except -1:
        # cpPolylineSetAdd: a new polyline v0-v1 at the end
        cdef Polyline *grown
        cdef Polyline line
        line.count = 0
        line.capacity = 0
        line.verts = NULL
        if pl_reserve(&line, DEFAULT_POLYLINE_CAPACITY) < 0:
            _no_memory()
        if self.n == self.capacity:
            grown = <Polyline *>realloc(self.lines, 2 * self.capacity * sizeof(Polyline))
            if grown == NULL:
                pl_free(&line)
                _no_memory()
            self.lines = grown
            self.capacity *= 2
        line.verts[0] = v0
        line.verts[1] = v1
        line.count = 2
        self.lines[self.n] = line
        self.n += 1
        return 0

    cdef int join(self, Py_ssize_t before, Py_ssize_t after) except -1:
        # cpPolylineSetJoin: append `after` to `before`, then fill after's
        # slot with the last polyline
        cdef Polyline *lbefore = &self.lines[before]
        cdef Polyline *lafter = &self.lines[after]
        if pl_reserve(lbefore, lbefore.count + lafter.count) < 0:
            _no_memory()
        memcpy(lbefore.verts + lbefore.count, lafter.verts, lafter.count * sizeof(cpVect))
        lbefore.count += lafter.count
        pl_free(lafter)
        self.n -= 1
        self.lines[after] = self.lines[self.n]
        return 0

    cdef int collect(self, cpVect v0, cpVect v1) except -1:
        # cpPolylineSetCollectSegment
        cdef Py_ssize_t before = self.find_ends(v0)
        cdef Py_ssize_t after = self.find_starts(v1)
        if before >= 0 and after >= 0:
            if before == after:
                # closes a loop
                if pl_push(&self.lines[before], v1) < 0:
                    _no_memory()
            else:
                self.join(before, after)
        elif before >= 0:
            if pl_push(&self.lines[before], v1) < 0:
                _no_memory()
        elif after >= 0:
            if pl_enqueue(&self.lines[after], v0) < 0:
                _no_memory()
        else:
            self.add(v0, v1)
        return 0

    def collect_segment(self, v0, v1):
        """Add the segment v0-v1: it extends the polyline that ends at v0 or
        starts at v1, joins two polylines, closes a loop, or starts a new
        polyline.

        >>> lines = PolylineSet()
        >>> for a, b in [((0, 0), (1, 0)), ((1, 0), (0, 1)), ((0, 1), (0, 0))]:
        ...     lines.collect_segment(a, b)
        >>> lines[0]
        [Vec2d(0.0, 0.0), Vec2d(1.0, 0.0), Vec2d(0.0, 1.0), Vec2d(0.0, 0.0)]

        :param v0: start of the segment, (x, y)
        :param v1: end of the segment, (x, y)
        """
        self.collect(cpv_from_object(v0), cpv_from_object(v1))

    def __len__(self):
        return self.n

    def __getitem__(self, index):
        """The polyline at ``index`` (negative counts from the end)."""
        cdef Py_ssize_t i
        if isinstance(index, slice):
            raise TypeError("PolylineSet does not support slicing")
        i = index
        if i < 0:
            i += self.n
        if i < 0 or i >= self.n:
            raise IndexError("PolylineSet index out of range")
        return pl_to_list(self.lines[i].verts, self.lines[i].count)

    def __iter__(self):
        cdef Py_ssize_t i = 0
        while i < self.n:
            yield pl_to_list(self.lines[i].verts, self.lines[i].count)
            i += 1

    def __reversed__(self):
        cdef Py_ssize_t i = self.n
        while i > 0:
            i -= 1
            if i < self.n:
                yield pl_to_list(self.lines[i].verts, self.lines[i].count)

    def __contains__(self, value):
        for line in self:
            if line is value or line == value:
                return True
        return False

    def index(self, value, start=0, stop=None):
        """Index of the first polyline equal to value (as Sequence.index)."""
        return list(self).index(value, start, len(self) if stop is None else stop)

    def count(self, value):
        """How many polylines equal value (as Sequence.count)."""
        return list(self).count(value)


# pymunk's PolylineSet derives from Sequence; an extension type cannot, so it
# is registered (isinstance works) and defines the mixin methods itself.
_Sequence.register(PolylineSet)


# -- marching squares (cpMarch.c) --------------------------------------------------------

cdef double _sample_value(object value) except? -1.0:
    try:
        return value
    except TypeError:
        raise TypeError(f"sample_func must return a number, not {type(value).__name__}") from None

cdef inline double _sample(object func, double x, double y) except? -1.0:
    # pymunk hands the sample function an (x, y) tuple of floats
    cdef object value = func((x, y))
    if PyFloat_CheckExact(value):
        return PyFloat_AS_DOUBLE(value)
    return _sample_value(value)

cdef inline int seg(PolylineSet lines, cpVect v0, cpVect v1) except -1:
    # Munk2D emits each segment reversed (v1, v0) and skips empty ones.
    if not cpveql(v0, v1):
        lines.collect(v1, v0)
    return 0

cdef inline cpFloat midlerp(cpFloat x0, cpFloat x1, cpFloat s0, cpFloat s1, cpFloat t) noexcept nogil:
    # the position between x0 and x1 where the samples s0, s1 cross t
    return cpflerp(x0, x1, (t - s0) / (s1 - s0))

cdef int cell_soft(cpFloat t, cpFloat a, cpFloat b, cpFloat c, cpFloat d,
                   cpFloat x0, cpFloat x1, cpFloat y0, cpFloat y1, PolylineSet lines) except -1:
    # cpMarchCellSoft: a, b are the samples at (x0, y0), (x1, y0); c, d at
    # (x0, y1), (x1, y1); the crossing points are interpolated.
    cdef int case = (<int>(a > t)) | (<int>(b > t) << 1) | (<int>(c > t) << 2) | (<int>(d > t) << 3)
    if case == 0x1:
        seg(lines, cpv(x0, midlerp(y0, y1, a, c, t)), cpv(midlerp(x0, x1, a, b, t), y0))
    elif case == 0x2:
        seg(lines, cpv(midlerp(x0, x1, a, b, t), y0), cpv(x1, midlerp(y0, y1, b, d, t)))
    elif case == 0x3:
        seg(lines, cpv(x0, midlerp(y0, y1, a, c, t)), cpv(x1, midlerp(y0, y1, b, d, t)))
    elif case == 0x4:
        seg(lines, cpv(midlerp(x0, x1, c, d, t), y1), cpv(x0, midlerp(y0, y1, a, c, t)))
    elif case == 0x5:
        seg(lines, cpv(midlerp(x0, x1, c, d, t), y1), cpv(midlerp(x0, x1, a, b, t), y0))
    elif case == 0x6:
        seg(lines, cpv(midlerp(x0, x1, a, b, t), y0), cpv(x1, midlerp(y0, y1, b, d, t)))
        seg(lines, cpv(midlerp(x0, x1, c, d, t), y1), cpv(x0, midlerp(y0, y1, a, c, t)))
    elif case == 0x7:
        seg(lines, cpv(midlerp(x0, x1, c, d, t), y1), cpv(x1, midlerp(y0, y1, b, d, t)))
    elif case == 0x8:
        seg(lines, cpv(x1, midlerp(y0, y1, b, d, t)), cpv(midlerp(x0, x1, c, d, t), y1))
    elif case == 0x9:
        seg(lines, cpv(x0, midlerp(y0, y1, a, c, t)), cpv(midlerp(x0, x1, a, b, t), y0))
        seg(lines, cpv(x1, midlerp(y0, y1, b, d, t)), cpv(midlerp(x0, x1, c, d, t), y1))
    elif case == 0xA:
        seg(lines, cpv(midlerp(x0, x1, a, b, t), y0), cpv(midlerp(x0, x1, c, d, t), y1))
    elif case == 0xB:
        seg(lines, cpv(x0, midlerp(y0, y1, a, c, t)), cpv(midlerp(x0, x1, c, d, t), y1))
    elif case == 0xC:
        seg(lines, cpv(x1, midlerp(y0, y1, b, d, t)), cpv(x0, midlerp(y0, y1, a, c, t)))
    elif case == 0xD:
        seg(lines, cpv(x1, midlerp(y0, y1, b, d, t)), cpv(midlerp(x0, x1, a, b, t), y0))
    elif case == 0xE:
        seg(lines, cpv(midlerp(x0, x1, a, b, t), y0), cpv(x0, midlerp(y0, y1, a, c, t)))
    return 0

cdef inline int segs(PolylineSet lines, cpVect a, cpVect b, cpVect c) except -1:
    # an elbow a-b-c, emitted second half first as Munk2D does
    seg(lines, b, c)
    seg(lines, a, b)
    return 0

cdef int cell_hard(cpFloat t, cpFloat a, cpFloat b, cpFloat c, cpFloat d,
                   cpFloat x0, cpFloat x1, cpFloat y0, cpFloat y1, PolylineSet lines) except -1:
    # cpMarchCellHard: the contour runs through the cell's centre lines.
    cdef cpFloat xm = cpflerp(x0, x1, 0.5)
    cdef cpFloat ym = cpflerp(y0, y1, 0.5)
    cdef int case = (<int>(a > t)) | (<int>(b > t) << 1) | (<int>(c > t) << 2) | (<int>(d > t) << 3)
    if case == 0x1:
        segs(lines, cpv(x0, ym), cpv(xm, ym), cpv(xm, y0))
    elif case == 0x2:
        segs(lines, cpv(xm, y0), cpv(xm, ym), cpv(x1, ym))
    elif case == 0x3:
        seg(lines, cpv(x0, ym), cpv(x1, ym))
    elif case == 0x4:
        segs(lines, cpv(xm, y1), cpv(xm, ym), cpv(x0, ym))
    elif case == 0x5:
        seg(lines, cpv(xm, y1), cpv(xm, y0))
    elif case == 0x6:
        # the saddle: two elbows meeting at the centre, as Munk2D draws them
        segs(lines, cpv(xm, y0), cpv(xm, ym), cpv(x0, ym))
        segs(lines, cpv(xm, y1), cpv(xm, ym), cpv(x1, ym))
    elif case == 0x7:
        segs(lines, cpv(xm, y1), cpv(xm, ym), cpv(x1, ym))
    elif case == 0x8:
        segs(lines, cpv(x1, ym), cpv(xm, ym), cpv(xm, y1))
    elif case == 0x9:
        segs(lines, cpv(x1, ym), cpv(xm, ym), cpv(xm, y0))
        segs(lines, cpv(x0, ym), cpv(xm, ym), cpv(xm, y1))
    elif case == 0xA:
        seg(lines, cpv(xm, y0), cpv(xm, y1))
    elif case == 0xB:
        segs(lines, cpv(x0, ym), cpv(xm, ym), cpv(xm, y1))
    elif case == 0xC:
        seg(lines, cpv(x1, ym), cpv(x0, ym))
    elif case == 0xD:
        segs(lines, cpv(x1, ym), cpv(xm, ym), cpv(xm, y0))
    elif case == 0xE:
        segs(lines, cpv(xm, y0), cpv(xm, ym), cpv(x0, ym))
    return 0

cdef unsigned long _samples(object n, str what) except? 0:
    cdef object i = PyNumber_Index(n)
    if i < 1:
        # 0 makes Munk2D loop over 2**64 rows
        raise ValueError(f"{what} must be at least 1, got {i}")
    if i > ULONG_MAX:
        raise OverflowError(f"{what} is too large: {i}")
    return <unsigned long>i

cdef PolylineSet _march(object bb, object x_samples, object y_samples, object threshold,
                        object sample_func, bint hard):
    # cpMarchCells: samples row by row from the bottom (bb.b), keeping the
    # previous row so that each grid point is sampled once, in Munk2D's order.
    cdef cpBB box = cpbb_from_object(bb)
    cdef unsigned long xs = _samples(x_samples, "x_samples")
    cdef unsigned long ys = _samples(y_samples, "y_samples")
    cdef cpFloat t
    cdef PolylineSet lines = PolylineSet()
    cdef cpFloat x_denom = 1.0 / <cpFloat>(xs - 1)
    cdef cpFloat y_denom = 1.0 / <cpFloat>(ys - 1)
    cdef cpFloat *buffer
    cdef cpFloat a, b, c, d, x0, x1, y0, y1
    cdef unsigned long i, j
    try:
        t = threshold
    except TypeError:
        raise TypeError(f"threshold must be a number, not {type(threshold).__name__}") from None
    if not callable(sample_func):
        raise TypeError(f"sample_func must be callable, not {type(sample_func).__name__}")
    buffer = <cpFloat *>calloc(xs, sizeof(cpFloat))
    if buffer == NULL:
        raise MemoryError(f"cannot allocate a row of {xs} samples")
    try:
        for i in range(xs):
            buffer[i] = _sample(sample_func, cpflerp(box.l, box.r, i * x_denom), box.b)
        for j in range(ys - 1):
            y0 = cpflerp(box.b, box.t, (j + 0) * y_denom)
            y1 = cpflerp(box.b, box.t, (j + 1) * y_denom)
            b = buffer[0]
            d = _sample(sample_func, box.l, y1)
            buffer[0] = d
            for i in range(xs - 1):
                x0 = cpflerp(box.l, box.r, (i + 0) * x_denom)
                x1 = cpflerp(box.l, box.r, (i + 1) * x_denom)
                a = b
                b = buffer[i + 1]
                c = d
                d = _sample(sample_func, x1, y1)
                buffer[i + 1] = d
                if hard:
                    cell_hard(t, a, b, c, d, x0, x1, y0, y1, lines)
                else:
                    cell_soft(t, a, b, c, d, x0, x1, y0, y1, lines)
    finally:
        free(buffer)
    return lines

def march_soft(bb, x_samples, y_samples, threshold, sample_func):
    """Trace the contour of an anti-aliased image where it crosses
    ``threshold``: crossing points are interpolated between samples.

    ``sample_func((x, y))`` is called once per point of an
    ``x_samples`` by ``y_samples`` grid spread over ``bb`` (row by row from
    ``bb.bottom``) and returns a float. An exception it raises ends the march
    and propagates.

    >>> from tamias2d import BB
    >>> def disc(point):
    ...     x, y = point
    ...     return 1.0 - (x * x + y * y) / 4.0
    >>> lines = march_soft(BB(-2, -2, 2, 2), 5, 5, 0.5, disc)
    >>> len(lines), len(lines[0])
    (1, 9)
    >>> lines[0][:3]
    [Vec2d(0.0, 1.3333333333333335), Vec2d(-1.0, 1.0), Vec2d(-1.3333333333333335, 0.0)]

    :param BB bb: the area to sample.
    :param int x_samples: samples across (>= 1).
    :param int y_samples: samples up (>= 1).
    :param float threshold: the level of the contour.
    :param sample_func: ``func(point: tuple[float, float]) -> float``
    :rtype: PolylineSet
    """
    return _march(bb, x_samples, y_samples, threshold, sample_func, False)

def march_hard(bb, x_samples, y_samples, threshold, sample_func):
    """Trace the contour of an aliased (pixel) image where it crosses
    ``threshold``: the contour runs halfway between samples, with right
    angles. Arguments as :func:`march_soft`.

    >>> from tamias2d import BB
    >>> def square(point):
    ...     x, y = point
    ...     return 1.0 if 1 <= x <= 2 and 1 <= y <= 2 else 0.0
    >>> lines = march_hard(BB(0, 0, 3, 3), 4, 4, 0.5, square)
    >>> [tuple(v) for v in lines[0]]  # doctest: +NORMALIZE_WHITESPACE
    [(2.0, 2.5), (1.0, 2.5), (0.5, 2.5), (0.5, 2.0), (0.5, 1.0), (0.5, 0.5), (1.0, 0.5),
     (2.0, 0.5), (2.5, 0.5), (2.5, 1.0), (2.5, 2.0), (2.5, 2.5), (2.0, 2.5)]

    :rtype: PolylineSet
    """
    return _march(bb, x_samples, y_samples, threshold, sample_func, True)
