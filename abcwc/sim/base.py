"""SimBase: the simulated chair behind the one Base interface.

A top-down pymunk world (no gravity) holds the walls, the walkers and the chair: a
rigid body shaped like the chair's footprint, with its origin at base_link (the
drive-axle midpoint). The drive wheels are modelled the way pymunk's top-down "tank"
example does it: a kinematic control body carries the wheels' velocity, and a pivot
joint plus a gear joint with bias switched off pull the chair to that velocity with
at most the tyres' friction force and torque. So the chair does not slip sideways
unless something pushes harder than the tyres grip. The front casters are free and
carry no force. Every control period (20 ms) the interface board's rules run
(:class:`abcwc.control.InterfaceBoard`), the motor controller turns pot bytes into
wheel speeds (:mod:`abcwc.sim.motor`), physics advances, and the sensors report.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
import pymunk

from abcwc.base import BodyMixin
from abcwc.control.interface_board import InterfaceBoard
from abcwc.geometry import wrap_angle
from abcwc.params import ChairParams, default_params
from abcwc.perception.camera import PinholeCamera
from abcwc.perception.signs import house_sign
from abcwc.sim.colour_camera import PlanarTarget, render_colour
from abcwc.sim.motor import ChairErrors, MotorController, resolve_errors
from abcwc.sim.people import (
    LOOK_AHEAD,
    PASSING_CLEARANCE,
    PERSON_COLLISION_TYPE,
    Walker,
    circles_of,
)
from abcwc.sim.raycast import visible_segments
from abcwc.sim.sensors import Encoders, Gyro, IrRing, ScanSensor, Sonar
from abcwc.sim.world import World, load_world
from abcwc.types import (
    CAMERA_FRAME,
    CameraImage,
    LaserScan,
    Pose2D,
    PotCommand,
    SensorFrame,
    SimTruth,
    StatusFlags,
    Twist,
)

CAMERA_MODES = ("rgb", "gray")
"""What ``SimBase(camera=...)`` can render: colour, or grey at a third of the cost."""

CHAIR_COLLISION_TYPE = 1
WALL_COLLISION_TYPE = 2
WALL_RADIUS = 0.005  # m, collision thickness of a wall line (sensors see the line)
TYRE_FRICTION = 0.8  # rubber on indoor floor
GRAVITY = 9.81
PHYSICS_SUBSTEPS = 1  # 20 ms steps: the tyres never need more than their grip


class SimBase(BodyMixin):
    """The simulated chair. Same surface as the real one (:class:`abcwc.hw.SerialBase`).

    ``send`` a PotCommand or Twist, ``step`` one control period, read the SensorFrame;
    or ``run(controller, seconds)``. The same ``seed`` gives the same run.
    """

    run_verb = "simulating"

    def __init__(
        self,
        world: str | World = "lab",
        seed: int = 0,
        errors: ChairErrors | str | None = "worn",
        params: ChairParams | None = None,
        lidar: bool = False,
        depth_scan: bool = False,
        start: Pose2D | str | None = None,
        people: bool = True,
        camera: str | None = None,
    ):
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        self.params = p = params or default_params()
        self.world = world if isinstance(world, World) else load_world(world)
        self.seed = int(seed)
        self.errors = resolve_errors(errors)
        self.period = p.control_period
        rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(self.seed).spawn(7)]
        self.board = InterfaceBoard(p)
        self.motors = MotorController(p, self.errors, self.period, rngs[0])
        self.encoders = Encoders(p, self.errors.encoder_wheel_left, self.errors.encoder_wheel_right)
        self.gyro = Gyro(p.gyro, self.period, rngs[1])
        self.sonar = Sonar(p.sonar, rngs[2])
        self.ir = IrRing(p.ir, rngs[3])
        self.lidar = ScanSensor(p.lidar, rngs[4]) if lidar else None
        self.depth_camera = (
            ScanSensor(p.depth_scan, rngs[5], depth_noise=True) if depth_scan else None
        )
        if camera is not None and camera not in CAMERA_MODES:
            raise ValueError(f"camera must be None or one of {', '.join(CAMERA_MODES)}, "
                             f"got {camera!r}")
        self.camera_mode = camera
        # the Kinect's colour camera beside its depth camera: 640 x 480, 57 x 43 degrees
        self.camera = PinholeCamera.from_fov(640, 480, p.depth_scan.fov_deg,
                                             p.depth_scan.vertical_fov_deg)
        self._camera_rng = rngs[6]
        self._image: CameraImage | None = None
        self._build_space(self._start_pose(start), people)
        # what each sensor can see of the walls and objects from its height (static)
        w = self.world
        self._seen = {
            "sonar": visible_segments(w.walls, w.bands, p.sonar.height,
                                      p.sonar.vertical_half_angle),
            "ir": visible_segments(w.walls, w.bands, p.ir.height, 0.0),
            "lidar": visible_segments(w.walls, w.bands, p.lidar.height,
                                      p.lidar.vertical_half_angle),
            "depth_scan": visible_segments(w.walls, w.bands, p.depth_scan.height,
                                           p.depth_scan.vertical_half_angle),
        }
        self.t = 0.0
        self.steps = 0
        self.joystick = (p.joystick_centre, p.joystick_centre)
        self.collisions = 0
        self.collision_impulse = 0.0
        self.max_collision_impulse = 0.0
        self._pots = PotCommand(p.pot_neutral, p.pot_neutral)
        self._surface_speeds = (0.0, 0.0)
        self._flags = StatusFlags.WATCHDOG_TRIPPED
        self._last_scan: dict[str, LaserScan | None] = {"lidar": None, "depth_scan": None}
        self._sonar_reading = p.sonar.max_range
        self._ir_reading = np.full(6, np.inf)
        self._read_slow_sensors(force=True)
        self._frame = self._make_frame(gyro_z=self.gyro.read(0.0))
        self._init_safety()

    # ----------------------------------------------------------------- set-up
    def _start_pose(self, start: Pose2D | str | None) -> Pose2D:
        if start is None:
            return self.world.start
        if isinstance(start, str):
            if start not in self.world.places:
                raise ValueError(f"unknown place {start!r} in world {self.world.name!r}; "
                                 f"places: {', '.join(self.world.places)}")
            return self.world.places[start]
        if isinstance(start, Pose2D):
            return start
        raise ValueError(f"start must be a Pose2D or a place name, got {start!r}")

    def _build_space(self, start: Pose2D, people: bool) -> None:
        p = self.params
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.collision_slop = 0.001  # metres: pymunk's default (0.1) suits pixels
        for x1, y1, x2, y2 in self.world.walls:
            wall = pymunk.Segment(space.static_body, (x1, y1), (x2, y2), WALL_RADIUS)
            wall.collision_type = WALL_COLLISION_TYPE
            wall.friction = 0.5
            space.add(wall)
        mass = p.total_mass
        outline = p.footprint
        moment = pymunk.moment_for_poly(mass, outline)
        chair = pymunk.Body(mass, moment)
        shape = pymunk.Poly(chair, outline)
        shape.collision_type = CHAIR_COLLISION_TYPE
        shape.friction = 0.5
        chair.position = (start.x, start.y)
        chair.angle = start.theta
        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position = chair.position
        traction = pymunk.PivotJoint(control, chair, (0, 0), (0, 0))
        traction.max_bias = 0.0
        traction.max_force = TYRE_FRICTION * mass * GRAVITY
        steering = pymunk.GearJoint(control, chair, 0.0, 1.0)
        steering.max_bias = 0.0
        steering.max_force = TYRE_FRICTION * mass * GRAVITY * p.wheel_base / 2
        space.add(chair, shape, control, traction, steering)
        self.walkers = [Walker(spec, space) for spec in self.world.people] if people else []
        space.on_collision(CHAIR_COLLISION_TYPE, WALL_COLLISION_TYPE,
                           begin=self._on_contact, post_solve=self._on_impulse)
        space.on_collision(CHAIR_COLLISION_TYPE, PERSON_COLLISION_TYPE,
                           begin=self._on_contact, post_solve=self._on_impulse)
        self.space, self.chair, self._control = space, chair, control
        self._chair_shape = shape

    def _on_contact(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        self.collisions += 1

    def _on_impulse(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        impulse = abs(arbiter.total_impulse)
        self.collision_impulse += impulse
        self.max_collision_impulse = max(self.max_collision_impulse, impulse)

    # ----------------------------------------------------------------- state
    @property
    def pose(self) -> Pose2D:
        """Ground-truth pose of base_link in the world frame."""
        x, y = self.chair.position
        return Pose2D(x, y, wrap_angle(self.chair.angle))

    @property
    def last_command(self) -> PotCommand | None:
        """The last host command as pot bytes (before the board's clamps and cap)."""
        return self.board.last_command

    # ----------------------------------------------------------------- commands
    def _write(self, command: PotCommand | Twist) -> None:
        """The interface board takes the command (after the safety filter)."""
        self.board.command(command, self.t)

    def stop(self) -> None:
        """Command both pots to neutral now."""
        self.board.stop(self.t)
        self._stopped()

    def set_joystick(self, fb: int | None = None, lr: int | None = None) -> None:
        """Set the virtual joystick's ADC readings (pot scale; 254 is centred).

        A deflection outside 248..260 on either axis overrides every host command.
        """
        values = []
        for name, value, old in (("fb", fb, self.joystick[0]), ("lr", lr, self.joystick[1])):
            if value is None:
                values.append(old)
                continue
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"joystick {name} must be an integer ADC value 0..1023, "
                                 f"got {value!r}")
            if not 0 <= value <= self.params.adc_max:
                raise ValueError(f"joystick {name} {value} outside 0..{self.params.adc_max}")
            values.append(int(value))
        self.joystick = (values[0], values[1])

    def release_joystick(self) -> None:
        """Let the joystick spring back to the centre."""
        c = self.params.joystick_centre
        self.joystick = (c, c)

    def carry(self, dx: float, dy: float, dtheta: float) -> None:
        """Move the chair by ``(dx, dy)`` m and turn it ``dtheta`` rad in the world frame
        as a carer lifting it would: its wheels turn no tick and its estimators do not
        know (a kidnapping, to test what a lost localiser does). ValueError for a move
        that is not three finite numbers."""
        moves = (dx, dy, dtheta)
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                   and math.isfinite(v) for v in moves):
            raise ValueError(f"carry takes finite dx, dy (m) and dtheta (rad), got {moves!r}")
        x, y = self.chair.position
        self.chair.position = self._control.position = (x + dx, y + dy)
        self.chair.angle = self._control.angle = self.chair.angle + dtheta

    def set_speed_cap(self, offset: int) -> None:
        """Limit host commands to 128 +- ``offset`` pot bytes (as the real chair's cap)."""
        self.board.set_speed_cap(offset)

    # ----------------------------------------------------------------- stepping
    def step(self) -> SensorFrame:
        """Advance one control period and return the new SensorFrame."""
        out = self.board.update(self.t, *self.joystick)
        return self.step_with_pots(out.pots, out.flags)

    def step_with_pots(self, pots: PotCommand,
                       flags: StatusFlags = StatusFlags.NONE) -> SensorFrame:
        """Advance one control period with ``pots`` on the motor controller.

        :meth:`step` calls this with the interface board's decision; a firmware in
        the loop calls it with the bytes the real firmware wrote, bypassing the board.
        """
        dt = self.period
        self._pots, self._flags = pots, flags
        # pymunk moves bodies with the velocities solved in the previous step, then
        # solves new ones: this step executes the wheel motion decided last period.
        self.encoders.advance(*self._surface_speeds, dt)
        motion = self.motors.advance(pots)
        self._surface_speeds = (motion.surface_left, motion.surface_right)
        # The velocity set now moves the chair in the next step, after this step has
        # turned it by its present rate; aim it along the chord of that next step's arc,
        # half-way through its turn, so the true path is an arc (as a real chair's)
        # rather than a polygon of chords along a lagging heading.
        theta = self.chair.angle + self.chair.angular_velocity * dt + motion.w * dt / 2
        self._control.velocity = (motion.v * math.cos(theta), motion.v * math.sin(theta))
        self._control.angular_velocity = motion.w
        sub = dt / PHYSICS_SUBSTEPS
        for walker in self.walkers:
            walker.steer(dt, *self._walker_sees_chair(walker))
        for _ in range(PHYSICS_SUBSTEPS):
            self.space.step(sub)
        self.steps += 1
        self.t = self.steps * dt
        gyro_z = self.gyro.read(self.chair.angular_velocity)
        self._read_slow_sensors()
        self._frame = self._make_frame(gyro_z)
        return self._frame

    def _walker_sees_chair(self, walker: Walker) -> tuple[bool, bool]:
        """(touching, way_blocked) for one walker: in contact with the chair now, and the
        chair within ``LOOK_AHEAD`` of its body along the way it is walking."""
        position = walker.body.position
        gap = self._chair_shape.point_query(position).distance - walker.spec.radius
        # the body, widened by the passing clearance, swept from its front to LOOK_AHEAD
        # beyond (a chair touching it from behind is not "in the way")
        hx, hy = walker.heading()
        width = 0.95 * walker.spec.radius + PASSING_CLEARANCE
        start = walker.spec.radius
        reach = max(walker.spec.radius + LOOK_AHEAD - width, start)
        near = (position.x + hx * start, position.y + hy * start)
        ahead = (position.x + hx * reach, position.y + hy * reach)
        seen = self._chair_shape.segment_query(near, ahead, width)
        return gap <= 0.005, seen is not None

    def _read_slow_sensors(self, force: bool = False) -> None:
        """10 Hz sensors, staggered over the five periods of each 100 ms."""
        phase = self.steps % 5
        pose = self.pose
        seen = self._seen
        circles = circles_of(self.walkers)
        if force or phase == 0:
            self._sonar_reading = self.sonar.read(pose, seen["sonar"], circles)
        if force or phase == 1:
            self._ir_reading = self.ir.read(pose, seen["ir"], circles)
        if self.lidar is not None and (force or phase == 2):
            self._last_scan["lidar"] = self.lidar.read(pose, seen["lidar"], circles, self.t)
        if self.depth_camera is not None and (force or phase == 3):
            self._last_scan["depth_scan"] = self.depth_camera.read(
                pose, seen["depth_scan"], circles, self.t)
        if self.camera_mode is not None and (force or phase == 4):
            self._image = self.render_camera()

    @cached_property
    def _wall_targets(self) -> tuple[PlanarTarget, ...]:
        """The world's signs and markers as the camera draws them (made at the first
        image, not for a chair that never takes one)."""
        return tuple(
            PlanarTarget(sign.name, house_sign(sign.word), sign.width, sign.centre, sign.facing)
            for sign in self.world.signs) + tuple(
            PlanarTarget(f"marker {m.marker_id}", m.image(), m.width, m.centre, m.facing)
            for m in self.world.markers)

    def render_camera(self, rng: bool = True) -> CameraImage:
        """What the colour camera sees now (with the frame's lighting, blur, noise and
        the motion blur of the chair's own motion, drawn from the seeded generator; the
        ideal image with ``rng`` False)."""
        p, w, camera = self.params, self.world, self.camera
        body = self.chair
        ahead = (body.velocity.x * math.cos(body.angle) + body.velocity.y * math.sin(body.angle))
        targets = self._wall_targets + tuple(
            t for t in (walker.tag_target() for walker in self.walkers) if t is not None)
        pixels = render_colour(camera, self.pose, p.depth_scan.mount, p.depth_scan.height,
                               w.walls, w.bands, circles_of(self.walkers), targets,
                               self._camera_rng if rng else None,
                               gray=self.camera_mode == "gray",
                               motion=(ahead, body.angular_velocity))
        return CameraImage(pixels, camera.fx, camera.fy, camera.cx, camera.cy, self.t)

    def _make_frame(self, gyro_z: float) -> SensorFrame:
        left, right = self.encoders.counts
        return SensorFrame(
            t=self.t, ticks_left=left, ticks_right=right, gyro_z=gyro_z,
            sonar=self._sonar_reading, ir=self._ir_reading,
            joystick_fb=self.joystick[0], joystick_lr=self.joystick[1],
            pot_fb=self._pots.fb, pot_lr=self._pots.lr, flags=self._flags,
            truth=SimTruth(self.pose, self.collisions), lidar=self._last_scan["lidar"],
            depth_scan=self._last_scan["depth_scan"],
            readings={CAMERA_FRAME: self._image} if self._image is not None else None,
        )

    # ----------------------------------------------------------------- runs
    def log_meta(self) -> dict:
        """What a log needs to say where it came from."""
        e = self.errors
        return {
            "source": "sim", "world": self.world.name, "seed": self.seed,
            "period": self.period, "start_time": self.t,
            "errors": {k: getattr(e, k) for k in e.__dataclass_fields__},
        }
