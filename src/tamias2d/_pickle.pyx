"""Copy and pickle state in pymunk's layout, shared by Body, Shape and
Constraint (what pymunk's ``PickleMixin`` does), and the lazy loader of
``tamias2d._snapshot``.

A class lists the attributes of its state in three class attributes:
``_pickle_attrs_init`` (passed to ``__init__`` on restore, in order),
``_pickle_attrs_general`` (set after ``__init__``, in order) and
``_pickle_attrs_skip`` (documented as not pickled). User attributes
(``__dict__`` entries not starting with ``_``) are the ``custom`` part; the
class adds and restores what does not fit (callbacks, the sleeping flag, a
shape's mass or density) itself.

>>> import tamias2d
>>> state = tamias2d.SimpleMotor(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 2).__getstate__()
>>> list(state), [k for k, v in state["init"]]
(['init', 'general', 'custom', 'special'], ['a', 'b', 'rate'])
"""
import copy as _copy
import copyreg as _copyreg

cdef object _snapshot = None


cdef object snapshot_module():
    global _snapshot
    if _snapshot is None:
        from tamias2d import _snapshot as module
        _snapshot = module
    return _snapshot


cdef dict pymunk_getstate(object obj):
    cls = type(obj)
    cdef dict d = {"init": [], "general": [], "custom": [], "special": []}
    cdef list init = d["init"], general = d["general"], custom = d["custom"]
    for a in cls._pickle_attrs_init:
        init.append((a, getattr(obj, a)))
    for a in cls._pickle_attrs_general:
        general.append((a, getattr(obj, a)))
    for k, v in getattr(obj, "__dict__").items():
        if k[0] != "_":
            custom.append((k, v))
    return d


cdef int pymunk_setstate(object obj, dict state) except -1:
    obj.__init__(*[v for k, v in state["init"]])
    for k, v in state["general"]:
        setattr(obj, k, v)
    for k, v in state["custom"]:
        setattr(obj, k, v)
    return 0


cdef tuple pymunk_reduce(object obj):
    return (_copyreg.__newobj__, (type(obj),), obj.__getstate__())


cdef object deep_copy(object obj):
    return _copy.deepcopy(obj)
