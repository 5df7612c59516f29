"""The ``duckie`` command as a user runs it: real processes, real exit codes."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from autograder.course import ROOT

FIGURE_LINE = re.compile(r"^[a-z0-9_]+: \S+$")


def duckie(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_bench_lists_the_benchmarks():
    result = duckie("bench")
    assert result.returncode == 0
    assert "messages: build, serialize and read back the course's messages" in result.stdout


def test_bench_messages_prints_figures_headline_last():
    result = duckie("bench", "messages")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert all(FIGURE_LINE.match(line) for line in lines), lines
    names = [line.split(":")[0] for line in lines]
    assert names[0] == "import_messages_ms"
    assert names[-1] == "encoder_round_trips_per_s"
    assert float(lines[-1].split(": ")[1]) > 0


def test_bench_mission_says_where_the_time_goes_and_leaves_messages_as_they_were():
    from duckielib.messages import String
    from duckielib.messages.message import Message
    from duckielib.tools import runner
    from duckielib.tools.bench import mission

    to_bytes, recorded = Message.to_bytes, runner.RECORDED
    figures = dict(mission.run())
    assert list(figures)[-1] == "mission_realtime_factor"
    wall = float(figures["mission_wall_s"])
    assert 0 < float(figures["mission_physics_wall_s"]) < wall, "the physics is a part of a run"
    assert float(figures["mission_wall_s_objects_no_bag"]) > 0
    assert int(figures["mission_bag_messages"]) > 9000
    # Run apart, the clock goes to the nodes and back at each of their steps and each tick.
    assert 3000 < int(figures["mission_apart_exchanges"]) < int(figures["mission_bag_messages"])
    assert float(figures["mission_apart_wall_s"]) > wall
    assert float(figures["mission_realtime_factor"]) == pytest.approx(
        float(figures["mission_simulated_s"]) / wall, rel=0.01
    )
    assert (Message.to_bytes, runner.RECORDED) == (to_bytes, recorded), "put back after the bound"
    assert String.from_bytes(String(data="hi").to_bytes()) == String(data="hi")


@pytest.mark.notebook
def test_bench_kernel_times_a_notebooks_kernel_and_first_cell_without_touching_course(
    monkeypatch,
):
    from duckielib.tools.bench import kernel

    monkeypatch.setattr(kernel, "NOTEBOOKS", ["03_frames"])
    before = sorted((ROOT / "course" / "03_frames").rglob("*"))
    figures = kernel.run()
    names = [name for name, _ in figures]
    assert names == [
        "kernel_ready_s",
        "first_cell_s",
        "kernel_to_first_cell_s_03_frames",
        "kernel_to_first_cell_max_s",
        "kernel_to_first_cell_s",
    ]
    values = {name: float(value) for name, value in figures}
    assert values["kernel_ready_s"] > 0
    assert values["first_cell_s"] > 0
    assert values["kernel_to_first_cell_s"] == pytest.approx(
        values["kernel_ready_s"] + values["first_cell_s"], abs=0.011
    )
    assert sorted((ROOT / "course" / "03_frames").rglob("*")) == before


def test_bench_kernel_says_which_first_cell_raised(tmp_path):
    from duckielib.errors import DuckielibError
    from duckielib.tools.bench.kernel import time_first_cell

    box = tmp_path / "box"
    box.mkdir()
    with pytest.raises(DuckielibError, match=r"^The first cell of box raised ZeroDivisionError"):
        time_first_cell(box, "1/0")


def test_unknown_benchmark_is_one_sentence_without_traceback():
    result = duckie("bench", "warp-drive")
    assert result.returncode == 1
    assert result.stderr == (
        "duckie: There is no benchmark called 'warp-drive'; choose one of: "
        + ", ".join(sorted(_benchmark_names()))
        + ".\n"
    )
    assert "Traceback" not in result.stderr


def test_mission_refuses_an_unknown_mission_with_usage():
    result = duckie("mission", "--mission", "circle")
    assert result.returncode == 2
    assert "invalid choice: 'circle'" in result.stderr


@pytest.mark.parametrize("exported", [False, True])
def test_an_unfinished_solution_stops_the_mission_at_once_naming_the_first_notebook(
    tmp_path, exported
):
    # The untouched release, as a folder of notebooks or exported into one module: either way
    # the run stops before it starts, with the same sentence, and writes nothing.
    solution = str(ROOT / "course")
    if exported:
        solution = str(tmp_path / "mine.py")
        assert duckie("export", str(ROOT / "course"), "-o", solution).returncode == 0
    result = duckie("mission", "--solution", solution, "--out", str(tmp_path / "run"))
    assert result.returncode == 1
    assert result.stderr == (
        "duckie: Finish notebook 05_odometry: write delta_phi, estimate_pose, WheelPairing "
        "(their cells still raise NotImplementedError), save the notebook, and try again.\n"
    )
    assert result.stdout == ""
    assert not (tmp_path / "run").exists()


def test_bad_command_line_exits_2_with_usage():
    result = duckie("fly")
    assert result.returncode == 2
    assert "usage: duckie" in result.stderr


def _benchmark_names():
    from duckielib.tools.bench import benchmarks

    return benchmarks()


def test_a_disk_that_fills_up_ends_the_mission_with_a_sentence(tmp_path):
    limited = (
        "import resource, signal, sys\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))\n"
        "from duckielib.tools.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", limited, "mission", "--out", str(tmp_path), "--no-animation"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    assert result.stderr.startswith("duckie: Recording the bag failed (OSError: ")
    assert "mission.bag.active, which duckie bag repair recovers" in result.stderr
    assert (tmp_path / "mission.bag.active").exists()
    assert not (tmp_path / "mission.bag").exists()
    errors = [line for line in (tmp_path / "log.txt").read_text().splitlines() if "[ERROR]" in line]
    assert len(errors) == 1, errors
    assert "[/record_1]: Stopped recording mission.bag" in errors[0]


def _interrupted_mission(folder, patch):
    """Run ``duckie mission`` in a child process whose ``patch`` arranges a Ctrl-C."""
    child = (
        "import os, signal, sys, threading, time\n"
        "import duckielib.tools.runner as runner\n"
        f"{patch}\n"
        "from duckielib.tools.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    return subprocess.run(
        [sys.executable, "-c", child, "mission", "--out", str(folder)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_ctrl_c_during_the_drive_stops_the_wheels_and_keeps_the_bag(tmp_path):
    from duckielib.bags import Bag

    # Ctrl-C once the simulated clock passes 10 s (of 64), however fast the machine runs.
    patch = (
        "from duckielib.sim.simulator import Simulator\n"
        "advance = Simulator._advance\n"
        "def _advance(self, count):\n"
        "    advance(self, count)\n"
        "    if self._steps * self.dt >= 10.0 and not getattr(self, 'pressed', False):\n"
        "        self.pressed = True\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "Simulator._advance = _advance\n"
    )
    result = _interrupted_mission(tmp_path, patch)
    assert (result.returncode, result.stderr) == (130, "duckie: interrupted.\n")
    bag = Bag(tmp_path / "mission.bag")  # closed and indexed
    executed = bag.read("/duckiebot/wheels_driver_node/wheels_cmd_executed")
    times = [item.time for item in executed]
    assert 9.9 < times[-1] < 10.5, f"interrupted at 10 s of simulated time, not {times[-1]:.2f} s"
    assert (executed[-1].message.vel_left, executed[-1].message.vel_right) == (0.0, 0.0)


def test_ctrl_c_that_compiled_code_turns_into_another_error_still_ends_as_interrupted(tmp_path):
    # matplotlib's drawing code reports a Ctrl-C that lands inside it as a ValueError.
    patch = (
        "def _animation(*args):\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        time.sleep(5)\n"
        "    except KeyboardInterrupt:\n"
        "        raise ValueError('Invalid affine transformation matrix') from None\n"
        "runner._animation = _animation\n"
    )
    result = _interrupted_mission(tmp_path, patch)
    assert (result.returncode, result.stderr) == (130, "duckie: interrupted.\n")
    assert (tmp_path / "mission.bag").exists()


def assert_one_sentence(result, status, start):
    """``result`` ended with ``status`` and the one line ``duckie: START...``, no traceback."""
    assert result.returncode == status, result.stderr
    assert "Traceback" not in result.stderr
    said = result.stderr.splitlines()
    assert len(said) == 1, said
    assert said[0].startswith(f"duckie: {start}"), said[0]
    assert said[0].endswith("."), said[0]


@pytest.mark.parametrize(
    ("out", "said"),
    [
        ("/proc/x", "Cannot create the folder /proc/x for the run's files (No such file or "),
        ("/dev/null", "/dev/null is a file, not a folder: choose a folder for the run's files"),
    ],
)
def test_a_folder_the_run_cannot_write_to_is_one_sentence(out, said):
    result = duckie("mission", "--out", out, "--no-animation")
    assert_one_sentence(result, 1, said)


def test_a_negative_seed_is_refused_by_the_command_line():
    result = duckie("mission", "--seed", "-1")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.splitlines()[-1] == (
        "duckie mission: error: argument --seed: give a whole number 0 or more, not '-1'"
    )


@pytest.mark.parametrize("given", ["0", "-2", "soon", "inf"])
def test_a_stall_limit_that_is_not_a_duration_is_refused(given):
    result = duckie("mission", "--stall-limit", given)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.splitlines()[-1] == (
        f"duckie mission: error: argument --stall-limit: give a number of seconds above 0, "
        f"not '{given}'"
    )


def test_an_unknown_stop_colour_is_refused_naming_the_option_and_the_patterns():
    result = duckie("mission", "--stop-color", "PINK")
    assert result.returncode == 2
    last = result.stderr.splitlines()[-1]
    assert last.startswith("duckie mission: error: argument --stop-color: give an LED pattern's")
    assert "RED, GREEN, BLUE" in last
    assert last.endswith("not 'PINK'")


@pytest.mark.parametrize("call", ["sys.exit(3)", "exit()"])
def test_a_solution_that_exits_while_imported_is_named(tmp_path, call):
    solution = tmp_path / "mine.py"
    solution.write_text(f"import sys\n\n{call}\n")
    result = duckie("mission", "--solution", str(solution), "--out", str(tmp_path / "run"))
    assert_one_sentence(
        result,
        1,
        f"The solution from {solution} called sys.exit() or exit() while being imported: ",
    )
    assert not (tmp_path / "run").exists()


def test_sigterm_during_the_drive_ends_as_ctrl_c_does(tmp_path):
    from duckielib.bags import Bag

    # SIGTERM once the simulated clock passes 10 s, as `kill` or a job scheduler sends it.
    patch = (
        "from duckielib.sim.simulator import Simulator\n"
        "advance = Simulator._advance\n"
        "def _advance(self, count):\n"
        "    advance(self, count)\n"
        "    if self._steps * self.dt >= 10.0 and not getattr(self, 'sent', False):\n"
        "        self.sent = True\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "Simulator._advance = _advance\n"
    )
    result = _interrupted_mission(tmp_path, patch)
    assert (result.returncode, result.stderr) == (
        143,
        "duckie: stopped by SIGTERM (a request to end).\n",
    )
    assert not (tmp_path / "mission.bag.active").exists()
    executed = Bag(tmp_path / "mission.bag").read(
        "/duckiebot/wheels_driver_node/wheels_cmd_executed"
    )
    assert 9.9 < executed[-1].time < 10.5
    assert (executed[-1].message.vel_left, executed[-1].message.vel_right) == (0.0, 0.0)


def test_a_recording_cut_off_by_a_killed_run_is_kept_and_said(tmp_path):
    cut_off = b"#ROSBAG V2.0\n" + b"\0" * 100
    (tmp_path / "mission.bag.active").write_bytes(cut_off)
    (tmp_path / "unfinished-1.bag.active").write_bytes(b"an earlier one")
    result = duckie("mission", "--out", str(tmp_path), "--no-animation")
    assert result.returncode == 0, result.stderr
    kept = tmp_path / "unfinished-2.bag.active"
    assert kept.read_bytes() == cut_off
    assert (tmp_path / "unfinished-1.bag.active").read_bytes() == b"an earlier one"
    assert (
        f"note: {tmp_path / 'mission.bag.active'} is a recording that was cut off before it "
        f"finished; it is kept as {kept}, and 'duckie bag repair {kept} "
        f"{tmp_path / 'unfinished-2.bag'}' recovers its messages.\n"
    ) in result.stdout
    assert (tmp_path / "mission.bag").exists()


def test_no_error_sentence_repeats_its_full_stop(tmp_path):
    # Messages that end with another error's text (a library's, a student's) must not end
    # with ".." where that text has its own full stop.
    broken = tmp_path / "broken.bag"
    broken.write_bytes(b"#ROSBAG V2.0\nxx")
    failing = tmp_path / "failing.py"
    failing.write_text('raise ValueError("Bad value.")\n')
    sample = str(_sample_bag())
    solution = tmp_path / "ticks.py"
    solution.write_text(
        (ROOT / "tests" / "bags" / "bagtools.py").read_text()
        + "\n\ndef delta_phi(ticks, prev_ticks, resolution):\n"
        + '    raise ValueError("Ticks went wrong.")\n'
    )
    commands = [
        ("bag", "info", str(broken)),
        ("bag", "odometry", sample, "--solution", str(solution)),
        ("mission", "--solution", str(failing), "--out", str(tmp_path / "run")),
        ("mission", "--out", "/dev/null"),
    ]
    for command in commands:
        result = duckie(*command)
        assert result.returncode == 1, (command, result.stderr)
        (said,) = result.stderr.splitlines()
        assert said.startswith("duckie: ")
        assert re.search(r"(?<!\.)\.\.(?!\.)", said) is None, said
        assert said.endswith("."), said
    assert said.startswith("duckie: /dev/null is a file")


def _sample_bag():
    from duckielib.bags import sample_bag

    return sample_bag()


def test_the_quick_starts_sample_output_is_what_the_mission_prints(tmp_path):
    # The README shows what `make run` prints: each line it shows (`...` stands for the rest)
    # is a line of the real printout, in the same order.
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    sample = re.search(r"and prints:\n\n```text\n(.*?)```", readme, re.S)
    assert sample is not None
    shown = [line for line in sample[1].splitlines() if line.strip() != "..."]
    command = ["mission", "--out", str(tmp_path), "--no-animation", "--no-figure"]
    result = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", *command],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    printed = result.stdout.splitlines()
    at = [printed.index(line) if line in printed else -1 for line in shown]
    assert -1 not in at, f"the README shows lines the run does not print: {shown} vs {printed}"
    assert at == sorted(at)
