"""Every bag ``duckie mission`` writes replays whole in Debian's ``rosbag play``.

ROS 1 refuses record times below its smallest valid time (1 ns): Debian's rosbag_storage
drops such a message when it loads the bag's index, so ``rosbag play`` would skip what the
simulation publishes at its very start (the first LED pattern, the first true pose). Here a
mission bag is played on a real roscore, recorded again by ``rosbag record``, and every topic
must arrive with every message.
"""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from duckielib.bags import Bag

pytestmark = [pytest.mark.ros, pytest.mark.slow]


@pytest.fixture(scope="module")
def mission_bag(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mission")
    result = subprocess.run(
        # The straight task's bag (35 s, 4,929 messages): as short a mission as there is, so
        # the replay can go slowly enough for the recorder to keep up on a busy machine.
        [
            sys.executable,
            "-m",
            "duckielib.tools.cli",
            "mission",
            "--mission",
            "straight",
            "--no-animation",
            "--no-figure",
            "--out",
            str(folder),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    return folder / "mission.bag"


def test_a_mission_bag_replays_whole_in_rosbag_play(master, mission_bag):
    original = Bag(mission_bag)
    counts = {name: info.count for name, info in original.topics.items()}
    # The first messages are recorded as the simulation starts.
    assert min(message.time_ns for message in original.messages()) < 1_000_000
    # Wall-clock time for this replay: record times are the messages' receipt times.
    master.api.setParam("/test", "/use_sim_time", False)
    replayed = master.folder / "replayed.bag"
    recorder = master.record(replayed, sorted(counts))
    # Played once the recorder listens to every topic: its first messages are not lost.
    # At three times its speed: about 90 messages a second per topic, which rosbag record's
    # subscribers (100 messages of queue each) keep up with under load; at 8 times they once
    # dropped some.
    command = ["rosbag", "play", "--wait-for-subscribers", "--rate", "3", "--queue", "10000"]
    play = subprocess.run(
        [*command, str(mission_bag)],
        env=master.env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    time.sleep(1.0)  # the last messages reach the recorder
    master.stop(recorder)
    master.wait_for_bag(replayed)
    assert play.returncode == 0, play.stdout + play.stderr
    assert "invalid time" not in play.stdout + play.stderr
    got = {name: info.count for name, info in Bag(replayed).topics.items()}
    assert got == counts
