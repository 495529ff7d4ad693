# Type stub of tamias2d.batch (compiled). NumPy is imported by the functions
# on first use; the stub needs it only for the array types.
from collections.abc import Iterable, Sequence
from enum import Flag
from typing import Any

from typing_extensions import disjoint_base

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
    "BodyFields",
    "ArbiterFields",
    "Buffer",
    "get_space_bodies",
    "set_space_bodies",
    "get_space_arbiters",
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

# pymunk's batch API (pymunk.batch of pymunk 7.3).
class BodyFields(Flag):
    BODY_ID = 1
    POSITION = 2
    ANGLE = 4
    VELOCITY = 8
    ANGULAR_VELOCITY = 16
    FORCE = 32
    TORQUE = 64
    ALL = 0xFFFF

class ArbiterFields(Flag):
    BODY_A_ID = 1
    BODY_B_ID = 2
    TOTAL_IMPULSE = 4
    TOTAL_KE = 8
    IS_FIRST_CONTACT = 16
    NORMAL = 32
    CONTACT_COUNT = 64
    POINT_A_1 = 128
    POINT_B_1 = 256
    DISTANCE_1 = 512
    POINT_A_2 = 1024
    POINT_B_2 = 2048
    DISTANCE_2 = 4096
    ALL = 0xFFFF

@disjoint_base
class Buffer:
    def __init__(self) -> None: ...
    def clear(self) -> None: ...
    # Memoryviews of the bytes of the arrays (format "B").
    def float_buf(self) -> memoryview: ...
    # `buffer`: any object with the buffer protocol (collections.abc.Buffer
    # from Python 3.12) holding C doubles or raw bytes.
    def set_float_buf(self, buffer: Any) -> None: ...
    def int_buf(self) -> memoryview: ...
    def set_int_buf(self, buffer: Any) -> None: ...

def get_space_bodies(space: Space, fields: BodyFields, buffers: Buffer) -> None: ...
def set_space_bodies(space: Space, fields: BodyFields, buffers: Buffer) -> None: ...
def get_space_arbiters(space: Space, fields: ArbiterFields, buffers: Buffer) -> None: ...
