"""The notebooks' driving experiments on the virtual Duckiebot: run, record, report.

A notebook shows the experiment (a driver node, the moves, the speeds); the plumbing of a run
lives here: a fresh robot with the course's odometry node running the student's functions, a
node that records what happened, and the tables that compare the odometry with the truth.

- :func:`drive_task`: a list of moves, ``("straight", metres)`` or ``("rotate", radians)``,
  carried out by a driver node, recorded as a :class:`TaskRun`;
- :func:`run_with_odometry`: any node, with the odometry on, for a fixed time: the robot and
  two :class:`~duckielib.bags.PoseTrack` (what the odometry said, where the robot really was);
- :func:`turned_on_the_spot`: how far a robot at rest turns for a command on the spot;
- :func:`drive_until_encoders_fall_silent`: a node driving while its encoders stop publishing;
- :func:`how_a_node_ends`: whether a node returns or is killed, and what the wheels do then;
- :func:`moves_done`, :func:`planned_poses`, :func:`print_task_report`, :func:`speed_sweep_row`,
  :func:`speed_sweep_table`: what a run did, against what it was asked.

The student's functions (their odometry, ``angle_error``, ``distance_along``) come in as
arguments: this module never holds them. Frames and units: SI units and radians, poses
``(x, y, theta)`` in the task's world frame.

Laptop side; never deployed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from duckielib.bags import PoseTrack
from duckielib.messages import Pose2DStamped, Twist2DStamped, WheelEncoderStamped
from duckielib.missions import TASK_START
from duckielib.nodes import odometry_node
from duckielib.ros import Graph, rosnode, rosparam, rospy
from duckielib.sim.duckiebot import VirtualDuckiebot
from duckielib.sim.noise import NoiseProfile
from duckielib.solution import SolutionError

__all__ = [
    "RECORDED_FIELDS",
    "TaskRun",
    "describe_amount",
    "drive_task",
    "drive_until_encoders_fall_silent",
    "expected_seconds",
    "how_a_node_ends",
    "kill_node",
    "moves_done",
    "planned_poses",
    "pose_logger",
    "print_task_report",
    "recorder_node",
    "run_with_odometry",
    "speed_sweep_row",
    "speed_sweep_table",
    "turned_on_the_spot",
    "warn_if_odometry_is_far",
]

#: A move of a task: ``("straight", metres)`` or ``("rotate", radians)``, negative for
#: backwards or clockwise.
Move = Tuple[str, float]
Pose = Tuple[float, float, float]
Noise = Union[str, NoiseProfile]
#: The minus sign of the tables (a typographic minus, not a hyphen).
MINUS = "\N{MINUS SIGN}"

#: What :func:`recorder_node` keeps of each topic's messages, after their time.
RECORDED_FIELDS: Dict[str, Callable[[Any], Tuple[float, ...]]] = {
    "odometry_node/pose": lambda m: (m.x, m.y, m.theta),
    "simulator_node/ground_truth_pose": lambda m: (m.x, m.y, m.theta),
    "car_cmd_switch_node/cmd": lambda m: (m.v, m.omega),
    "right_wheel_encoder_node/tick": lambda m: (m.data,),
}
_RECORDED_TYPES = {
    "car_cmd_switch_node/cmd": Twist2DStamped,
    "right_wheel_encoder_node/tick": WheelEncoderStamped,
}


def recorder_node(store: Dict[str, List[Tuple[float, ...]]]) -> None:
    """A node: append ``(t, ...)`` of every message on :data:`RECORDED_FIELDS`' topics.

    Args:
        store: filled with one list per topic (relative name), times in simulated seconds.
    """
    rospy.init_node("recorder_node")

    def on_message(msg: Any, topic: str) -> None:
        store[topic].append((rospy.get_time(), *RECORDED_FIELDS[topic](msg)))

    for topic in RECORDED_FIELDS:
        store[topic] = []
        message_class = _RECORDED_TYPES.get(topic, Pose2DStamped)
        rospy.Subscriber(topic, message_class, on_message, callback_args=topic, queue_size=10)
    rospy.spin()


@dataclass
class TaskRun:
    """One task run: the robot, the moves asked, the driver's log and what was recorded.

    Attributes:
        bot: the robot, shut down, at the end of the run.
        moves: the moves asked for.
        log: the driver's records, one dict per move it finished: ``move``, ``t_stop`` and
            ``at_stop`` (when the zero command was sent, the odometry's pose then), ``t_end``
            and ``at_end`` (after the rest), and for rotations ``turned`` (rad).
        store: what :func:`recorder_node` recorded, by topic.
    """

    bot: VirtualDuckiebot
    moves: List[Move]
    log: List[Dict[str, Any]]
    store: Dict[str, List[Tuple[float, ...]]]

    def track(self, topic: str, label: str) -> PoseTrack:
        """A recorded pose topic as a track (t, x, y, theta arrays)."""
        samples = self.store[topic]
        if not samples:
            empty = np.zeros(0)
            return PoseTrack(empty, empty, empty, empty, label)
        t, x, y, theta = np.array(samples).T
        return PoseTrack(t, x, y, theta, label)

    @property
    def odometry(self) -> PoseTrack:
        """The odometry's poses over the run."""
        return self.track("odometry_node/pose", "odometry")

    @property
    def truth(self) -> PoseTrack:
        """Where the robot really was over the run (the simulator's ground truth)."""
        return self.track("simulator_node/ground_truth_pose", "ground truth")

    def truth_at(self, t: float) -> Tuple[float, ...]:
        """The true pose (x, y, theta) at time ``t`` (s): the last sample at or before it."""
        samples = self.store["simulator_node/ground_truth_pose"]
        index = max(0, int(np.searchsorted([s[0] for s in samples], t, side="right")) - 1)
        return samples[index][1:]


def expected_seconds(moves: Sequence[Move], v: float, omega: float, settle_s: float) -> float:
    """How long ``moves`` should take at ``v`` (m/s) and ``omega`` (rad/s), with the rests, in s."""
    return sum(abs(goal) / (v if kind == "straight" else omega) + settle_s for kind, goal in moves)


def drive_task(
    driver: Callable[..., None],
    solution: Any,
    moves: Sequence[Move],
    *,
    start: Pose = TASK_START,
    noise: Noise = "ideal",
    v: float,
    omega: float,
    settle_s: float,
    params: Optional[Dict[str, Any]] = None,
    seed: int = 0,
    slow_down: bool = False,
    limit: Optional[float] = None,
    far: float = 1.0,
) -> TaskRun:
    """Drive ``moves`` on a fresh robot with the student's odometry, recorded.

    The robot starts at ``start`` with the odometry node (running ``solution``'s functions),
    :func:`recorder_node` and ``driver(moves, v=v, omega=omega, slow_down=slow_down, log=log)``,
    and runs until the driver has logged every move or ``limit`` seconds have passed.

    Args:
        driver: the driver node's main function.
        solution: the student's functions (a module or a notebook's namespace object).
        moves: the moves to drive.
        start: the start pose (x, y, theta), in metres and radians.
        noise: the simulator's noise profile.
        v: forward speed of straight moves, m/s.
        omega: turn rate of rotations, rad/s.
        settle_s: the driver's rest after each move, s.
        params: ROS parameters to set first, ``{relative name: value}``.
        seed: the simulator's seed.
        slow_down: passed to the driver.
        limit: the longest run, simulated s (default: 1.5 times the moves' time, plus 3 s).
        far: a final odometry further than this from the truth (m) is reported as wrong.

    Returns:
        The run; :func:`warn_if_odometry_is_far` has already said if the odometry went wrong.
    """
    bot = VirtualDuckiebot(seed=seed, noise=noise, start_pose=start)
    for name, value in (params or {}).items():
        rosparam.set(bot.namespace + name, value, graph=bot.graph)
    log: List[Dict[str, Any]] = []
    store: Dict[str, List[Tuple[float, ...]]] = {}
    bot.launch(odometry_node, rospy, solution, start)
    bot.launch(recorder_node, store)
    bot.launch(driver, list(moves), v=v, omega=omega, slow_down=slow_down, log=log)
    if limit is None:
        limit = 1.5 * expected_seconds(moves, v, omega, settle_s) + 3.0
    bot.run_until(lambda: len(log) == len(moves), timeout=limit)  # never wait forever
    bot.shutdown()
    run = TaskRun(bot, list(moves), log, store)
    poses = store["odometry_node/pose"]
    if not poses:
        print(
            "The odometry published no pose at all: your WheelPairing (notebook 05) never "
            "returned a pair of changes."
        )
    else:
        truth = store["simulator_node/ground_truth_pose"][-1]
        warn_if_odometry_is_far(poses[-1][1:3], truth[1:3], far, "within tens of centimetres")
    return run


def warn_if_odometry_is_far(
    odometry: Sequence[float], truth: Sequence[float], far: float, closer: str = "far closer"
) -> bool:
    """Say so if the odometry's final position is more than ``far`` metres from the truth.

    Args:
        odometry: the odometry's final (x, y), in metres.
        truth: where the robot really was then, (x, y).
        far: the largest distance a working odometry could be off, in metres.
        closer: how close a working odometry stays, in words.

    Returns:
        Whether it was that far (and a sentence was printed).
    """
    off = math.hypot(odometry[0] - truth[0], odometry[1] - truth[1])
    if off <= far:
        return False
    print(
        f"Your odometry ended {100 * off:.0f} cm from where the robot really was: a working "
        f"odometry stays {closer} here. delta_phi, estimate_pose or WheelPairing (notebook 05) "
        "is wrong in a way their visible tests do not catch, and every number that comes from "
        "the odometry is wrong with it: fix notebook 05 first."
    )
    return True


def describe_amount(move: Move) -> str:
    """How much a move asks for, as text: ``"+1.25 m"`` or ``"-90°"``."""
    kind, goal = move
    return f"{goal:+.2f} m" if kind == "straight" else f"{math.degrees(goal):+.0f}°"


def moves_done(run: TaskRun, count: Optional[int] = None) -> List[Dict[str, Any]]:
    """The driver's records of the run's first ``count`` moves (all by default).

    Raises:
        SolutionError: if the driver did not finish them, with a sentence that says why.
    """
    count = len(run.moves) if count is None else count
    if len(run.log) < count:
        move = run.moves[len(run.log)]
        raise SolutionError(
            f"The driver never finished move {len(run.log) + 1} of {len(run.moves)} ({move[0]} "
            f"{describe_amount(move)}) in {run.bot.time:.0f} simulated seconds: the odometry "
            "never said its goal was reached. Your odometry (notebook 05), distance_along or "
            "AngleTracker is wrong in a way their visible tests do not catch: report(...) of "
            "this run shows where the odometry believed the robot was."
        )
    return run.log[:count]


def planned_poses(start: Sequence[float], moves: Sequence[Move]) -> List[Pose]:
    """Where each move should end if the robot did exactly what it was asked: ``[(x, y, theta)]``.

    Headings are kept in [0, 2*pi).
    """
    x, y, theta = start
    poses = []
    for kind, goal in moves:
        if kind == "straight":
            x, y = x + goal * math.cos(theta), y + goal * math.sin(theta)
        else:
            theta = (theta + goal) % (2 * math.pi)
        poses.append((x, y, theta))
    return poses


def print_task_report(
    run: TaskRun, start: Sequence[float], angle_error: Callable[[float, float], float]
) -> None:
    """Print, for each move, where it should have ended and where the odometry and truth say.

    The last column is the truth minus the plan, in cm and degrees. A sentence follows when
    the driver did not finish every move.

    Args:
        run: the run.
        start: where the task started, (x, y, theta).
        angle_error: the student's ``angle_error(target, current)``, in radians.
    """
    print(
        "move               planned (x, y, θ)      odometry (x, y, θ)     truth (x, y, θ)"
        f"        truth {MINUS} planned"
    )
    for record, planned in zip(run.log, planned_poses(start, run.moves)):
        kind, _ = record["move"]
        truth = run.truth_at(record["t_end"])
        gap = 100 * math.hypot(truth[0] - planned[0], truth[1] - planned[1])
        turn = math.degrees(angle_error(truth[2], planned[2]))
        poses = "  ".join(
            f"({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f})" for p in (planned, record["at_end"], truth)
        )
        amount = describe_amount(record["move"])
        print(f"{kind:8s} {amount:>8s}  {poses}  {gap:5.1f} cm, {turn:+5.1f}°")
    if len(run.log) < len(run.moves):
        print(
            f"The driver finished {len(run.log)} of the {len(run.moves)} moves in "
            f"{run.bot.time:.0f} simulated seconds: the odometry never said the next goal "
            "was reached."
        )


def speed_sweep_row(
    run: TaskRun,
    v: float,
    start: Sequence[float],
    goal: float,
    along: Callable[[Sequence[float], Sequence[float]], float],
    lateral: Callable[[Sequence[float], Sequence[float]], float],
) -> Dict[str, float]:
    """What one run of a speed sweep did, in metres: where it stopped, the odometry's error.

    Args:
        run: a straight task's run, its first move ``goal`` metres forward.
        v: the run's speed, m/s.
        start: where it started.
        goal: the first move's length, m.
        along: how far a pose is ahead of a start pose along its heading (``distance_along``).
        lateral: how far a pose is to the left of a start pose's heading line.

    Returns:
        ``v``, ``done`` (moves finished), ``seconds``, ``from_start`` (m, at the end); when the
        first move finished, also ``along`` (truth minus goal), ``side``, ``odometry`` (the
        odometry's position error), ``odometry_along`` and ``odometry_side``.
    """
    x, y, _ = run.bot.sim.pose
    row = {
        "v": v,
        "done": len(run.log),
        "seconds": run.bot.time,
        "from_start": math.hypot(x - start[0], y - start[1]),
    }
    if run.log:  # the forward move finished
        forward = run.log[0]
        truth = run.truth_at(forward["t_end"])
        odometry_end = forward["at_end"]
        row["along"] = along(start, truth) - goal
        row["side"] = lateral(start, truth)
        row["odometry"] = math.hypot(truth[0] - odometry_end[0], truth[1] - odometry_end[1])
        row["odometry_along"] = along(start, odometry_end) - along(start, truth)
        row["odometry_side"] = lateral(start, odometry_end) - lateral(start, truth)
    return row


def speed_sweep_table(rows: Sequence[Dict[str, float]], moves: int) -> str:
    """The rows of :func:`speed_sweep_row` as a table in centimetres, one line per speed.

    Args:
        rows: the sweep's rows.
        moves: how many moves a finished run did.
    """
    lines = [
        f"           where the robot stopped     odometry {MINUS} truth there"
        "        after the way back",
        "  v (m/s)   along (cm)   side (cm)   along   sideways   all (cm)   from the start (cm)",
    ]
    for row in rows:
        if row["done"] == moves:
            lines.append(
                f"{row['v']:8.3f} {100 * row['along']:11.1f} {100 * row['side']:11.1f} "
                f"{100 * row['odometry_along']:7.1f} {100 * row['odometry_side']:10.1f} "
                f"{100 * row['odometry']:10.1f} {100 * row['from_start']:21.1f}"
            )
        else:
            lines.append(
                f"{row['v']:8.3f}   did not finish: {row['done']:.0f} of {moves} moves in "
                f"{row['seconds']:.0f} s, ending {100 * row['from_start']:.1f} cm from the start"
            )
    return "\n".join(lines)


def pose_logger(poses: Dict[str, List[Tuple[float, float, float, float]]]) -> None:
    """A node: append each odometry and true pose, as (t in s, x, y, theta), to ``poses``.

    Args:
        poses: gets the lists ``"odometry"`` (``odometry_node/pose``) and ``"truth"``
            (``simulator_node/ground_truth_pose``).
    """
    rospy.init_node("pose_logger")

    def on_pose(msg: Any, name: str) -> None:
        poses[name].append((rospy.get_time(), msg.x, msg.y, msg.theta))

    for name, topic in (
        ("odometry", "odometry_node/pose"),
        ("truth", "simulator_node/ground_truth_pose"),
    ):
        poses[name] = []
        rospy.Subscriber(topic, Pose2DStamped, on_pose, callback_args=name, queue_size=10)
    rospy.spin()


def run_with_odometry(
    node: Callable[..., None],
    *args: Any,
    solution: Any,
    run_for: float,
    start: Pose = TASK_START,
    noise: Noise = "realistic",
    seed: int = 0,
    far: float = 2.5,
    echo_logs: bool = True,
) -> Tuple[VirtualDuckiebot, PoseTrack, PoseTrack]:
    """Run ``node(*args)`` with the student's odometry on a new robot for ``run_for`` seconds.

    Args:
        node: the node's main function.
        *args: its arguments.
        solution: the student's functions, which the odometry node runs.
        run_for: how long to run, simulated s.
        start: the start pose (x, y, theta), in metres and radians.
        noise: the simulator's noise profile.
        seed: the simulator's seed.
        far: a final odometry further than this from the truth (m) is reported as wrong.
        echo_logs: whether the nodes' log lines are printed.

    Returns:
        ``(bot, odometry, truth)``: the robot (shut down), and the odometry's and the true
        poses as tracks.

    Raises:
        SolutionError: if the odometry published no pose at all.
    """
    graph = Graph(echo_logs=echo_logs)
    bot = VirtualDuckiebot(seed=seed, noise=noise, start_pose=start, graph=graph)
    poses: Dict[str, List[Tuple[float, float, float, float]]] = {"odometry": [], "truth": []}
    bot.launch(odometry_node, rospy, solution, start)
    bot.launch(pose_logger, poses)
    bot.launch(node, *args)
    bot.run(run_for)
    bot.shutdown()
    if not poses["odometry"]:
        raise SolutionError(
            f"Your odometry published no pose in {run_for:.1f} simulated seconds: your "
            "WheelPairing (notebook 05) never returned a pair of changes. Fix notebook 05 first."
        )
    warn_if_odometry_is_far(poses["odometry"][-1][1:3], poses["truth"][-1][1:3], far)
    tracks = []
    for name, label in (("odometry", "odometry"), ("truth", "ground truth")):
        t, x, y, theta = np.array(poses[name]).T
        tracks.append(PoseTrack(t, x, y, theta, label))
    return bot, tracks[0], tracks[1]


def _spin(omega: float, seconds: float) -> None:
    """A node: ask for a turn on the spot at ``omega`` (rad/s) for ``seconds``, then stop."""
    rospy.init_node("spin")
    commands = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    rate = rospy.Rate(20)
    end = rospy.get_time() + seconds
    while not rospy.is_shutdown() and rospy.get_time() < end:
        commands.publish(Twist2DStamped(v=0.0, omega=omega))
        rate.sleep()
    commands.publish(Twist2DStamped(v=0.0, omega=0.0))


def turned_on_the_spot(
    noise: Noise, omega: float, seconds: float = 1.0, start: Pose = TASK_START, seed: int = 0
) -> float:
    """How far a robot at rest turns, in degrees, when asked to turn on the spot.

    The command ``omega`` (rad/s, negative clockwise) is sent at 20 Hz for ``seconds``, then a
    zero command; the robot is given half a second more to stop.

    Returns:
        The turn, signed clockwise positive, in degrees in [-180, 180).
    """
    robot = VirtualDuckiebot(seed=seed, noise=noise, start_pose=start, graph=Graph(echo_logs=False))
    robot.launch(_spin, omega, seconds)
    robot.run(seconds + 0.5)
    return math.degrees((start[2] - robot.sim.pose[2] + math.pi) % (2 * math.pi) - math.pi)


def drive_until_encoders_fall_silent(
    node: Callable[..., None],
    *args: Any,
    silence_at: float,
    end_at: float,
    start: Pose = TASK_START,
    noise: Noise = "realistic",
    seed: int = 1,
    step: float = 0.02,
) -> Tuple[VirtualDuckiebot, np.ndarray, np.ndarray]:
    """Run ``node(*args)`` on a new robot whose encoder drivers stop at ``silence_at``.

    As if the encoders' cable came loose: from ``silence_at`` on no tick is published, while
    the robot still drives.

    Args:
        node: the node's main function.
        *args: its arguments.
        silence_at: when the encoders fall silent, simulated s.
        end_at: the end of the run, simulated s.
        start: the start pose (x, y, theta), in metres and radians.
        noise: the simulator's noise profile.
        seed: the simulator's seed.
        step: how often the distance is sampled, s.

    Returns:
        ``(bot, times, distances)``: the robot, and the true distance from the start (m) at
        each sample time (s).
    """
    bot = VirtualDuckiebot(seed=seed, noise=noise, start_pose=start)
    bot.launch(node, *args)
    times, distances = [], []
    while bot.time < end_at:
        if bot.time >= silence_at:
            for wheel in ("left", "right"):
                encoder = bot.graph.nodes.get(f"{bot.namespace}{wheel}_wheel_encoder_node")
                if encoder is not None:
                    encoder.shutdown("the encoder cable came loose")
        bot.run(step)
        x, y, _ = bot.sim.pose
        times.append(bot.time)
        distances.append(math.hypot(x - start[0], y - start[1]))
    return bot, np.array(times), np.array(distances)


def kill_node(bot: VirtualDuckiebot, name: str) -> bool:
    """End a node from outside, as ``rosnode kill`` or Ctrl-C do: its shutdown hooks run.

    Args:
        bot: the robot the node runs on.
        name: the node's name in the robot's namespace.

    Returns:
        Whether the node was still there to kill.
    """
    node = bot.graph.nodes.get(bot.namespace + name)
    if node is not None:
        node.shutdown("killed")
    return node is not None


def how_a_node_ends(
    driver: Callable[..., None],
    *args: Any,
    name: str,
    solution: Any,
    start: Pose = TASK_START,
    seed: int = 0,
    kill_after: Optional[float] = None,
    watch_for: float = 3.0,
) -> Tuple[str, float, bool, float]:
    """Run ``driver(*args)`` with the odometry on the ideal robot, and see how it ends.

    It runs until the node leaves ``rosnode list`` (at most 10 s), or is killed with
    :func:`kill_node` after ``kill_after`` seconds; then the robot runs ``watch_for`` seconds
    more.

    Args:
        driver: the node's main function.
        *args: its arguments.
        name: the node's name (as it calls ``rospy.init_node``).
        solution: the student's functions, which the odometry node runs.
        start: the start pose (x, y, theta), in metres and radians.
        seed: the simulator's seed.
        kill_after: when to kill the node, simulated s; None to let it end by itself.
        watch_for: how long to watch the robot after the node ended, s.

    Returns:
        ``(how, ended_at, alive, rolled)``: ``"returned"``, ``"killed"`` or ``"running"``
        (still running after 10 s); when, in s; whether it is still in ``rosnode list`` at the
        end; how far the robot moved after it ended, in m.
    """
    bot = VirtualDuckiebot(seed=seed, noise="ideal", start_pose=start)
    bot.launch(odometry_node, rospy, solution, start)
    bot.launch(driver, *args)
    node = bot.namespace + name
    if kill_after is None:
        ended = bot.run_until(
            lambda: bot.time > 0.1 and node not in rosnode.list(graph=bot.graph), 10.0
        )
        how = "returned" if ended else "running"
    else:
        bot.run(kill_after)
        how = "killed" if kill_node(bot, name) else "returned"
    ended_at, where = bot.time, bot.sim.pose
    bot.run(watch_for)
    rolled = math.hypot(bot.sim.pose[0] - where[0], bot.sim.pose[1] - where[1])
    alive = node in rosnode.list(graph=bot.graph)
    bot.shutdown()
    return how, ended_at, alive, rolled
