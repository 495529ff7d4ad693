"""tamias2d: a 2D rigid-body physics engine, a Cython port of Chipmunk2D.

It follows Munk2D (the Chipmunk2D fork inside pymunk 7.3) closely enough that
the same scene gives the same numbers, and offers pymunk's Python API. To run
a pymunk program unchanged, call ``tamias2d.install_as_pymunk()`` before it
imports pymunk (then ``import pymunk`` and ``import pymunk.pygame_util`` give
tamias2d), or start it with ``tamias2d run program.py``.
"""
version = "0.1.0"
# The Chipmunk the port follows: Munk2D 2.0.1 as pymunk 7.3 compiles it.
chipmunk_version = "2.0.1-tamias2d"

from . import errors
from .body import Body
from .shape import (Shape, Circle, Segment, Poly, ShapeFilter, PointQueryInfo,
    SegmentQueryInfo, ShapeQueryInfo, moment_for_circle, moment_for_segment, moment_for_box,
    moment_for_poly, area_for_circle, area_for_segment, area_for_poly, centroid_for_poly)
from .space_debug_draw_options import SpaceDebugDrawOptions
from .vector import Vec2d, BB, Transform
from .collision import ContactPoint, ContactPointSet
from .arbiter import Arbiter
from .space import Space, empty_callback
from . import batch
from . import constraints
from .constraints import (Constraint, PinJoint, SlideJoint, PivotJoint, GrooveJoint,
    DampedSpring, DampedRotarySpring, RotaryLimitJoint, RatchetJoint, GearJoint, SimpleMotor)
from ._pymunk_hook import install_as_pymunk
from ._step_spaces import step_spaces
from . import sweeps
from .sweeps import sweep

# The package's public names (`from tamias2d import *`), the documented API of
# docs/api/; the modules batch, constraints, errors, ... are reached as
# attributes, as pymunk's are.
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
