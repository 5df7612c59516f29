"""The sample bag notebook 10 analyses until a student's own mission runs."""

from __future__ import annotations

import pytest

from duckielib.bags import SAMPLES, Bag, sample_bag
from duckielib.bags.behaviour import mission_report
from duckielib.errors import BagError
from duckielib.missions import SQUARE_THEN_CIRCLE
from duckielib.tools.runner import run_mission


def test_the_sample_is_a_whole_mission_whose_odometry_drifts_as_a_real_robots():
    assert SAMPLES == [
        "calibration_drive",
        "square_then_circle_other_robot",
        "square_then_circle_realistic",
    ]
    report = mission_report(sample_bag(), SQUARE_THEN_CIRCLE)
    assert [state.name for state in report.states] == [s.name for s in SQUARE_THEN_CIRCLE.states]
    assert report.states_in_order
    assert report.stops_held
    assert report.finished
    # Its odometry believes it is home; by the ground truth it ended tens of centimetres away,
    # as real robots did (62 to 64 cm): on the open floor no wall held it anywhere.
    assert not report.closed
    assert 0.5 < report.distance_to_start < 0.9
    assert report.wall_contacts == []
    assert len(report.problems) == 1
    assert "the difference is odometry's drift" in report.problems[0]


@pytest.mark.slow
def test_the_sample_holds_what_a_mission_run_records_today(tmp_path):
    # Same topics, types and md5 sums as a fresh run: record it again when these change.
    run = run_mission(noise="realistic", seed=0, out=tmp_path, animation=False)
    fresh, sample = Bag(run.files["bag"]).topics, Bag(sample_bag()).topics
    assert {name: (info.type, info.md5sum) for name, info in sample.items()} == {
        name: (info.type, info.md5sum) for name, info in fresh.items()
    }
    ratio = {name: sample[name].count / fresh[name].count for name in fresh}
    assert all(0.9 < value < 1.1 for value in ratio.values()), ratio


def test_the_other_robots_mission_calibrates_back_to_the_sample_robot():
    from duckielib.sim.calibrate import CALIBRATION_SAMPLE_ROBOT, calibrate_bag

    bag = sample_bag("square_then_circle_other_robot")
    report = mission_report(bag, SQUARE_THEN_CIRCLE)
    assert report.finished
    assert report.states_in_order
    fitted = calibrate_bag(bag).profile
    assert fitted.right_gain == pytest.approx(CALIBRATION_SAMPLE_ROBOT["right_gain"], rel=0.03)
    assert fitted.turning_scrub == pytest.approx(CALIBRATION_SAMPLE_ROBOT["turning_scrub"], rel=0.1)


def test_an_unknown_sample_is_named_with_those_there_are():
    with pytest.raises(BagError, match=r"no sample bag 'd_shape'.*square_then_circle_realistic"):
        sample_bag("d_shape")
