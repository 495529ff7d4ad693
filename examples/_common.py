"""What every example shares: the command line, the window loop and the
headless pictures. Not an example itself.

An example builds its world in screen units (pixels, y pointing up, the
origin at the bottom left of the window, as pymunk's examples do with
``pygame_util.positive_y_is_up = True``) and hands two functions to
:func:`run`:

* ``update(frame)`` advances the simulation by one frame (``DT`` seconds);
* ``draw(canvas)`` draws that frame with ``canvas.space(space)``,
  ``canvas.line(...)`` and ``canvas.text(...)``.

In a window (the default) the loop runs at 60 frames a second until the
window is closed or Escape is pressed. With ``--headless`` no window opens:
the loop runs ``--frames`` frames as fast as it can and writes the last one
to a PNG drawn with Pillow (``tamias2d.pillow_util``), or every few frames
to an animated GIF with ``--gif``.
"""
import argparse
import sys
from pathlib import Path

FPS = 60
DT = 1.0 / FPS

BACKGROUND = (248, 249, 250)
INK = (44, 62, 80)
# Fill colours for shapes (shape.color), the same as the demo's.
PALETTE = [(52, 152, 219, 255), (231, 76, 60, 255), (241, 196, 15, 255),
           (46, 204, 113, 255), (155, 89, 182, 255), (230, 126, 34, 255),
           (26, 188, 156, 255)]
GROUND = (127, 140, 141, 255)


def _frame_count(text):
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"--frames must be at least 1, got {n}")
    return n


def parse_args(description, argv=None):
    """The options every example takes; returns the argparse namespace."""
    parser = argparse.ArgumentParser(description=description.strip().splitlines()[0])
    parser.add_argument("--headless", action="store_true",
                        help="no window: run --frames frames and write a picture")
    parser.add_argument("--frames", type=_frame_count, default=None,
                        help="frames to run (headless: the example's own default; "
                             "in a window: close after this many)")
    parser.add_argument("--gif", action="store_true",
                        help="headless: write an animated GIF instead of a PNG")
    parser.add_argument("--out", default=None,
                        help="picture to write (default: NAME.png or NAME.gif here; "
                             "in a window, a screenshot at the end if given)")
    return parser.parse_args(argv)


def default_out(args, suffix=None):
    """The picture path: --out, or the example's name in the current folder."""
    if args.out:
        return Path(args.out)
    name = Path(sys.modules["__main__"].__file__).stem
    return Path(name + (suffix or (".gif" if args.gif else ".png")))


def pressed(key_name):
    """Whether a key (a pygame key name: "left", "space", "a" ...) is held
    down; always False headless, where there is no keyboard."""
    if "pygame" not in sys.modules:
        return False
    import pygame

    if not pygame.display.get_init() or pygame.display.get_surface() is None:
        return False
    return bool(pygame.key.get_pressed()[pygame.key.key_code(key_name)])


def world_pos(event_pos, height):
    """A pygame pixel position -> world coordinates (y flipped)."""
    return (event_pos[0], height - event_pos[1])


class _Canvas:
    """Drawing calls shared by the two back ends; world coordinates."""

    def __init__(self, options, size):
        self.options = options
        self.size = size
        options.flags = options.DRAW_SHAPES | options.DRAW_CONSTRAINTS
        options.shape_outline_color = INK + (255,)
        options.constraint_color = (90, 100, 110, 255)

    def space(self, space, offset=(0, 0)):
        """Draw a space, shifted by offset (to show two spaces side by side,
        or to follow a body)."""
        import tamias2d

        self.options.transform = tamias2d.Transform.translation(*offset)
        space.debug_draw(self.options)
        self.options.transform = tamias2d.Transform.identity()


def _pygame_options(screen):
    """pygame_util.DrawOptions, with see-through polygon fills (pygame's
    draw functions ignore alpha; Pillow's drawing blends it)."""
    import pygame
    from tamias2d import pygame_util

    class DrawOptions(pygame_util.DrawOptions):
        def draw_polygon(self, verts, radius, outline_color, fill_color):
            if fill_color.a >= 255:
                return super().draw_polygon(verts, radius, outline_color, fill_color)
            layer = pygame.Surface(self.surface.get_size(), pygame.SRCALPHA)
            points = [pygame_util.to_pygame(v, self.surface) for v in verts]
            pygame.draw.polygon(layer, fill_color.as_int(), points)
            self.surface.blit(layer, (0, 0))

    pygame_util.positive_y_is_up = True
    return DrawOptions(screen)


class _PygameCanvas(_Canvas):
    def __init__(self, screen):
        import pygame

        super().__init__(_pygame_options(screen), screen.get_size())
        self.screen = screen
        self.font = pygame.font.Font(None, 22)
        self._pg = pygame

    def clear(self):
        self.screen.fill(BACKGROUND)

    def _p(self, p):
        return round(p[0]), round(self.size[1] - p[1])

    def line(self, a, b, color, width=1):
        self._pg.draw.line(self.screen, color[:3], self._p(a), self._p(b), max(1, round(width)))

    def text(self, lines, at=(10, 8), color=INK):
        """Lines of text from a point in window pixels (top left origin), on
        a pale backdrop so that they stay readable over shapes."""
        x, y = at
        for line in [lines] if isinstance(lines, str) else lines:
            label = self.font.render(line, True, color)
            backdrop = self._pg.Surface((label.get_width() + 6, label.get_height()))
            backdrop.fill(BACKGROUND)
            backdrop.set_alpha(200)
            self.screen.blit(backdrop, (x - 3, y))
            self.screen.blit(label, (x, y))
            y += self.font.get_linesize()

    def picture(self):
        return self.screen


class _PillowCanvas(_Canvas):
    def __init__(self, size):
        from tamias2d import pillow_util

        # Drawn at twice the size and scaled down, for smooth edges.
        options = pillow_util.DrawOptions(size, bb=(0, 0, size[0], size[1]),
                                          background=BACKGROUND + (255,), supersample=2)
        super().__init__(options, size)
        self._texts = []

    def clear(self):
        self.options.clear()
        self._texts = []

    def line(self, a, b, color, width=1):
        from tamias2d.space_debug_draw_options import SpaceDebugColor

        c = SpaceDebugColor(*color[:3], 255)
        self.options.draw_fat_segment(a, b, width / 2, c, c)

    def text(self, lines, at=(10, 8), color=INK):
        # Drawn on the final image once the shapes are in (see picture()).
        self._texts.append(([lines] if isinstance(lines, str) else list(lines), at, color))

    def picture(self):
        from PIL import ImageDraw, ImageFont

        image = self.options.image
        try:
            font = ImageFont.load_default(15)
        except TypeError:  # Pillow < 10.1 has one fixed bitmap font
            font = ImageFont.load_default()
        draw = ImageDraw.Draw(image, "RGBA")  # RGBA: the backdrop blends
        for lines, (x, y), color in self._texts:
            for line in lines:
                left, top, right, bottom = draw.textbbox((x, y), line, font=font)
                draw.rectangle((left - 3, y, right + 3, y + 18), fill=BACKGROUND + (200,))
                draw.text((x, y), line, fill=tuple(color[:3]), font=font)
                y += 18
        self._texts = []
        return image


def run(args, update, draw, *, title, size=(800, 500), frames=300, on_event=None):
    """Run an example: in a window, or headless into a picture.

    :param update: ``update(frame)``, one frame of simulation.
    :param draw: ``draw(canvas)``, draws the current frame.
    :param frames: the headless frame count when --frames is not given.
    :param on_event: ``on_event(event)`` for every pygame event but quitting
        (window only).
    :returns: the number of frames run.
    """
    if args.headless:
        return _run_headless(args, update, draw, size, args.frames or frames)
    return _run_window(args, update, draw, title, size, on_event)


def _run_headless(args, update, draw, size, frames):
    from tamias2d import pillow_util

    canvas = _PillowCanvas(size)

    def render():
        canvas.clear()
        draw(canvas)
        return canvas.picture()

    gif = None
    if args.gif:
        # About 60 frames whatever the length, played at the simulated speed.
        every = max(1, frames // 60)
        gif = pillow_util.GifWriter(duration=1000 * every / FPS)
    for frame in range(frames):
        update(frame)
        if gif is not None and (frame % every == 0 or frame == frames - 1):
            gif.add(render())
    out = default_out(args)
    if gif is not None:
        gif.save(out)
    else:
        render().save(out)
    print(f"wrote {out} after {frames} frames")
    return frames


def _run_window(args, update, draw, title, size, on_event):
    import pygame

    # Only what the loop uses (no audio: nothing to open on a silent machine).
    pygame.display.init()
    pygame.font.init()
    screen = pygame.display.set_mode(size)
    pygame.display.set_caption(title)
    canvas = _PygameCanvas(screen)
    clock = pygame.time.Clock()
    frame = 0
    running = True
    while running and (args.frames is None or frame < args.frames):
        for event in pygame.event.get():
            if event.type == pygame.QUIT or (event.type == pygame.KEYDOWN
                                             and event.key == pygame.K_ESCAPE):
                running = False
            elif on_event is not None:
                on_event(event)
        update(frame)
        frame += 1
        canvas.clear()
        draw(canvas)
        pygame.display.flip()
        clock.tick(FPS)
    if args.out:
        pygame.image.save(screen, str(args.out))
        print(f"wrote {args.out} after {frame} frames")
    pygame.quit()
    return frame
