"""The type stubs (src/tamias2d/*.pyi and py.typed).

- ``python -m mypy.stubtest tamias2d --allowlist tests/stubtest_allowlist.txt
  --mypy-config-file tests/stubtest_mypy.ini`` compares every stub with the
  module it describes, imported: a public name missing from a stub, a
  signature or a read-only property that differs, fails the test with
  stubtest's report. (The allowlist names Cython's own module attributes; the
  mypy settings keep errors in private pure-Python modules, which have no
  stubs, from stopping the check.)
- ``tests/typing_sample.py``, a pymunk-style program, must pass
  ``mypy --strict`` (its assert_type calls pin the types the stubs give) and
  must run.
- A snippet of wrong calls must give a mypy error on each marked line, and on
  no other, so the stubs are known to reject what they should.

All of it runs on the tamias2d this process imported (the checkout with an
in-place build, or an installed one), in subprocesses started from a
temporary folder. Skipped only when mypy is not installed.
"""
import importlib.machinery
import os
import pkgutil
import re
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("mypy")

import tamias2d  # noqa: E402

TESTS = os.path.dirname(os.path.abspath(__file__))
ALLOWLIST = os.path.join(TESTS, "stubtest_allowlist.txt")
MYPY_INI = os.path.join(TESTS, "stubtest_mypy.ini")
SAMPLE = os.path.join(TESTS, "typing_sample.py")
# The folder holding the tamias2d package this process uses.
PACKAGE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(tamias2d.__file__)))


def run_python(args, cwd, timeout=120):
    env = dict(os.environ)
    env["PYTHONPATH"] = PACKAGE_ROOT + os.pathsep + env.get("PYTHONPATH", "")
    env.pop("MYPYPATH", None)
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)


def run_mypy(path, tmp_path):
    return run_python(["-m", "mypy", "--strict", "--no-error-summary", "--hide-error-context",
                       "--no-color-output", "--cache-dir", str(tmp_path / "mypy-cache"), path],
                      cwd=tmp_path)


def public_modules():
    """name -> True for a compiled module, False for a pure-Python one."""
    folder = os.path.dirname(os.path.abspath(tamias2d.__file__))
    found = {"__init__": False}
    for info in pkgutil.iter_modules([folder]):
        if info.name.startswith("_") and info.name != "__main__":
            continue
        compiled = any(os.path.isfile(os.path.join(folder, info.name + suffix))
                       for suffix in importlib.machinery.EXTENSION_SUFFIXES)
        found[info.name] = compiled
    return found


def test_package_ships_stubs():
    folder = os.path.dirname(os.path.abspath(tamias2d.__file__))
    assert os.path.isfile(os.path.join(folder, "py.typed"))
    modules = public_modules()
    assert {"vector", "body", "shape", "collision", "arbiter", "constraints", "space",
            "batch"} <= {name for name, compiled in modules.items() if compiled}
    for name, compiled in modules.items():
        # A pure-Python module may go without a stub: mypy reads its source.
        if compiled or name in ("__init__", "errors", "space_debug_draw_options",
                                "pygame_util", "pillow_util"):
            assert os.path.isfile(os.path.join(folder, name + ".pyi")), name


def test_mypy_settings_name_every_public_module():
    # stubtest_mypy.ini ignores errors in every tamias2d submodule but the
    # ones it names: a new public module has to be named there to be checked.
    with open(MYPY_INI) as f:
        text = f.read()
    names = set(re.search(r"^\[mypy-(tamias2d,[^\]]*)\]\nignore_errors = False$", text,
                          re.MULTILINE).group(1).split(","))
    expected = {"tamias2d"} | {"tamias2d." + name for name in public_modules()
                               if name != "__init__"}
    assert names == expected


# Drawing modules whose back end is optional (the `draw` extra): without it
# they refuse to import, and stubtest can only check them where it is there.
OPTIONAL_BACKENDS = {"matplotlib_util": "matplotlib", "pyglet_util": "pyglet"}


def test_stubtest_is_clean(tmp_path):
    import importlib.util
    args = ["-m", "mypy.stubtest", "tamias2d", "--allowlist", ALLOWLIST,
            "--mypy-config-file", MYPY_INI]
    missing = [m for m, lib in OPTIONAL_BACKENDS.items() if importlib.util.find_spec(lib) is None]
    if missing:
        extra = tmp_path / "missing_backends.txt"
        extra.write_text("".join(rf"tamias2d\.{m}" + "\n" for m in missing))
        args += ["--allowlist", str(extra)]
    result = run_python(args, cwd=tmp_path)
    report = result.stdout + result.stderr
    assert result.returncode == 0 and "Success" in result.stdout, report
    # An allowlist entry that no longer matches anything is reported as a note.
    assert "unused allowlist entry" not in report, report


def test_typing_sample_passes_mypy_strict(tmp_path):
    result = run_mypy(SAMPLE, tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr


def test_typing_sample_runs(tmp_path):
    result = run_python([SAMPLE], cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr


# Each line marked "# error" must be reported by mypy; no other line may be.
WRONG = '''
import tamias2d as pymunk

space = pymunk.Space()
body = pymunk.Body(mass="x")  # error: a str mass
circle = pymunk.Circle(body, 5)
circle.radius = 6  # error: radius is read-only (unsafe_set_radius sets it)
space.gravity = "down"  # error: not a pair of numbers
space.on_collision(1, 2, begn=lambda arbiter, space, data: None)  # error: no such keyword
space.step()  # error: dt is missing
v = pymunk.Vec2d(1, 2) * (1, 2)  # error: a Vec2d scales by a number only
body.position.z  # error: Vec2d has no z
body.velocity_func = lambda b: None  # error: the integrator takes 4 arguments
hits: list[pymunk.Shape] = space.point_query((0, 0), 1, pymunk.ShapeFilter())  # error
pymunk.PivotJoint(body, body, (0, 0), (0, 0), (0, 0))  # error: 1 pivot or 2 anchors
nearest = space.point_query_nearest((0, 0), 1, pymunk.ShapeFilter())
nearest.shape  # error: nearest may be None
pymunk.Poly(None, [(0, 0), (1, 0), (0, 1)], radius="1")  # error: a str radius
body.color = "red"  # user attributes are allowed, as with pymunk
'''


def test_wrong_calls_are_type_errors(tmp_path):
    path = tmp_path / "wrong.py"
    path.write_text(textwrap.dedent(WRONG))
    expected = {i for i, line in enumerate(WRONG.splitlines(), 1) if "# error" in line}
    result = run_mypy(str(path), tmp_path)
    output = result.stdout + result.stderr
    reported = {int(m.group(1)) for m in re.finditer(r"^[^\n:]*wrong\.py:(\d+): error:", output,
                                                     re.MULTILINE)}
    assert result.returncode == 1, output
    assert reported == expected, (
        f"lines expected to be errors but not reported: {sorted(expected - reported)}; "
        f"lines reported but not expected: {sorted(reported - expected)}\n{output}")


def stub_attributes():
    """(module, class) -> {name: settable} for the properties and instance
    attributes each class of the stubs declares."""
    import ast

    folder = os.path.dirname(os.path.abspath(tamias2d.__file__))
    found = {}
    for name in public_modules():
        path = os.path.join(folder, name + ".pyi")
        if not os.path.isfile(path):
            continue
        module = "tamias2d" if name == "__init__" else "tamias2d." + name
        with open(path) as f:
            tree = ast.parse(f.read())
        for node in tree.body:
            if not isinstance(node, ast.ClassDef):
                continue
            attrs = found.setdefault((module, node.name), {})
            for item in node.body:
                if isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                    if "ClassVar" not in ast.unparse(item.annotation):
                        attrs[item.target.id] = True
                elif isinstance(item, ast.FunctionDef):
                    for dec in item.decorator_list:
                        if isinstance(dec, ast.Name) and dec.id == "property":
                            attrs.setdefault(item.name, False)
                        elif isinstance(dec, ast.Attribute) and dec.attr == "setter":
                            attrs[item.name] = True
    return found


def settable_problems(obj, declared):
    """The attributes of obj whose stub says settable (or read-only) while
    assigning its own value back says otherwise. stubtest cannot see this for
    the properties of cdef classes, whose descriptors do not tell."""
    problems = []
    seen = set()
    for cls in type(obj).__mro__:
        for name, settable in declared.get((cls.__module__, cls.__name__), {}).items():
            if name in seen:
                continue
            seen.add(name)
            try:
                setattr(obj, name, getattr(obj, name))
                writable = True
            except AttributeError:
                writable = False
            except Exception:  # refused for this value or state, but it has a setter
                writable = True
            if writable != settable:
                problems.append(f"{cls.__name__}.{name}: stub says "
                                f"{'settable' if settable else 'read-only'}")
    return problems


def test_read_only_properties_match_runtime():
    from tamias2d import constraints as c

    declared = stub_attributes()
    space = tamias2d.Space()
    a, b = tamias2d.Body(1, 10), tamias2d.Body(1, 10)
    b.position = 0, 5
    circle = tamias2d.Circle(a, 5)
    circle.collision_type = 1
    objects = [space, a, circle, tamias2d.Segment(b, (0, 0), (1, 0), 1),
               tamias2d.Poly.create_box(b), tamias2d.SpaceDebugDrawOptions(),
               c.PinJoint(a, b), c.SlideJoint(a, b, (0, 0), (0, 0), 0, 1),
               c.PivotJoint(a, b, (0, 0)), c.GrooveJoint(a, b, (0, 0), (1, 0), (0, 0)),
               c.DampedSpring(a, b, (0, 0), (0, 0), 1, 1, 1),
               c.DampedRotarySpring(a, b, 0, 1, 1), c.RotaryLimitJoint(a, b, 0, 1),
               c.RatchetJoint(a, b, 0, 1), c.GearJoint(a, b, 0, 1), c.SimpleMotor(a, b, 1)]
    space.add(a, b, circle, tamias2d.Circle(b, 5))
    problems = []

    def pre_solve(arbiter, space, data):
        problems.extend(settable_problems(arbiter, declared))
        cps = arbiter.contact_point_set
        problems.extend(settable_problems(cps, declared))
        problems.extend(settable_problems(cps.points[0], declared))

    space.on_collision(1, None, pre_solve=pre_solve)
    space.step(0.01)
    objects.append(space._handlers[(1, None)])
    for obj in objects:
        problems.extend(settable_problems(obj, declared))
    assert problems == []
    assert declared[("tamias2d.arbiter", "Arbiter")]  # the stubs were read
