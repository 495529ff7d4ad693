"""A car on hilly ground: suspension and a motor.

Each wheel slides on a GrooveJoint (a slot under the chassis) and is pushed
down by a DampedSpring, which makes the suspension; a SimpleMotor between
the chassis and each wheel drives it. The motor's max_force is its torque
limit: the wheels then spin at the rate asked for only while the torque
suffices (uphill they slow down). The view follows the car.

Keys: Right / Left to drive forwards / backwards. Headless, the throttle is
held forwards.

    python examples/car.py
    python examples/car.py --headless --frames 480
"""
import math

import _common
import tamias2d

WIDTH, HEIGHT = 900, 500
space = tamias2d.Space()
space.gravity = (0, -900)

# Hills: a long chain of static segments, gentle first, then higher.
ground = [(x, 150 + 70 * math.sin(x / 250) * min(1.0, max(0, x) / 2000) + 8 * math.sin(x / 40))
          for x in range(-400, 6000, 20)]
ground = [(ground[0][0], 600)] + ground + [(ground[-1][0], 600)]  # walls at the ends
for a, b in zip(ground, ground[1:]):
    shape = tamias2d.Segment(space.static_body, a, b, 3)
    shape.friction = 1.0
    shape.color = _common.GROUND
    space.add(shape)
# The car. Its parts share a group so that the wheels don't rub the chassis.
car = tamias2d.ShapeFilter(group=1)
chassis = tamias2d.Body(10, tamias2d.moment_for_box(10, (110, 26)))
chassis.position = 100, 240
body_shape = tamias2d.Poly.create_box(chassis, (110, 26), 3)
body_shape.filter, body_shape.color = car, _common.PALETTE[1]
space.add(chassis, body_shape)
motors = []
for x in (-38, 38):
    wheel = tamias2d.Body(2, tamias2d.moment_for_circle(2, 0, 20))
    wheel.position = chassis.position + (x, -28)
    tyre = tamias2d.Circle(wheel, 20)
    tyre.friction, tyre.filter, tyre.color = 1.5, car, (95, 100, 110, 255)
    groove = tamias2d.GrooveJoint(chassis, wheel, (x, -10), (x, -35), (0, 0))
    spring = tamias2d.DampedSpring(chassis, wheel, (x, 0), (0, 0),
                                   rest_length=35, stiffness=900, damping=40)
    motor = tamias2d.SimpleMotor(chassis, wheel, 0)
    motor.max_force = 60000  # the motor's torque limit
    motors.append(motor)
    space.add(wheel, tyre, groove, spring, motor)


def update(frame):
    if args.headless or _common.pressed("right"):
        throttle = 1
    elif _common.pressed("left"):
        throttle = -1
    else:
        throttle = 0
    for motor in motors:
        # The motor keeps wheel.angular_velocity - chassis.angular_velocity
        # at -rate: a positive rate turns the wheel clockwise (y up), which
        # rolls the car to the right. A rate of 0 holds the wheels: a brake.
        motor.rate = 14 * throttle
    space.step(_common.DT)


def camera():
    return (WIDTH / 3 - chassis.position.x, HEIGHT / 2 - chassis.position.y)


def draw(canvas):
    canvas.space(space, offset=camera())
    canvas.text([f"speed {chassis.velocity.length:4.0f} px/s, at x = {chassis.position.x:.0f}",
                 "Right / Left: drive"])


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: car", size=(WIDTH, HEIGHT), frames=480)
    print(f"the car got to x = {chassis.position.x:.0f}")
