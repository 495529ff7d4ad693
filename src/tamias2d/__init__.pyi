# Type stub of the tamias2d package: the names tamias2d/__init__.py imports.
from . import batch as batch
from . import constraints as constraints
from . import errors as errors
from . import sweeps as sweeps
from .arbiter import Arbiter as Arbiter
from .body import Body as Body
from .collision import ContactPoint as ContactPoint
from .collision import ContactPointSet as ContactPointSet
from .constraints import Constraint as Constraint
from .constraints import DampedRotarySpring as DampedRotarySpring
from .constraints import DampedSpring as DampedSpring
from .constraints import GearJoint as GearJoint
from .constraints import GrooveJoint as GrooveJoint
from .constraints import PinJoint as PinJoint
from .constraints import PivotJoint as PivotJoint
from .constraints import RatchetJoint as RatchetJoint
from .constraints import RotaryLimitJoint as RotaryLimitJoint
from .constraints import SimpleMotor as SimpleMotor
from .constraints import SlideJoint as SlideJoint
from .shape import Circle as Circle
from .shape import PointQueryInfo as PointQueryInfo
from .shape import Poly as Poly
from .shape import Segment as Segment
from .shape import SegmentQueryInfo as SegmentQueryInfo
from .shape import Shape as Shape
from .shape import ShapeFilter as ShapeFilter
from .shape import ShapeQueryInfo as ShapeQueryInfo
from .shape import area_for_circle as area_for_circle
from .shape import area_for_poly as area_for_poly
from .shape import area_for_segment as area_for_segment
from .shape import centroid_for_poly as centroid_for_poly
from .shape import moment_for_box as moment_for_box
from .shape import moment_for_circle as moment_for_circle
from .shape import moment_for_poly as moment_for_poly
from .shape import moment_for_segment as moment_for_segment
from .space import Space as Space
from .space import empty_callback as empty_callback
from .space_debug_draw_options import SpaceDebugDrawOptions as SpaceDebugDrawOptions
from .sweeps import sweep as sweep
from .vector import BB as BB
from .vector import Transform as Transform
from .vector import Vec2d as Vec2d

__all__ = [
    "version", "chipmunk_version",
    "Vec2d", "BB", "Transform",
    "Body",
    "Shape", "Circle", "Segment", "Poly", "ShapeFilter",
    "PointQueryInfo", "SegmentQueryInfo", "ShapeQueryInfo",
    "moment_for_circle", "moment_for_segment", "moment_for_box", "moment_for_poly",
    "area_for_circle", "area_for_segment", "area_for_poly", "centroid_for_poly",
    "Space", "empty_callback",
    "Arbiter", "ContactPoint", "ContactPointSet",
    "Constraint", "PinJoint", "SlideJoint", "PivotJoint", "GrooveJoint", "DampedSpring",
    "DampedRotarySpring", "RotaryLimitJoint", "RatchetJoint", "GearJoint", "SimpleMotor",
    "SpaceDebugDrawOptions",
    "install_as_pymunk", "step_spaces", "sweep",
]

version: str
chipmunk_version: str

def install_as_pymunk() -> None: ...

from collections.abc import Iterable as _Iterable
def step_spaces(spaces: _Iterable[Space], dt: float, *, threads: int | None = None,
                steps: int = 1) -> None: ...
