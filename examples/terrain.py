"""Terrain from a picture: marching squares, then simplified static segments.

A small greyscale image (drawn here with Pillow, so that no binary file is
needed: any PNG loaded with Image.open works the same) is the terrain map:
white is rock. ``autogeometry.march_soft`` traces the outline where the
grey level crosses one half, interpolating between pixels, and
``simplify_curves`` drops the points that are needed for less than a pixel
of accuracy. Each outline becomes a chain of static segments; balls and
boxes then rain onto it.

    python examples/terrain.py
    python examples/terrain.py --headless --frames 360
"""
import math
import random

from PIL import Image, ImageDraw, ImageFilter

import _common
import tamias2d
from tamias2d import autogeometry

WIDTH, HEIGHT = 900, 500
SCALE = 5  # world pixels per image pixel
rng = random.Random(8)


def terrain_image(w=WIDTH // SCALE, h=HEIGHT // SCALE):
    """Hills with a cave and two floating islands, white on black."""
    image = Image.new("L", (w, h), 0)
    draw = ImageDraw.Draw(image)
    # Image rows run downwards: row h - y is height y.
    hills = [(x, h - (22 + 10 * math.sin(x / 9) + 6 * math.sin(x / 3.7 + 1))) for x in range(w)]
    draw.polygon(hills + [(w, h), (0, h)], fill=255)
    draw.ellipse((95, h - 24, 135, h - 8), fill=0)         # a cave in the hill
    draw.ellipse((20, h - 70, 60, h - 58), fill=255)       # floating islands
    draw.ellipse((120, h - 78, 165, h - 64), fill=255)
    draw.rectangle((0, 0, 2, h), fill=255)                 # walls at the sides
    draw.rectangle((w - 3, 0, w, h), fill=255)
    # A slight blur gives march_soft grey levels to interpolate: smoother outlines.
    return image.filter(ImageFilter.GaussianBlur(0.8))


image = terrain_image()
pixels = image.load()


def sample(point):
    """The grey level (0..1) at a world point, from the image's pixels."""
    x = min(image.width - 1, max(0, int(point[0] / SCALE)))
    y = min(image.height - 1, max(0, int(image.height - 1 - point[1] / SCALE)))
    return pixels[x, y] / 255.0


space = tamias2d.Space()
space.gravity = (0, -900)
# One sample per image pixel over the whole world.
bb = tamias2d.BB(0, 0, WIDTH - 1, HEIGHT - 1)
outlines = autogeometry.march_soft(bb, image.width, image.height, 0.5, sample)
traced = simplified = 0
for outline in outlines:
    points = autogeometry.simplify_curves(outline, 1.0)
    traced += len(outline)
    simplified += len(points)
    for a, b in zip(points, points[1:]):
        segment = tamias2d.Segment(space.static_body, a, b, 3)
        segment.friction = 0.8
        segment.color = _common.GROUND
        space.add(segment)


def update(frame):
    if frame % 4 == 0 and frame < 320:
        body = tamias2d.Body()
        body.position = rng.uniform(30, WIDTH - 30), HEIGHT + 20
        if rng.random() < 0.6:
            shape = tamias2d.Circle(body, rng.uniform(6, 10))
        else:
            shape = tamias2d.Poly.create_box(body, (rng.uniform(12, 20), rng.uniform(12, 20)))
        shape.density, shape.friction = 0.01, 0.7
        shape.color = _common.PALETTE[rng.randrange(len(_common.PALETTE))]
        space.add(body, shape)
    # Two steps a frame: a falling body then moves less than its radius plus
    # the outline's per step, so it can't pass through the thin outline.
    for _ in range(2):
        space.step(_common.DT / 2)


def draw(canvas):
    canvas.space(space)
    canvas.text(f"{len(outlines)} outlines, {traced} traced points, {simplified} after "
                f"simplify_curves", at=(20, 8))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: terrain from an image",
                size=(WIDTH, HEIGHT), frames=360)
