"""Copy and pickle state in pymunk's layout, shared by Body, Shape and
Constraint (pymunk's ``PickleMixin``), and the lazy loader of
``tamias2d._snapshot``.

A class lists the attributes of its state in three class attributes:
``_pickle_attrs_init`` (passed to ``__init__`` on restore, in order),
``_pickle_attrs_general`` (set after ``__init__``, in order) and
``_pickle_attrs_skip`` (documented as not pickled). User attributes
(``__dict__`` entries not starting with ``_``) are the ``custom`` part.
A class adds what does not fit (callbacks, the sleeping flag, a shape's mass
or density) in ``_pickle_extra_state`` and restores it in
``_pickle_restore_special``.

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


cdef class PickleMixin:
    """Base of the objects copied and pickled in pymunk's layout: a dict of
    ``init``, ``general``, ``custom`` and ``special`` lists of (name, value)
    pairs.

    >>> import tamias2d
    >>> isinstance(tamias2d.Body(1, 2), tamias2d._pickle.PickleMixin)
    True
    """

    _pickle_attrs_init = []
    _pickle_attrs_general = []
    _pickle_attrs_skip = []

    def __getstate__(self):
        """The object's state as pymunk lays it out (used by copy and pickle).

        >>> import tamias2d
        >>> sorted(tamias2d.Body(1, 2).__getstate__())
        ['custom', 'general', 'init', 'special']
        """
        cls = type(self)
        d = {"init": [], "general": [], "custom": [], "special": []}
        for a in cls._pickle_attrs_init:
            d["init"].append((a, getattr(self, a)))
        for a in cls._pickle_attrs_general:
            d["general"].append((a, getattr(self, a)))
        for k, v in getattr(self, "__dict__").items():
            if k[0] != "_":
                d["custom"].append((k, v))
        self._pickle_extra_state(d)
        return d

    def _pickle_extra_state(self, dict state):
        # What the attribute lists cannot say; appended to `state` in place.
        pass

    def __setstate__(self, state):
        """Restore a state made by :meth:`__getstate__` (used by unpickling).

        >>> import tamias2d
        >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
        >>> j = tamias2d.SimpleMotor(a, b, 2)
        >>> j.__setstate__(tamias2d.SimpleMotor(a, b, 5).__getstate__())
        >>> j.rate
        5.0
        """
        self.__init__(*[v for k, v in state["init"]])
        for k, v in state["general"]:
            setattr(self, k, v)
        for k, v in state["custom"]:
            setattr(self, k, v)
        for k, v in state["special"]:
            self._pickle_restore_special(k, v)

    def _pickle_restore_special(self, str name, value):
        pass

    def __reduce__(self):
        return (_copyreg.__newobj__, (type(self),), self.__getstate__())

    def copy(self):
        """A deep copy (a shape's body and a joint's bodies are copied too).

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.position = 5, 6
        >>> c = b.copy()
        >>> c.position, c is b
        (Vec2d(5.0, 6.0), False)
        """
        return _copy.deepcopy(self)
