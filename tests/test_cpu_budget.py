"""What `make test` says of the suite's cost: its costliest modules, each area and its budget."""

from __future__ import annotations

from cpu_budget import BUDGETS, Meter, area_of, busy_line, cpu_seconds, machine_ticks, summary


def test_each_module_belongs_to_one_area_with_a_budget():
    assert area_of("tests/adversarial/test_class.py") == "attacks on the grader"
    assert area_of("tests/autograder/test_hub.py") == "the class hub"
    assert area_of("tests/autograder/test_grade.py") == "grading"
    assert area_of("tests/course/test_course_run_all.py") == "the course's notebooks"
    assert area_of("tests/test_purity.py") == "the library"
    assert {area_of(module) for module in ("tests/x.py", "tests/sim/x.py")} <= set(BUDGETS)


def test_the_summary_names_the_costliest_modules_and_the_areas_over_their_budget():
    meter = Meter()
    meter.add("tests/sim/test_live.py", 10.0)
    meter.merge({"tests/adversarial/test_class.py": 400.0, "tests/sim/test_live.py": 30.0})
    lines = summary(meter.by_module, pace=2.0, most=1)
    assert lines[0].startswith("CPU seconds by test module")
    assert "440 s in all, 220 s at pace 1" in lines[0]
    assert lines[1].split() == ["400", "tests/adversarial/test_class.py"]
    assert lines[2].split()[:3] == ["40", "the", "other"]
    # At pace 1: the attacks cost 200 of their budget of 155; the simulator 20 of 25.
    attacks = next(line for line in lines if line.endswith("OVER"))
    assert attacks.split()[:3] == ["200", "of", "155"]
    assert lines[-1] == (
        "Over budget: attacks on the grader (README, The suite's budget: a new test of a heavy "
        "kind joins a shared run)."
    )
    assert summary({}, pace=1.0) == []


def test_a_process_counts_what_it_and_its_children_spent():
    import subprocess
    import sys

    before = cpu_seconds()
    subprocess.run([sys.executable, "-c", "sum(range(3_000_000))"], check=True)
    assert cpu_seconds() - before > 0.05


def test_the_run_says_how_busy_the_machine_was():
    import subprocess
    import sys

    before = machine_ticks()
    subprocess.run([sys.executable, "-c", "sum(range(3_000_000))"], check=True)
    after = machine_ticks()
    assert 0 < after[0] - before[0] <= after[1] - before[1]
    assert busy_line((100, 400), (250, 600), 2) == (
        "The machine's 2 CPUs were busy 75% of the run (every process on it, the suite's and "
        "any other)."
    )
    assert busy_line(before, before, 2) == ""
