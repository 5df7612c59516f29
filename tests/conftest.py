"""Shared test configuration.

In CI (the ``CI`` environment variable is set) a skipped test is a failure: everything the
suite can check must run there, including the real-ROS tests, since CI installs Debian's ROS 1
packages first. On a laptop without them, those tests are skipped with the reason.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest
from cpu_budget import Meter, busy_line, cpu_seconds, machine_ticks, summary
from pace import pace
from shared_runs import content_key

_IN_CI = os.environ.get("CI", "").lower() not in ("", "0", "false", "no")
#: Debian's Chromium, which the browser tests drive (Playwright's own download is not used).
CHROMIUM = Path("/usr/bin/chromium")


#: The test modules that take longest (their shared setup included), longest first. `make test`
#: hands whole modules to its workers (pytest-xdist's ``--dist loadscope``, so a module's
#: fixtures are made once) in this order, then the rest as collected, so that the workers end
#: together. Figures from ``pytest --durations``; a stale order costs balance, never a test.
LONGEST_FIRST = (
    "tests/course/test_course_autograde.py",
    "tests/adversarial/test_adversarial.py",
    "tests/autograder/test_hub.py",
    "tests/course/test_course_run_all.py",
    "tests/autograder/test_grade_cluster.py",
    "tests/course/test_course_lab.py",
    "tests/autograder/test_grade.py",
    "tests/adversarial/test_class.py",
    "tests/autograder/test_grade_missions.py",
    "tests/real_ros/test_robot_safety.py",
    # It reads the class test_course_autograde.py grades (a shared run): started after it.
    "tests/autograder/test_driving.py",
    "tests/autograder/test_execute.py",
    "tests/real_ros/test_robot_e2e.py",
    "tests/autograder/test_bench_grade.py",
    "tests/autograder/test_tamper.py",
    "tests/course/test_course_mistakes.py",
    "tests/autograder/test_grade_manual.py",
    "tests/tools/test_cli.py",
    "tests/tools/test_handin.py",
    "tests/autograder/test_formgrade_browser.py",
    "tests/tools/test_runner.py",
    "tests/real_ros/test_bag_replay.py",
)


def pytest_configure(config):
    # Measured before the workers start, so that they and what they run share one pace.
    config.pace = pace()
    # Likewise the key of the shared runs (tests/shared_runs.py).
    content_key()
    config.cpu_meter = Meter()
    config.machine_ticks = machine_ticks()
    # A suite started in the background (`nohup make test &`) begins with Ctrl-C ignored, and
    # every process it starts would inherit that: the tests of what Ctrl-C does need it as in
    # a terminal. (A handler, unlike "ignore", is not passed on to the processes started.)
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_report_header(config):
    return f"pace: {config.pace:.2f} (the time limits of the tests, times the reference's)"


def pytest_collection_modifyitems(config, items):
    # Each test's own time limit grows with the pace, as the limits the tests set do.
    default = config.getoption("timeout", None)
    default = config.getini("timeout") if default is None else default
    for item in items:
        marker = item.get_closest_marker("timeout")
        limit = marker.args[0] if marker is not None and marker.args else default
        if limit and config.pace > 1:
            item.add_marker(pytest.mark.timeout(float(limit) * config.pace), append=False)
    rank = {module: place for place, module in enumerate(LONGEST_FIRST)}
    # A stable sort: each module's tests stay together and in their order.
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


def pytest_xdist_make_scheduler(config, log):
    # Whole modules to each worker, as pytest-xdist's loadscope, but a worker's crash neither
    # stalls the run nor runs the crashed test again (tests/scheduling.py).
    if config.getvalue("dist") != "loadscope":
        return None
    from scheduling import CrashSafeScopes

    return CrashSafeScopes(config, log)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    # What the test costs, its setup and teardown (a module's shared ones) included.
    before = cpu_seconds()
    yield
    item.config.cpu_meter.add(item.nodeid.split("::")[0], cpu_seconds() - before)


def pytest_sessionfinish(session):
    # A pytest-xdist worker hands its figures to the controller.
    if hasattr(session.config, "workeroutput"):
        session.config.workeroutput["cpu_by_module"] = session.config.cpu_meter.by_module


def pytest_testnodedown(node, error):
    node.config.cpu_meter.merge(getattr(node, "workeroutput", {}).get("cpu_by_module", {}))


def pytest_terminal_summary(terminalreporter, config):
    for line in summary(config.cpu_meter.by_module, config.pace):
        terminalreporter.write_line(line)
    busy = busy_line(config.machine_ticks, machine_ticks(), os.cpu_count() or 1)
    if busy and config.cpu_meter.by_module:
        terminalreporter.write_line(busy)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if _IN_CI and report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[-1] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = f"Skipped in CI, where every test must run: {reason}"


@pytest.fixture(scope="session")
def sandbox():
    """The grader's bubblewrap sandbox, checked once: the tests that need it skip without it."""
    import shutil

    from autograder.sandbox import check_sandbox

    if shutil.which("bwrap") is None:
        pytest.skip("bubblewrap is not installed; run `make ros`.")
    check_sandbox()


@pytest.fixture(scope="module")
def browser():
    """Debian's Chromium, headless, driven by Playwright: the tests that need it skip without it."""
    if not CHROMIUM.exists():
        pytest.skip("Chromium is not installed; install it with `make ros`.")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as driver:
        chromium = driver.chromium.launch(
            executable_path=str(CHROMIUM),
            args=[
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
            ],
        )
        yield chromium
        chromium.close()


@pytest.fixture(scope="session")
def graded_course(sandbox, tmp_path_factory):
    """The course graded once per run for every module that reads it, whichever worker
    asks first (tests/shared_runs.py): its folder, the results by student, the mistakes."""
    from shared_runs import graded_course as grade
    from shared_runs import shared

    return shared(tmp_path_factory, "graded_course", grade)
