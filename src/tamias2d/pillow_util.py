"""Draw a space into a Pillow image, with no window and no display.

>>> import tamias2d
>>> from tamias2d import pillow_util
>>> space = tamias2d.Space()
>>> space.add(tamias2d.Segment(space.static_body, (-100, 0), (100, 0), 4))
>>> options = pillow_util.DrawOptions((200, 100), bb=(-110, -10, 110, 100))
>>> space.debug_draw(options)
>>> options.image.size
(200, 100)

:class:`DrawOptions` maps world coordinates to pixels with the options'
``transform`` (see :meth:`DrawOptions.fit`) and, by default, flips the y axis
so that positive y points up in the picture. With ``supersample=k`` it draws
at k times the size and scales down, which smooths the edges.

:class:`GifWriter` collects frames and writes an animated GIF.

Pillow is needed (``pip install 'tamias2d[demo]'``); it is imported when this
module is.
"""
import math

try:
    from PIL import Image, ImageDraw
except ImportError as exc:  # pragma: no cover - exercised only without Pillow
    raise ImportError(
        "tamias2d.pillow_util needs Pillow: pip install 'tamias2d[demo]' "
        "(or pip install Pillow)"
    ) from exc

from .space_debug_draw_options import SpaceDebugColor, SpaceDebugDrawOptions

__all__ = ["DrawOptions", "PillowDrawing", "GifWriter", "save_gif", "bb_transform"]

__docformat__ = "reStructuredText"

# Beyond this radius (in canvas pixels) circles are drawn as clipped
# polygons: Pillow's ellipse routine costs time in proportion to the radius.
_MAX_ELLIPSE_RADIUS = 2000.0


def _bb_values(bb):
    """(left, bottom, right, top) from a BB-like object or a 4-sequence."""
    if all(hasattr(bb, n) for n in ("left", "bottom", "right", "top")):
        values = (bb.left, bb.bottom, bb.right, bb.top)
    else:
        try:
            values = tuple(bb)
        except TypeError:
            raise TypeError(
                "bb must be a BB or 4 numbers (left, bottom, right, top), "
                f"not {type(bb).__name__}"
            ) from None
        if len(values) != 4:
            raise ValueError(
                f"bb must have 4 components (left, bottom, right, top), got {len(values)}"
            )
    left, bottom, right, top = (float(v) for v in values)
    if not all(math.isfinite(v) for v in (left, bottom, right, top)):
        raise ValueError(f"bb must be finite, got {(left, bottom, right, top)}")
    if right <= left or top <= bottom:
        raise ValueError(
            f"bb must have right > left and top > bottom, got {(left, bottom, right, top)}"
        )
    return left, bottom, right, top


def bb_transform(bb, size, margin=0):
    """The transform (a, b, c, d, tx, ty) that fits bb into an image of the
    given (width, height) in pixels: uniform scale, bb centred, ``margin``
    pixels kept free on every side. The result keeps y pointing up; the
    drawer flips it.

    >>> bb_transform((0, 0, 10, 5), (200, 100))
    (20.0, 0.0, 0.0, 20.0, 0.0, 0.0)
    >>> bb_transform((0, 0, 10, 10), (200, 100), margin=10)
    (8.0, 0.0, 0.0, 8.0, 60.0, 10.0)
    """
    left, bottom, right, top = _bb_values(bb)
    width, height = size
    avail_w = width - 2 * margin
    avail_h = height - 2 * margin
    if avail_w <= 0 or avail_h <= 0:
        raise ValueError(f"margin {margin} leaves no room in an image of size {size}")
    s = min(avail_w / (right - left), avail_h / (top - bottom))
    tx = width / 2 - s * (left + right) / 2
    ty = height / 2 - s * (bottom + top) / 2
    return (s, 0.0, 0.0, s, tx, ty)


def _rgba(color):
    """A drawable (r, g, b, a) tuple of ints in 0..255 from a debug colour."""
    out = []
    for c in color:
        c = float(c)
        if c != c:  # NaN
            c = 0.0
        out.append(int(min(255.0, max(0.0, round(c)))))
    return tuple(out)


def _finite(*values):
    return all(math.isfinite(v) for v in values)


def _clip_convex(points, xmin, ymin, xmax, ymax):
    """Clip a convex polygon to a rectangle (Sutherland-Hodgman)."""

    def clip(pts, inside, cross):
        out = []
        n = len(pts)
        for i in range(n):
            p = pts[i]
            q = pts[(i + 1) % n]
            pin = inside(p)
            qin = inside(q)
            if pin:
                out.append(p)
                if not qin:
                    out.append(cross(p, q))
            elif qin:
                out.append(cross(p, q))
        return out

    def at_x(x):
        def cross(p, q):
            t = (x - p[0]) / (q[0] - p[0])
            return (x, p[1] + t * (q[1] - p[1]))
        return cross

    def at_y(y):
        def cross(p, q):
            t = (y - p[1]) / (q[1] - p[1])
            return (p[0] + t * (q[0] - p[0]), y)
        return cross

    pts = list(points)
    for inside, cross in (
        (lambda p: p[0] >= xmin, at_x(xmin)),
        (lambda p: p[0] <= xmax, at_x(xmax)),
        (lambda p: p[1] >= ymin, at_y(ymin)),
        (lambda p: p[1] <= ymax, at_y(ymax)),
    ):
        if not pts:
            break
        pts = clip(pts, inside, cross)
    return pts


def _clip_line(p, q, xmin, ymin, xmax, ymax):
    """Clip the line p-q to a rectangle (Liang-Barsky); None if outside."""
    x0, y0 = p
    dx = q[0] - x0
    dy = q[1] - y0
    t0, t1 = 0.0, 1.0
    for pk, qk in ((-dx, x0 - xmin), (dx, xmax - x0), (-dy, y0 - ymin), (dy, ymax - y0)):
        if pk == 0:
            if qk < 0:
                return None
        else:
            t = qk / pk
            if pk < 0:
                if t > t1:
                    return None
                t0 = max(t0, t)
            else:
                if t < t0:
                    return None
                t1 = min(t1, t)
    return (x0 + t0 * dx, y0 + t0 * dy), (x0 + t1 * dx, y0 + t1 * dy)


def _arc(cx, cy, r, a0, a1, n):
    """n + 1 points on the circle (cx, cy, r) from angle a0 to a1."""
    return [
        (cx + r * math.cos(a0 + (a1 - a0) * i / n), cy + r * math.sin(a0 + (a1 - a0) * i / n))
        for i in range(n + 1)
    ]


def _arc_steps(r, sweep):
    """How many chords keep an arc of radius r (pixels) within ~1/4 pixel."""
    if r <= 0:
        return 1
    # chord error r * (1 - cos(step / 2)) <= 0.25
    step = 2 * math.acos(max(-1.0, 1 - 0.25 / r)) if r > 0.25 else math.pi
    return max(2, min(4096, int(math.ceil(abs(sweep) / step))))


class PillowDrawing:
    """The Pillow drawing methods, as a mixin over a debug-draw options
    base class (:class:`DrawOptions` mixes it into tamias2d's; the demo can
    mix it into pymunk's to draw a pymunk space the same way). The
    parameters are those of :class:`DrawOptions`.

    >>> import pymunk
    >>> class PymunkDrawOptions(PillowDrawing, pymunk.SpaceDebugDrawOptions):
    ...     pass
    >>> PymunkDrawOptions((20, 10)).image.size
    (20, 10)
    """

    def __init__(self, image_or_size=(640, 480), bb=None, *, positive_y_is_up=True,
                 background=(255, 255, 255, 255), margin=0, supersample=1,
                 line_width=1.0, segment_width=None):
        super().__init__()
        if isinstance(image_or_size, Image.Image):
            target = image_or_size
        else:
            try:
                width, height = image_or_size
                width, height = int(width), int(height)
            except (TypeError, ValueError):
                raise TypeError(
                    "image_or_size must be a PIL.Image.Image or (width, height), "
                    f"not {image_or_size!r}"
                ) from None
            if width <= 0 or height <= 0:
                raise ValueError(f"image size must be positive, got {(width, height)}")
            target = Image.new("RGB", (width, height), _rgba(background))
        k = int(supersample)
        if k < 1:
            raise ValueError(f"supersample must be >= 1, got {supersample}")
        if not (line_width > 0):
            raise ValueError(f"line_width must be positive, got {line_width}")

        self.positive_y_is_up = bool(positive_y_is_up)
        self.background = SpaceDebugColor(*_rgba(background))
        self.line_width = float(line_width)
        # Thin segments (constraints, contact points) may be drawn wider.
        self.segment_width = self.line_width if segment_width is None else float(segment_width)
        if not (self.segment_width > 0):
            raise ValueError(f"segment_width must be positive, got {segment_width}")
        self.supersample = k
        self._target = target
        mode = "RGBA" if target.mode == "RGBA" else "RGB"
        if k == 1 and target.mode == mode:
            self._canvas = target
        else:
            self._canvas = target.convert(mode)
            if k > 1:
                self._canvas = self._canvas.resize(
                    (target.width * k, target.height * k), Image.Resampling.NEAREST
                )
        self._draw = ImageDraw.Draw(self._canvas, "RGBA")
        self._dirty = False
        if bb is not None:
            self.fit(bb, margin)

    # -- geometry --------------------------------------------------------

    @property
    def size(self):
        """(width, height) of the output image in pixels.

        >>> DrawOptions((30, 20)).size
        (30, 20)
        """
        return self._target.size

    def fit(self, bb, margin=0):
        """Set :attr:`transform` so that the world box bb (left, bottom,
        right, top) fills the image, centred, with margin pixels free.

        >>> options = DrawOptions((100, 50))
        >>> options.fit((0, 0, 10, 10))
        >>> options.to_image((5, 5))
        (50.0, 25.0)
        """
        self.transform = bb_transform(bb, self.size, margin)

    def _canvas_point(self, p):
        """A point already mapped by transform -> canvas pixel coordinates."""
        k = self.supersample
        x = float(p[0])
        y = float(p[1])
        if self.positive_y_is_up:
            y = self._target.height - y
        return (x * k, y * k)

    def _transform_values(self):
        stored = getattr(self, "_transform", None)
        if isinstance(stored, tuple) and len(stored) == 6:
            return stored  # tamias2d's options keep the six floats directly
        t = self.transform
        return (t.a, t.b, t.c, t.d, t.tx, t.ty)

    def to_image(self, p):
        """World point -> image pixel coordinates (floats), applying the
        transform and the y flip.

        >>> DrawOptions((10, 10)).to_image((2, 3))
        (2.0, 7.0)
        """
        a, b, c, d, tx, ty = self._transform_values()
        x = float(p[0])
        y = float(p[1])
        wx = a * x + c * y + tx
        wy = b * x + d * y + ty
        if self.positive_y_is_up:
            wy = self._target.height - wy
        return (wx, wy)

    def from_image(self, p):
        """Image pixel coordinates -> world point (the inverse of to_image).

        >>> DrawOptions((10, 10)).from_image((2.0, 7.0))
        (2.0, 3.0)
        """
        a, b, c, d, tx, ty = self._transform_values()
        x = float(p[0])
        y = float(p[1])
        if self.positive_y_is_up:
            y = self._target.height - y
        det = a * d - b * c
        if det == 0:
            raise ValueError("the transform is not invertible")
        x -= tx
        y -= ty
        return ((d * x - c * y) / det, (a * y - b * x) / det)

    # -- image -----------------------------------------------------------

    @property
    def image(self):
        """The image drawn into (the one given, or the one made).

        With ``supersample`` > 1 reading this scales the drawing down into it.

        >>> from PIL import Image
        >>> picture = Image.new("RGB", (8, 8))
        >>> DrawOptions(picture).image is picture
        True
        """
        self._flush()
        return self._target

    def clear(self, color=None):
        """Fill the image with the background colour (or the given one).

        >>> options = DrawOptions((4, 4), background=(0, 0, 0, 255))
        >>> options.clear((9, 9, 9, 255))
        >>> options.image.getpixel((0, 0))
        (9, 9, 9)
        """
        fill = _rgba(self.background if color is None else color)
        # Paste replaces pixels (alpha included) instead of blending.
        self._canvas.paste(fill if self._canvas.mode == "RGBA" else fill[:3],
                           (0, 0) + self._canvas.size)
        self._dirty = True

    def _flush(self):
        if not self._dirty or self._canvas is self._target:
            self._dirty = False
            return
        out = self._canvas
        if self.supersample > 1:
            out = out.reduce(self.supersample)
        if out.mode != self._target.mode:
            out = out.convert(self._target.mode)
        self._target.paste(out, (0, 0))
        self._dirty = False

    def __exit__(self, type, value, traceback):
        self._flush()
        return None

    # -- helpers in canvas pixels -----------------------------------------

    def _lw(self):
        return max(1, int(round(self.line_width * self.supersample)))

    def _bounds(self, pad=0.0):
        w, h = self._canvas.size
        return (-pad, -pad, w + pad, h + pad)

    def _visible(self, xmin, ymin, xmax, ymax):
        w, h = self._canvas.size
        return xmax >= -2 and ymax >= -2 and xmin <= w + 2 and ymin <= h + 2

    def _polygon(self, pts, fill, outline):
        """Fill and outline a convex canvas polygon, clipped to the canvas."""
        pad = 4.0 * self._lw()
        xs = [p[0] for p in pts]
        ys = [p[1] for p in pts]
        if not self._visible(min(xs), min(ys), max(xs), max(ys)):
            return
        w, h = self._canvas.size
        if min(xs) < -pad or min(ys) < -pad or max(xs) > w + pad or max(ys) > h + pad:
            pts = _clip_convex(pts, -pad, -pad, w + pad, h + pad)
            if len(pts) < 3:
                return
        lw = self._lw()
        if lw == 1:
            self._draw.polygon(pts, fill=fill, outline=outline)
        else:
            # Pillow strokes wide polygon outlines through a full-canvas mask;
            # a closed wide line over the fill costs far less.
            self._draw.polygon(pts, fill=fill)
            if outline is not None:
                self._draw.line(list(pts) + [pts[0], pts[1]], fill=outline, width=lw,
                                joint="curve")
        self._dirty = True

    def _line(self, p, q, color, width):
        pad = float(width)
        clipped = _clip_line(p, q, *self._bounds(pad))
        if clipped is None:
            return
        self._draw.line(clipped, fill=color, width=width)
        self._dirty = True

    def _disc(self, cx, cy, r, fill, outline):
        """A filled circle with an outline, in canvas pixels."""
        if not self._visible(cx - r, cy - r, cx + r, cy + r):
            return
        lw = self._lw()
        if r < 0.5:
            r = 0.5
        if r > _MAX_ELLIPSE_RADIUS:
            self._polygon(_arc(cx, cy, r, 0.0, 2 * math.pi, _arc_steps(r, 2 * math.pi))[:-1],
                          fill, outline)
            return
        width = lw if outline is not None and r > lw else 0
        self._draw.ellipse((cx - r, cy - r, cx + r, cy + r), fill=fill,
                           outline=outline if width else None, width=width)
        self._dirty = True

    # -- the primitives --------------------------------------------------

    def draw_circle(self, pos, angle, radius, outline_color, fill_color):
        """A filled, outlined circle with a line from the centre showing the
        rotation angle.

        >>> o = DrawOptions((20, 20))
        >>> o.draw_circle((10, 10), 0.0, 6.0, SpaceDebugColor(0, 0, 0, 255),
        ...               SpaceDebugColor(0, 0, 255, 255))
        >>> o.image.getpixel((10, 13))
        (0, 0, 255)
        """
        cx, cy = self._canvas_point(pos)
        r = float(radius) * self.supersample
        angle = float(angle)
        if not _finite(cx, cy, r, angle):
            return
        outline = _rgba(outline_color)
        self._disc(cx, cy, abs(r), _rgba(fill_color), outline)
        if abs(r) >= 2 * self._lw():
            # The edge point in world orientation, then flipped like pos.
            ex = float(pos[0]) + float(radius) * math.cos(angle)
            ey = float(pos[1]) + float(radius) * math.sin(angle)
            self._line((cx, cy), self._canvas_point((ex, ey)), outline, self._lw())

    def draw_segment(self, a, b, color):
        """A thin line.

        >>> o = DrawOptions((20, 20))
        >>> o.draw_segment((0, 10), (20, 10), SpaceDebugColor(255, 0, 0, 255))
        >>> o.image.getpixel((5, 10))
        (255, 0, 0)
        """
        p = self._canvas_point(a)
        q = self._canvas_point(b)
        if not _finite(*p, *q):
            return
        width = max(1, int(round(self.segment_width * self.supersample)))
        self._line(p, q, _rgba(color), width)

    def draw_fat_segment(self, a, b, radius, outline_color, fill_color):
        """A segment with round caps of the given radius.

        >>> o = DrawOptions((20, 20))
        >>> o.draw_fat_segment((5, 10), (15, 10), 3.0, SpaceDebugColor(0, 0, 0, 255),
        ...                    SpaceDebugColor(0, 255, 0, 255))
        >>> o.image.getpixel((10, 9))
        (0, 255, 0)
        """
        p = self._canvas_point(a)
        q = self._canvas_point(b)
        r = abs(float(radius)) * self.supersample
        if not _finite(*p, *q, r):
            return
        fill = _rgba(fill_color)
        outline = _rgba(outline_color)
        dx = q[0] - p[0]
        dy = q[1] - p[1]
        length = math.hypot(dx, dy)
        if r < 1.0:
            # Too thin for an outline: one line in the outline colour.
            if length == 0:
                self._disc(p[0], p[1], max(r, 0.5), outline, None)
            else:
                self._line(p, q, outline, max(self._lw(), int(round(2 * r))))
            return
        if length == 0:
            self._disc(p[0], p[1], r, fill, outline)
            return
        if not self._visible(min(p[0], q[0]) - r, min(p[1], q[1]) - r,
                             max(p[0], q[0]) + r, max(p[1], q[1]) + r):
            return
        base = math.atan2(dy, dx)
        n = _arc_steps(r, math.pi)
        pts = _arc(q[0], q[1], r, base - math.pi / 2, base + math.pi / 2, n)
        pts += _arc(p[0], p[1], r, base + math.pi / 2, base + 3 * math.pi / 2, n)
        self._polygon(pts, fill, outline)

    def draw_polygon(self, verts, radius, outline_color, fill_color):
        """A convex polygon; a positive radius rounds it (the Minkowski sum
        with a disc, as the collision shape is).

        >>> o = DrawOptions((20, 20))
        >>> o.draw_polygon([(5, 5), (15, 5), (15, 15), (5, 15)], 2.0,
        ...                SpaceDebugColor(0, 0, 0, 255), SpaceDebugColor(255, 0, 0, 255))
        >>> o.image.getpixel((10, 10)), o.image.getpixel((10, 4))
        ((255, 0, 0), (255, 0, 0))
        """
        pts = [self._canvas_point(v) for v in verts]
        r = abs(float(radius)) * self.supersample
        if not pts or not all(_finite(*p) for p in pts) or not _finite(r):
            return
        fill = _rgba(fill_color)
        outline = _rgba(outline_color)
        n = len(pts)
        area2 = sum(pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1]
                    for i in range(n))
        if n < 3 or area2 == 0:
            # Degenerate (a point or a line): draw it as fat segments.
            rr = max(r, 1.0) / self.supersample
            if n == 1:
                self.draw_circle(verts[0], 0.0, rr, outline_color, fill_color)
            for i in range(n - 1):
                self.draw_fat_segment(verts[i], verts[i + 1], rr, outline_color, fill_color)
            return
        if r < 0.75:
            self._polygon(pts, fill, outline)
            return
        # Rounded corners: around each vertex, an arc from the outward normal
        # of the edge coming in to that of the edge going out.
        ccw = area2 > 0
        normals = []
        for i in range(n):
            (x0, y0), (x1, y1) = pts[i], pts[(i + 1) % n]
            ex, ey = x1 - x0, y1 - y0
            normals.append(math.atan2(-ex, ey) if ccw else math.atan2(ex, -ey))
        outline_pts = []
        for i in range(n):
            a_in = normals[i - 1]
            a_out = normals[i]
            sweep = (a_out - a_in) % (2 * math.pi)
            if not ccw:
                sweep = sweep - 2 * math.pi if sweep else 0.0
            steps = _arc_steps(r, sweep) if sweep else 1
            outline_pts += _arc(pts[i][0], pts[i][1], r, a_in, a_in + sweep, steps)
        self._polygon(outline_pts, fill, outline)

    def draw_dot(self, size, pos, color):
        """A filled dot; size is in output pixels (the transform does not
        scale it).

        >>> o = DrawOptions((20, 20))
        >>> o.draw_dot(5.0, (10, 10), SpaceDebugColor(0, 0, 0, 255))
        >>> o.image.getpixel((10, 10))
        (0, 0, 0)
        """
        cx, cy = self._canvas_point(pos)
        r = 0.5 * abs(float(size)) * self.supersample
        if not _finite(cx, cy, r):
            return
        self._disc(cx, cy, max(r, 1.0), _rgba(color), None)


class DrawOptions(PillowDrawing, SpaceDebugDrawOptions):
    """Debug drawing into a Pillow image (headless).

    :param image_or_size: a Pillow image to draw into (RGB or RGBA are drawn
        in place; other modes are converted back after drawing), or a
        (width, height) for a new RGB image filled with ``background``.
    :param bb: if given, the world box (left, bottom, right, top) or BB to
        fit into the image; sets :attr:`transform` (see :meth:`fit`).
    :param positive_y_is_up: True (default) flips the picture so that
        increasing y points up, as in physics; False keeps image coordinates
        (y down).
    :param background: fill colour of a new image and of :meth:`clear`.
    :param margin: pixels kept free around ``bb``.
    :param supersample: draw at this many times the size and scale down,
        for smooth edges (1 draws directly).
    :param line_width: width of outlines, in output pixels.
    :param segment_width: width of thin segments (constraints, contact
        points), in output pixels; line_width if not given.

    >>> options = DrawOptions((40, 30), bb=(0, 0, 4, 3))
    >>> options.draw_circle((20, 15), 0.0, 10.0, SpaceDebugColor(0, 0, 0, 255),
    ...                     SpaceDebugColor(255, 0, 0, 255))
    >>> options.image.getpixel((20, 10))
    (255, 0, 0)
    >>> options.to_image((0, 0)), options.from_image((40, 0))
    ((0.0, 30.0), (4.0, 3.0))
    """


class GifWriter:
    """Collects frames and writes them as an animated GIF.

    :param duration: milliseconds each frame is shown (GIF stores
        hundredths of a second).
    :param loop: how many times to play; 0 loops forever.

    >>> from PIL import Image
    >>> gif = GifWriter(duration=50)
    >>> gif.add(Image.new("RGB", (8, 8), "white"))
    >>> gif.add(Image.new("RGB", (8, 8), "black"))
    >>> len(gif)
    2
    """

    def __init__(self, duration=40, loop=0):
        if not (duration > 0):
            raise ValueError(f"duration must be positive, got {duration}")
        self.duration = duration
        self.loop = int(loop)
        self.frames = []

    def __len__(self):
        return len(self.frames)

    def add(self, image):
        """Add a copy of the image as the next frame (stored with a palette,
        so that many frames stay small in memory).

        >>> from PIL import Image
        >>> gif = GifWriter()
        >>> gif.add(Image.new("RGB", (4, 4), "red"))
        >>> gif.frames[0].mode
        'P'
        """
        if self.frames and image.size != self.frames[0].size:
            raise ValueError(
                f"frame size {image.size} differs from the first frame's {self.frames[0].size}"
            )
        rgb = image.convert("RGB")
        self.frames.append(rgb.quantize(colors=255, method=Image.Quantize.FASTOCTREE,
                                        dither=Image.Dither.NONE))

    def save(self, path):
        """Write the frames to path as an animated GIF.

        >>> import os, tempfile
        >>> from PIL import Image
        >>> gif = GifWriter()
        >>> gif.add(Image.new("RGB", (8, 8), "red"))
        >>> path = os.path.join(tempfile.mkdtemp(), "a.gif")
        >>> gif.save(path)
        >>> Image.open(path).format
        'GIF'
        """
        if not self.frames:
            raise ValueError("no frames to save")
        first, rest = self.frames[0], self.frames[1:]
        first.save(path, format="GIF", save_all=True, append_images=rest,
                   duration=self.duration, loop=self.loop, disposal=1)


def save_gif(frames, path, duration=40, loop=0):
    """Write a sequence of Pillow images to path as an animated GIF.

    >>> import os, tempfile
    >>> from PIL import Image
    >>> path = os.path.join(tempfile.mkdtemp(), "b.gif")
    >>> save_gif([Image.new("RGB", (4, 4), c) for c in ("red", "blue")], path)
    >>> Image.open(path).n_frames
    2
    """
    writer = GifWriter(duration=duration, loop=loop)
    for frame in frames:
        writer.add(frame)
    writer.save(path)
