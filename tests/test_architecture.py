"""The module layering of docs/architecture.md ("Which module may cimport
which"), checked on the sources: every ``cimport`` of an engine module names
a module beneath it, and every module has a place in the list.
"""
import pathlib
import re

import pytest

SRC = pathlib.Path(__file__).resolve().parent.parent / "src" / "tamias2d"

# Bottom first; modules on one line may not cimport each other.
LAYERS = [
    ["_config"],
    ["vector"],
    ["_structs"],
    ["_containers", "_threadguard", "_threads", "_pickle"],
    ["_private"],
    ["_spatialindex"],
    ["_bbtree", "_spacehash"],
    ["body"],
    ["shape"],
    ["collision"],
    ["arbiter", "constraints"],
    ["_space_step"],
    ["_soft_step"],
    ["_space_query"],
    ["space"],
    ["_snapshot", "batch", "_step_spaces", "autogeometry"],
    ["_testing"],
]
RANK = {name: i for i, layer in enumerate(LAYERS) for name in layer}
CIMPORT = re.compile(r"^\s*(?:from\s+tamias2d\.(\w+)\s+cimport|cimport\s+tamias2d\.(\w+))", re.M)


def cimports(path):
    text = path.read_text()
    return {a or b for a, b in CIMPORT.findall(text)}


def engine_files():
    return sorted(list(SRC.glob("*.pyx")) + list(SRC.glob("*.pxd")))


def test_every_module_has_a_layer():
    unknown = sorted({p.stem for p in engine_files()} - set(RANK))
    assert not unknown, (f"{unknown}: add them to LAYERS here and to the list in "
                         f"docs/architecture.md")


@pytest.mark.parametrize("path", engine_files(), ids=lambda p: p.name)
def test_cimports_run_downwards(path):
    me = RANK[path.stem]
    upward = sorted(m for m in cimports(path) - {path.stem} if RANK.get(m, -1) >= me)
    assert not upward, f"{path.name} cimports {upward}, which are not beneath it"


def test_the_checker_sees_an_upward_cimport(tmp_path):
    bad = tmp_path / "body.pyx"
    bad.write_text("from tamias2d.space cimport Space\n")
    assert cimports(bad) == {"space"} and RANK["space"] > RANK["body"]
