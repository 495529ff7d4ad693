"""pymunk's own unit tests, run against tamias2d.

Every unit test file installed with pymunk runs (in a child process, with
``pymunk`` aliased to tamias2d: see pymunk_compat.py). The tests listed in
EXPECTED_TO_PASS must pass; the others are only counted, and the table of
passed / failed / errors per file is printed at the end of the session.

When a module lands, add the names of the pymunk tests it makes pass, one per
line (``python tests/pymunk_compat.py test_body.py`` shows what passes).
"""
import pytest

import pymunk_compat

EXPECTED_TO_PASS = {
    "test_body.py": [
        "UnitTestBody.test_constraints",
        "UnitTestBody.test_coordinate_conversion",
        "UnitTestBody.test_custom_callbacks_can_be_reinstalled",
        "UnitTestBody.test_dynamic",
        "UnitTestBody.test_each_arbiters",
        "UnitTestBody.test_force",
        "UnitTestBody.test_impulse",
        "UnitTestBody.test_kinematic",
        "UnitTestBody.test_kinetic_energy",
        "UnitTestBody.test_mass",
        "UnitTestBody.test_mass_moment_from_shape",
        "UnitTestBody.test_moment",
        "UnitTestBody.test_pickle",
        "UnitTestBody.test_pickle_circular_ref",
        "UnitTestBody.test_position_func",
        "UnitTestBody.test_properties",
        "UnitTestBody.test_repr",
        "UnitTestBody.test_reset_callback_getters",
        "UnitTestBody.test_reset_callbacks_stay_reset_after_copy",
        "UnitTestBody.test_shapes",
        "UnitTestBody.test_sleep",
        "UnitTestBody.test_sleep_with_group",
        "UnitTestBody.test_static",
        "UnitTestBody.test_velocity_conversion",
        "UnitTestBody.test_velocity_func",
    ],
    "test_bb.py": [
        "UnitTestBB.testCreation",
        "UnitTestBB.testMerge",
        "UnitTestBB.testMethods",
        "UnitTestBB.testPickle",
    ],
    "test_common.py": [
        "UnitTestBugs.testGC",
        "UnitTestBugs.testManyBoxCrash",
        "UnitTestBugs.testNoStaticShape",
        "UnitTestBugs.testWeakKeysView",
        "UnitTestBugs.testX",
        "UnitTestGeneral.testAreaHelpers",
        "UnitTestGeneral.testGeneral",
        "UnitTestGeneral.testMomentHelpers",
    ],
    "test_shape.py": [
        "UnitTestCircle.testCircleBB",
        "UnitTestCircle.testCircleNoBody",
        "UnitTestCircle.testOffset",
        "UnitTestCircle.testOffsetUnsafe",
        "UnitTestCircle.testPickle",
        "UnitTestCircle.testRadius",
        "UnitTestCircle.testRadiusUnsafe",
        "UnitTestPoly.testBB",
        "UnitTestPoly.testCreateBox",
        "UnitTestPoly.testInit",
        "UnitTestPoly.testPickle",
        "UnitTestPoly.testRadius",
        "UnitTestPoly.testRadiusUnsafe",
        "UnitTestPoly.testVertices",
        "UnitTestPoly.testVerticesUnsafe",
        "UnitTestSegment.testBB",
        "UnitTestSegment.testPickle",
        "UnitTestSegment.testProperties",
        "UnitTestSegment.testPropertiesUnsafe",
        "UnitTestSegment.testSegmentSegmentCollision",
        "UnitTestSegment.testSetNeighbors",
        "UnitTestShape.testArea",
        "UnitTestShape.testCenterOfGravity",
        "UnitTestShape.testCollisionType",
        "UnitTestShape.testDensity",
        "UnitTestShape.testElasticity",
        "UnitTestShape.testFilter",
        "UnitTestShape.testFriction",
        "UnitTestShape.testMass",
        "UnitTestShape.testMoment",
        "UnitTestShape.testNoBody",
        "UnitTestShape.testPickle",
        "UnitTestShape.testPointQuery",
        "UnitTestShape.testRemoveBody",
        "UnitTestShape.testSegmentQuery",
        "UnitTestShape.testSensor",
        "UnitTestShape.testShapesCollide",
        "UnitTestShape.testSpace",
        "UnitTestShape.testSurfaceVelocity",
        "UnitTestShape.testSwitchBody",
    ],
    "test_shape_filter.py": [
        "UnitTestShapeFilter.testConstants",
        "UnitTestShapeFilter.testEq",
        "UnitTestShapeFilter.testInit",
        "UnitTestShapeFilter.testPickle",
    ],
    "test_transform.py": [
        "UnitTestTransform.testPickle",
    ],
    "test_vec2d.py": [
        "UnitTestVec2d.testComparison",
        "UnitTestVec2d.testCreationAndAccess",
        "UnitTestVec2d.testLength",
    ],
    "test_arbiter.py": [
        "UnitTestArbiter.testContactPointSet",
        "UnitTestArbiter.testFriction",
        "UnitTestArbiter.testImpulse",
        "UnitTestArbiter.testIsFirstContact",
        "UnitTestArbiter.testIsRemoval",
        "UnitTestArbiter.testNormal",
        "UnitTestArbiter.testProcessCollision",
        "UnitTestArbiter.testRestitution",
        "UnitTestArbiter.testShapesAndBodies",
        "UnitTestArbiter.testSurfaceVelocity",
        "UnitTestArbiter.testTotalKE",
    ],
    # Left out of test_space.py on purpose: testPickleCachedArbiters expects
    # pymunk's copy to lose the bodies' pending bias velocities (the copy then
    # lags one step behind the original); tamias2d's copy steps on exactly as
    # the original does (tests/test_copy_pickle.py).
    "test_space.py": [
        "UnitTestSpace.testAddBodyAsserts",
        "UnitTestSpace.testAddConstraintAsserts",
        "UnitTestSpace.testAddRemove",
        "UnitTestSpace.testAddShapeAsserts",
        "UnitTestSpace.testBBQuery",
        "UnitTestSpace.testBBQuerySensor",
        "UnitTestSpace.testCollisionHandlerAddRemoveInStep",
        "UnitTestSpace.testCollisionHandlerBegin",
        "UnitTestSpace.testCollisionHandlerDefaultCallbacks",
        "UnitTestSpace.testCollisionHandlerOrder",
        "UnitTestSpace.testCollisionHandlerPostSolve",
        "UnitTestSpace.testCollisionHandlerPreSolve",
        "UnitTestSpace.testCollisionHandlerRemoveAfterSeparate",
        "UnitTestSpace.testCollisionHandlerRemoveInStep",
        "UnitTestSpace.testCollisionHandlerSeparate",
        "UnitTestSpace.testCopyMethods",
        "UnitTestSpace.testDebugDraw",
        "UnitTestSpace.testDefaultCollisionHandler",
        "UnitTestSpace.testDeleteSpaceWithObjects",
        "UnitTestSpace.testPicklePymunkVersionCheck",
        "UnitTestSpace.testPointQuery",
        "UnitTestSpace.testPointQueryNearest",
        "UnitTestSpace.testPointQueryNearestWithShapeFilter",
        "UnitTestSpace.testPointQuerySensor",
        "UnitTestSpace.testPostStepCallback",
        "UnitTestSpace.testProperties",
        "UnitTestSpace.testReindexShape",
        "UnitTestSpace.testReindexShapesForBody",
        "UnitTestSpace.testReindexStatic",
        "UnitTestSpace.testReindexStaticCollision",
        "UnitTestSpace.testRemoveInSeparateWithinStep",
        "UnitTestSpace.testRemoveInSeparateWithoutStep",
        "UnitTestSpace.testSameTypeCollisionHandler",
        "UnitTestSpace.testSegmentQuery",
        "UnitTestSpace.testSegmentQueryFirst",
        "UnitTestSpace.testSegmentQuerySensor",
        "UnitTestSpace.testSensorQueries",
        "UnitTestSpace.testShapeQuery",
        "UnitTestSpace.testShapeQuerySensor",
        "UnitTestSpace.testSpatialHash",
        "UnitTestSpace.testStaticPointQueries",
        "UnitTestSpace.testStaticSegmentQueries",
        "UnitTestSpace.testThreaded",
        "UnitTestSpace.testWildcardCollisionHandler",
        "UnitTestSpace.test_each_phase_keeps_its_data",
        "UnitTestSpace.test_shared_data_references_are_copied_together",
        "UnitTestSpace.test_state_without_handler_data",
    ],
    "test_constraint.py": [
        "UnitTestConstraint.testA",
        "UnitTestConstraint.testActivate",
        "UnitTestConstraint.testB",
        "UnitTestConstraint.testCollideBodies",
        "UnitTestConstraint.testErrorBias",
        "UnitTestConstraint.testImpulse",
        "UnitTestConstraint.testMaxBias",
        "UnitTestConstraint.testMaxForce",
        "UnitTestConstraint.testPickle",
        "UnitTestConstraint.testPostSolve",
        "UnitTestConstraint.testPrePostSolveOrder",
        "UnitTestConstraint.testPreSolve",
        "UnitTestConstraint.test_body_types",
        "UnitTestConstraint.test_delete",
        "UnitTestDampedRotarySpring.testDamping",
        "UnitTestDampedRotarySpring.testPickle",
        "UnitTestDampedRotarySpring.testRestAngle",
        "UnitTestDampedRotarySpring.testStiffness",
        "UnitTestDampedRotarySpring.testTorqueFunc",
        "UnitTestDampedSpring.testAnchor",
        "UnitTestDampedSpring.testDamping",
        "UnitTestDampedSpring.testForceFunc",
        "UnitTestDampedSpring.testPickle",
        "UnitTestDampedSpring.testRestLength",
        "UnitTestDampedSpring.testStiffness",
        "UnitTestGearJoint.testPhase",
        "UnitTestGearJoint.testPickle",
        "UnitTestGearJoint.testRatio",
        "UnitTestGrooveJoint.testAnchor",
        "UnitTestGrooveJoint.testGroove",
        "UnitTestGrooveJoint.testPickle",
        "UnitTestPinJoint.testAnchor",
        "UnitTestPinJoint.testDistane",
        "UnitTestPinJoint.testPickle",
        "UnitTestPivotJoint.testAnchorByAnchor",
        "UnitTestPivotJoint.testAnchorByPivot",
        "UnitTestPivotJoint.testPickle",
        "UnitTestRatchetJoint.testAngle",
        "UnitTestRatchetJoint.testPhase",
        "UnitTestRatchetJoint.testPickle",
        "UnitTestRatchetJoint.testRatchet",
        "UnitTestRotaryLimitJoint.testMax",
        "UnitTestRotaryLimitJoint.testMin",
        "UnitTestRotaryLimitJoint.testPickle",
        "UnitTestSimleMotor.testPickle",
        "UnitTestSimleMotor.testSimpleMotor",
        "UnitTestSlideJoint.testAnchor",
        "UnitTestSlideJoint.testMax",
        "UnitTestSlideJoint.testMin",
        "UnitTestSlideJoint.testPickle",
    ],
    "test_autogeometry.py": [
        "UnitTestAutoGeometry.test_convex_decomposition",
        "UnitTestAutoGeometry.test_is_closed",
        "UnitTestAutoGeometry.test_march_hard",
        "UnitTestAutoGeometry.test_march_soft",
        "UnitTestAutoGeometry.test_simplify_curves",
        "UnitTestAutoGeometry.test_simplify_vertexes",
        "UnitTestAutoGeometry.test_to_convex_hull",
        "UnitTestPolylineSet.test_collect_segment",
    ],
    "test_space_debug_draw_options.py": [
        "UnitTestSpaceDebugDrawOptions.testTransform",
    ],
    "test_batch.py": [
        "UnitTestBatch.test_buffer",
        "UnitTestBatch.test_empty",
        "UnitTestBatch.test_get_arbiter_sensor",
        "UnitTestBatch.test_get_arbiters",
        "UnitTestBatch.test_get_bodies",
        "UnitTestBatch.test_set_bodies",
    ],
}

PYMUNK_TEST_FILES = pymunk_compat.pymunk_test_files()


def test_expectations_name_real_tests():
    """A typo in EXPECTED_TO_PASS must not pass silently."""
    for filename, names in EXPECTED_TO_PASS.items():
        assert filename in PYMUNK_TEST_FILES, f"pymunk has no tests/{filename}"
        declared = set(pymunk_compat.declared_tests(filename))
        unknown = [n for n in names if n not in declared]
        assert not unknown, f"{filename} defines no test named {unknown}"
        assert len(set(names)) == len(names), f"{filename}: a name is listed twice"


@pytest.mark.parametrize("filename", PYMUNK_TEST_FILES)
def test_pymunk_test_file(filename):
    expected = EXPECTED_TO_PASS.get(filename, [])
    # A file nobody expects to pass yet gets a shorter leash if it hangs.
    result = pymunk_compat.run_test_file(filename, timeout=600 if expected else 120)
    counts = result.counts()
    print(f"{filename}: {counts['passed']} passed, {counts['failed']} failed, "
          f"{counts['error']} errors, {counts['skipped']} skipped")
    not_listed = [n for n in result.names("passed") if n not in expected]
    if not_listed:
        print(f"{filename}: passing but not in EXPECTED_TO_PASS: {not_listed}")
    failing = [n for n in expected if result.outcome(n) != "passed"]
    report = "\n\n".join(f"--- {n}: {result.outcome(n)}\n{result.detail(n)}" for n in failing)
    assert not failing, (f"{len(failing)} pymunk test(s) of {filename} expected to pass "
                         f"did not:\n{report}")


# -- the runner itself ---------------------------------------------------------------

FAKE_TESTS = '''
import os, time, unittest
import pymunk
from pymunk.vec2d import Vec2d

class T(unittest.TestCase):
    def test_pass(self):
        assert pymunk.Vec2d is Vec2d and type(Vec2d(1, 2)).__module__ == "tamias2d.vector"
    def test_fail(self):
        self.assertEqual(1, 2)
    def test_error(self):
        raise RuntimeError("boom")
    def test_skip(self):
        self.skipTest("why not")
    def test_subtest(self):
        for i in range(3):
            with self.subTest(i=i):
                self.assertLess(i, 2)
    def test_crash(self):
        if os.environ.get("FAKE_CRASH"):
            os.abort()
'''


def test_runner_outcomes_and_crash_recovery(tmp_path, monkeypatch):
    (tmp_path / "test_fake.py").write_text(FAKE_TESTS)
    monkeypatch.setenv("TAMIAS2D_PYMUNK_TESTS_DIR", str(tmp_path))
    summary = dict(pymunk_compat.SUMMARY)
    try:
        result = pymunk_compat.run_test_file("test_fake.py", timeout=120)
        assert result.crash is None and result.load_error is None
        outcomes = {n: result.outcome(n) for n in result.declared}
        assert outcomes == {"T.test_pass": "passed", "T.test_fail": "failed",
                            "T.test_error": "error", "T.test_skip": "skipped",
                            "T.test_subtest": "failed", "T.test_crash": "passed"}
        assert "boom" in result.detail("T.test_error")
        # a test that kills the process: the file is rerun one test at a time
        monkeypatch.setenv("FAKE_CRASH", "1")
        result = pymunk_compat.run_test_file("test_fake.py", timeout=120)
        assert result.crash is not None
        assert result.outcome("T.test_pass") == "passed"
        assert result.outcome("T.test_crash") == "error"
        assert "crash" in result.detail("T.test_crash")
    finally:
        pymunk_compat.SUMMARY.clear()
        pymunk_compat.SUMMARY.update(summary)


def test_alias_is_undone():
    import sys
    import pymunk
    import tamias2d
    with pymunk_compat.pymunk_aliased_to_tamias2d():
        import pymunk as aliased
        assert aliased is tamias2d
        assert sys.modules["pymunk.vec2d"].Vec2d is tamias2d.Vec2d
    assert sys.modules["pymunk"] is pymunk
    assert not hasattr(tamias2d, "vec2d")
    from pymunk.vec2d import Vec2d
    assert Vec2d.__module__ == "pymunk.vec2d"
