"""Debug drawing: SpaceDebugDrawOptions against pymunk's, the Pillow drawer,
and what of pygame_util can run without a display.

pymunk's options are the reference for every setting and for
color_for_shape. The Pillow drawer is checked by looking at pixels: a shape
must leave its colour where it is, the background must stay elsewhere, and
positive y must point up.
"""
import doctest
import math
import struct

import pymunk
import pytest

import tamias2d
from tamias2d import pygame_util
from tamias2d.space_debug_draw_options import SpaceDebugColor, SpaceDebugDrawOptions

pytest.importorskip("PIL", reason="Pillow (in the test extra) is needed for the drawer tests")
from PIL import Image  # noqa: E402

from tamias2d import pillow_util  # noqa: E402


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


# --- SpaceDebugDrawOptions vs pymunk -------------------------------------


def test_exported_like_pymunk():
    assert tamias2d.SpaceDebugDrawOptions is SpaceDebugDrawOptions


def test_flag_constants_and_default_flags():
    ours, ref = SpaceDebugDrawOptions, pymunk.SpaceDebugDrawOptions
    assert (ours.DRAW_SHAPES, ours.DRAW_CONSTRAINTS, ours.DRAW_COLLISION_POINTS) == (
        ref.DRAW_SHAPES, ref.DRAW_CONSTRAINTS, ref.DRAW_COLLISION_POINTS)
    assert ours().flags == ref().flags == 7


@pytest.mark.parametrize("name", ["shape_outline_color", "constraint_color",
                                  "collision_point_color"])
def test_default_colours(name):
    ours = getattr(SpaceDebugDrawOptions(), name)
    ref = getattr(pymunk.SpaceDebugDrawOptions(), name)
    assert ours == ref
    assert type(ours).__name__ == "SpaceDebugColor"
    assert all(type(c) is float for c in ours)  # floats, as they come out of C


@pytest.mark.parametrize("name", ["shape_dynamic_color", "shape_static_color",
                                  "shape_kinematic_color", "shape_sleeping_color"])
def test_state_colours_are_plain_attributes(name):
    ours, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    assert getattr(ours, name) == getattr(ref, name)
    assert [type(c) for c in getattr(ours, name)] == [type(c) for c in getattr(ref, name)]
    setattr(ours, name, (1, 2, 3, 4))
    setattr(ref, name, (1, 2, 3, 4))
    assert getattr(ours, name) == getattr(ref, name) == (1, 2, 3, 4)
    # An instance's setting does not leak into the class.
    assert getattr(SpaceDebugDrawOptions, name) == getattr(pymunk.SpaceDebugDrawOptions, name)


@pytest.mark.parametrize("value", [
    (10, 20, 30, 40), [1, 2, 3, 4], (0.1, 0.2, 254.9, 1e-3), (1e40, -1e40, 0, 255),
    (255.0, 255.5, -0.0, 3.3), SpaceDebugColor(5, 6, 7, 8),
])
@pytest.mark.parametrize("name", ["shape_outline_color", "constraint_color",
                                  "collision_point_color"])
def test_colour_setters_round_like_c_float(name, value):
    ours, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    setattr(ours, name, value)
    setattr(ref, name, value)
    got, want = getattr(ours, name), getattr(ref, name)
    assert tuple(got) == tuple(want)
    assert tuple(got) == tuple(f32(float(v)) if abs(v) < 1e39 else math.copysign(math.inf, v)
                               for v in value)


@pytest.mark.parametrize("bad, error", [
    ("abcd", TypeError), (None, TypeError), (5, TypeError), ((1, "a", 2, 3), TypeError),
    ((1, 2, 3, 4, 5), ValueError),
])
def test_colour_setters_reject_like_pymunk(bad, error):
    ours, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    with pytest.raises(error):
        ours.shape_outline_color = bad
    with pytest.raises(error):
        ref.shape_outline_color = bad
    # Ours is left unchanged (pymunk's cffi struct may keep the fields it
    # wrote before the bad one).
    assert ours.shape_outline_color == (44, 62, 80, 255)


def test_short_colour_is_an_error_not_a_partial_update():
    # pymunk (cffi) fills only the given fields and keeps the old alpha;
    # tamias2d says what is wrong instead of half-updating the colour.
    ref = pymunk.SpaceDebugDrawOptions()
    ref.shape_outline_color = (1, 2, 3)
    assert ref.shape_outline_color == (1, 2, 3, 255)
    ours = SpaceDebugDrawOptions()
    with pytest.raises(ValueError, match="4 components"):
        ours.shape_outline_color = (1, 2, 3)
    assert ours.shape_outline_color == (44, 62, 80, 255)


@pytest.mark.parametrize("value", [0, 1, 2, 4, 7, 8, 255, 2**31, 2**32 - 1, True])
def test_flags_values(value):
    ours, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    ours.flags = value
    ref.flags = value
    assert ours.flags == ref.flags
    assert type(ours.flags) is int


@pytest.mark.parametrize("bad, error", [
    (-1, OverflowError), (2**32, OverflowError), (1.5, TypeError), ("a", TypeError),
    (None, TypeError),
])
def test_flags_rejects_like_pymunk(bad, error):
    ours, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    with pytest.raises(error):
        ours.flags = bad
    with pytest.raises(error):
        ref.flags = bad
    assert ours.flags == 7


def test_transform_default_and_set():
    ours, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    assert tuple(ours.transform) == tuple(ref.transform)
    for t in [(1, 2, 3, 4, 5, 6), pymunk.Transform.scaling(2), [0.5, 0, 0, 0.5, 10, -3]]:
        ours.transform = t
        ref.transform = t
        assert tuple(ours.transform) == tuple(ref.transform)
        assert isinstance(ours.transform, tamias2d.vector.Transform)
    ours.transform = tamias2d.vector.Transform.translation(2, 3)
    assert tuple(ours.transform) == (1.0, 0.0, 0.0, 1.0, 2.0, 3.0)


@pytest.mark.parametrize("bad, error", [("abcdef", TypeError), (None, TypeError),
                                        ((1, 2), ValueError), ((1, 2, 3, 4, 5, "x"), TypeError)])
def test_transform_rejects_bad_input(bad, error):
    options = SpaceDebugDrawOptions()
    with pytest.raises(error):
        options.transform = bad
    assert options._transform == (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)


def test_context_manager_and_switch():
    options = SpaceDebugDrawOptions()
    with options as entered:
        assert entered is None
    assert options._use_chipmunk_debug_draw is True


def test_base_methods_print_like_pymunk(capsys):
    args = {
        "draw_circle": ((1.0, 2.0), 0.5, 3.0, SpaceDebugColor(1, 2, 3, 4), SpaceDebugColor(5, 6, 7, 8)),
        "draw_segment": ((1.0, 2.0), (3.0, 4.0), SpaceDebugColor(1, 2, 3, 4)),
        "draw_fat_segment": ((1.0, 2.0), (3.0, 4.0), 2.0, SpaceDebugColor(1, 2, 3, 4),
                             SpaceDebugColor(5, 6, 7, 8)),
        "draw_polygon": ([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)], 1.0, SpaceDebugColor(1, 2, 3, 4),
                         SpaceDebugColor(5, 6, 7, 8)),
        "draw_dot": (5.0, (1.0, 2.0), SpaceDebugColor(1, 2, 3, 4)),
        "draw_shape": ("shape",),
    }
    for name, a in args.items():
        getattr(SpaceDebugDrawOptions(), name)(*a)
        ours = capsys.readouterr().out
        getattr(pymunk.SpaceDebugDrawOptions(), name)(*a)
        ref = capsys.readouterr().out
        assert ours == ref, name


def test_c_colour_conversion():
    options = SpaceDebugDrawOptions()
    assert options._c((1, 2, 3.3, 4)) == (1.0, 2.0, f32(3.3), 4.0)
    with pytest.raises(ValueError):
        options._c((1, 2, 3))
    with pytest.raises(TypeError):
        options._c("rgba")


# --- color_for_shape -------------------------------------------------------


class FakeBody:
    def __init__(self, body_type, sleeping=False):
        self.body_type = body_type
        self.is_sleeping = sleeping


class FakeShape:
    def __init__(self, body):
        self.body = body


@pytest.mark.parametrize("body", [
    None, FakeBody(0), FakeBody(1), FakeBody(2), FakeBody(0, sleeping=True),
    FakeBody(1, sleeping=True), FakeBody(2, sleeping=True),
], ids=["no body", "dynamic", "kinematic", "static", "sleeping", "kinematic+sleep",
        "static+sleep"])
def test_color_for_shape_follows_body_like_pymunk(body):
    shape = FakeShape(body)
    assert SpaceDebugDrawOptions().color_for_shape(shape) == \
        pymunk.SpaceDebugDrawOptions().color_for_shape(shape)


def test_color_for_shape_uses_options_colours_and_shape_color():
    options = SpaceDebugDrawOptions()
    options.shape_static_color = (1, 2, 3, 4)
    assert options.color_for_shape(FakeShape(FakeBody(2))) == (1, 2, 3, 4)
    shape = FakeShape(FakeBody(2))
    shape.color = [9, 8, 7, 6]
    got = options.color_for_shape(shape)
    assert got == pymunk.SpaceDebugDrawOptions().color_for_shape(shape) == (9, 8, 7, 6)
    assert isinstance(got, SpaceDebugColor)


def test_color_for_shape_with_real_bodies():
    options, ref = SpaceDebugDrawOptions(), pymunk.SpaceDebugDrawOptions()
    for engine, opts in ((tamias2d, options), (pymunk, ref)):
        kinds = [engine.Body(1, 1), engine.Body(body_type=engine.Body.KINEMATIC),
                 engine.Body(body_type=engine.Body.STATIC)]
        colours = [opts.color_for_shape(engine.Circle(b, 1)) for b in kinds]
        colours.append(opts.color_for_shape(engine.Circle(None, 1)))
        c = engine.Circle(kinds[0], 1)
        c.color = (255, 0, 0, 255)
        colours.append(opts.color_for_shape(c))
        if engine is tamias2d:
            ours = colours
        else:
            assert ours == colours
    assert ours[:3] == [options.shape_dynamic_color, options.shape_kinematic_color,
                        options.shape_static_color]


def test_color_for_shape_sleeping_body():
    for engine in (tamias2d, pymunk):
        space = engine.Space()
        space.gravity = (0, -100)
        space.sleep_time_threshold = 0.1
        ground = engine.Segment(space.static_body, (-10, 0), (10, 0), 1)
        body = engine.Body(1, 10)
        body.position = (0, 2)
        ball = engine.Circle(body, 1)
        ball.friction = 1
        space.add(ground, body, ball)
        for _ in range(200):
            space.step(1 / 60)
        assert body.is_sleeping, engine.__name__
        assert SpaceDebugDrawOptions().color_for_shape(ball) == \
            SpaceDebugDrawOptions.shape_sleeping_color


# --- Space.debug_draw with the base options (printing) --------------------


def test_debug_draw_prints_like_pymunk(capsys):
    def scene(engine, options):
        space = engine.Space()
        body = engine.Body(1, 10)
        body.position = 4, 5
        space.add(body,
                  engine.Circle(body, 2, offset=(-4, -5)),
                  engine.Segment(body, (0, 0), (3, 4), 3),
                  engine.Poly(body, [(5, 0), (5, 5), (7, 3)], None, 4),
                  engine.Circle(space.static_body, 10))
        space.step(0.1)
        options.transform = (2, 0, 0, 2, 2, 3)
        space.debug_draw(options)
        return capsys.readouterr().out

    ours = scene(tamias2d, SpaceDebugDrawOptions())
    ref = scene(pymunk, pymunk.SpaceDebugDrawOptions())
    assert ours == ref


def test_debug_draw_flags_select_what_is_drawn(capsys):
    space = tamias2d.Space()
    body = tamias2d.Body(1, 10)
    space.add(body, tamias2d.Circle(body, 10), tamias2d.Circle(space.static_body, 3))
    space.step(0.01)
    options = SpaceDebugDrawOptions()
    options.flags = 0
    space.debug_draw(options)
    assert capsys.readouterr().out == ""
    options.flags = SpaceDebugDrawOptions.DRAW_SHAPES
    space.debug_draw(options)
    assert capsys.readouterr().out.count("draw_circle") == 2
    options.flags = SpaceDebugDrawOptions.DRAW_COLLISION_POINTS
    space.debug_draw(options)
    out = capsys.readouterr().out
    assert "draw_circle" not in out and "draw_segment" in out


# --- the Pillow drawer ----------------------------------------------------


WHITE = (255, 255, 255)
RED = SpaceDebugColor(255, 0, 0, 255)
BLACK = SpaceDebugColor(0, 0, 0, 255)


def pymunk_pillow_options(*args, **kwargs):
    """The Pillow drawer on pymunk's options base, to draw pymunk spaces."""
    cls = type("PymunkPillow", (pillow_util.PillowDrawing, pymunk.SpaceDebugDrawOptions), {})
    return cls(*args, **kwargs)


def pixels(image):
    """The RGB pixels of an image as a list of tuples."""
    data = image.convert("RGB").tobytes()
    return [tuple(data[i:i + 3]) for i in range(0, len(data), 3)]


def count_colour(image, colour):
    return sum(1 for p in pixels(image) if p == tuple(colour[:3]))


def test_new_image_and_background():
    options = pillow_util.DrawOptions((30, 20), background=(1, 2, 3, 255))
    assert options.image.size == (30, 20)
    assert options.image.mode == "RGB"
    assert count_colour(options.image, (1, 2, 3)) == 30 * 20


def test_circle_lands_where_it_should_with_y_up():
    options = pillow_util.DrawOptions((100, 80))
    options.draw_circle((30, 60), 0.0, 10.0, BLACK, RED)   # near the top when y is up
    img = options.image
    assert img.getpixel((30, 23))[:3] == (255, 0, 0)   # just below the centre's angle line
    assert img.getpixel((30, 60))[:3] == WHITE
    assert img.getpixel((90, 70))[:3] == WHITE
    # The angle line (angle 0 points to +x) is drawn in the outline colour.
    assert img.getpixel((35, 20))[:3] == (0, 0, 0)


def test_y_down_option():
    options = pillow_util.DrawOptions((100, 80), positive_y_is_up=False)
    options.draw_circle((30, 60), 0.0, 10.0, BLACK, RED)
    assert options.image.getpixel((30, 63))[:3] == (255, 0, 0)
    assert options.image.getpixel((30, 20))[:3] == WHITE


def test_circle_angle_line_follows_angle():
    options = pillow_util.DrawOptions((100, 100))
    options.draw_circle((50, 50), math.pi / 2, 30.0, BLACK, RED)  # pointing up (+y)
    img = options.image
    assert img.getpixel((50, 30))[:3] == (0, 0, 0)   # above the centre in the picture
    assert img.getpixel((50, 70))[:3] == (255, 0, 0)  # below: fill only


def test_fat_segment_has_round_caps():
    options = pillow_util.DrawOptions((100, 60))
    options.draw_fat_segment((20, 30), (80, 30), 10.0, BLACK, RED)
    img = options.image
    assert img.getpixel((50, 30))[:3] == (255, 0, 0)
    assert img.getpixel((13, 30))[:3] == (255, 0, 0)   # inside the left cap
    assert img.getpixel((11, 21))[:3] == WHITE          # outside the cap's corner
    assert img.getpixel((50, 45))[:3] == WHITE


def test_polygon_and_rounded_polygon():
    square = [(20, 20), (60, 20), (60, 60), (20, 60)]
    sharp = pillow_util.DrawOptions((80, 80))
    sharp.draw_polygon(square, 0.0, BLACK, RED)
    assert sharp.image.getpixel((40, 40))[:3] == (255, 0, 0)
    assert sharp.image.getpixel((40, 15))[:3] == WHITE
    rounded = pillow_util.DrawOptions((80, 80))
    rounded.draw_polygon(square, 8.0, BLACK, RED)
    img = rounded.image
    assert img.getpixel((40, 14))[:3] == (255, 0, 0)   # the radius grows the sides
    assert img.getpixel((13, 13))[:3] == WHITE          # but rounds the corners
    # Clockwise vertices give the same picture (but for a few outline pixels
    # where the rasteriser starts the outline elsewhere).
    cw = pillow_util.DrawOptions((80, 80))
    cw.draw_polygon(square[::-1], 8.0, BLACK, RED)
    differ = sum(1 for p, q in zip(pixels(cw.image), pixels(img)) if p != q)
    assert differ <= 8


def test_segment_and_dot():
    options = pillow_util.DrawOptions((50, 50))
    options.draw_segment((5, 25), (45, 25), RED)
    options.draw_dot(6.0, (25, 10), BLACK)
    img = options.image
    assert img.getpixel((25, 25))[:3] == (255, 0, 0)
    assert img.getpixel((25, 40))[:3] == (0, 0, 0)


def test_bad_and_huge_input_is_skipped_or_clipped():
    options = pillow_util.DrawOptions((50, 50))
    nan, inf = float("nan"), float("inf")
    options.draw_circle((nan, 1), 0.0, 5.0, BLACK, RED)
    options.draw_segment((0, 0), (inf, 1), RED)
    options.draw_fat_segment((nan, 0), (1, 1), 3.0, BLACK, RED)
    options.draw_polygon([(0, 0), (nan, 0), (1, 1)], 0.0, BLACK, RED)
    options.draw_dot(3.0, (inf, inf), RED)
    assert count_colour(options.image, WHITE) == 50 * 50
    # Far away: nothing drawn.
    options.draw_circle((1e9, 1e9), 0.0, 5.0, BLACK, RED)
    assert count_colour(options.image, WHITE) == 50 * 50
    # Enormous shapes covering the view are clipped, not rasterised whole.
    options.draw_circle((0, -1e7), 0.0, 1e7 + 25, BLACK, RED)
    options.draw_fat_segment((-1e9, 5), (1e9, 5), 5.0, BLACK, RED)
    img = options.image
    assert img.getpixel((25, 30))[:3] == (255, 0, 0)   # world y 20: inside the circle
    assert img.getpixel((25, 10))[:3] == WHITE          # world y 40: outside
    assert img.getpixel((25, 45))[:3] == (255, 0, 0)   # the segment along world y 5
    # Degenerate polygons (a point, a line) still show.
    options.clear()
    options.draw_polygon([(10, 10)], 0.0, BLACK, RED)
    options.draw_polygon([(20, 20), (40, 20)], 0.0, BLACK, RED)
    assert count_colour(options.image, WHITE) < 50 * 50


def test_fit_bb_and_coordinate_mapping():
    options = pillow_util.DrawOptions((200, 100), bb=(-10, 0, 10, 10))
    assert options.to_image((-10, 0)) == (0.0, 100.0)
    assert options.to_image((10, 10)) == (200.0, 0.0)
    assert options.from_image((100.0, 50.0)) == (0.0, 5.0)
    with_margin = pillow_util.DrawOptions((200, 100), bb=(0, 0, 10, 10), margin=10)
    assert with_margin.to_image((5, 5)) == (100.0, 50.0)
    assert with_margin.to_image((0, 0))[1] == 90.0
    with pytest.raises(ValueError):
        pillow_util.DrawOptions((10, 10), bb=(0, 0, 0, 1))
    with pytest.raises(ValueError):
        pillow_util.DrawOptions((10, 10), bb=(0, 0, 1))
    with pytest.raises(ValueError):
        pillow_util.DrawOptions((10, 10), bb=(0, 0, 1, 1), margin=5)


def test_constructor_checks():
    with pytest.raises(TypeError):
        pillow_util.DrawOptions("big")
    with pytest.raises(ValueError):
        pillow_util.DrawOptions((0, 10))
    with pytest.raises(ValueError):
        pillow_util.DrawOptions((10, 10), supersample=0)


def test_draws_into_given_image_in_place():
    image = Image.new("RGB", (40, 40), (0, 0, 255))
    options = pillow_util.DrawOptions(image)
    options.draw_circle((20, 20), 0.0, 5.0, BLACK, RED)
    assert options.image is image
    assert image.getpixel((20, 23)) == (255, 0, 0)
    assert image.getpixel((2, 2)) == (0, 0, 255)
    # Supersampled drawing is written back into the given image too.
    image2 = Image.new("RGBA", (40, 40), (0, 0, 255, 255))
    options2 = pillow_util.DrawOptions(image2, supersample=3)
    options2.draw_circle((20, 20), 0.0, 5.0, BLACK, RED)
    assert options2.image is image2
    assert image2.getpixel((20, 22)) == (255, 0, 0, 255)
    assert image2.getpixel((2, 2)) == (0, 0, 255, 255)
    # Other modes are drawn in colour and converted back.
    grey = Image.new("L", (20, 20), 0)
    options3 = pillow_util.DrawOptions(grey)
    options3.draw_circle((10, 10), 0.0, 5.0, SpaceDebugColor(255, 255, 255, 255),
                         SpaceDebugColor(255, 255, 255, 255))
    assert options3.image.mode == "L" and grey.getpixel((10, 13)) == 255


def test_supersampling_keeps_size_and_smooths():
    plain = pillow_util.DrawOptions((60, 60))
    smooth = pillow_util.DrawOptions((60, 60), supersample=4)
    for o in (plain, smooth):
        o.draw_circle((30, 30), 0.0, 20.0, BLACK, RED)
    assert smooth.image.size == (60, 60)
    assert len(set(pixels(smooth.image))) > len(set(pixels(plain.image)))  # edge pixels are blended
    assert smooth.image.getpixel((30, 40))[:3] == (255, 0, 0)


def test_transparent_colours_blend():
    options = pillow_util.DrawOptions((20, 20))
    options.draw_circle((10, 10), 0.0, 8.0, BLACK, SpaceDebugColor(255, 0, 0, 128))
    r, g, b = options.image.getpixel((10, 6))
    assert r == 255 and 120 < g < 135 and 120 < b < 135


def test_pillow_drawer_draws_a_pymunk_space():
    # The drawer through a real Space.debug_draw (pymunk's walk of the
    # space, which tamias2d's Space.debug_draw reproduces).
    space = pymunk.Space()
    ground = pymunk.Segment(space.static_body, (-100, 0), (100, 0), 5)
    body = pymunk.Body(1, 100)
    body.position = (-50, 50)
    ball = pymunk.Circle(body, 10)
    box_body = pymunk.Body(1, 100)
    box_body.position = (50, 50)
    box = pymunk.Poly.create_box(box_body, (30, 30))
    box.color = (255, 0, 0, 255)
    space.add(ground, body, ball, box_body, box)
    options = pymunk_pillow_options((220, 120), bb=(-110, -10, 110, 110))
    space.debug_draw(options)
    img = options.image

    def at(p):
        x, y = options.to_image(p)
        return img.getpixel((int(x), int(y)))[:3]

    assert at((-50, 45)) == tuple(pillow_util._rgba(options.shape_dynamic_color))[:3]
    assert at((50, 50)) == (255, 0, 0)
    assert at((0, 0)) == tuple(pillow_util._rgba(options.shape_static_color))[:3]
    assert at((0, 80)) == WHITE
    assert at((-50, 80)) == WHITE


def test_pillow_drawer_same_picture_as_with_pymunk():
    def scene(engine, options):
        space = engine.Space()
        space.gravity = (0, -900)
        ground = engine.Segment(space.static_body, (-100, 0), (100, 0), 5)
        space.add(ground)
        for i in range(5):
            b = engine.Body(1, engine.moment_for_box(1, (20, 20)))
            b.position = (-40 + 20 * i, 20 + 25 * i)
            space.add(b, engine.Poly.create_box(b, (20, 20), 1))
            c = engine.Body(1, engine.moment_for_circle(1, 0, 8))
            c.position = (40 - 20 * i, 30 + 25 * i)
            space.add(c, engine.Circle(c, 8))
        for _ in range(60):
            space.step(1 / 60)
        options.fit((-110, -10, 110, 200))
        space.debug_draw(options)
        return options.image

    ours = scene(tamias2d, pillow_util.DrawOptions((220, 210)))
    ref = scene(pymunk, pymunk_pillow_options((220, 210)))
    assert ours.tobytes() == ref.tobytes()
    assert count_colour(ours, WHITE) < 220 * 210 * 0.95


# --- GIF ------------------------------------------------------------------


def test_gif_writer(tmp_path):
    writer = pillow_util.GifWriter(duration=50)
    for c in ("red", "green", "blue"):
        writer.add(Image.new("RGB", (16, 8), c))
    path = tmp_path / "x.gif"
    writer.save(str(path))
    gif = Image.open(path)
    assert gif.format == "GIF" and gif.n_frames == 3 and gif.size == (16, 8)
    gif.seek(2)
    assert gif.convert("RGB").getpixel((0, 0)) == (0, 0, 255)
    with pytest.raises(ValueError):
        writer.add(Image.new("RGB", (4, 4)))
    with pytest.raises(ValueError):
        pillow_util.GifWriter().save(str(tmp_path / "empty.gif"))


# --- pygame_util ------------------------------------------------------------


class FakeSurface:
    def __init__(self, height):
        self.height = height

    def get_height(self):
        return self.height


@pytest.fixture
def y_up():
    old = pygame_util.positive_y_is_up
    pygame_util.positive_y_is_up = True
    yield
    pygame_util.positive_y_is_up = old


def test_pygame_util_api_matches_pymunk():
    assert set(pygame_util.__all__) == {"DrawOptions", "get_mouse_pos", "to_pygame",
                                        "from_pygame", "positive_y_is_up"}
    assert pygame_util.positive_y_is_up is False
    assert issubclass(pygame_util.DrawOptions, SpaceDebugDrawOptions)


def test_to_and_from_pygame_y_down():
    s = FakeSurface(100)
    assert pygame_util.to_pygame((10.4, 20.6), s) == (10, 21)
    assert pygame_util.from_pygame((10, 21), s) == (10, 21)


def test_to_and_from_pygame_y_up(y_up):
    s = FakeSurface(100)
    assert pygame_util.to_pygame((10.4, 20.6), s) == (10, 79)
    assert pygame_util.from_pygame((10, 79), s) == (10, 21)
    for p in [(0, 0), (3, 100), (50, 37)]:
        assert pygame_util.from_pygame(pygame_util.to_pygame(p, s), s) == p


def test_pygame_missing_gives_a_clear_error(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pygame", None)   # makes `import pygame` fail
    with pytest.raises(ImportError, match="pip install pygame"):
        pygame_util.DrawOptions(FakeSurface(10))
    with pytest.raises(ImportError, match="pip install pygame"):
        pygame_util.get_mouse_pos(FakeSurface(10))


def test_pygame_draw_options_draw_on_a_surface(y_up):
    pygame = pytest.importorskip("pygame", reason="pygame is not installed")
    surface = pygame.Surface((100, 80))
    surface.fill((255, 255, 255))
    options = pygame_util.DrawOptions(surface)
    options.draw_circle((30, 60), 0.0, 10.0, BLACK, RED)
    options.draw_fat_segment((10, 10), (90, 10), 4.0, BLACK, SpaceDebugColor(0, 255, 0, 255))
    options.draw_polygon([(60, 30), (80, 30), (80, 50), (60, 50)], 2.0, BLACK,
                         SpaceDebugColor(0, 0, 255, 255))
    options.draw_segment((0, 0), (99, 79), BLACK)
    options.draw_dot(3.0, (5, 40), BLACK)
    assert tuple(surface.get_at((30, 23)))[:3] == (255, 0, 0)       # y flipped
    assert tuple(surface.get_at((50, 70)))[:3] == (0, 255, 0)
    assert tuple(surface.get_at((70, 40)))[:3] == (0, 0, 255)
    assert tuple(surface.get_at((95, 30)))[:3] == (255, 255, 255)


# --- doctests of the drawing modules ----------------------------------------


@pytest.mark.parametrize("module_name", ["space_debug_draw_options", "pillow_util", "pygame_util"])
def test_doctests(module_name):
    import importlib

    module = importlib.import_module("tamias2d." + module_name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {module_name}"
