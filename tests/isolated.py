"""Run a test in a child process, so that a crash is a failed test.

A segfault or abort in the engine would kill the whole pytest run. A test
decorated with :func:`isolated` runs in a ``fork()`` of the pytest process
instead: a child killed by a signal, or still running after ``timeout``
seconds, makes that one test fail with the signal's name, and the rest of
the session goes on. A Python failure in the child (an assertion, a
hypothesis falsifying example) is sent back and re-raised as the test's
failure, with the child's traceback; the child's output lands in the
captured output of the test as usual.

Set TAMIAS2D_NO_FORK=1 to run the tests in the pytest process (to debug
them with pdb).

>>> @isolated(timeout=10)
... def check():
...     assert 1 + 1 == 2
>>> check()
"""
import functools
import inspect
import os
import pickle
import select
import signal
import sys
import time
import traceback

import pytest

SEED_ENV = "TAMIAS2D_SEED"


def _signal_name(num):
    try:
        return signal.Signals(num).name
    except ValueError:
        return f"signal {num}"


def run_in_child(fn, args=(), kwargs=None, timeout=120.0):
    """Call fn(*args, **kwargs) in a forked child. Returns
    ("ok", fn's return value, which must pickle), ("error", (type name,
    message, traceback text)), ("skip", reason), ("signal", name) or
    ("timeout", seconds)."""
    kwargs = kwargs or {}
    sys.stdout.flush()
    sys.stderr.flush()
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # child
        os.close(r)
        status = 0
        try:
            try:
                payload = ("ok", fn(*args, **kwargs))
            except pytest.skip.Exception as exc:
                payload = ("skip", str(exc))
            except BaseException as exc:
                payload = ("error", (type(exc).__name__, str(exc), traceback.format_exc()))
                status = 1
            data = pickle.dumps(payload)
            sys.stdout.flush()
            sys.stderr.flush()
            view = memoryview(data)
            while view:
                n = os.write(w, view)
                view = view[n:]
        finally:
            os._exit(status)
    os.close(w)
    chunks = []
    deadline = time.monotonic() + timeout
    timed_out = False
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            timed_out = True
            break
        ready, _, _ = select.select([r], [], [], min(left, 1.0))
        if ready:
            chunk = os.read(r, 1 << 16)
            if not chunk:
                break
            chunks.append(chunk)
    os.close(r)
    if timed_out:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        return ("timeout", timeout)
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        return ("signal", _signal_name(os.WTERMSIG(status)))
    try:
        return pickle.loads(b"".join(chunks))
    except Exception:
        return ("error", ("ChildExit", f"the child exited with status "
                          f"{os.WEXITSTATUS(status)} and no result", ""))


def isolated(timeout=120.0, note=None):
    """Decorator: run the test in a forked child (see the module docstring).
    `note()`, if given, returns text added to any failure (a seed, say)."""
    def deco(fn):
        def wrapper(*args, **kwargs):
            if os.environ.get("TAMIAS2D_NO_FORK", "") not in ("", "0"):
                return fn(*args, **kwargs)
            kind, info = run_in_child(fn, args, kwargs, timeout)
            extra = f"\n{note()}" if note is not None else ""
            if kind == "ok":
                return None
            if kind == "skip":
                pytest.skip(info)
            if kind == "signal":
                pytest.fail(f"{fn.__name__}: the test process was killed by {info} (a crash in "
                            f"the engine; the faulthandler traceback, if any, is on stderr){extra}",
                            pytrace=False)
            if kind == "timeout":
                pytest.fail(f"{fn.__name__}: still running after {info} s (a hang?); killed{extra}",
                            pytrace=False)
            name, message, tb = info
            pytest.fail(f"{fn.__name__} failed in the child process:\n{tb}{extra}", pytrace=False)

        wrapper.__name__ = fn.__name__
        wrapper.__qualname__ = getattr(fn, "__qualname__", fn.__name__)
        wrapper.__doc__ = fn.__doc__
        wrapper.__module__ = fn.__module__
        wrapper.__signature__ = inspect.signature(fn)
        if hasattr(fn, "pytestmark"):
            wrapper.pytestmark = list(fn.pytestmark)
        return wrapper
    return deco
