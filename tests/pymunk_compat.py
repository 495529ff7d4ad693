"""Run pymunk's own unit tests against tamias2d.

pymunk ships its unit tests inside the package (``pymunk/tests/test_*.py``).
They are not copied into this repository: a test file is loaded from the
installed pymunk with ``importlib`` while ``sys.modules["pymunk"]`` and every
``pymunk.<submodule>`` name point at tamias2d, so ``import pymunk as p`` and
``from pymunk.vec2d import Vec2d`` inside the test file get tamias2d objects.

Each file runs in a child Python process, so the aliasing cannot leak into
the pymunk that other tests compare against, and a crash or a hang in the
engine costs one file's results, not the test session. If the child dies,
the file's tests are run again one per process to find out which test it was.

Command line (for a quick look at one file)::

    python tests/pymunk_compat.py test_bb.py            # summary and failures
    python tests/pymunk_compat.py test_bb.py --json out.json --only UnitTestBB.testMerge
"""
import argparse
import ast
import contextlib
import functools
import importlib
import importlib.util
import json
import os
import pkgutil
import subprocess
import sys
import tempfile
import traceback
import types
import unittest
from dataclasses import dataclass, field

# pymunk submodule -> the tamias2d module that holds its names. Submodules not
# listed are looked up as tamias2d.<same name>, then in tamias2d itself.
MODULE_MAP = {
    "vec2d": "tamias2d.vector",
    "bb": "tamias2d.vector",
    "transform": "tamias2d.vector",
    "shapes": "tamias2d.shape",
    "body": "tamias2d.body",
    "space": "tamias2d.space",
    "arbiter": "tamias2d.arbiter",
}

# Filled by run_test_file, printed by the terminal summary hook in conftest.py.
SUMMARY = {}


@functools.lru_cache(maxsize=None)
def pymunk_package_dir():
    """The installed pymunk package directory, found without importing it.
    Cached: once "pymunk" is aliased, find_spec would answer with tamias2d."""
    spec = importlib.util.find_spec("pymunk")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("pymunk is not installed: the pymunk test suite cannot run")
    return list(spec.submodule_search_locations)[0]


def pymunk_tests_dir():
    """pymunk's tests directory; TAMIAS2D_PYMUNK_TESTS_DIR overrides it (the
    runner's own tests point it at synthetic test files)."""
    return os.environ.get("TAMIAS2D_PYMUNK_TESTS_DIR") or os.path.join(pymunk_package_dir(), "tests")


def pymunk_test_files():
    """Names of pymunk's unit test files, e.g. ``["test_arbiter.py", ...]``."""
    return sorted(f for f in os.listdir(pymunk_tests_dir())
                  if f.startswith("test_") and f.endswith(".py"))


def declared_tests(filename):
    """``Class.method`` names of the tests a pymunk test file defines, read
    from its source (so they are known even if the file fails to load)."""
    with open(os.path.join(pymunk_tests_dir(), filename), encoding="utf-8") as f:
        tree = ast.parse(f.read(), filename)
    names = []
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            for item in node.body:
                if (isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef))
                        and item.name.startswith("test")):
                    names.append(f"{node.name}.{item.name}")
    return names


# -- the alias ----------------------------------------------------------------------

class _ForwardingModule(types.ModuleType):
    """Stands in for a pymunk submodule: attribute lookups go, in order, to the
    tamias2d modules that hold the same names. They are imported on first use,
    so a tamias2d module that is missing or broken only affects the tests that
    need it."""

    def __init__(self, name, target_names):
        super().__init__(name)
        self._target_names = target_names
        self._resolved = None
        self._problems = []

    def _targets(self):
        if self._resolved is None:
            self._resolved = []
            for target in self._target_names:
                try:
                    self._resolved.append(importlib.import_module(target))
                except ModuleNotFoundError as e:
                    if e.name != target:
                        self._problems.append(f"{target}: {e!r}")
                except Exception as e:  # a broken module: say so when a name is missing
                    self._problems.append(f"{target}: {e!r}")
        return self._resolved

    def __getattr__(self, attr):
        if attr.startswith("__") and attr != "__all__":
            raise AttributeError(attr)
        targets = self._targets()
        for target in targets:
            if hasattr(target, attr):
                return getattr(target, attr)
        if attr == "__all__":
            names = []
            for target in targets:
                names.extend(getattr(target, "__all__", ()))
            return names
        problems = f"; import problems: {'; '.join(self._problems)}" if self._problems else ""
        raise AttributeError(
            f"tamias2d has no {attr!r} for {self.__name__} (looked in "
            f"{', '.join(self._target_names)}){problems}")


def _pymunk_submodules():
    return sorted(info.name for info in pkgutil.iter_modules([pymunk_package_dir()])
                  if info.name != "tests")


@contextlib.contextmanager
def pymunk_aliased_to_tamias2d():
    """While active, ``import pymunk`` gives tamias2d and ``import
    pymunk.<sub>`` a module forwarding to the tamias2d modules of MODULE_MAP,
    ``tamias2d.<sub>`` and tamias2d. On exit the previous ``sys.modules``
    entries and tamias2d's attributes are restored."""
    import tamias2d
    submodules = _pymunk_submodules()
    saved = {k: v for k, v in sys.modules.items() if k == "pymunk" or k.startswith("pymunk.")}
    added_attrs = []
    for k in saved:
        del sys.modules[k]
    try:
        sys.modules["pymunk"] = tamias2d
        for sub in submodules:
            targets = [MODULE_MAP[sub]] if sub in MODULE_MAP else []
            targets += ["tamias2d." + sub, "tamias2d"]
            module = _ForwardingModule("pymunk." + sub, targets)
            sys.modules["pymunk." + sub] = module
            # "import pymunk.batch; pymunk.batch.f()" reads the attribute
            if sub not in vars(tamias2d):
                setattr(tamias2d, sub, module)
                added_attrs.append(sub)
        yield
    finally:
        for k in [k for k in sys.modules if k == "pymunk" or k.startswith("pymunk.")]:
            del sys.modules[k]
        sys.modules.update(saved)
        for attr in added_attrs:
            with contextlib.suppress(AttributeError):
                delattr(tamias2d, attr)


# -- running one file (in this process) ---------------------------------------------

class _Recorder(unittest.TestResult):
    """Keeps one outcome per test: passed, failed, error, skipped,
    expected_failure or unexpected_success."""

    def __init__(self, prefix):
        super().__init__()
        self.prefix = prefix
        self.outcomes = {}

    def _name(self, test):
        tid = test.id()
        return tid[len(self.prefix):] if tid.startswith(self.prefix) else tid

    def _set(self, test, outcome, detail=""):
        name = self._name(test)
        previous = self.outcomes.get(name)
        # a failing subtest makes the whole test fail
        if previous is not None and previous["outcome"] in ("failed", "error"):
            return
        self.outcomes[name] = {"outcome": outcome, "detail": detail}

    def addSuccess(self, test):
        self._set(test, "passed")

    def addFailure(self, test, err):
        self._set(test, "failed", self._exc_info_to_string(err, test))

    def addError(self, test, err):
        self._set(test, "error", self._exc_info_to_string(err, test))

    def addSkip(self, test, reason):
        self._set(test, "skipped", reason)

    def addExpectedFailure(self, test, err):
        self._set(test, "expected_failure")

    def addUnexpectedSuccess(self, test):
        self._set(test, "unexpected_success")

    def addSubTest(self, test, subtest, err):
        if err is not None:
            outcome = "failed" if issubclass(err[0], test.failureException) else "error"
            name = self._name(test)
            self.outcomes[name] = {"outcome": outcome,
                                   "detail": f"{subtest}: " + self._exc_info_to_string(err, test)}


def run_in_this_process(filename, only=None):
    """Load and run one pymunk test file with pymunk aliased to tamias2d.
    Returns ``{"load_error": str or None, "tests": {name: {"outcome", "detail"}}}``."""
    path = os.path.join(pymunk_tests_dir(), filename)
    modname = "_pymunk_suite_" + os.path.splitext(filename)[0]
    prefix = modname + "."
    result = {"load_error": None, "tests": {}}
    with pymunk_aliased_to_tamias2d():
        try:
            spec = importlib.util.spec_from_file_location(modname, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[modname] = module
            spec.loader.exec_module(module)
        except BaseException:
            result["load_error"] = traceback.format_exc()
            sys.modules.pop(modname, None)
            return result
        try:
            suite = unittest.defaultTestLoader.loadTestsFromModule(module)
            if only:
                suite = unittest.TestSuite(t for t in _flatten(suite) if t.id()[len(prefix):] in only)
            recorder = _Recorder(prefix)
            suite.run(recorder)
            result["tests"] = recorder.outcomes
        finally:
            sys.modules.pop(modname, None)
    return result


def _flatten(suite):
    for test in suite:
        if isinstance(test, unittest.TestSuite):
            yield from _flatten(test)
        else:
            yield test


# -- running one file (in a child process) ------------------------------------------

@dataclass
class FileResult:
    filename: str
    declared: list
    tests: dict = field(default_factory=dict)   # name -> {"outcome", "detail"}
    load_error: str = None
    crash: str = None                             # set when a child process died

    def names(self, outcome):
        return sorted(n for n, r in self.tests.items() if r["outcome"] == outcome)

    def counts(self):
        counts = {"passed": 0, "failed": 0, "error": 0, "skipped": 0, "other": 0}
        for r in self.tests.values():
            key = r["outcome"] if r["outcome"] in counts else "other"
            counts[key] += 1
        # tests that never ran (load error, crash) count as errors
        counts["error"] += len([n for n in self.declared if n not in self.tests])
        return counts

    def outcome(self, name):
        if name in self.tests:
            return self.tests[name]["outcome"]
        return "not run"

    def detail(self, name):
        if name in self.tests:
            return self.tests[name]["detail"]
        return self.load_error or self.crash or "the test did not run"


def _tamias2d_root():
    """The directory holding the tamias2d package under test: the one this
    process imports, or else this repository's."""
    spec = importlib.util.find_spec("tamias2d")
    if spec is not None and spec.origin:
        return os.path.dirname(os.path.dirname(os.path.abspath(spec.origin)))
    return os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _child_env():
    root = _tamias2d_root()
    env = dict(os.environ)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env.setdefault("PYTHONFAULTHANDLER", "1")
    return env


def _run_child(filename, only, timeout):
    """(result dict or None, crash message or None)."""
    with tempfile.TemporaryDirectory(prefix="pymunk-suite-") as tmp:
        out = os.path.join(tmp, "result.json")
        cmd = [sys.executable, os.path.abspath(__file__), filename, "--json", out]
        for name in only or ():
            cmd += ["--only", name]
        try:
            proc = subprocess.run(cmd, env=_child_env(), capture_output=True, text=True,
                                  timeout=timeout)
        except subprocess.TimeoutExpired:
            return None, f"timed out after {timeout} s"
        if proc.returncode != 0 or not os.path.exists(out):
            tail = (proc.stderr or "")[-3000:]
            return None, f"child process exited with code {proc.returncode}\n{tail}"
        with open(out, encoding="utf-8") as f:
            return json.load(f), None


def run_test_file(filename, timeout=600, per_test_timeout=120):
    """Run one pymunk test file against tamias2d in a child process."""
    result = FileResult(filename, declared_tests(filename))
    data, crash = _run_child(filename, None, timeout)
    if data is not None:
        result.tests = data["tests"]
        result.load_error = data["load_error"]
    else:
        # find the culprit: one child per test
        result.crash = crash
        for name in result.declared:
            one, one_crash = _run_child(filename, [name], per_test_timeout)
            if one is None:
                result.tests[name] = {"outcome": "error", "detail": f"crash: {one_crash}"}
            elif one["load_error"]:
                result.load_error = one["load_error"]
                break
            else:
                result.tests.update(one["tests"])
    SUMMARY[filename] = result
    return result


def format_summary(results):
    """A table of passed / failed / errors per file."""
    lines = [f"{'pymunk test file':34s} {'passed':>6s} {'failed':>6s} {'errors':>6s} {'skipped':>7s}"]
    for filename in sorted(results):
        c = results[filename].counts()
        note = ""
        if results[filename].load_error:
            last = results[filename].load_error.strip().splitlines()[-1]
            note = f"  (load error: {last})"
        elif results[filename].crash:
            note = "  (crashed; tests rerun one by one)"
        lines.append(f"{filename:34s} {c['passed']:6d} {c['failed']:6d} {c['error']:6d} "
                     f"{c['skipped']:7d}{note}")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("filename", help="a pymunk test file, e.g. test_bb.py")
    parser.add_argument("--json", help="write the results here (used by the parent process)")
    parser.add_argument("--only", action="append", help="run only this Class.method")
    args = parser.parse_args(argv)
    if importlib.util.find_spec("tamias2d") is None:
        sys.path.insert(0, _tamias2d_root())
    if args.json:
        data = run_in_this_process(args.filename, args.only)
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(data, f)
        return 0
    result = run_test_file(args.filename)
    print(format_summary({args.filename: result}))
    for name in sorted(result.declared):
        if result.outcome(name) not in ("passed", "skipped"):
            print(f"\n--- {name}: {result.outcome(name)}\n{result.detail(name)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
