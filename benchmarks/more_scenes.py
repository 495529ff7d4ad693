"""Scene builders of the benchmarks, beyond those of tests/scenes.py.

Like tests/scenes.py, every builder takes the engine module (``pymunk`` or
``tamias2d``) and makes the same objects in the same order with pymunk 7.3's
API, so both engines get the same input and (being bitwise equal) run the
same motion.
"""
import math


def box_moment(mass, w, h):
    return mass * (w * w + h * h) / 12.0


def circle_moment(mass, r):
    return mass * 0.5 * r * r


# -- speed scenes ------------------------------------------------------------------

def static_field(mod, pegs=1000, balls=20):
    """A Galton board: `pegs` static circles in staggered rows, `balls`
    dynamic circles falling through them onto the ground. Many static
    shapes, few moving ones."""
    space = mod.Space()
    space.gravity = 0, -900
    pitch = 24.0
    cols = max(4, int(math.sqrt(pegs * 2.0)))
    rows = int(math.ceil(pegs / cols))
    half = cols * pitch / 2.0 + pitch
    static = space.static_body
    floor = mod.Segment(static, (-half, 0), (half, 0), 2.0)
    floor.friction = 0.8
    space.add(floor)
    for x in (-half, half):
        wall = mod.Segment(static, (x, 0), (x, (rows + 12) * pitch), 2.0)
        space.add(wall)
    made = 0
    for r in range(rows):
        y = 60.0 + r * pitch
        for c in range(cols):
            if made == pegs:
                break
            x = -cols * pitch / 2.0 + c * pitch + (pitch / 2.0 if r % 2 else 0.0)
            peg = mod.Circle(static, 3.0, (x, y))
            peg.elasticity = 0.3
            peg.friction = 0.3
            space.add(peg)
            made += 1
    top = 60.0 + rows * pitch + 20.0
    for i in range(balls):
        body = mod.Body(1.0, circle_moment(1.0, 5.0))
        body.position = -cols * pitch / 3.0 + (i * 37.0) % (cols * pitch * 2.0 / 3.0), top + (i // 10) * 14.0
        ball = mod.Circle(body, 5.0)
        ball.elasticity = 0.3
        ball.friction = 0.3
        space.add(body, ball)
    return space


def sparse_field(mod, count=1000):
    """`count` circles on a grid, far apart, drifting together without
    gravity (same velocity, different spins): they never touch. Measures
    what a body costs when nothing collides (integration, broad phase)."""
    space = mod.Space()
    pitch = 40.0
    per_row = max(1, int(math.sqrt(count)))
    for i in range(count):
        row, col = divmod(i, per_row)
        body = mod.Body(1.0, circle_moment(1.0, 4.0))
        body.position = col * pitch, row * pitch
        body.velocity = 30.0, 20.0
        body.angular_velocity = ((i % 5) - 2) * 0.5
        space.add(body, mod.Circle(body, 4.0))
    return space


def box_wall(mod, count=1000, layers=5, size=10.0):
    """`count` boxes in columns of `layers` standing side by side (0.5 apart)
    on a long ground: the width grows with the count, the height does not,
    so contacts per body stay the same at every size (one per box: columns of
    5 stand still at dt 1/60 and 10 iterations; columns of 10 topple)."""
    space = mod.Space()
    space.gravity = 0, -900
    cols = max(1, int(math.ceil(count / layers)))
    pitch = size + 0.5
    half = cols * pitch / 2.0 + 40.0 * size   # room for the end columns to topple
    ground = mod.Segment(space.static_body, (-half, 0), (half, 0), 1.0)
    ground.friction = 0.8
    space.add(ground)
    made = 0
    for c in range(cols):
        x = -cols * pitch / 2.0 + c * pitch + size / 2.0
        for r in range(layers):
            if made == count:
                break
            body = mod.Body(1.0, box_moment(1.0, size, size))
            body.position = x, 1.0 + size / 2.0 + r * (size + 0.25)
            shape = mod.Poly.create_box(body, (size, size))
            shape.friction = 0.8
            space.add(body, shape)
            made += 1
    return space


def sleeping_wall(mod, count=1000):
    """The box wall with sleeping enabled (bodies idle for 0.5 s fall asleep):
    after a few seconds every box sleeps, and a step should cost next to
    nothing."""
    space = box_wall(mod, count=count)
    space.sleep_time_threshold = 0.5
    return space


def with_post_solve(space, counter):
    """Install a Python post_solve callback on every contact pair (the
    global handler) that reads the arbiter's impulse, as a game reading
    impact strengths for sounds would; counter[0] counts the calls."""
    def post_solve(arbiter, sp, data):
        counter[0] += 1
        j = arbiter.total_impulse
        if j.x * j.x + j.y * j.y > 1e12:
            counter[1] += 1
    space.on_collision(None, None, post_solve=post_solve)
    return space


def callback_rain(mod, count=250, scenes=None):
    """tests/scenes.py's rain with a Python post_solve callback on every contact."""
    space = scenes.rain(mod, count=count)
    space.bench_counter = [0, 0]
    return with_post_solve(space, space.bench_counter)


# -- scenes with known answers (speed against error) ---------------------------------

def free_flight(mod, count=20):
    """IM1: `count` bodies without shapes under gravity plus a constant force
    (set before every step by ``apply``). Returns (space, apply, exact) where
    exact(t) gives the closed-form positions."""
    space = mod.Space()
    g = (0.0, -9.81)
    space.gravity = g
    bodies, params = [], []
    for i in range(count):
        m = 1.0 + 0.5 * i
        body = mod.Body(m, 1.0 + i)
        p0 = (0.412 + i, 0.502 - 0.25 * i)
        v0 = (2.51 - 0.1 * i, 5.0 + 0.3 * i)
        f = (98.1 * ((i % 3) - 1), 20.0 + 3.0 * i)
        body.position = p0
        body.velocity = v0
        space.add(body)
        bodies.append(body)
        params.append((m, p0, v0, f))

    def apply():
        for body, (m, p0, v0, f) in zip(bodies, params):
            body.force = f

    def exact(t):
        out = []
        for m, p0, v0, f in params:
            ax, ay = g[0] + f[0] / m, g[1] + f[1] / m
            out.append((p0[0] + v0[0] * t + 0.5 * ax * t * t,
                        p0[1] + v0[1] * t + 0.5 * ay * t * t))
        return out

    return space, bodies, apply, exact


def spin(mod, count=20):
    """IM2: `count` bodies spinning under a constant torque (set before every
    step). Returns (space, bodies, apply, exact) with exact(t) the angles."""
    space = mod.Space()
    bodies, params = [], []
    for i in range(count):
        inertia = 74.5 * (1.0 + 0.1 * i)
        body = mod.Body(56.2, inertia)
        a0, w0, tau = 0.1 * i, 2.1 - 0.2 * i, 200.0 * ((i % 4) - 1.5)
        body.angle = a0
        body.angular_velocity = w0
        space.add(body)
        bodies.append(body)
        params.append((inertia, a0, w0, tau))

    def apply():
        for body, (inertia, a0, w0, tau) in zip(bodies, params):
            body.torque = tau

    def exact(t):
        return [a0 + w0 * t + 0.5 * tau / inertia * t * t for inertia, a0, w0, tau in params]

    return space, bodies, apply, exact


def head_on(mod, kind="box", restitution=0.8, m1=2.0, m2=3.0, v1=300.0, v2=-200.0):
    """IM3: two bodies on the x axis meeting head on, no gravity, no
    friction; elasticity product = `restitution`. Returns (space, a, b,
    exact) with exact = the closed-form velocities after the impact."""
    space = mod.Space()
    size = 20.0
    bodies = []
    for m, x, v in ((m1, -100.0, v1), (m2, 100.0, v2)):
        if kind == "box":
            body = mod.Body(m, box_moment(m, size, size))
            shape = mod.Poly.create_box(body, (size, size))
        else:
            body = mod.Body(m, circle_moment(m, size / 2.0))
            shape = mod.Circle(body, size / 2.0)
        body.position = x, 0.0
        body.velocity = v, 0.0
        shape.friction = 0.0
        shape.elasticity = restitution if not bodies else 1.0
        space.add(body, shape)
        bodies.append(body)
    e = restitution
    total = m1 * v1 + m2 * v2
    u1 = (total + m2 * e * (v2 - v1)) / (m1 + m2)
    u2 = (total + m1 * e * (v1 - v2)) / (m1 + m2)
    return space, bodies[0], bodies[1], (u1, u2)


def incline(mod, angle_deg=30.0, mu=0.2, size=20.0):
    """A box released on a static segment inclined by `angle_deg`, friction
    product `mu`. Returns (space, box, slope_direction, exact_acceleration)
    with exact = g (sin a - mu cos a) along the slope."""
    space = mod.Space()
    g = 900.0
    space.gravity = 0, -g
    a = math.radians(angle_deg)
    d = (math.cos(a), -math.sin(a))           # down the slope
    n = (math.sin(a), math.cos(a))            # out of the slope
    length = 2000.0
    start = (-0.5 * length * d[0], -0.5 * length * d[1])
    end = (0.5 * length * d[0], 0.5 * length * d[1])
    slope = mod.Segment(space.static_body, start, end, 0.0)
    slope.friction = 1.0
    space.add(slope)
    box = mod.Body(1.0, box_moment(1.0, size, size))
    # resting on the slope, a third of the way down from the top end
    s = -0.3 * length
    box.position = s * d[0] + (size / 2.0) * n[0], s * d[1] + (size / 2.0) * n[1]
    box.angle = -a
    shape = mod.Poly.create_box(box, (size, size))
    shape.friction = mu
    space.add(box, shape)
    return space, box, d, g * (math.sin(a) - mu * math.cos(a))
