"""The live view of weakly held keys that pymunk returns for
``Body.constraints``: it reads the keys of a ``weakref.WeakKeyDictionary``
at iteration time, so objects that die stop showing up (also in the middle of
an iteration).

>>> import weakref
>>> class Thing: pass
>>> a, b = Thing(), Thing()
>>> d = weakref.WeakKeyDictionary({a: None, b: None})
>>> view = WeakKeysView(d)
>>> del b
>>> len(view), a in view
(1, True)
"""
from collections.abc import KeysView

__all__ = ["WeakKeysView"]


class WeakKeysView(KeysView):
    """A read-only, live view of the keys of a WeakKeyDictionary (the type
    of ``Body.constraints``, as in pymunk).

    >>> import weakref
    >>> class Thing: pass
    >>> t = Thing()
    >>> list(WeakKeysView(weakref.WeakKeyDictionary({t: 1}))) == [t]
    True
    """

    def __init__(self, weak_dict):
        super().__init__(weak_dict)

    def __iter__(self):
        # The dictionary's own key iterator guards against entries dying
        # while it runs.
        yield from self._mapping.keys()

    def __len__(self):
        return len(self._mapping)

    def __contains__(self, key):
        return key in self._mapping

    def __repr__(self):
        return f"{type(self).__name__}({list(self)!r})"
