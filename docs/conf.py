"""Sphinx configuration of the tamias2d documentation.

Build it with (from the repository root, after ``pip install ".[docs]"``)::

    python -m sphinx -W -b html docs docs/_build/html

``-W`` turns every warning into an error. The API reference is read from the
compiled modules, so tamias2d must be importable: the installed package, or a
development build (``python setup.py build_ext --inplace``) with
``PYTHONPATH=src``.
"""
import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent

# Sphinx 9 documents a compiled module from its .pyi stub when there is one;
# the stubs carry types but no docstrings, so read the compiled modules.
os.environ["SPHINX_AUTODOC_IGNORE_NATIVE_MODULE_TYPE_STUBS"] = "1"

try:
    import tamias2d
except ImportError:
    # A checkout with a development build in src/ and nothing installed.
    sys.path.insert(0, str(ROOT / "src"))
    import tamias2d

sys.path.insert(0, str(DOCS / "_ext"))

project = "tamias2d"
author = "The tamias2d developers"
copyright = "the tamias2d developers (MIT license)"
version = release = tamias2d.version

extensions = [
    "sphinx.ext.autodoc",
    "myst_parser",
    "tamias2d_sphinx",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_ext", "Thumbs.db", ".DS_Store"]

# MyST: the docs/*.md pages are plain CommonMark with GitHub tables; headings
# down to ### get anchors so that [text](page.md#heading) links resolve.
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3

autodoc_default_options = {
    "members": True,
    "undoc-members": True,
    "show-inheritance": True,
}
autodoc_member_order = "bysource"
# Cython's embedsignature puts each signature at the top of the docstring;
# docs/_ext/tamias2d_sphinx.py rewrites it in Python notation.
autodoc_docstring_signature = True
autoclass_content = "class"
autodoc_typehints = "signature"
add_module_names = False

# Curly quotes and ellipses, but "--" stays two hyphens (command-line options).
smartquotes_action = "qe"


html_theme = "furo" if __import__("importlib").util.find_spec("furo") else "alabaster"
html_title = f"tamias2d {release}"
html_static_path = []

# The examples gallery (docs/examples.rst): examples/*.py of the checkout.
tamias2d_examples_dir = str(ROOT / "examples")
tamias2d_gallery_run = True
tamias2d_gallery_frames = 60
