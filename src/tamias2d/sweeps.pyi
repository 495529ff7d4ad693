# Type stub of tamias2d.sweeps (pure Python; dask and ray are optional).
from collections.abc import Callable, Mapping, Sequence
from multiprocessing.context import BaseContext
from typing import Any, Literal, TypeVar

__all__ = ["sweep", "grid_points", "BACKENDS"]

_R = TypeVar("_R")

# A dict of value lists (their cartesian product) or a list of dicts.
_Grid = Mapping[str, Sequence[Any]] | Sequence[Mapping[str, Any]]

BACKENDS: tuple[str, ...]

def grid_points(grid: _Grid) -> list[dict[str, Any]]: ...
def sweep(
    fn: Callable[..., _R],
    grid: _Grid,
    *,
    scene: object = None,
    backend: Literal["process", "serial", "dask", "ray"] = "process",
    workers: int | None = None,
    client: Any = None,
    chunksize: int | None = None,
    mp_context: BaseContext | str | None = None,
) -> list[_R]: ...
