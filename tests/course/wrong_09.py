"""Deliberately wrong solutions of notebook 09_mission, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it. Each mistake is the reference node with one
thing wrong, so it fails for that mistake alone: the test drives the mission and checks the
states and colours, the stops, 'done', where the square and the return end, and the circle's
direction.
"""

WRONG = {
    "mission_node": {
        "LED colours never set (no call to the light service)": '''import math

import rospy
from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import Empty, String

from duckielib.missions import Arc, ReturnToStart, Rotate, Stop, Straight

CONTROL_HZ = 20.0  # how often the control loops read the pose and send a command, Hz
SPEED = 0.2  # top speed on straight legs, m/s
ARC_SPEED = 0.15  # speed along arcs, m/s
TURN_RATE = 2.0  # fastest turn on the spot, rad/s
HEADING_TOLERANCE = math.radians(1.0)  # close enough to a goal heading, rad
MIN_SPEED = 0.06  # slower and a realistic robot's wheels may not turn at all, m/s
SETTLE_S = 0.3  # standing still after each move, so the wheels come to rest, s
MOVE_TIME_LIMIT = 30.0  # a turn that takes longer than this gives up, s


def mission_node(mission):
    """A node that carries out a mission state by state, each state shown by its LED colour.

    Run it in the robot's namespace next to the odometry node and the light service node
    (``run_mission`` starts all three). It returns when the mission is over.

    Args:
        mission: the ``Mission`` to carry out (``duckielib.missions``): ``mission.states`` in
            order, each with a ``name``, an LED ``color`` and its ``moves`` (``Stop``,
            ``Rotate``, ``Straight``, ``Arc``, ``ReturnToStart``), and ``mission.start``, the
            start pose (x, y, theta) in the world frame, in metres and radians.

    Subscribers:
        odometry_node/pose (duckietown_msgs/Pose2DStamped): the robot's pose in the world
            frame, by your odometry; the node waits for the first one before it starts.

    Publishers:
        car_cmd_switch_node/cmd (duckietown_msgs/Twist2DStamped): the driving commands, v in
            m/s and omega in rad/s; (0, 0) during stops, between moves and at the end.
        ~state (std_msgs/String, latched): each state's name when the state starts (after its
            colour is set), and ``"done"`` once the last state is over.
        shutdown (std_msgs/Empty): one message at the very end, so the light service ends.

    Services called:
        light_service_node/set_color (duckietown_msgs/ChangePattern): the state's colour
            (``state.color``) at the start of each state.

    Returns:
        None, once the mission is over and the shutdown message is sent.
    """
    rospy.init_node("mission_node")
    pose = []  # the latest odometry pose [x, y, theta]; empty until the first one arrives

    def on_pose(msg):
        pose[:] = [msg.x, msg.y, msg.theta]

    rospy.Subscriber("odometry_node/pose", Pose2DStamped, on_pose, queue_size=1)
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    rate = rospy.Rate(CONTROL_HZ)
    dt = 1.0 / CONTROL_HZ

    def drive(v, omega):
        commands.publish(Twist2DStamped(v=v, omega=omega))

    rospy.on_shutdown(lambda: drive(0.0, 0.0))  # however the node ends, the wheels stop
    while not pose and not rospy.is_shutdown():
        rate.sleep()

    def settle():
        # The encoders count by the sign of the last command: let the wheels come to rest
        # before the next move, or their last turns are counted the wrong way.
        drive(0.0, 0.0)
        rospy.sleep(SETTLE_S)

    def turn_to(heading):
        pid = PID(kp=2.5, ki=0.5, kd=0.0, limit=TURN_RATE)
        close = still = 0  # control steps in a row near the goal, and without turning
        last = pose[2]
        deadline = rospy.get_time() + MOVE_TIME_LIMIT
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            error = angle_error(heading, pose[2])
            close = close + 1 if abs(error) < HEADING_TOLERANCE else 0
            # Near the goal a weak command may not turn the wheels at all (the motors' dead
            # zone): stopped within a few tolerances is as good as it gets.
            still = still + 1 if abs(angle_error(pose[2], last)) < 1e-3 else 0
            last = pose[2]
            if close >= 5 or (still >= 10 and abs(error) < 3 * HEADING_TOLERANCE):
                break
            drive(0.0, pid.update(error, dt))
            rate.sleep()
        settle()

    def bearing_to(point):
        return math.atan2(point[1] - pose[1], point[0] - pose[0])

    def go_to(point):
        if math.hypot(point[0] - pose[0], point[1] - pose[1]) > 0.02:
            turn_to(bearing_to(point))  # face the point first
        while not rospy.is_shutdown():
            distance = math.hypot(point[0] - pose[0], point[1] - pose[1])
            # Arrived, or just passed it (the point is behind): driving on would only overshoot.
            if distance < 0.005 or abs(angle_error(bearing_to(point), pose[2])) > math.pi / 2:
                break
            v, omega = go_to_point(pose, point, SPEED, 3.0)
            if distance < 0.05:
                omega = 0.0  # close to the point its bearing swings wildly: stop steering
            drive(max(v, MIN_SPEED), omega)
            rate.sleep()
        settle()

    def arc(radius, angle):
        tracker = AngleTracker(pose[2])
        sign = 1.0 if angle > 0 else -1.0  # +1: curve left (counter-clockwise), -1: right
        while not rospy.is_shutdown():
            left = abs(angle) - sign * tracker.update(pose[2])  # radians still to turn
            if left <= 0.0:
                break
            v = ARC_SPEED * min(1.0, max(0.2, left / 0.3))  # slow down over the last 0.3 rad
            drive(v, sign * v / radius)
            rate.sleep()
        settle()

    goal = tuple(mission.start)  # the planned pose: where the last move should have ended
    started = rospy.get_time()
    for state in mission.states:
        announce.publish(String(data=state.name))
        rospy.loginfo(f"state {state.name} ({state.color})")
        for move in state.moves:
            x, y, theta = goal
            if isinstance(move, Stop):
                drive(0.0, 0.0)
                rospy.sleep(move.seconds)
            elif isinstance(move, Rotate):
                goal = (x, y, (theta + move.angle) % (2 * math.pi))
                turn_to(goal[2])
            elif isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
                go_to(goal)
            elif isinstance(move, Arc):
                sign = 1.0 if move.angle > 0 else -1.0
                cx = x - sign * move.radius * math.sin(theta)  # the circle's centre
                cy = y + sign * move.radius * math.cos(theta)
                end = (theta + move.angle) % (2 * math.pi)
                goal = (
                    cx + sign * move.radius * math.sin(end),
                    cy - sign * move.radius * math.cos(end),
                    end,
                )
                arc(move.radius, move.angle)
            elif isinstance(move, ReturnToStart):
                goal = tuple(mission.start)
                go_to(goal)
                turn_to(goal[2])
    drive(0.0, 0.0)
    announce.publish(String(data="done"))
    elapsed = rospy.get_time() - started
    x, y, theta = pose
    rospy.loginfo(
        f"mission {mission.name} done in {elapsed:.1f} s; final pose by odometry: "
        f"x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad"
    )
    shutdown.publish(Empty())
''',
        "every stop lasts 1 s instead of the state's time": '''import math

import rospy
from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import Empty, String

from duckielib.missions import Arc, ReturnToStart, Rotate, Stop, Straight

CONTROL_HZ = 20.0  # how often the control loops read the pose and send a command, Hz
SPEED = 0.2  # top speed on straight legs, m/s
ARC_SPEED = 0.15  # speed along arcs, m/s
TURN_RATE = 2.0  # fastest turn on the spot, rad/s
HEADING_TOLERANCE = math.radians(1.0)  # close enough to a goal heading, rad
MIN_SPEED = 0.06  # slower and a realistic robot's wheels may not turn at all, m/s
SETTLE_S = 0.3  # standing still after each move, so the wheels come to rest, s
MOVE_TIME_LIMIT = 30.0  # a turn that takes longer than this gives up, s


def mission_node(mission):
    """A node that carries out a mission state by state, each state shown by its LED colour.

    Run it in the robot's namespace next to the odometry node and the light service node
    (``run_mission`` starts all three). It returns when the mission is over.

    Args:
        mission: the ``Mission`` to carry out (``duckielib.missions``): ``mission.states`` in
            order, each with a ``name``, an LED ``color`` and its ``moves`` (``Stop``,
            ``Rotate``, ``Straight``, ``Arc``, ``ReturnToStart``), and ``mission.start``, the
            start pose (x, y, theta) in the world frame, in metres and radians.

    Subscribers:
        odometry_node/pose (duckietown_msgs/Pose2DStamped): the robot's pose in the world
            frame, by your odometry; the node waits for the first one before it starts.

    Publishers:
        car_cmd_switch_node/cmd (duckietown_msgs/Twist2DStamped): the driving commands, v in
            m/s and omega in rad/s; (0, 0) during stops, between moves and at the end.
        ~state (std_msgs/String, latched): each state's name when the state starts (after its
            colour is set), and ``"done"`` once the last state is over.
        shutdown (std_msgs/Empty): one message at the very end, so the light service ends.

    Services called:
        light_service_node/set_color (duckietown_msgs/ChangePattern): the state's colour
            (``state.color``) at the start of each state.

    Returns:
        None, once the mission is over and the shutdown message is sent.
    """
    rospy.init_node("mission_node")
    pose = []  # the latest odometry pose [x, y, theta]; empty until the first one arrives

    def on_pose(msg):
        pose[:] = [msg.x, msg.y, msg.theta]

    rospy.Subscriber("odometry_node/pose", Pose2DStamped, on_pose, queue_size=1)
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    rate = rospy.Rate(CONTROL_HZ)
    dt = 1.0 / CONTROL_HZ

    def drive(v, omega):
        commands.publish(Twist2DStamped(v=v, omega=omega))

    rospy.on_shutdown(lambda: drive(0.0, 0.0))  # however the node ends, the wheels stop
    while not pose and not rospy.is_shutdown():
        rate.sleep()

    def settle():
        # The encoders count by the sign of the last command: let the wheels come to rest
        # before the next move, or their last turns are counted the wrong way.
        drive(0.0, 0.0)
        rospy.sleep(SETTLE_S)

    def turn_to(heading):
        pid = PID(kp=2.5, ki=0.5, kd=0.0, limit=TURN_RATE)
        close = still = 0  # control steps in a row near the goal, and without turning
        last = pose[2]
        deadline = rospy.get_time() + MOVE_TIME_LIMIT
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            error = angle_error(heading, pose[2])
            close = close + 1 if abs(error) < HEADING_TOLERANCE else 0
            # Near the goal a weak command may not turn the wheels at all (the motors' dead
            # zone): stopped within a few tolerances is as good as it gets.
            still = still + 1 if abs(angle_error(pose[2], last)) < 1e-3 else 0
            last = pose[2]
            if close >= 5 or (still >= 10 and abs(error) < 3 * HEADING_TOLERANCE):
                break
            drive(0.0, pid.update(error, dt))
            rate.sleep()
        settle()

    def bearing_to(point):
        return math.atan2(point[1] - pose[1], point[0] - pose[0])

    def go_to(point):
        if math.hypot(point[0] - pose[0], point[1] - pose[1]) > 0.02:
            turn_to(bearing_to(point))  # face the point first
        while not rospy.is_shutdown():
            distance = math.hypot(point[0] - pose[0], point[1] - pose[1])
            # Arrived, or just passed it (the point is behind): driving on would only overshoot.
            if distance < 0.005 or abs(angle_error(bearing_to(point), pose[2])) > math.pi / 2:
                break
            v, omega = go_to_point(pose, point, SPEED, 3.0)
            if distance < 0.05:
                omega = 0.0  # close to the point its bearing swings wildly: stop steering
            drive(max(v, MIN_SPEED), omega)
            rate.sleep()
        settle()

    def arc(radius, angle):
        tracker = AngleTracker(pose[2])
        sign = 1.0 if angle > 0 else -1.0  # +1: curve left (counter-clockwise), -1: right
        while not rospy.is_shutdown():
            left = abs(angle) - sign * tracker.update(pose[2])  # radians still to turn
            if left <= 0.0:
                break
            v = ARC_SPEED * min(1.0, max(0.2, left / 0.3))  # slow down over the last 0.3 rad
            drive(v, sign * v / radius)
            rate.sleep()
        settle()

    goal = tuple(mission.start)  # the planned pose: where the last move should have ended
    started = rospy.get_time()
    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        rospy.loginfo(f"state {state.name} ({state.color})")
        for move in state.moves:
            x, y, theta = goal
            if isinstance(move, Stop):
                drive(0.0, 0.0)
                rospy.sleep(1.0)
            elif isinstance(move, Rotate):
                goal = (x, y, (theta + move.angle) % (2 * math.pi))
                turn_to(goal[2])
            elif isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
                go_to(goal)
            elif isinstance(move, Arc):
                sign = 1.0 if move.angle > 0 else -1.0
                cx = x - sign * move.radius * math.sin(theta)  # the circle's centre
                cy = y + sign * move.radius * math.cos(theta)
                end = (theta + move.angle) % (2 * math.pi)
                goal = (
                    cx + sign * move.radius * math.sin(end),
                    cy - sign * move.radius * math.cos(end),
                    end,
                )
                arc(move.radius, move.angle)
            elif isinstance(move, ReturnToStart):
                goal = tuple(mission.start)
                go_to(goal)
                turn_to(goal[2])
    drive(0.0, 0.0)
    announce.publish(String(data="done"))
    elapsed = rospy.get_time() - started
    x, y, theta = pose
    rospy.loginfo(
        f"mission {mission.name} done in {elapsed:.1f} s; final pose by odometry: "
        f"x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad"
    )
    shutdown.publish(Empty())
''',
        "Rotate moves ignored": '''import math

import rospy
from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import Empty, String

from duckielib.missions import Arc, ReturnToStart, Rotate, Stop, Straight

CONTROL_HZ = 20.0  # how often the control loops read the pose and send a command, Hz
SPEED = 0.2  # top speed on straight legs, m/s
ARC_SPEED = 0.15  # speed along arcs, m/s
TURN_RATE = 2.0  # fastest turn on the spot, rad/s
HEADING_TOLERANCE = math.radians(1.0)  # close enough to a goal heading, rad
MIN_SPEED = 0.06  # slower and a realistic robot's wheels may not turn at all, m/s
SETTLE_S = 0.3  # standing still after each move, so the wheels come to rest, s
MOVE_TIME_LIMIT = 30.0  # a turn that takes longer than this gives up, s


def mission_node(mission):
    """A node that carries out a mission state by state, each state shown by its LED colour.

    Run it in the robot's namespace next to the odometry node and the light service node
    (``run_mission`` starts all three). It returns when the mission is over.

    Args:
        mission: the ``Mission`` to carry out (``duckielib.missions``): ``mission.states`` in
            order, each with a ``name``, an LED ``color`` and its ``moves`` (``Stop``,
            ``Rotate``, ``Straight``, ``Arc``, ``ReturnToStart``), and ``mission.start``, the
            start pose (x, y, theta) in the world frame, in metres and radians.

    Subscribers:
        odometry_node/pose (duckietown_msgs/Pose2DStamped): the robot's pose in the world
            frame, by your odometry; the node waits for the first one before it starts.

    Publishers:
        car_cmd_switch_node/cmd (duckietown_msgs/Twist2DStamped): the driving commands, v in
            m/s and omega in rad/s; (0, 0) during stops, between moves and at the end.
        ~state (std_msgs/String, latched): each state's name when the state starts (after its
            colour is set), and ``"done"`` once the last state is over.
        shutdown (std_msgs/Empty): one message at the very end, so the light service ends.

    Services called:
        light_service_node/set_color (duckietown_msgs/ChangePattern): the state's colour
            (``state.color``) at the start of each state.

    Returns:
        None, once the mission is over and the shutdown message is sent.
    """
    rospy.init_node("mission_node")
    pose = []  # the latest odometry pose [x, y, theta]; empty until the first one arrives

    def on_pose(msg):
        pose[:] = [msg.x, msg.y, msg.theta]

    rospy.Subscriber("odometry_node/pose", Pose2DStamped, on_pose, queue_size=1)
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    rate = rospy.Rate(CONTROL_HZ)
    dt = 1.0 / CONTROL_HZ

    def drive(v, omega):
        commands.publish(Twist2DStamped(v=v, omega=omega))

    rospy.on_shutdown(lambda: drive(0.0, 0.0))  # however the node ends, the wheels stop
    while not pose and not rospy.is_shutdown():
        rate.sleep()

    def settle():
        # The encoders count by the sign of the last command: let the wheels come to rest
        # before the next move, or their last turns are counted the wrong way.
        drive(0.0, 0.0)
        rospy.sleep(SETTLE_S)

    def turn_to(heading):
        pid = PID(kp=2.5, ki=0.5, kd=0.0, limit=TURN_RATE)
        close = still = 0  # control steps in a row near the goal, and without turning
        last = pose[2]
        deadline = rospy.get_time() + MOVE_TIME_LIMIT
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            error = angle_error(heading, pose[2])
            close = close + 1 if abs(error) < HEADING_TOLERANCE else 0
            # Near the goal a weak command may not turn the wheels at all (the motors' dead
            # zone): stopped within a few tolerances is as good as it gets.
            still = still + 1 if abs(angle_error(pose[2], last)) < 1e-3 else 0
            last = pose[2]
            if close >= 5 or (still >= 10 and abs(error) < 3 * HEADING_TOLERANCE):
                break
            drive(0.0, pid.update(error, dt))
            rate.sleep()
        settle()

    def bearing_to(point):
        return math.atan2(point[1] - pose[1], point[0] - pose[0])

    def go_to(point):
        if math.hypot(point[0] - pose[0], point[1] - pose[1]) > 0.02:
            turn_to(bearing_to(point))  # face the point first
        while not rospy.is_shutdown():
            distance = math.hypot(point[0] - pose[0], point[1] - pose[1])
            # Arrived, or just passed it (the point is behind): driving on would only overshoot.
            if distance < 0.005 or abs(angle_error(bearing_to(point), pose[2])) > math.pi / 2:
                break
            v, omega = go_to_point(pose, point, SPEED, 3.0)
            if distance < 0.05:
                omega = 0.0  # close to the point its bearing swings wildly: stop steering
            drive(max(v, MIN_SPEED), omega)
            rate.sleep()
        settle()

    def arc(radius, angle):
        tracker = AngleTracker(pose[2])
        sign = 1.0 if angle > 0 else -1.0  # +1: curve left (counter-clockwise), -1: right
        while not rospy.is_shutdown():
            left = abs(angle) - sign * tracker.update(pose[2])  # radians still to turn
            if left <= 0.0:
                break
            v = ARC_SPEED * min(1.0, max(0.2, left / 0.3))  # slow down over the last 0.3 rad
            drive(v, sign * v / radius)
            rate.sleep()
        settle()

    goal = tuple(mission.start)  # the planned pose: where the last move should have ended
    started = rospy.get_time()
    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        rospy.loginfo(f"state {state.name} ({state.color})")
        for move in state.moves:
            x, y, theta = goal
            if isinstance(move, Stop):
                drive(0.0, 0.0)
                rospy.sleep(move.seconds)
            elif isinstance(move, Rotate):
                pass
            elif isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
                go_to(goal)
            elif isinstance(move, Arc):
                sign = 1.0 if move.angle > 0 else -1.0
                cx = x - sign * move.radius * math.sin(theta)  # the circle's centre
                cy = y + sign * move.radius * math.cos(theta)
                end = (theta + move.angle) % (2 * math.pi)
                goal = (
                    cx + sign * move.radius * math.sin(end),
                    cy - sign * move.radius * math.cos(end),
                    end,
                )
                arc(move.radius, move.angle)
            elif isinstance(move, ReturnToStart):
                goal = tuple(mission.start)
                go_to(goal)
                turn_to(goal[2])
    drive(0.0, 0.0)
    announce.publish(String(data="done"))
    elapsed = rospy.get_time() - started
    x, y, theta = pose
    rospy.loginfo(
        f"mission {mission.name} done in {elapsed:.1f} s; final pose by odometry: "
        f"x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad"
    )
    shutdown.publish(Empty())
''',
        "ReturnToStart does nothing": '''import math

import rospy
from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import Empty, String

from duckielib.missions import Arc, ReturnToStart, Rotate, Stop, Straight

CONTROL_HZ = 20.0  # how often the control loops read the pose and send a command, Hz
SPEED = 0.2  # top speed on straight legs, m/s
ARC_SPEED = 0.15  # speed along arcs, m/s
TURN_RATE = 2.0  # fastest turn on the spot, rad/s
HEADING_TOLERANCE = math.radians(1.0)  # close enough to a goal heading, rad
MIN_SPEED = 0.06  # slower and a realistic robot's wheels may not turn at all, m/s
SETTLE_S = 0.3  # standing still after each move, so the wheels come to rest, s
MOVE_TIME_LIMIT = 30.0  # a turn that takes longer than this gives up, s


def mission_node(mission):
    """A node that carries out a mission state by state, each state shown by its LED colour.

    Run it in the robot's namespace next to the odometry node and the light service node
    (``run_mission`` starts all three). It returns when the mission is over.

    Args:
        mission: the ``Mission`` to carry out (``duckielib.missions``): ``mission.states`` in
            order, each with a ``name``, an LED ``color`` and its ``moves`` (``Stop``,
            ``Rotate``, ``Straight``, ``Arc``, ``ReturnToStart``), and ``mission.start``, the
            start pose (x, y, theta) in the world frame, in metres and radians.

    Subscribers:
        odometry_node/pose (duckietown_msgs/Pose2DStamped): the robot's pose in the world
            frame, by your odometry; the node waits for the first one before it starts.

    Publishers:
        car_cmd_switch_node/cmd (duckietown_msgs/Twist2DStamped): the driving commands, v in
            m/s and omega in rad/s; (0, 0) during stops, between moves and at the end.
        ~state (std_msgs/String, latched): each state's name when the state starts (after its
            colour is set), and ``"done"`` once the last state is over.
        shutdown (std_msgs/Empty): one message at the very end, so the light service ends.

    Services called:
        light_service_node/set_color (duckietown_msgs/ChangePattern): the state's colour
            (``state.color``) at the start of each state.

    Returns:
        None, once the mission is over and the shutdown message is sent.
    """
    rospy.init_node("mission_node")
    pose = []  # the latest odometry pose [x, y, theta]; empty until the first one arrives

    def on_pose(msg):
        pose[:] = [msg.x, msg.y, msg.theta]

    rospy.Subscriber("odometry_node/pose", Pose2DStamped, on_pose, queue_size=1)
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    rate = rospy.Rate(CONTROL_HZ)
    dt = 1.0 / CONTROL_HZ

    def drive(v, omega):
        commands.publish(Twist2DStamped(v=v, omega=omega))

    rospy.on_shutdown(lambda: drive(0.0, 0.0))  # however the node ends, the wheels stop
    while not pose and not rospy.is_shutdown():
        rate.sleep()

    def settle():
        # The encoders count by the sign of the last command: let the wheels come to rest
        # before the next move, or their last turns are counted the wrong way.
        drive(0.0, 0.0)
        rospy.sleep(SETTLE_S)

    def turn_to(heading):
        pid = PID(kp=2.5, ki=0.5, kd=0.0, limit=TURN_RATE)
        close = still = 0  # control steps in a row near the goal, and without turning
        last = pose[2]
        deadline = rospy.get_time() + MOVE_TIME_LIMIT
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            error = angle_error(heading, pose[2])
            close = close + 1 if abs(error) < HEADING_TOLERANCE else 0
            # Near the goal a weak command may not turn the wheels at all (the motors' dead
            # zone): stopped within a few tolerances is as good as it gets.
            still = still + 1 if abs(angle_error(pose[2], last)) < 1e-3 else 0
            last = pose[2]
            if close >= 5 or (still >= 10 and abs(error) < 3 * HEADING_TOLERANCE):
                break
            drive(0.0, pid.update(error, dt))
            rate.sleep()
        settle()

    def bearing_to(point):
        return math.atan2(point[1] - pose[1], point[0] - pose[0])

    def go_to(point):
        if math.hypot(point[0] - pose[0], point[1] - pose[1]) > 0.02:
            turn_to(bearing_to(point))  # face the point first
        while not rospy.is_shutdown():
            distance = math.hypot(point[0] - pose[0], point[1] - pose[1])
            # Arrived, or just passed it (the point is behind): driving on would only overshoot.
            if distance < 0.005 or abs(angle_error(bearing_to(point), pose[2])) > math.pi / 2:
                break
            v, omega = go_to_point(pose, point, SPEED, 3.0)
            if distance < 0.05:
                omega = 0.0  # close to the point its bearing swings wildly: stop steering
            drive(max(v, MIN_SPEED), omega)
            rate.sleep()
        settle()

    def arc(radius, angle):
        tracker = AngleTracker(pose[2])
        sign = 1.0 if angle > 0 else -1.0  # +1: curve left (counter-clockwise), -1: right
        while not rospy.is_shutdown():
            left = abs(angle) - sign * tracker.update(pose[2])  # radians still to turn
            if left <= 0.0:
                break
            v = ARC_SPEED * min(1.0, max(0.2, left / 0.3))  # slow down over the last 0.3 rad
            drive(v, sign * v / radius)
            rate.sleep()
        settle()

    goal = tuple(mission.start)  # the planned pose: where the last move should have ended
    started = rospy.get_time()
    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        rospy.loginfo(f"state {state.name} ({state.color})")
        for move in state.moves:
            x, y, theta = goal
            if isinstance(move, Stop):
                drive(0.0, 0.0)
                rospy.sleep(move.seconds)
            elif isinstance(move, Rotate):
                goal = (x, y, (theta + move.angle) % (2 * math.pi))
                turn_to(goal[2])
            elif isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
                go_to(goal)
            elif isinstance(move, Arc):
                sign = 1.0 if move.angle > 0 else -1.0
                cx = x - sign * move.radius * math.sin(theta)  # the circle's centre
                cy = y + sign * move.radius * math.cos(theta)
                end = (theta + move.angle) % (2 * math.pi)
                goal = (
                    cx + sign * move.radius * math.sin(end),
                    cy - sign * move.radius * math.cos(end),
                    end,
                )
                arc(move.radius, move.angle)
            elif isinstance(move, ReturnToStart):
                pass
    drive(0.0, 0.0)
    announce.publish(String(data="done"))
    elapsed = rospy.get_time() - started
    x, y, theta = pose
    rospy.loginfo(
        f"mission {mission.name} done in {elapsed:.1f} s; final pose by odometry: "
        f"x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad"
    )
    shutdown.publish(Empty())
''',
        "never publishes 'done'": '''import math

import rospy
from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import Empty, String

from duckielib.missions import Arc, ReturnToStart, Rotate, Stop, Straight

CONTROL_HZ = 20.0  # how often the control loops read the pose and send a command, Hz
SPEED = 0.2  # top speed on straight legs, m/s
ARC_SPEED = 0.15  # speed along arcs, m/s
TURN_RATE = 2.0  # fastest turn on the spot, rad/s
HEADING_TOLERANCE = math.radians(1.0)  # close enough to a goal heading, rad
MIN_SPEED = 0.06  # slower and a realistic robot's wheels may not turn at all, m/s
SETTLE_S = 0.3  # standing still after each move, so the wheels come to rest, s
MOVE_TIME_LIMIT = 30.0  # a turn that takes longer than this gives up, s


def mission_node(mission):
    """A node that carries out a mission state by state, each state shown by its LED colour.

    Run it in the robot's namespace next to the odometry node and the light service node
    (``run_mission`` starts all three). It returns when the mission is over.

    Args:
        mission: the ``Mission`` to carry out (``duckielib.missions``): ``mission.states`` in
            order, each with a ``name``, an LED ``color`` and its ``moves`` (``Stop``,
            ``Rotate``, ``Straight``, ``Arc``, ``ReturnToStart``), and ``mission.start``, the
            start pose (x, y, theta) in the world frame, in metres and radians.

    Subscribers:
        odometry_node/pose (duckietown_msgs/Pose2DStamped): the robot's pose in the world
            frame, by your odometry; the node waits for the first one before it starts.

    Publishers:
        car_cmd_switch_node/cmd (duckietown_msgs/Twist2DStamped): the driving commands, v in
            m/s and omega in rad/s; (0, 0) during stops, between moves and at the end.
        ~state (std_msgs/String, latched): each state's name when the state starts (after its
            colour is set), and ``"done"`` once the last state is over.
        shutdown (std_msgs/Empty): one message at the very end, so the light service ends.

    Services called:
        light_service_node/set_color (duckietown_msgs/ChangePattern): the state's colour
            (``state.color``) at the start of each state.

    Returns:
        None, once the mission is over and the shutdown message is sent.
    """
    rospy.init_node("mission_node")
    pose = []  # the latest odometry pose [x, y, theta]; empty until the first one arrives

    def on_pose(msg):
        pose[:] = [msg.x, msg.y, msg.theta]

    rospy.Subscriber("odometry_node/pose", Pose2DStamped, on_pose, queue_size=1)
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    rate = rospy.Rate(CONTROL_HZ)
    dt = 1.0 / CONTROL_HZ

    def drive(v, omega):
        commands.publish(Twist2DStamped(v=v, omega=omega))

    rospy.on_shutdown(lambda: drive(0.0, 0.0))  # however the node ends, the wheels stop
    while not pose and not rospy.is_shutdown():
        rate.sleep()

    def settle():
        # The encoders count by the sign of the last command: let the wheels come to rest
        # before the next move, or their last turns are counted the wrong way.
        drive(0.0, 0.0)
        rospy.sleep(SETTLE_S)

    def turn_to(heading):
        pid = PID(kp=2.5, ki=0.5, kd=0.0, limit=TURN_RATE)
        close = still = 0  # control steps in a row near the goal, and without turning
        last = pose[2]
        deadline = rospy.get_time() + MOVE_TIME_LIMIT
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            error = angle_error(heading, pose[2])
            close = close + 1 if abs(error) < HEADING_TOLERANCE else 0
            # Near the goal a weak command may not turn the wheels at all (the motors' dead
            # zone): stopped within a few tolerances is as good as it gets.
            still = still + 1 if abs(angle_error(pose[2], last)) < 1e-3 else 0
            last = pose[2]
            if close >= 5 or (still >= 10 and abs(error) < 3 * HEADING_TOLERANCE):
                break
            drive(0.0, pid.update(error, dt))
            rate.sleep()
        settle()

    def bearing_to(point):
        return math.atan2(point[1] - pose[1], point[0] - pose[0])

    def go_to(point):
        if math.hypot(point[0] - pose[0], point[1] - pose[1]) > 0.02:
            turn_to(bearing_to(point))  # face the point first
        while not rospy.is_shutdown():
            distance = math.hypot(point[0] - pose[0], point[1] - pose[1])
            # Arrived, or just passed it (the point is behind): driving on would only overshoot.
            if distance < 0.005 or abs(angle_error(bearing_to(point), pose[2])) > math.pi / 2:
                break
            v, omega = go_to_point(pose, point, SPEED, 3.0)
            if distance < 0.05:
                omega = 0.0  # close to the point its bearing swings wildly: stop steering
            drive(max(v, MIN_SPEED), omega)
            rate.sleep()
        settle()

    def arc(radius, angle):
        tracker = AngleTracker(pose[2])
        sign = 1.0 if angle > 0 else -1.0  # +1: curve left (counter-clockwise), -1: right
        while not rospy.is_shutdown():
            left = abs(angle) - sign * tracker.update(pose[2])  # radians still to turn
            if left <= 0.0:
                break
            v = ARC_SPEED * min(1.0, max(0.2, left / 0.3))  # slow down over the last 0.3 rad
            drive(v, sign * v / radius)
            rate.sleep()
        settle()

    goal = tuple(mission.start)  # the planned pose: where the last move should have ended
    started = rospy.get_time()
    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        rospy.loginfo(f"state {state.name} ({state.color})")
        for move in state.moves:
            x, y, theta = goal
            if isinstance(move, Stop):
                drive(0.0, 0.0)
                rospy.sleep(move.seconds)
            elif isinstance(move, Rotate):
                goal = (x, y, (theta + move.angle) % (2 * math.pi))
                turn_to(goal[2])
            elif isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
                go_to(goal)
            elif isinstance(move, Arc):
                sign = 1.0 if move.angle > 0 else -1.0
                cx = x - sign * move.radius * math.sin(theta)  # the circle's centre
                cy = y + sign * move.radius * math.cos(theta)
                end = (theta + move.angle) % (2 * math.pi)
                goal = (
                    cx + sign * move.radius * math.sin(end),
                    cy - sign * move.radius * math.cos(end),
                    end,
                )
                arc(move.radius, move.angle)
            elif isinstance(move, ReturnToStart):
                goal = tuple(mission.start)
                go_to(goal)
                turn_to(goal[2])
    drive(0.0, 0.0)
    elapsed = rospy.get_time() - started
    x, y, theta = pose
    rospy.loginfo(
        f"mission {mission.name} done in {elapsed:.1f} s; final pose by odometry: "
        f"x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad"
    )
    shutdown.publish(Empty())
''',
        "arcs always counter-clockwise (the angle's sign ignored)": '''import math

import rospy
from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import Empty, String

from duckielib.missions import Arc, ReturnToStart, Rotate, Stop, Straight

CONTROL_HZ = 20.0  # how often the control loops read the pose and send a command, Hz
SPEED = 0.2  # top speed on straight legs, m/s
ARC_SPEED = 0.15  # speed along arcs, m/s
TURN_RATE = 2.0  # fastest turn on the spot, rad/s
HEADING_TOLERANCE = math.radians(1.0)  # close enough to a goal heading, rad
MIN_SPEED = 0.06  # slower and a realistic robot's wheels may not turn at all, m/s
SETTLE_S = 0.3  # standing still after each move, so the wheels come to rest, s
MOVE_TIME_LIMIT = 30.0  # a turn that takes longer than this gives up, s


def mission_node(mission):
    """A node that carries out a mission state by state, each state shown by its LED colour.

    Run it in the robot's namespace next to the odometry node and the light service node
    (``run_mission`` starts all three). It returns when the mission is over.

    Args:
        mission: the ``Mission`` to carry out (``duckielib.missions``): ``mission.states`` in
            order, each with a ``name``, an LED ``color`` and its ``moves`` (``Stop``,
            ``Rotate``, ``Straight``, ``Arc``, ``ReturnToStart``), and ``mission.start``, the
            start pose (x, y, theta) in the world frame, in metres and radians.

    Subscribers:
        odometry_node/pose (duckietown_msgs/Pose2DStamped): the robot's pose in the world
            frame, by your odometry; the node waits for the first one before it starts.

    Publishers:
        car_cmd_switch_node/cmd (duckietown_msgs/Twist2DStamped): the driving commands, v in
            m/s and omega in rad/s; (0, 0) during stops, between moves and at the end.
        ~state (std_msgs/String, latched): each state's name when the state starts (after its
            colour is set), and ``"done"`` once the last state is over.
        shutdown (std_msgs/Empty): one message at the very end, so the light service ends.

    Services called:
        light_service_node/set_color (duckietown_msgs/ChangePattern): the state's colour
            (``state.color``) at the start of each state.

    Returns:
        None, once the mission is over and the shutdown message is sent.
    """
    rospy.init_node("mission_node")
    pose = []  # the latest odometry pose [x, y, theta]; empty until the first one arrives

    def on_pose(msg):
        pose[:] = [msg.x, msg.y, msg.theta]

    rospy.Subscriber("odometry_node/pose", Pose2DStamped, on_pose, queue_size=1)
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    rate = rospy.Rate(CONTROL_HZ)
    dt = 1.0 / CONTROL_HZ

    def drive(v, omega):
        commands.publish(Twist2DStamped(v=v, omega=omega))

    rospy.on_shutdown(lambda: drive(0.0, 0.0))  # however the node ends, the wheels stop
    while not pose and not rospy.is_shutdown():
        rate.sleep()

    def settle():
        # The encoders count by the sign of the last command: let the wheels come to rest
        # before the next move, or their last turns are counted the wrong way.
        drive(0.0, 0.0)
        rospy.sleep(SETTLE_S)

    def turn_to(heading):
        pid = PID(kp=2.5, ki=0.5, kd=0.0, limit=TURN_RATE)
        close = still = 0  # control steps in a row near the goal, and without turning
        last = pose[2]
        deadline = rospy.get_time() + MOVE_TIME_LIMIT
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            error = angle_error(heading, pose[2])
            close = close + 1 if abs(error) < HEADING_TOLERANCE else 0
            # Near the goal a weak command may not turn the wheels at all (the motors' dead
            # zone): stopped within a few tolerances is as good as it gets.
            still = still + 1 if abs(angle_error(pose[2], last)) < 1e-3 else 0
            last = pose[2]
            if close >= 5 or (still >= 10 and abs(error) < 3 * HEADING_TOLERANCE):
                break
            drive(0.0, pid.update(error, dt))
            rate.sleep()
        settle()

    def bearing_to(point):
        return math.atan2(point[1] - pose[1], point[0] - pose[0])

    def go_to(point):
        if math.hypot(point[0] - pose[0], point[1] - pose[1]) > 0.02:
            turn_to(bearing_to(point))  # face the point first
        while not rospy.is_shutdown():
            distance = math.hypot(point[0] - pose[0], point[1] - pose[1])
            # Arrived, or just passed it (the point is behind): driving on would only overshoot.
            if distance < 0.005 or abs(angle_error(bearing_to(point), pose[2])) > math.pi / 2:
                break
            v, omega = go_to_point(pose, point, SPEED, 3.0)
            if distance < 0.05:
                omega = 0.0  # close to the point its bearing swings wildly: stop steering
            drive(max(v, MIN_SPEED), omega)
            rate.sleep()
        settle()

    def arc(radius, angle):
        tracker = AngleTracker(pose[2])
        sign = 1.0
        while not rospy.is_shutdown():
            left = abs(angle) - sign * tracker.update(pose[2])  # radians still to turn
            if left <= 0.0:
                break
            v = ARC_SPEED * min(1.0, max(0.2, left / 0.3))  # slow down over the last 0.3 rad
            drive(v, sign * v / radius)
            rate.sleep()
        settle()

    goal = tuple(mission.start)  # the planned pose: where the last move should have ended
    started = rospy.get_time()
    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        rospy.loginfo(f"state {state.name} ({state.color})")
        for move in state.moves:
            x, y, theta = goal
            if isinstance(move, Stop):
                drive(0.0, 0.0)
                rospy.sleep(move.seconds)
            elif isinstance(move, Rotate):
                goal = (x, y, (theta + move.angle) % (2 * math.pi))
                turn_to(goal[2])
            elif isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
                go_to(goal)
            elif isinstance(move, Arc):
                sign = 1.0 if move.angle > 0 else -1.0
                cx = x - sign * move.radius * math.sin(theta)  # the circle's centre
                cy = y + sign * move.radius * math.cos(theta)
                end = (theta + move.angle) % (2 * math.pi)
                goal = (
                    cx + sign * move.radius * math.sin(end),
                    cy - sign * move.radius * math.cos(end),
                    end,
                )
                arc(move.radius, move.angle)
            elif isinstance(move, ReturnToStart):
                goal = tuple(mission.start)
                go_to(goal)
                turn_to(goal[2])
    drive(0.0, 0.0)
    announce.publish(String(data="done"))
    elapsed = rospy.get_time() - started
    x, y, theta = pose
    rospy.loginfo(
        f"mission {mission.name} done in {elapsed:.1f} s; final pose by odometry: "
        f"x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad"
    )
    shutdown.publish(Empty())
''',
    },
}
