# Type stub of tamias2d.batch (compiled). NumPy is imported by the functions
# on first use; the stub needs it only for the array types.
from collections.abc import Iterable, Sequence
from typing import Any
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .space import Space

__all__ = [
    "BODY_FIELDS",
    "ARBITER_FIELDS",
    "get_bodies",
    "set_bodies",
    "body_columns",
    "get_body_ids",
    "get_arbiters",
    "arbiter_dtype",
    "get_spaces_bodies",
    "set_spaces_bodies",
]

BODY_FIELDS: dict[str, int]
ARBITER_FIELDS: tuple[str, ...]

def body_columns(fields: str | Sequence[str]) -> list[str]: ...
def get_bodies(
    space: Space, fields: str | Sequence[str], out: NDArray[np.float64] | None = None
) -> NDArray[np.float64]: ...
def set_bodies(space: Space, values: ArrayLike, fields: str | Sequence[str]) -> None: ...
def get_body_ids(space: Space) -> NDArray[np.uintp]: ...
def arbiter_dtype() -> np.dtype[np.void]: ...

# Records of arbiter_dtype(); with fields (a name or names), a structured
# view of those fields only.
def get_arbiters(
    space: Space, fields: str | Sequence[str] | None = None
) -> NDArray[np.void]: ...

def get_spaces_bodies(spaces: Iterable[Space], fields: str | Sequence[str],
                      out: NDArray[np.float64] | None = None
                      ) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...
def set_spaces_bodies(spaces: Iterable[Space], values: Any, fields: str | Sequence[str]) -> None: ...
