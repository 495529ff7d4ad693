"""Build of the tamias2d extension modules.

Every ``src/tamias2d/*.pyx`` is cythonized with one set of directives. The C flags
keep floating-point arithmetic exactly as Munk2D compiled by pymunk does it: no
fused multiply-add (``-ffp-contract=off``), no ``-ffast-math``, no
``-march=native``.

The soft solver's module (_soft_step) is built with GCC's inlining limits
raised (SOFT_STEP_GCC_ARGS): its per-contact and per-body functions are
called once per contact or body from one loop each, and left as calls they
cost the rain of benchmarks/callgrind_steps.py 2% of its step. Only GCC
knows those parameters; other compilers build it as the rest.

Environment:
  TAMIAS2D_DEBUG=1       bounds and wraparound checks on, ``-O0 -g``.
  TAMIAS2D_ONLY=a,b      build only the named modules (for working on one
                         module while others are in progress).
"""
import glob
import os
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

try:
    from Cython.Build import cythonize
except ImportError:  # pragma: no cover - pyproject lists Cython as a build requirement
    sys.exit("tamias2d needs Cython >= 3.1 to build: pip install 'Cython>=3.1'")

DEBUG = os.environ.get("TAMIAS2D_DEBUG", "") not in ("", "0")
ONLY = [m for m in os.environ.get("TAMIAS2D_ONLY", "").split(",") if m]

directives = {
    "language_level": 3,
    "boundscheck": DEBUG,
    "wraparound": DEBUG,
    "cdivision": True,
    "embedsignature": True,
    "initializedcheck": DEBUG,
    # No "freethreading_compatible": the step releases the GIL (so spaces
    # stepped in different threads run in parallel in any build), but the
    # Python-level methods of Space, Body and Shape rely on the GIL to be
    # atomic with respect to each other (add/remove, reindex, property
    # setters). A free-threaded interpreter therefore keeps the GIL on for
    # tamias2d. See docs/architecture.md, "Copy, pickle and threads".
}

if sys.platform == "win32":
    compile_args = ["/O2", "/fp:precise"]
else:
    compile_args = ["-O0", "-g"] if DEBUG else ["-O3"]
    compile_args += ["-ffp-contract=off", "-fno-strict-aliasing", "-fwrapv"]

extensions = []
for path in sorted(glob.glob(os.path.join("src", "tamias2d", "*.pyx"))):
    name = os.path.splitext(os.path.basename(path))[0]
    if ONLY and name not in ONLY:
        continue
    extensions.append(Extension(
        "tamias2d." + name,
        [path],
        extra_compile_args=compile_args,
        define_macros=[("CYTHON_TRACE", "0")],
    ))

# Inlining limits for the soft step's module (see the docstring). Inlining
# changes no arithmetic: -ffp-contract=off and no -ffast-math hold everywhere.
SOFT_STEP_GCC_ARGS = ["--param", "max-inline-insns-single=2000",
                      "--param", "max-inline-insns-auto=100"]


def _is_gcc(command):
    """Whether the C compiler `command` (a list, as distutils keeps it) is GCC."""
    words = [w for w in command if not w.endswith("ccache")]
    if not words:
        return False
    try:
        out = subprocess.run([words[0], "--version"], capture_output=True, text=True,
                             timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return False
    return "Free Software Foundation" in out and "clang" not in out.lower()


class BuildExt(build_ext):
    def build_extensions(self):
        if (not DEBUG and self.compiler.compiler_type == "unix"
                and _is_gcc(self.compiler.compiler_so)):
            for ext in self.extensions:
                if ext.name == "tamias2d._soft_step":
                    ext.extra_compile_args = list(ext.extra_compile_args) + SOFT_STEP_GCC_ARGS
        super().build_extensions()


setup(
    cmdclass={"build_ext": BuildExt},
    ext_modules=cythonize(
        extensions,
        compiler_directives=directives,
        include_path=["src"],
        annotate=DEBUG,
        nthreads=0,
    ),
)
