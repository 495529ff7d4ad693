"""``import pymunk`` gives tamias2d: the import hook behind
:func:`tamias2d.install_as_pymunk` and ``tamias2d run SCRIPT``.

After :func:`install_as_pymunk`, ``import pymunk`` returns a small alias
module named ``pymunk`` whose attributes are tamias2d's, and
``import pymunk.<module>`` / ``from pymunk.<module> import ...`` return the
tamias2d module that holds that pymunk module's names (``pymunk.vec2d`` is
``tamias2d.vector``, ``pymunk.shapes`` is ``tamias2d.shape``, ...). No module
is copied: every name is the tamias2d object itself, so ``pymunk.Body is
tamias2d.Body``.

Under the hook ``pymunk.version`` is ``"7.3.1"``, the pymunk release whose API
and numbers tamias2d reproduces, so that version checks in programs take the
pymunk 7.3 path; ``pymunk.tamias2d_version`` is tamias2d's own version and
``pymunk.__tamias2d__`` is True, for a program that wants to know.

>>> import tamias2d._pymunk_hook as hook
>>> hook.PYMUNK_MODULES["vec2d"], hook.PYMUNK_MODULES["shapes"]
('vector', 'shape')
"""
import importlib
import importlib.abc
import importlib.machinery
import os
import runpy
import sys
import types

import tamias2d

# The pymunk API level tamias2d implements (what pymunk.version says under
# the hook).
PYMUNK_API_VERSION = "7.3.1"

# pymunk 7.3's public modules -> the tamias2d module holding their names.
PYMUNK_MODULES = {
    "vec2d": "vector",
    "bb": "vector",
    "transform": "vector",
    "body": "body",
    "shapes": "shape",
    "shape_filter": "shape",
    "query_info": "shape",
    "contact_point_set": "collision",
    "arbiter": "arbiter",
    "constraints": "constraints",
    "space": "space",
    "space_debug_draw_options": "space_debug_draw_options",
    "batch": "batch",
    "autogeometry": "autogeometry",
    "util": "util",
    "pygame_util": "pygame_util",
    "pyglet_util": "pyglet_util",
    "matplotlib_util": "matplotlib_util",
}


class _PymunkAlias(types.ModuleType):
    """The module ``pymunk`` under the hook: tamias2d's names, pymunk's
    version. Submodules imported through it become its attributes, as in a
    package."""

    def __getattr__(self, name):
        try:
            return getattr(tamias2d, name)
        except AttributeError:
            pass
        if name in PYMUNK_MODULES:
            # pymunk's __init__ imports these modules, so `pymunk.vec2d` works
            # without an import statement.
            return importlib.import_module("pymunk." + name)
        raise AttributeError(f"module 'pymunk' (tamias2d) has no attribute {name!r}")

    def __dir__(self):
        return sorted(set(dir(tamias2d)) | set(self.__dict__))


class _Loader(importlib.abc.Loader):
    """Hands out the already imported tamias2d module."""

    def __init__(self, module):
        self.module = module

    def create_module(self, spec):
        return self.module

    def exec_module(self, module):
        pass


class _PymunkFinder(importlib.abc.MetaPathFinder):
    """Finds ``pymunk.<module>`` among tamias2d's modules."""

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith("pymunk."):
            return None
        sub = fullname[len("pymunk."):]
        target_name = PYMUNK_MODULES.get(sub)
        if target_name is None:
            raise ModuleNotFoundError(
                f"No module named {fullname!r}: tamias2d stands in for pymunk (see "
                f"tamias2d.install_as_pymunk) and has no counterpart of pymunk.{sub}; "
                f"its public modules are {sorted(PYMUNK_MODULES)}", name=fullname)
        module = importlib.import_module("tamias2d." + target_name)
        return importlib.machinery.ModuleSpec(fullname, _Loader(module))


_finder = _PymunkFinder()


def _make_alias():
    alias = _PymunkAlias("pymunk", tamias2d.__doc__)
    alias.__path__ = []  # a package, so that `import pymunk.x` asks the finder
    alias.__file__ = tamias2d.__file__
    alias.__package__ = "pymunk"
    alias.__spec__ = importlib.machinery.ModuleSpec("pymunk", None, is_package=True)
    alias.__spec__.submodule_search_locations = []
    alias.__all__ = [n for n in dir(tamias2d) if not n.startswith("_")
                     and not isinstance(getattr(tamias2d, n), types.ModuleType)]
    alias.version = PYMUNK_API_VERSION
    alias.chipmunk_version = tamias2d.chipmunk_version
    alias.tamias2d_version = tamias2d.version
    alias.__tamias2d__ = True
    return alias


def installed():
    """True when ``import pymunk`` gives tamias2d."""
    return getattr(sys.modules.get("pymunk"), "__tamias2d__", False) is True


def install_as_pymunk():
    """Make ``import pymunk`` (and every ``import pymunk.<module>`` of pymunk
    7.3's public modules) give tamias2d. Call it before the program imports
    pymunk; calling it again does nothing.

    Raises RuntimeError if the real pymunk was imported already (objects of
    the two engines cannot be mixed in one space).

    >>> import subprocess, sys
    >>> code = ("import tamias2d; tamias2d.install_as_pymunk(); "
    ...         "import pymunk, pymunk.vec2d; from pymunk.shapes import Circle; "
    ...         "print(pymunk.Body is tamias2d.Body, pymunk.vec2d.Vec2d is tamias2d.Vec2d, "
    ...         "Circle is tamias2d.Circle, pymunk.version)")
    >>> print(subprocess.run([sys.executable, "-c", code], capture_output=True,
    ...                      text=True).stdout.strip())
    True True True 7.3.1
    """
    if installed():
        return
    loaded = sorted(n for n in sys.modules if n == "pymunk" or n.startswith("pymunk."))
    if loaded:
        raise RuntimeError(
            "pymunk is already imported (" + ", ".join(loaded[:5]) + "); call "
            "tamias2d.install_as_pymunk() before anything imports pymunk")
    if _finder not in sys.meta_path:
        # First: a real pymunk installed beside tamias2d must not be found.
        sys.meta_path.insert(0, _finder)
    sys.modules["pymunk"] = _make_alias()


def run_script(path, args=()):
    """Run the pymunk program at `path` as ``__main__`` with ``sys.argv =
    [path, *args]``, on tamias2d (what ``tamias2d run`` does)."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such script: {path}")
    install_as_pymunk()
    sys.argv = [path, *args]
    # As `python SCRIPT` does: the script's folder comes first on sys.path.
    sys.path.insert(0, os.path.dirname(os.path.abspath(path)))
    runpy.run_path(path, run_name="__main__")
