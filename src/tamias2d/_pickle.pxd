# The pymunk-style copy/pickle state shared by Body, Shape and Constraint,
# and the one lazy accessor of tamias2d._snapshot. This module sits beneath
# body (it cimports nothing of tamias2d), so body, shape, constraints and
# space can all cimport it. (Functions, not a base class: a cdef base in
# another module would cost the subclasses Cython's vectorcall constructor,
# +18% instructions per Body().)

# tamias2d._snapshot, imported on first use (it cimports the space, which
# sits above every module that calls this).
cdef object snapshot_module()

# pymunk's layout: {"init", "general", "custom", "special"}, lists of
# (name, value) pairs, from the class's _pickle_attrs_init and
# _pickle_attrs_general and the user attributes (__dict__ entries not
# starting with "_"); "special" is left for the class to fill.
cdef dict pymunk_getstate(object obj)
# Re-run __init__ with the "init" values, then set "general" and "custom";
# the class restores "special" itself.
cdef int pymunk_setstate(object obj, dict state) except -1
# __reduce__ and copy() of the three classes.
cdef tuple pymunk_reduce(object obj)
cdef object deep_copy(object obj)
