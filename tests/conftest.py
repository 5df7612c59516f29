"""Shared test configuration.

In CI (the ``CI`` environment variable is set) a skipped test is a failure: everything the
suite can check must run there, including the real-ROS tests, since CI installs Debian's ROS 1
packages first. On a laptop without them, those tests are skipped with the reason.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

_IN_CI = os.environ.get("CI", "").lower() not in ("", "0", "false", "no")
#: Debian's Chromium, which the browser tests drive (Playwright's own download is not used).
CHROMIUM = Path("/usr/bin/chromium")


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
