"""Run a pymunk program headless for a number of frames and print the state
of its spaces, on pymunk or (through the import hook) on tamias2d.

    python run_pymunk_program.py ENGINE SCRIPT FRAMES [ARGS...]

ENGINE is ``pymunk`` or ``tamias2d``. pygame runs with SDL's dummy drivers;
each ``pygame.display.flip``/``update`` is a frame, and after FRAMES frames
the bodies of every live Space are printed as JSON (position, angle,
velocity, angular velocity as repr strings, so equal output means equal
bits) and the process exits. ``random`` is seeded, so the two engines get
the same scene. RUN_PYMUNK_KEYS (names of keys, e.g. ``"d u"``) presses those
keys before the first frame.
"""
import gc
import json
import os
import random
import runpy
import sys

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

engine, script, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
if engine == "tamias2d":
    import tamias2d
    tamias2d.install_as_pymunk()
import pymunk  # noqa: E402

if engine == "tamias2d":
    assert getattr(pymunk, "__tamias2d__", False), "the hook did not take"


def dump_and_exit():
    spaces = [o for o in gc.get_objects() if isinstance(o, pymunk.Space)]
    out = []
    for s in spaces:
        out.append([[repr(tuple(b.position)), repr(b.angle), repr(tuple(b.velocity)),
                     repr(b.angular_velocity)] for b in s.bodies])
    out.sort()
    sys.stdout.write("STATE " + json.dumps({"frames": count[0], "spaces": out}) + "\n")
    sys.stdout.flush()
    os._exit(0)


count = [0]
try:
    import pygame

    def frame(*args, _flip=pygame.display.flip, **kwargs):
        count[0] += 1
        if count[0] >= frames:
            dump_and_exit()

    pygame.display.flip = frame
    pygame.display.update = frame

    # RUN_PYMUNK_KEYS="d u": the program's first pygame.event.get() also
    # returns a KEYDOWN for each of these keys (to switch on a mode).
    keys = os.environ.get("RUN_PYMUNK_KEYS", "").split()
    if keys:
        def get(*args, _get=pygame.event.get, **kwargs):
            events = _get(*args, **kwargs)
            while keys:
                events.append(pygame.event.Event(pygame.KEYDOWN, key=pygame.key.key_code(keys.pop(0)),
                                                 mod=0, unicode="", scancode=0))
            return events

        pygame.event.get = get
except ImportError:
    pass

random.seed(0)
sys.argv = [script, *sys.argv[4:]]
sys.path.insert(0, os.path.dirname(os.path.abspath(script)))
runpy.run_path(script, run_name="__main__")
dump_and_exit()
