"""The rule of the untouched-release gate, on runs made up to break it in each way."""

from __future__ import annotations

from coursetools import too_early

from duckielib.tools.handin import NotebookRun, RaisedCell


def made_up_run(stop_number, kind="code", error="NameError: name 'x' is not defined"):
    run = NotebookRun(name="07_control", seconds=1.0, exercises={"PID": 15, "go_to_point": 35})
    run.tests = {"test_PID": False, "test_go_to_point": False}
    if stop_number is not None:
        run.raised.append(RaisedCell(stop_number, kind, None, "open_straight = ...", error))
    return run


def test_a_stop_before_the_first_exercise_is_too_early():
    # Notebook 07 as it was: a demo cell raised long before PID.
    reason = too_early(made_up_run(11, error="NodeCrashed: Node odometry_node stopped"))
    assert reason.startswith("07_control: Run All stops at cell 11 (open_straight = ...)")
    assert "before the first exercise (PID, cell 15)" in reason
    finish = "SolutionError: Finish notebook 05_odometry: write delta_phi."
    assert "before the first exercise" in too_early(made_up_run(4, error=finish))


def test_the_first_exercise_its_test_or_a_finish_sentence_may_stop_run_all():
    assert too_early(made_up_run(16, kind="test", error="NotImplementedError")) is None
    assert too_early(made_up_run(15, kind="exercise", error="SyntaxError: invalid")) is None
    finish = "SolutionError: Finish notebook 07_control: write PID first."
    assert too_early(made_up_run(16, error=finish)) is None
    fix = "SolutionError: Fix notebook 05_odometry first: delta_phi fails its visible test: ..."
    assert too_early(made_up_run(16, error=fix)) is None
    assert "before the first exercise" in too_early(made_up_run(4, error=fix))
    assert too_early(made_up_run(None)) is None


def test_a_bare_error_after_the_first_exercise_must_say_what_to_finish():
    reason = too_early(made_up_run(16, error="NotImplementedError"))
    assert "without saying which exercise to finish first" in reason


def test_a_notebook_without_exercises_must_run_to_the_end():
    run = NotebookRun(name="01_getting_started", seconds=1.0)
    assert too_early(run) is None
    run.raised.append(RaisedCell(3, "code", None, "import rospy", "ModuleNotFoundError: rospy"))
    assert too_early(run).startswith("01_getting_started has no exercise, yet Run All stops")
    run.raised.clear()
    run.stopped = "the kernel died"
    assert too_early(run) == "01_getting_started: the kernel died"


def test_a_claim_holds_only_with_its_words_and_numbers_that_back_it():
    from claims import Claim, check_claim

    claim = Claim(
        says="The trim straightens the robot.",
        printed=r"drift (?P<before>[-\d.]+) cm before, (?P<after>[-\d.]+) cm after",
        holds=lambda before, after: abs(after) < 0.5 * abs(before),
        meaning="the drift at least halves",
    )
    markdown = "Look at the figure.  The trim\nstraightens the robot. Then..."
    assert check_claim(claim, markdown, "drift 3.1 cm before, 0.4 cm after\n") is None
    broken = check_claim(claim, markdown, "drift 3.1 cm before, 2.9 cm after\n")
    assert broken == (
        "'The trim straightens the robot.' (the drift at least halves) does not hold: "
        "before = 3.1, after = 2.9"
    )
    assert check_claim(claim, "The trim helps.", "drift 3.1 cm before, 0.4 cm after").startswith(
        "the text no longer says 'The trim straightens the robot.'"
    )
    assert check_claim(claim, markdown, "no numbers").startswith("nothing printed matches")
