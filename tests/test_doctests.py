"""Run the ``>>>`` examples in the docstrings of every tamias2d module.

Compiled modules need two additions to what doctest finds by itself:
- the properties of cdef classes are getset descriptors, which
  ``doctest.DocTestFinder`` skips; the finder below collects them;
- Cython also lists docstrings in the module's ``__test__`` dict (that is how
  doctest reaches properties as ``Class.prop.__get__``). Entries whose text the
  finder already has are dropped, so each docstring runs once.
"""
import doctest
import importlib
import importlib.machinery
import inspect
import io
import pkgutil

import pytest

import tamias2d

OPTIONFLAGS = doctest.ELLIPSIS

# Modules that need an optional third-party package to import.
OPTIONAL_DEPENDENCIES = {"pygame", "pyglet", "matplotlib", "PIL"}


def _module_names():
    names = ["tamias2d"]
    names += ["tamias2d." + info.name for info in pkgutil.iter_modules(tamias2d.__path__)]
    return sorted(names)


class CythonDocTestFinder(doctest.DocTestFinder):
    """DocTestFinder that also collects the docstrings of cdef-class
    properties and members (getset and member descriptors)."""

    def _find(self, tests, obj, name, module, source_lines, globs, seen):
        super()._find(tests, obj, name, module, source_lines, globs, seen)
        if inspect.isclass(obj) and self._recurse and self._from_module(module, obj):
            for attr, value in vars(obj).items():
                if not (inspect.isgetsetdescriptor(value) or inspect.ismemberdescriptor(value)):
                    continue
                if getattr(value, "__objclass__", obj) is not obj:
                    continue
                if id(value) in seen or not isinstance(value.__doc__, str):
                    continue
                seen[id(value)] = 1
                test = self._get_test(value, f"{name}.{attr}", module, globs, source_lines)
                if test is not None and test.examples:
                    tests.append(test)


def _examples_key(test):
    # Not the docstring text: embedsignature adds a signature line to
    # __doc__ that the __test__ copy lacks.
    return tuple((ex.source, ex.want, ex.exc_msg) for ex in test.examples)


def collect(module):
    """The doctests of a module, each docstring once."""
    tests = [t for t in CythonDocTestFinder().find(module) if t.examples]
    own = [t for t in tests if ".__test__." not in t.name]
    seen = {_examples_key(t) for t in own}
    from_test_dict = [t for t in tests if ".__test__." in t.name and _examples_key(t) not in seen]
    return own + from_test_dict


def _public_definitions(module):
    """Public functions and classes the module itself defines."""
    return [name for name, value in vars(module).items()
            if not name.startswith("_") and (inspect.isclass(value) or callable(value))
            and getattr(value, "__module__", None) == module.__name__]


def _is_extension(module):
    path = getattr(module, "__file__", "") or ""
    return path.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES))


def _import(modname):
    try:
        return importlib.import_module(modname)
    except ModuleNotFoundError as e:
        if e.name and e.name.split(".")[0] in OPTIONAL_DEPENDENCIES:
            pytest.skip(f"{modname} needs {e.name}")
        raise


@pytest.mark.parametrize("modname", _module_names())
def test_doctests(modname):
    module = _import(modname)
    tests = collect(module)
    out = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=OPTIONFLAGS)
    for test in tests:
        runner.run(test, out=out.write)
    results = runner.summarize(verbose=False)
    assert results.failed == 0, f"{results.failed} doctest example(s) failed in {modname}:\n{out.getvalue()}"
    if _is_extension(module) and _public_definitions(module):
        # A compiled module with public functions or classes has examples:
        # finding none means they were not collected, not that there are none.
        assert results.attempted > 0, f"no doctest examples found in compiled {modname}"


def test_finder_reaches_compiled_docstrings():
    from tamias2d import vector
    names = {t.name for t in collect(vector)}
    for expected in ("tamias2d.vector", "tamias2d.vector.Vec2d.length",
                     "tamias2d.vector.Vec2d.__add__", "tamias2d.vector.BB.segment_query",
                     "tamias2d.vector.Transform.__matmul__"):
        assert expected in names
    # the __test__ copies were dropped
    assert not [n for n in names if ".__test__." in n]
    assert sum(len(t.examples) for t in collect(vector)) > 100


def test_finder_reaches_cdef_class_properties():
    """Properties of cdef classes are getset descriptors: check they are run."""
    for modname, cls in (("tamias2d.body", "Body"), ("tamias2d.shape", "Circle"),
                         ("tamias2d.space", "Space")):
        try:
            module = importlib.import_module(modname)
        except ImportError:
            continue
        klass = getattr(module, cls, None)
        if klass is None:
            continue
        props = [a for a, v in vars(klass).items()
                 if inspect.isgetsetdescriptor(v) and ">>>" in (v.__doc__ or "")]
        if not props:
            continue
        names = {t.name for t in collect(module)}
        missing = [p for p in props if f"{modname}.{cls}.{p}" not in names]
        assert not missing, f"doctests of {cls} properties not collected: {missing}"
        return
    pytest.skip("no compiled cdef class with documented properties yet")


def test_testing_module_doctests_are_collected():
    """tamias2d._testing defines only private names, which the guard in
    test_doctests does not cover: check every documented example there runs."""
    module = importlib.import_module("tamias2d._testing")
    documented = {f"tamias2d._testing.{name}" for name, value in vars(module).items()
                  if (inspect.isclass(value) or callable(value))
                  and getattr(value, "__module__", None) == module.__name__
                  and ">>>" in (value.__doc__ or "")}
    assert len(documented) >= 20     # what moved here from the engine modules
    names = {t.name for t in collect(module)}
    assert documented <= names, f"doctests not collected: {sorted(documented - names)}"
