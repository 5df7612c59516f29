"""The Duckiebot's driver nodes, written against the rospy API, driving the simulator.

These are the nodes a real Duckiebot runs (Duckietown's dt-duckiebot-interface and
dt-car-interface, distro daffy), with the same topics, services, parameters and behaviour, but
with the simulator instead of the motor board, the encoders, the LED board and the camera.
They are the robot's firmware: a student talks to them through topics and services exactly as
on the robot, and never needs to read them.

Every driver takes the ``rospy`` it runs with (the in-process graph's, or Debian's real one),
the :class:`~duckielib.sim.Simulator` and the robot's namespace (``/VEH/``), and uses absolute
names under that namespace, so the same classes can share one node or have one node each.

Nodes, under ``/VEH/`` (see spec/duckiebot-interface.md):

=========================== =====================================================================
wheels_driver_node          sub ``~wheels_cmd``, ``~emergency_stop``; pub ``~wheels_cmd_executed``
left_wheel_encoder_node     pub ``~tick`` (30 Hz); the right one likewise
kinematics_node             sub ``car_cmd_switch_node/cmd``; pub ``wheels_driver_node/wheels_cmd``,
                            ``~velocity``; params ``~radius ~baseline ~gain ~trim ~k ~limit
                            ~v_max ~omega_max``
car_cmd_switch_node         sub ``joy_mapper_node/car_cmd`` (joystick mode); pub ``~cmd``
led_emitter_node            srv ``~set_pattern``, ``~set_custom_pattern``; pub ``~led_pattern``
camera_node                 pub ``~image/compressed`` (30 Hz, rendered only when subscribed)
simulator_node              pub ``~ground_truth_pose`` (simulator only: no robot has it)
=========================== =====================================================================
"""

from __future__ import annotations

from typing import Any, ClassVar, Dict, Optional, Sequence, Tuple

from duckielib import leds as led_tables
from duckielib.config import RobotConfig
from duckielib.errors import ConfigError, SimulationError
from duckielib.ros.backend import message_classes
from duckielib.rostime import NS_PER_S
from duckielib.sim.encoders import EncoderReading
from duckielib.sim.simulator import Simulator

__all__ = [
    "CameraNode",
    "CarCmdSwitchNode",
    "GroundTruthNode",
    "KinematicsNode",
    "LEDEmitterNode",
    "WheelEncoderNode",
    "WheelsDriverNode",
]

_KINEMATICS_PARAMS = ("radius", "baseline", "gain", "trim", "k", "limit", "v_max", "omega_max")


def stamp_at(rospy: Any, t_ns: int) -> Any:
    """A ``rospy.Time`` for ``t_ns`` integer nanoseconds (exact, no float rounding)."""
    return rospy.Time(t_ns // NS_PER_S, t_ns % NS_PER_S)


class WheelsDriverNode:
    """The motor driver: executes duty cycles unless the emergency stop is on.

    Subscribers:
        ~wheels_cmd (WheelsCmdStamped): duty cycles in [-1, 1] (clipped).
        ~emergency_stop (BoolStamped): True stops the wheels and ignores commands until False.

    Publishers:
        ~wheels_cmd_executed (WheelsCmdStamped): what the motors were given (zeros under e-stop).

    The wheels stop when the node shuts down.
    """

    def __init__(self, rospy: Any, sim: Simulator, veh: str) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.sim = sim
        self.estop = False
        base = veh + "wheels_driver_node/"
        self.pub_executed = rospy.Publisher(
            base + "wheels_cmd_executed", self.msg.WheelsCmdStamped, queue_size=1
        )
        self.executed = self.msg.WheelsCmdStamped()  # refilled for each command
        self.sub_cmd = rospy.Subscriber(
            base + "wheels_cmd", self.msg.WheelsCmdStamped, self.on_wheels_cmd, queue_size=1
        )
        self.sub_estop = rospy.Subscriber(
            base + "emergency_stop", self.msg.BoolStamped, self.on_emergency_stop, queue_size=1
        )
        rospy.on_shutdown(self.on_shutdown)

    def on_wheels_cmd(self, msg: Any) -> None:
        """Execute a command (zeros while the emergency stop is on) and report it."""
        left, right = (0.0, 0.0) if self.estop else (msg.vel_left, msg.vel_right)
        try:
            left, right = self.sim.set_wheel_duties(left, right)
        except SimulationError as error:
            self.rospy.logerr(f"Ignored a wheels command: {error}")
            return
        executed = self.executed
        executed.vel_left, executed.vel_right = left, right
        executed.header.frame_id = msg.header.frame_id
        executed.header.stamp = self.rospy.Time.now()
        self.pub_executed.publish(executed)

    def on_emergency_stop(self, msg: Any) -> None:
        """Engage or release the emergency stop."""
        self.estop = bool(msg.data)
        if self.estop:
            self.sim.set_wheel_duties(0.0, 0.0)
            self.rospy.loginfo("Emergency stop activated: the wheels ignore commands.")
        else:
            self.rospy.loginfo("Emergency stop released.")

    def on_shutdown(self) -> None:
        """Stop the motors."""
        self.sim.set_wheel_duties(0.0, 0.0)


class WheelEncoderNode:
    """One wheel's encoder: cumulative signed ticks, 135 per revolution, about 30 Hz.

    Publishers:
        ~tick (WheelEncoderStamped): ``data`` the count, ``resolution`` 135, ``type`` 1
            (incremental); the stamp is the sample's time. The two wheels' streams are not
            synchronised.

    Parameters:
        ~resolution, ~publish_frequency: read-only facts of the encoder, set for reference.
    """

    def __init__(self, rospy: Any, sim: Simulator, veh: str, wheel: str) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.wheel = wheel
        base = f"{veh}{wheel}_wheel_encoder_node/"
        rospy.set_param(base + "resolution", sim.config.resolution)
        rospy.set_param(base + "publish_frequency", sim.config.encoder_rate_hz)
        self.frame_id = f"{veh.strip('/')}/{wheel}_wheel_axis"
        self.resolution = sim.config.resolution
        self.pub_tick = rospy.Publisher(base + "tick", self.msg.WheelEncoderStamped, queue_size=1)
        # One message, refilled for each sample (publish() serializes it at once).
        self.tick = self.msg.WheelEncoderStamped(
            resolution=self.resolution, type=self.msg.WheelEncoderStamped.ENCODER_TYPE_INCREMENTAL
        )
        self.tick.header.frame_id = self.frame_id

    def publish(self, reading: EncoderReading) -> None:
        """Publish one encoder sample."""
        tick = self.tick
        tick.data = reading.ticks
        tick.header.stamp = stamp_at(self.rospy, round(reading.time * NS_PER_S))
        self.pub_tick.publish(tick)


class KinematicsNode:
    """The kinematics node: turns chassis commands (v, omega) into wheel duty cycles.

    Subscribers:
        car_cmd_switch_node/cmd (Twist2DStamped): v in m/s, omega in rad/s.

    Publishers:
        wheels_driver_node/wheels_cmd (WheelsCmdStamped): duty cycles.
        ~velocity (Twist2DStamped): the (v, omega) the clipped duty cycles give, open loop.

    Parameters (read at each command, so ``rosparam set`` takes effect at once):
        ~radius (m), ~baseline (m), ~gain, ~trim (negative steers right), ~k (rad/s per unit
        duty), ~limit (largest duty), ~v_max (m/s), ~omega_max (rad/s).
    """

    def __init__(
        self, rospy: Any, veh: str, config: RobotConfig, gain: Optional[float] = None
    ) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.base = veh + "kinematics_node/"
        params = config.kinematics_params()
        if gain is not None:
            params["gain"] = gain  # the robot's calibration file
        for name, value in params.items():
            if not rospy.has_param(self.base + name):
                rospy.set_param(self.base + name, value)
        self.pub_wheels = rospy.Publisher(
            veh + "wheels_driver_node/wheels_cmd", self.msg.WheelsCmdStamped, queue_size=1
        )
        self.pub_velocity = rospy.Publisher(
            self.base + "velocity", self.msg.Twist2DStamped, queue_size=1
        )
        self.sub_car_cmd = rospy.Subscriber(
            veh + "car_cmd_switch_node/cmd", self.msg.Twist2DStamped, self.on_car_cmd, queue_size=1
        )
        # The messages published, refilled for each command (publish() serializes at once).
        self.wheels = self.msg.WheelsCmdStamped()
        self.velocity = self.msg.Twist2DStamped()

    def _params(self) -> Tuple[float, ...]:
        """The eight parameters, read as one namespace for each command.

        Cached by rospy until a parameter changes, so a new trim reaches the next command.
        """
        values = self.rospy.get_param_cached(self.base[:-1])
        found = []
        for name in _KINEMATICS_PARAMS:
            value = values.get(name) if isinstance(values, dict) else None
            if value is None:
                raise ConfigError(f"Parameter {self.base + name} is not set.")
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ConfigError(f"Parameter {self.base + name} must be a number, not {value!r}.")
            found.append(float(value))
        return tuple(found)

    def on_car_cmd(self, msg: Any) -> None:
        """Command the wheels for (v, omega) and publish the resulting velocity."""
        try:
            radius, baseline, gain, trim, k, limit, v_max, omega_max = self._params()
        except (KeyError, ConfigError) as error:
            self.rospy.logerr(f"Ignored a car command: {error}")
            return
        v = min(max(msg.v, -v_max), v_max)
        omega = min(max(msg.omega, -omega_max), omega_max)
        # The robot's firmware, as Duckietown's kinematics node computes it.
        omega_r = (v + 0.5 * omega * baseline) / radius
        omega_l = (v - 0.5 * omega * baseline) / radius
        k_r_inv = (gain + trim) / k
        k_l_inv = (gain - trim) / k
        u_r = min(max(omega_r * k_r_inv, -limit), limit)
        u_l = min(max(omega_l * k_l_inv, -limit), limit)
        wheels = self.wheels
        wheels.vel_left, wheels.vel_right = u_l, u_r
        wheels.header = msg.header
        self.pub_wheels.publish(wheels)
        omega_r = u_r / k_r_inv if k_r_inv else 0.0
        omega_l = u_l / k_l_inv if k_l_inv else 0.0
        velocity = self.velocity
        velocity.v = radius * (omega_r + omega_l) / 2.0
        velocity.omega = radius * (omega_r - omega_l) / baseline
        velocity.header = msg.header
        self.pub_velocity.publish(velocity)


class CarCmdSwitchNode:
    """The car command switch, in joystick mode (the robot's default).

    Subscribers:
        joy_mapper_node/car_cmd (Twist2DStamped): the joystick's command.

    Publishers:
        ~cmd (Twist2DStamped): the command the kinematics node executes. Publishing on it
            directly also moves the robot.
    """

    def __init__(self, rospy: Any, veh: str) -> None:
        self.msg = message_classes(rospy)
        self.pub_cmd = rospy.Publisher(
            veh + "car_cmd_switch_node/cmd", self.msg.Twist2DStamped, queue_size=1
        )
        self.sub_joystick = rospy.Subscriber(
            veh + "joy_mapper_node/car_cmd",
            self.msg.Twist2DStamped,
            self.pub_cmd.publish,
            queue_size=1,
        )


class LEDEmitterNode:
    """The LED emitter: named and custom patterns on the five LEDs.

    Services:
        ~set_pattern (ChangePattern): a named pattern (``WHITE``, ``RED``, ``CAR_SIGNAL_A``...).
            An unknown name is logged as an error and ignored, as on the robot.
        ~set_custom_pattern (SetCustomLEDPattern): colours by name (one, or five by LED index),
            a frequency and a frequency mask. An invalid pattern is refused with an error.

    Publishers:
        ~led_pattern (LEDPattern, latched): what the LEDs show.

    Starts WHITE; turns the LEDs off when it shuts down.
    """

    def __init__(self, rospy: Any, sim: Simulator, veh: str) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.sim = sim
        base = veh + "led_emitter_node/"
        self.pub_pattern = rospy.Publisher(
            base + "led_pattern", self.msg.LEDPattern, queue_size=1, latch=True
        )
        self.srv_set_pattern = rospy.Service(
            base + "set_pattern", self.msg.ChangePattern, self.on_set_pattern
        )
        self.srv_set_custom_pattern = rospy.Service(
            base + "set_custom_pattern", self.msg.SetCustomLEDPattern, self.on_set_custom_pattern
        )
        self.show(led_tables.pattern_named(led_tables.START_PATTERN))
        rospy.on_shutdown(self.on_shutdown)

    def show(self, pattern: led_tables.Pattern) -> None:
        """Send ``pattern`` to the LEDs and publish it."""
        self.sim.show_led_pattern(pattern)
        colors = led_tables.pattern_colors(pattern)
        msg = self.msg.LEDPattern(
            color_list=[c if isinstance(c, str) else "custom" for c in pattern.color_list],
            rgb_vals=[self.msg.ColorRGBA(r=r, g=g, b=b, a=1.0) for r, g, b in colors],
            color_mask=[1] * led_tables.LED_COUNT,
            frequency=pattern.frequency,
            frequency_mask=list(pattern.frequency_mask),
        )
        msg.header.stamp = self.rospy.Time.now()
        self.pub_pattern.publish(msg)

    def on_set_pattern(self, request: Any) -> Any:
        """Show a named pattern; log and ignore an unknown name."""
        name = request.pattern_name.data.strip().strip("'\"")
        try:
            pattern = led_tables.pattern_named(name)
        except ConfigError as error:
            self.rospy.logerr(f"Pattern {name!r} ignored: {error}")
        else:
            self.show(pattern)
            self.rospy.loginfo(f"Pattern changed to {name}.")
        return self.msg.ChangePattern._response_class()

    def on_set_custom_pattern(self, request: Any) -> Any:
        """Show a custom pattern; refuse an invalid one with a ServiceException."""
        pattern_msg = request.pattern
        colors: Sequence[Any] = list(pattern_msg.color_list)
        if not colors:
            colors = [(c.r, c.g, c.b) for c in pattern_msg.rgb_vals]
        if len(colors) == 1:
            colors = colors[0]
        try:
            pattern = led_tables.custom_pattern(
                colors, pattern_msg.frequency, list(pattern_msg.frequency_mask)
            )
        except ConfigError as error:
            self.rospy.logerr(f"Custom pattern refused: {error}")
            raise self.rospy.ServiceException(str(error)) from None
        self.show(pattern)
        self.rospy.loginfo("Custom pattern set.")
        return self.msg.SetCustomLEDPattern._response_class()

    def on_shutdown(self) -> None:
        """Turn the LEDs off."""
        self.show(led_tables.pattern_named(led_tables.OFF_PATTERN))


class LEDDriverNode:
    """The LED driver: shows on the five LEDs each pattern sent on ``led_emitter_node/led_pattern``.

    On a Duckiebot the emitter publishes what the LEDs should show and the driver shows it, so
    a node that publishes an ``LEDPattern`` there (rather than calling the emitter's services)
    lights the LEDs too. A pattern the LEDs already show is left as it is (the emitter's own
    messages repeat what it has just set).

    Subscribers:
        led_emitter_node/led_pattern (LEDPattern): the pattern, by colour names and frequency
            or by ``rgb_vals`` (see :func:`duckielib.leds.pattern_of_message`).
    """

    def __init__(self, rospy: Any, sim: Simulator, veh: str) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.sim = sim
        self.sub_pattern = rospy.Subscriber(
            veh + "led_emitter_node/led_pattern", self.msg.LEDPattern, self.on_pattern
        )

    def on_pattern(self, msg: Any) -> None:
        """Show the message's pattern; log and ignore one the LEDs cannot show."""
        try:
            pattern = led_tables.pattern_of_message(
                list(msg.color_list),
                [(c.r, c.g, c.b) for c in msg.rgb_vals],
                msg.frequency,
                list(msg.frequency_mask),
            )
        except ConfigError as error:
            self.rospy.logwarn(f"LED pattern ignored: {error}")
            return
        shown = self.sim.led_pattern
        if (
            led_tables.pattern_colors(pattern) != led_tables.pattern_colors(shown)
            or pattern.frequency != shown.frequency
            or pattern.frequency_mask != shown.frequency_mask
        ):
            self.sim.show_led_pattern(pattern)


class CameraNode:
    """The camera: 640x480 JPEG frames at 30 Hz, rendered only while someone subscribes.

    Publishers:
        ~image/compressed (CompressedImage): ``format`` "jpeg", ``data`` the JPEG bytes.

    Parameters (set as the robot's camera driver sets them, for nodes that read them):
        ~framerate (30), ~res_w (640), ~res_h (480), ~exposure_mode ("sports"),
        ~allow_partial_fov (False).
    """

    #: The camera driver's parameters on a DB21 (daffy).
    PARAMETERS: ClassVar[Dict[str, Any]] = {
        "framerate": 30,
        "res_w": 640,
        "res_h": 480,
        "exposure_mode": "sports",
        "allow_partial_fov": False,
    }

    def __init__(self, rospy: Any, sim: Simulator, veh: str) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.sim = sim
        self.frame_id = veh.strip("/") + "/camera_optical_frame"
        for name, value in self.PARAMETERS.items():
            rospy.set_param(veh + "camera_node/" + name, value)
        self.pub_image = rospy.Publisher(
            veh + "camera_node/image/compressed", self.msg.CompressedImage, queue_size=1
        )

    def publish(self, t_ns: int) -> bool:
        """Publish the frame of time ``t_ns`` if anyone listens; return whether it did."""
        if self.pub_image.get_num_connections() == 0:
            return False
        msg = self.msg.CompressedImage(format="jpeg", data=self.sim.frame_jpeg())
        msg.header.stamp = stamp_at(self.rospy, t_ns)
        msg.header.frame_id = self.frame_id
        self.pub_image.publish(msg)
        return True


class GroundTruthNode:
    """Where the robot really is. Simulator only: a real Duckiebot has no such topic.

    Publishers:
        ~ground_truth_pose (Pose2DStamped): the true pose of the axle midpoint in the world
            frame (x, y in metres, theta in radians in [0, 2*pi)), 30 Hz.
        ~wall_contact (std_msgs/Bool, latched): whether the chassis touches one of the mat's
            walls: published with the first pose, then each time it changes (checked at the
            pose's rate).
    """

    def __init__(self, rospy: Any, sim: Simulator, veh: str) -> None:
        self.msg = message_classes(rospy)
        self.rospy = rospy
        self.sim = sim
        self.pub_pose = rospy.Publisher(
            veh + "simulator_node/ground_truth_pose", self.msg.Pose2DStamped, queue_size=1
        )
        self.pose = self.msg.Pose2DStamped()  # refilled for each publication
        self.pose.header.frame_id = "world"
        self.pub_contact = rospy.Publisher(
            veh + "simulator_node/wall_contact", self.msg.Bool, queue_size=1, latch=True
        )
        self.touching: Optional[bool] = None  # none published yet

    def publish(self, t_ns: int) -> None:
        """Publish the true pose at time ``t_ns``, and the wall contact if it changed."""
        pose = self.pose
        pose.x, pose.y, pose.theta = self.sim.pose
        pose.header.stamp = stamp_at(self.rospy, t_ns)
        self.pub_pose.publish(pose)
        touching = self.sim.touching_wall
        if touching != self.touching:
            self.touching = touching
            self.pub_contact.publish(self.msg.Bool(data=touching))
