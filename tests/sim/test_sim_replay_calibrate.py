"""Replaying a bag's commands into the simulator, and calibrating the motors from a bag."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from duckielib.bags import Bag, BagWriter
from duckielib.config import DB21
from duckielib.errors import BagError
from duckielib.messages import Header, WheelEncoderStamped, WheelsCmdStamped
from duckielib.rostime import Time
from duckielib.sim import NoiseProfile, Simulator, World
from duckielib.sim.calibrate import calibrate_bag, steady_speeds
from duckielib.sim.replay import replay_bag
from duckielib.sim.robot import loaded_speeds, steady_speed
from duckielib.tools.runner import run_mission

VEH = "/ente/"
#: An unusual robot: a wide dead band, a curve that bends, a right motor 15 % weaker, and
#: tyres that scrub less than the realistic ones (a small difference of the wheels' speeds
#: keeps 44 % of itself instead of 9 %).
TRUE_CURVE = ((0.18, 0.0), (0.5, 6.0), (1.0, 13.0))
TRUE_SCRUB = 4.0
UNUSUAL = NoiseProfile.realistic(
    name="unusual",
    speed_curve=TRUE_CURVE,
    right_gain=0.85,
    breakaway_pwm=None,
    turning_scrub=TRUE_SCRUB,
)
#: Held commands (left, right, seconds): speeds forward, a turn in place, and arcs.
DRIVE = [
    (0.3, 0.3, 2.0), (0.0, 0.0, 1.0), (0.45, 0.45, 2.0), (0.0, 0.0, 1.0), (0.6, 0.6, 2.0),
    (0.0, 0.0, 1.0), (0.8, 0.8, 2.0), (0.0, 0.0, 1.0), (-0.4, 0.4, 2.0), (0.0, 0.0, 1.0),
    (0.3, 0.6, 2.0), (0.0, 0.0, 1.0), (0.8, 0.45, 2.0), (0.0, 0.0, 1.0),
]  # fmt: skip


def stamp(seconds):
    return Header(stamp=Time.from_sec(seconds))


def record_drive(path, profile, drive=DRIVE, seed=3, start=5.0, clock_ahead=0.0):
    """A bag of the simulator driving ``drive``: commands at 10 Hz and both encoders' ticks,
    stamped from ``start`` seconds (as a robot's clock would), ``clock_ahead`` seconds ahead
    of the times they are recorded at."""
    sim = Simulator(seed=seed, noise=profile, world=World(tiles_x=30, tiles_y=30),
                    start_pose=(8.0, 8.0, 0.0), trace_rate_hz=0)  # fmt: skip
    with BagWriter(path) as bag:
        t = 0.0
        for left, right, seconds in drive:
            for k in range(round(seconds * 10)):
                now = t + k / 10
                sim.run_until(now)
                sim.set_wheel_duties(left, right)
                message = WheelsCmdStamped(
                    header=stamp(start + clock_ahead + now), vel_left=left, vel_right=right
                )
                bag.write(
                    VEH + "wheels_driver_node/wheels_cmd", message, round((start + now) * 1e9)
                )
                for reading in sim.pop_encoder_readings():
                    tick = WheelEncoderStamped(
                        header=stamp(start + clock_ahead + reading.time),
                        data=reading.ticks,
                        resolution=135,
                    )
                    topic = f"{VEH}{reading.wheel}_wheel_encoder_node/tick"
                    bag.write(topic, tick, round((start + reading.time) * 1e9))
            t += seconds
    return path


def test_a_mission_bag_replays_into_its_own_profile_tick_for_tick(tmp_path, capsys):
    from duckielib.tools.cli import main

    run = run_mission(out=tmp_path / "run", noise="realistic", seed=4, animation=False)
    report = replay_bag(run.folder / "mission.bag", noise="realistic", seed=4)
    assert report.commands > 500
    assert report.command_topic.endswith("wheels_cmd_executed")
    for real, simulated in zip(report.real_ticks, report.sim_ticks):
        assert len(real) > 1000
        assert np.array_equal(real, simulated)
    assert report.left.travel_ratio == report.right.travel_ratio == 1.0
    assert report.tick_rate_rms == 0.0
    # Another profile drives the same commands elsewhere, and the figures say by how much.
    ideal = replay_bag(run.folder / "mission.bag", noise="ideal", seed=4)
    assert ideal.tick_rate_rms > 0.5
    assert abs(ideal.right.travel_ratio - 1.0) > 0.01  # the realistic right wheel is weaker
    figures = ideal.figures()
    assert figures["noise"] == "ideal"
    assert set(figures) >= {"travel_ratio_left", "travel_ratio_right", "tick_rate_rms"}
    # The mission turns one full circle more clockwise than counter-clockwise (its circle).
    turn = figures["turn_ticks_real"] * 2 * math.pi * DB21.radius / 135 / DB21.baseline
    assert turn == pytest.approx(-2 * math.pi, abs=0.5)
    # The ideal robot's tyres let the whole of a speed difference turn it: on the realistic
    # robot's commands it turns several times as far.
    assert figures["turn_ratio"] > 3.0
    # A run that comes back to its heading: a net turn of a few ticks of thousands, and a
    # ratio of two small numbers would say nothing.
    there_and_back = [(0.3, 0.5, 2.0), (0.0, 0.0, 1.0), (0.5, 0.3, 2.0), (0.0, 0.0, 1.0)]
    bag = str(record_drive(tmp_path / "back.bag", "realistic", drive=there_and_back))
    back = replay_bag(bag, noise="ideal").figures()
    assert abs(back["turn_ticks_real"]) < 0.05 * back["real_travel_left"]
    assert math.isnan(back["turn_ratio"])
    assert main(["sim", "replay", bag, "--noise", "ideal", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["turn_ratio"] is None  # JSON has no NaN


def _speeds(profile, duty):
    """A profile's steady (left, right) wheel speeds for a duty, before the ground's drag."""
    right_curve = profile.right_speed_curve or profile.speed_curve
    return (
        profile.left_gain * steady_speed(profile.speed_curve, duty),
        profile.right_gain * steady_speed(right_curve, duty),
    )


def _on_ground(profile, duty):
    """A profile's steady (left, right) wheel speeds for a duty on both wheels, the ground's
    drag included: what the encoders of a robot driving straight see."""
    return loaded_speeds(
        *_speeds(profile, duty),
        profile.turning_resistance,
        profile.turning_scrub,
        profile.scrub_width,
    )


def assert_calibrated_back(fitted, duties):
    for duty in duties:
        for wheel, got, true in zip(
            ("left", "right"), _speeds(fitted, duty), _speeds(UNUSUAL, duty)
        ):
            assert got == pytest.approx(true, rel=0.05), (duty, wheel)
    assert fitted.turning_scrub == pytest.approx(TRUE_SCRUB, rel=0.05)


def test_a_bag_of_held_commands_calibrates_an_unusual_robot_back_within_5_percent(tmp_path):
    bag = record_drive(tmp_path / "unusual.bag", UNUSUAL)
    points = steady_speeds(bag)
    assert len(points["left"]) == len(points["right"]) == 7  # every held command but stops
    calibration = calibrate_bag(bag, name="ente")
    fitted = calibration.profile
    assert fitted.name == "ente"
    assert_calibrated_back(fitted, (0.3, 0.4, 0.5, 0.6, 0.8))
    figures = calibration.figures()
    assert figures["calibration_right_gain"] == fitted.right_gain
    assert figures["calibration_tick_rate_rms"] < 3.0
    assert figures["calibration_travel_ratio_left"] == pytest.approx(1.0, abs=0.02)
    assert figures["calibration_travel_ratio_right"] == pytest.approx(1.0, abs=0.02)
    assert figures["calibration_turn_ratio"] == pytest.approx(1.0, abs=0.05)
    # The default profile is far from this robot; the fitted one is close.
    before = replay_bag(bag, noise="realistic")
    assert before.tick_rate_rms > 5 * calibration.replay.tick_rate_rms


def test_an_unusual_robot_driven_closed_loop_calibrates_back_and_predicts_another_run(tmp_path):
    # The mission's own controller drives: commands change every 50 ms, none is held 1 s.
    run = run_mission(out=tmp_path / "square", noise=UNUSUAL, seed=4, animation=False, figure=False)
    bag = run.folder / "mission.bag"
    commands = Bag(bag).topics["/duckiebot/wheels_driver_node/wheels_cmd_executed"].count
    assert commands > 5 * run.summary["total_time"]
    calibration = calibrate_bag(bag, check=[record_drive(tmp_path / "held.bag", UNUSUAL)])
    low, high = calibration.driven
    assert 0.15 < low < 0.2
    assert 0.45 < high < 0.55
    assert_calibrated_back(calibration.profile, (0.25, 0.3, 0.4, 0.5))
    # Checked on a run it was not fitted on (held commands up to 0.8): each wheel's travel
    # and the turn within 5 %.
    figures = calibration.figures()
    assert figures["check_1_bag"] == "held.bag"
    for name in ("check_1_travel_ratio_left", "check_1_travel_ratio_right", "check_1_turn_ratio"):
        assert figures[name] == pytest.approx(1.0, abs=0.05), name


def test_a_bag_with_one_speed_calibrates_and_says_what_it_could_not_see(tmp_path):
    bag = record_drive(tmp_path / "one.bag", UNUSUAL, drive=[(0.4, 0.4, 3.0), (0.0, 0.0, 1.0)])
    calibration = calibrate_bag(bag)
    assert calibration.replay.left.travel_ratio == pytest.approx(1.0, abs=0.03)
    # One speed straight ahead cannot tell a weaker right motor from tyres that let less of
    # the difference through; the wheels' speeds on the ground are what the bag shows.
    for got, true in zip(_on_ground(calibration.profile, 0.4), _on_ground(UNUSUAL, 0.4)):
        assert got == pytest.approx(true, rel=0.03)
    assert calibration.notes == (
        "The wheels are never driven at different commands, so nothing says how the ground "
        "resists turning: the realistic robot's value is kept.",
    )


def test_a_bag_that_never_drives_the_wheels_is_refused_with_what_to_record(tmp_path):
    bag = record_drive(tmp_path / "still.bag", UNUSUAL, drive=[(0.0, 0.0, 3.0), (0.1, 0.1, 2.0)])
    with pytest.raises(BagError, match=r"drives the wheels for 0\.0 s only") as caught:
        calibrate_bag(bag)
    assert "any driving, your mission included" in str(caught.value)


def test_a_bag_without_commands_says_which_topic_to_record(tmp_path):
    with BagWriter(tmp_path / "ticks.bag") as bag:
        for k in range(10):
            tick = WheelEncoderStamped(header=stamp(k / 30), data=k, resolution=135)
            bag.write(VEH + "left_wheel_encoder_node/tick", tick, k * 33_000_000 + 1)
    with pytest.raises(
        BagError, match=r"needs the wheel commands .* wheels_driver_node/wheels_cmd"
    ):
        replay_bag(tmp_path / "ticks.bag")
    assert math.isfinite(1.0)


def test_the_commands_print_name_value_lines_and_write_a_profile_duckie_mission_takes(
    tmp_path, capsys
):
    from duckielib.tools.cli import main

    bag = record_drive(tmp_path / "unusual.bag", UNUSUAL)
    profile = tmp_path / "ente.json"
    assert main(["calibrate", str(bag), "-o", str(profile)]) == 0
    lines = dict(
        line.split(": ", 1) for line in capsys.readouterr().out.splitlines() if ": " in line
    )
    assert float(lines["calibration_speed_at_0.5_left"]) == pytest.approx(6.0, rel=0.05)
    assert float(lines["calibration_right_gain"]) == pytest.approx(0.85, rel=0.05)
    assert float(lines["calibration_tick_rate_rms"]) < 3.0
    assert {"calibration_travel_ratio_left", "calibration_travel_ratio_right"} <= set(lines)
    assert NoiseProfile.load(profile).name == "ente"
    assert main(["sim", "replay", str(bag), "--noise", str(profile), "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["noise"] == "ente"
    assert figures["turn_ratio"] == pytest.approx(1.0, abs=0.05)
    assert figures["travel_ratio_right"] == pytest.approx(1.0, abs=0.05)
    # A bag to check that is not there is said before anything is fitted, and nothing written.
    missing = tmp_path / "other.bag"
    assert main(["calibrate", str(bag), "--check", str(missing), "-o", str(tmp_path / "x.json")])
    assert f"There is no file {missing}." in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()
    with pytest.raises(SystemExit) as refused:
        main(["sim", "replay", str(bag), "--noise", "noisy"])
    assert refused.value.code == 2
    assert "give ideal, realistic or a profile file (robot.json), not 'noisy'" in (
        capsys.readouterr().err
    )


def test_the_motor_table_holds_the_real_commands_and_measures_the_simulated_wheels(capsys):
    from duckielib.sim.motors import REAL_DB21, motor_table
    from duckielib.tools.cli import main

    ideal = {row.what: row for row in motor_table("ideal")}
    assert [row[0] for row in REAL_DB21] == list(ideal)
    # The driver's linear law: duty 0.3 is PWM 118, (118 - 60) / 195 of 27 rad/s.
    assert ideal["straight, 0.30"].simulated == pytest.approx((27 * 58 / 195,) * 2, rel=1e-3)
    # A profile whose curve goes through the real straight figures gives them back.
    fitted = NoiseProfile.ideal(speed_curve=((0.12, 0.0), (0.175, 1.8), (0.3, 3.65), (0.4, 6.4)))
    rows = {row.what: row for row in motor_table(fitted)}
    for what in ("straight, 0.30", "straight, 0.40", "turning in place"):
        assert rows[what].ratio() == pytest.approx((1.0, 1.0), abs=0.05), what
    assert main(["sim", "motors", "--noise", "ideal"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split() == ["command", "duties", "simulated", "rad/s", "real", "DB21", "rad/s"]
    assert out[2].split()[-4:] == ["8.0", "8.0", "3.6-3.7", "3.6-3.7"]


def test_the_realistic_profile_gives_the_real_robots_figures_and_their_drift(tmp_path):
    from duckielib.sim.motors import motor_table

    # Every wheel of every command within 10 % of the middle of the real robots' range (the
    # issue's bound is 25 %), the arc's slow wheel dragged along as on the real robots.
    for row in motor_table("realistic"):
        for ratio in row.ratio():
            assert 0.9 < ratio < 1.1, row
    arc = {row.what: row for row in motor_table("realistic")}["arc, 0.18 inner, 0.62 outer"]
    alone = {row.what: row for row in motor_table(NoiseProfile.realistic(turning_scrub=0))}
    assert arc.simulated[0] > 2.5 * alone["arc, 0.18 inner, 0.62 outer"].simulated[0]
    # The mission with the reference solution finishes, and ends tens of centimetres from its
    # start by the ground truth while its own odometry believes it is home, as real robots did.
    run = run_mission(out=tmp_path / "realistic", noise="realistic", seed=0, animation=False)
    summary = run.summary
    assert summary["distance_to_start"] > 0.2
    odometry_end = summary["final_pose_odometry"]
    assert math.hypot(odometry_end[0] - 0.32, odometry_end[1] - 0.32) < 0.08
    # The ideal robot's odometry agrees with the truth over the whole mission.
    ideal = run_mission(out=tmp_path / "ideal", noise="ideal", seed=0, animation=False)
    assert ideal.summary["odometry_error"]["distance"] < 0.01
    assert not ideal.report.problems


def test_the_calibration_drive_recorded_on_the_realistic_robot_calibrates_back_to_it(tmp_path):
    from duckielib.sim.calibrate import CALIBRATION_DRIVE, record_calibration_drive

    bag = record_calibration_drive(tmp_path / "calibration.bag", "realistic", seed=2)
    counts = {name.rsplit("/", 2)[-2]: info.count for name, info in Bag(bag).topics.items()}
    seconds = sum(step[2] for step in CALIBRATION_DRIVE)
    assert counts["wheels_driver_node"] == pytest.approx(10 * seconds, abs=5)  # 10 Hz
    assert counts["left_wheel_encoder_node"] == pytest.approx(30 * (seconds + 1), abs=5)
    calibration = calibrate_bag(bag)
    realistic = NoiseProfile.realistic()
    fitted = calibration.profile
    # The fitted motors have no static friction (a wheel at rest starts at any command above
    # the dead band); the realistic one has, and the fit takes part of it as the ground's.
    assert fitted.turning_scrub == pytest.approx(realistic.turning_scrub, rel=0.15)
    for duty in (0.3, 0.4, 0.5):
        for got, true in zip(_speeds(fitted, duty), _speeds(realistic, duty)):
            assert got == pytest.approx(true, rel=0.05), duty
    # The kinematics gain that makes the robot drive 0.2 m/s when asked, and it does.
    assert 1.7 < fitted.kinematics_gain < 1.9
    assert calibration.figures()["calibration_kinematics_gain"] == fitted.kinematics_gain


def test_the_sample_calibration_bag_fits_its_robot_and_the_realistic_one_does_not():
    from duckielib.bags import sample_bag
    from duckielib.sim.calibrate import CALIBRATION_SAMPLE_ROBOT

    bag = sample_bag("calibration_drive")
    calibration = calibrate_bag(bag)
    assert calibration.profile.right_gain == pytest.approx(0.93, rel=0.02)
    assert calibration.profile.turning_scrub == pytest.approx(
        CALIBRATION_SAMPLE_ROBOT["turning_scrub"], rel=0.05
    )
    # Its dead band: no held command below 0.15 tells where it ends, and the fit stays below.
    assert 0.08 < calibration.profile.speed_curve[0][0] < 0.15
    assert steady_speed(calibration.profile.speed_curve, 0.4) == pytest.approx(
        steady_speed(CALIBRATION_SAMPLE_ROBOT["speed_curve"], 0.4), rel=0.03
    )
    assert calibration.replay.left.travel_ratio == pytest.approx(1.0, abs=0.02)
    realistic = replay_bag(bag, "realistic")
    assert realistic.left.travel_ratio > 1.2  # the sample's motors are weaker
    assert len(realistic.t[0]) == len(realistic.real_ticks[0]) == len(realistic.sim_ticks[0])
    assert len(realistic.t[1]) == len(realistic.real_ticks[1]) == len(realistic.sim_ticks[1])


def test_without_arcs_the_straight_runs_and_turns_in_place_still_tell_the_wheels_apart(tmp_path):
    # Driving straight, the ground's resistance to turns hides part of the right motor's
    # weakness; turning in place it does not: the two together give both.
    straight_and_in_place = [step for step in DRIVE if not (step[0] > 0 and step[0] != step[1])]
    bag = record_drive(tmp_path / "no_arcs.bag", UNUSUAL, drive=straight_and_in_place)
    calibration = calibrate_bag(bag)
    assert calibration.profile.right_gain == pytest.approx(0.85, rel=0.03)
    assert calibration.profile.turning_scrub == pytest.approx(TRUE_SCRUB, rel=0.15)
    # Straight runs alone cannot tell the two apart: the realistic robot's value is kept.
    only_straight = [step for step in DRIVE if step[0] == step[1]]
    straight = calibrate_bag(record_drive(tmp_path / "straight.bag", UNUSUAL, drive=only_straight))
    assert straight.profile.turning_scrub == pytest.approx(
        NoiseProfile.realistic().turning_scrub, rel=0.05
    )
    assert "nothing says how the ground resists turning" in straight.notes[-1]


def test_a_replay_says_where_odometry_puts_the_robot_not_only_how_far_the_wheels_turned(
    tmp_path, capsys
):
    from duckielib.solution import ODOMETRY_PARTS, load_solution
    from duckielib.tools.cli import main

    bag = record_drive(tmp_path / "unusual.bag", UNUSUAL)
    solution = load_solution(None, required=ODOMETRY_PARTS)
    same = replay_bag(bag, noise=UNUSUAL, seed=3, solution=solution).figures()
    # The bag's own robot: the same ticks (a wheel's count may cross a slot a step apart, a
    # tick at most), so the same headings and the same final pose.
    assert same["heading_ratio"] == 1.0
    assert same["final_gap_m"] <= 0.0002
    assert same["heading_change_real_rad"] == same["heading_change_sim_rad"] != 0.0
    # The ideal robot drives the same commands: its wheels turn more, and its turn in place
    # and its arcs turn it elsewhere. The figures say by how much, and odometry agrees with
    # the simulated robot's true heading, from which it is computed.
    ideal = replay_bag(bag, noise="ideal", seed=3, solution=solution).figures()
    assert abs(ideal["heading_gap_rad"]) > 0.3, ideal
    assert ideal["final_gap_m"] > 0.3, ideal
    assert ideal["heading_change_sim_rad"] == pytest.approx(
        ideal["heading_change_sim_truth_rad"], abs=0.15
    )
    plot = tmp_path / "replay.png"
    assert (
        main(["sim", "replay", str(bag), "--noise", "ideal", "--seed", "3", "--plot", str(plot)])
        == 0
    )
    lines = dict(
        line.split(": ", 1) for line in capsys.readouterr().out.splitlines() if ": " in line
    )
    assert float(lines["heading_gap_rad"]) == ideal["heading_gap_rad"]
    assert float(lines["final_gap_m"]) == ideal["final_gap_m"]
    assert plot.read_bytes().startswith(b"\x89PNG")
    # A real robot's bag is stamped in seconds since 1970: the three tracks the plot draws
    # still share one time axis, from the first command to the end of the drive.
    epoch = record_drive(tmp_path / "epoch.bag", UNUSUAL, start=1_741_836_000.0)
    paths = replay_bag(epoch, noise=UNUSUAL, seed=3, solution=solution).paths
    seconds = sum(step[2] for step in DRIVE)
    for track in (paths.real, paths.sim, paths.truth):
        assert -0.5 < track.t[0] < 0.5, track.label
        assert seconds - 2 < track.t[-1] < seconds + 0.5, track.label


def test_a_robot_clock_a_minute_ahead_is_said_and_the_times_aligned(tmp_path, capsys):
    from duckielib.tools.cli import main

    on_time = record_drive(tmp_path / "on_time.bag", UNUSUAL)
    ahead = record_drive(tmp_path / "ahead.bag", UNUSUAL, clock_ahead=60.26)
    report = replay_bag(ahead, noise=UNUSUAL, seed=3)
    assert report.notes == (
        "The robot's clock ran 60.26 s ahead of the recorder's (the encoders' header stamps "
        "against the times they were recorded): the encoders' times were moved onto the "
        "recorder's clock, on which the wheel commands are read.",
    )
    assert report.figures() == replay_bag(on_time, noise=UNUSUAL, seed=3).figures() | {
        "bag": "ahead.bag"
    }
    # Calibrating pairs the commands with the ticks of the same moments.
    fitted = calibrate_bag(ahead).figures()
    assert fitted == calibrate_bag(on_time).figures() | {"bag": "ahead.bag"}
    assert main(["sim", "replay", str(ahead), "--noise", "ideal"]) == 0
    assert "note: The robot's clock ran 60.26 s ahead" in capsys.readouterr().err
