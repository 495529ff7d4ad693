"""Runtime home of the constants declared in ``_config.pxd``.

The ``cdef const`` values of the .pxd are shared with the other modules
through this extension module, so every module that cimports ``_config``
imports it at load time.
"""
