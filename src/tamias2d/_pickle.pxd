# The pymunk-style copy/pickle state shared by Body, Shape and Constraint,
# and the one lazy accessor of tamias2d._snapshot. This module sits beneath
# body (it cimports nothing of tamias2d), so body, shape, constraints and
# space can all cimport it.

# tamias2d._snapshot, imported on first use (it cimports the space, which
# sits above every module that calls this).
cdef object snapshot_module()

cdef class PickleMixin:
    pass
