"""The code on the documentation's guide pages runs, and prints what the
pages say it prints.

On each page the ```python blocks run in order, as one program, in a fresh
interpreter (the pages install the pymunk import hook, which must not touch
this process) inside a temporary folder (the tutorial writes a picture). A
```text block that directly follows a ```python block is that block's
output and must match it exactly.
"""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parent.parent / "docs"
PAGES = ["tutorial.md", "coming-from-pymunk.md", "coming-from-box2d.md"]

_FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.S | re.M)


def code_blocks(text):
    """[(code, expected output or None)] of the page's python blocks."""
    fences = [(m.group(1), m.group(2), m.start(), m.end()) for m in _FENCE.finditer(text)]
    blocks = []
    for i, (lang, body, _start, end) in enumerate(fences):
        if lang != "python":
            continue
        expected = None
        if i + 1 < len(fences):
            next_lang, next_body, next_start, _ = fences[i + 1]
            if next_lang == "text" and not text[end:next_start].strip():
                expected = next_body
        blocks.append((body, expected))
    return blocks


# Runs the blocks in one namespace; prints a marker before each so that the
# output can be split per block.
_RUNNER = """
import json, sys
blocks = json.loads(sys.stdin.read())
namespace = {"__name__": "__main__"}
for i, code in enumerate(blocks):
    print(f"\\n@@block {i}@@", flush=True)
    exec(compile(code, f"<block {i}>", "exec"), namespace)
    sys.stdout.flush()
"""


def run_blocks(blocks, cwd):
    env = dict(os.environ)
    env.setdefault("SDL_VIDEODRIVER", "dummy")
    env["PYTHONPATH"] = os.pathsep.join(
        p for p in [str(Path(__import__("tamias2d").__file__).resolve().parent.parent),
                    env.get("PYTHONPATH")] if p)
    proc = subprocess.run([sys.executable, "-c", _RUNNER], input=json.dumps([c for c, _ in blocks]),
                          capture_output=True, text=True, cwd=cwd, env=env, timeout=120)
    assert proc.returncode == 0, f"a block failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}"
    parts = re.split(r"\n@@block (\d+)@@\n", "\n" + proc.stdout)
    return {int(parts[i]): parts[i + 1] for i in range(1, len(parts), 2)}


def test_code_blocks_are_found():
    blocks = code_blocks("text\n```python\nprint(1)\n```\n\n```text\n1\n```\n"
                         "```python\nx = 2\n```\nprose\n```text\nnot output\n```\n")
    assert blocks == [("print(1)\n", "1\n"), ("x = 2\n", None)]


@pytest.mark.parametrize("page", PAGES)
def test_page_code_runs_and_prints_what_the_page_says(page, tmp_path):
    blocks = code_blocks((DOCS / page).read_text(encoding="utf-8"))
    assert blocks, f"no python blocks on {page}"
    outputs = run_blocks(blocks, tmp_path)
    for i, (code, expected) in enumerate(blocks):
        if expected is not None:
            assert outputs.get(i, "").strip() == expected.strip(), (
                f"{page}, block {i + 1}:\n{code}\nprinted:\n{outputs.get(i)}\nthe page says:\n{expected}")
    if page == "tutorial.md":
        assert (tmp_path / "tutorial.png").is_file()
