"""``make lab`` opens the course as a student meets it, checked over its API and in Chromium.

The browser test drives Debian's Chromium with Playwright: it opens JupyterLab as ``make lab``
starts it, on a copy of the course filled with the reference answers, runs notebook 07 with
Run > Run All Cells, and checks that no cell shows an error, as a student would see it; then
it clicks Validate, which the students' configuration makes look at every cell.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import time
import urllib.error
import urllib.request
import warnings

import nbformat
import pytest
from coursetools import NAMES, reference_answers, student_copy
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from autograder.course import ROOT

pytestmark = [pytest.mark.slow, pytest.mark.notebook]

TOKEN = "course-lab-test"


def free_port():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def get(port, path):
    url = f"http://127.0.0.1:{port}{path}?token={TOKEN}"
    with urllib.request.urlopen(url, timeout=5) as response:
        return response.read().decode()


@contextlib.contextmanager
def lab(tmp_path, root=None):
    """JupyterLab as `make lab` starts it (on ``root`` instead of the repository, if given)."""
    port = free_port()
    env = {
        **os.environ,
        "JUPYTER_RUNTIME_DIR": str(tmp_path / "runtime"),
        "JUPYTER_CONFIG_DIR": str(tmp_path / "config"),
    }
    # Every cell in the page, not only those scrolled into view, so the test reads them all;
    # and the notebook's kernel started without asking, as a student who ticked "Always start
    # the preferred kernel" in JupyterLab's "Select Kernel" dialog has it (on a loaded machine
    # JupyterLab may not find the notebook's running session in time, and asks).
    settings = tmp_path / "config" / "lab" / "user-settings" / "@jupyterlab" / "notebook-extension"
    settings.mkdir(parents=True, exist_ok=True)
    (settings / "tracker.jupyterlab-settings").write_text(
        '{"windowingMode": "none", "autoStartDefaultKernel": true}'
    )
    options = f"--no-browser --port={port} --ip=127.0.0.1 --IdentityProvider.token={TOKEN}"
    folder = [] if root is None else [f"LAB_DIR={root}"]
    server = subprocess.Popen(
        ["make", "--no-print-directory", "lab", f"LAB_ARGS={options}", *folder],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                get(port, "/api/status")
                break
            except OSError:
                assert time.monotonic() < deadline, "JupyterLab did not start within 60 s"
                time.sleep(0.5)
        yield port
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(timeout=30)


@pytest.fixture(scope="module")
def student_lab(tmp_path_factory):
    """One student's JupyterLab for the browser tests, as ``make lab`` starts it: the course
    filled with the reference answers, the README beside it. Each test opens its own
    notebooks and changes only them.

    Yields:
        The student's folder and the server's port.
    """
    folder = tmp_path_factory.mktemp("lab")
    root = folder / "student"
    student_copy(root / "course", reference_answers())
    shutil.copy(ROOT / "README.md", root / "README.md")
    with lab(folder, root) as port:
        yield root, port


def test_jupyterlab_serves_the_course_without_the_instructor_tools(tmp_path):
    with lab(tmp_path) as port:
        root = {item["name"] for item in json.loads(get(port, "/api/contents"))["content"]}
        assert {"course", "README.md"} <= root
        listing = json.loads(get(port, "/api/contents/course"))["content"]
        assert sorted(item["name"] for item in listing) == NAMES
        assert "python3" in json.loads(get(port, "/api/kernelspecs"))["kernelspecs"]
        page = get(port, "/lab")
        config = re.search(r'id="jupyter-config-data"[^>]*>(.*?)</script>', page, re.S)
        disabled = set(json.loads(config.group(1))["disabledExtensions"])
        for plugin in ("formgrader", "create-assignment", "assignment-list", "course-list"):
            assert f"@jupyter/nbgrader:{plugin}" in disabled  # instructors' tools
        assert "@jupyter/nbgrader:validate-assignment" not in disabled
        with pytest.raises(urllib.error.HTTPError, match="404"):
            get(port, "/formgrader")


#: Escape sequences a terminal sends besides the text (colours, bracketed paste mode).
ESCAPES = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def test_duckie_runs_in_a_terminal_of_jupyterlab(student_lab):
    # `make lab` puts .venv/bin first on the server's PATH. Started without a terminal (as
    # here: its output goes nowhere), the server once opened login shells, whose profile
    # (/etc/profile) set PATH anew: `duckie handin` was "command not found" there.
    import websocket  # websocket-client, which jupyter_server uses

    _, port = student_lab
    request = urllib.request.Request(
        f"http://127.0.0.1:{port}/api/terminals",
        method="POST",
        headers={"Authorization": f"token {TOKEN}"},
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        name = json.loads(response.read())["name"]
    terminal = websocket.create_connection(
        f"ws://127.0.0.1:{port}/terminals/websocket/{name}?token={TOKEN}", timeout=30
    )
    try:
        terminal.send(json.dumps(["stdin", 'echo "duckie=$(command -v duckie) path=$PATH"\r']))
        shown, said = "", []
        deadline = time.monotonic() + 30
        while not said:
            assert time.monotonic() < deadline, f"the terminal did not answer: {shown!r}"
            kind, *text = json.loads(terminal.recv())
            shown += text[0] if kind == "stdout" else ""
            lines = re.split(r"[\r\n]+", ESCAPES.sub("", shown))
            said = [line for line in lines[:-1] if line.startswith("duckie=")]
    finally:
        terminal.close()
        request.method = "DELETE"
        request.full_url += f"/{name}"
        urllib.request.urlopen(request, timeout=10).close()
    duckie, path = re.fullmatch(r"duckie=(.*) path=(.*)", said[0]).groups()
    venv = str(ROOT / ".venv" / "bin")
    assert duckie == f"{venv}/duckie"
    folders = path.split(":")
    assert folders.index(venv) < folders.index("/usr/bin"), path  # before the system's


#: The notebook on screen (the others stay in the page, hidden), its prompts and its errors.
SHOWN = ".jp-NotebookPanel:not(.lm-mod-hidden)"
PROMPTS = f"{SHOWN} .jp-CodeCell .jp-InputPrompt"
STDERR = f"{SHOWN} .jp-RenderedText[data-mime-type='application/vnd.jupyter.stderr']"

#: Run All is over: no cell waits ([*]), and every cell has run or one raised (Run All stops).
FINISHED = """([prompts, stderr]) => {
    const shown = [...document.querySelectorAll(prompts)].map((prompt) => prompt.textContent);
    if (shown.length === 0 || shown.some((prompt) => prompt.includes("*"))) return false;
    return shown.every((prompt) => /\\[\\d+\\]/.test(prompt)) || !!document.querySelector(stderr);
}"""

#: Some cell is queued or running ([*]).
WAITING = """(prompts) => [...document.querySelectorAll(prompts)]
    .some((prompt) => prompt.textContent.includes("*"))"""

#: How often the page is asked whether Run All has begun or ended, in ms (by default it is
#: asked at every frame drawn, which keeps the browser busy while the kernel works).
POLL_MS = 200

#: Run All has begun: some cell waits or has run.
STARTED = """(prompts) => [...document.querySelectorAll(prompts)]
    .some((prompt) => /\\[(\\*|\\d+)\\]/.test(prompt.textContent))"""


def _session_ready(port, path, seconds=180):
    """Start the notebook's kernel through the server's API (it answers once it is started).

    The page then finds its session running. Left to the page, a kernel slow to start (a
    loaded machine) makes JupyterLab ask which kernel to start, in a dialog.
    """
    body = json.dumps(
        {"path": path, "type": "notebook", "name": "", "kernel": {"name": "python3"}}
    ).encode()
    request = urllib.request.Request(
        f"http://127.0.0.1:{port}/api/sessions?token={TOKEN}",
        data=body,
        method="POST",
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(request, timeout=seconds) as response:
        assert json.loads(response.read())["kernel"]["name"] == "python3"


def _take_the_notebooks_kernel(page, name):
    """In JupyterLab's "Select Kernel" dialog, take the kernel already running for the notebook.

    The dialog lists it (``09_mission.ipynb (0b930269)``) below the kernels it would start; a
    student picks it, and so does the test. If it is not listed, the dialog's default is taken.
    """
    dialog = page.locator(".jp-Dialog").first
    options = dialog.locator("select option")
    for index in range(options.count()):
        if options.nth(index).inner_text().startswith(f"{name}.ipynb ("):
            dialog.locator("select").first.select_option(index=index)
            break
    dialog.locator(".jp-mod-accept").first.click()
    dialog.wait_for(state="detached", timeout=20_000)


def _wait_until_run_all_is_over(page, name, seconds=180.0):
    """Wait until Run All is over; if it stopped short, with nothing left waiting, run it again.

    On a loaded machine JupyterLab can drop the queued cells after the first one (their
    prompts go back to ``[ ]`` with the kernel idle); a student clicks Run All again, and so
    does the test, twice at most, saying so in a warning.
    """
    deadline = time.monotonic() + seconds
    for again in range(3):
        left = max(1.0, deadline - time.monotonic())
        page.wait_for_function(
            f"(args) => ({FINISHED})(args) || !({WAITING})(args[0])",
            arg=[PROMPTS, STDERR],
            polling=POLL_MS,
            timeout=left * 1000,
        )
        page.wait_for_timeout(2000)  # nothing waiting for 2 s: not a gap between two cells
        if page.evaluate(FINISHED, [PROMPTS, STDERR]) or page.evaluate(WAITING, PROMPTS):
            page.wait_for_function(
                FINISHED,
                arg=[PROMPTS, STDERR],
                polling=POLL_MS,
                timeout=max(1.0, deadline - time.monotonic()) * 1000,
            )
            return
        if again < 2:
            warnings.warn(
                f"{name}: Run All stopped short with nothing waiting; ran it again", stacklevel=3
            )
            page.locator(".lm-MenuBar-itemLabel", has_text="Run").click(timeout=20_000)
            page.locator(".lm-Menu-itemLabel", has_text="Run All Cells").first.click()
            page.wait_for_function(WAITING, arg=PROMPTS, polling=POLL_MS, timeout=20_000)
    page.wait_for_function(FINISHED, arg=[PROMPTS, STDERR], polling=POLL_MS, timeout=1000)


def run_all_in_the_browser(page, port, name):
    """Open a notebook of course/ alone, Run > Run All Cells, wait until Run All is over.

    ``reset`` starts from an empty workspace: the notebooks opened before are not restored
    beside it.
    """
    _session_ready(port, f"course/{name}/{name}.ipynb")
    page.goto(f"http://127.0.0.1:{port}/lab/tree/course/{name}/{name}.ipynb?reset&token={TOKEN}")
    idle = f"{SHOWN} .jp-Notebook-ExecutionIndicator[data-status='idle']"
    page.wait_for_selector(idle, timeout=60_000)
    dialogs = []
    for _ in range(3):  # a click while the page is still settling can be lost: click again
        try:
            page.locator(".lm-MenuBar-itemLabel", has_text="Run").click(timeout=20_000)
            page.locator(".lm-Menu-itemLabel", has_text="Run All Cells").first.click()
            page.wait_for_function(STARTED, arg=PROMPTS, polling=POLL_MS, timeout=20_000)
            break
        except PlaywrightTimeout:
            # A dialog JupyterLab opened in the way: its words are kept, and said if Run All
            # never begins. A student takes the kernel it offers (Python 3), and closes others.
            shown = page.locator(".jp-Dialog").all_inner_texts()
            dialogs += shown
            if any(text.startswith("Select Kernel") for text in shown):
                _take_the_notebooks_kernel(page, name)
                page.wait_for_selector(idle, timeout=60_000)  # the kernel taken has started
            else:
                page.keyboard.press("Escape")
    else:
        pytest.fail(f"Run All of {name} never began; dialogs: {dialogs or 'none'}")
    if dialogs:
        warnings.warn(f"{name}: JupyterLab showed a dialog before Run All: {dialogs}", stacklevel=2)
    try:
        _wait_until_run_all_is_over(page, name)
    except PlaywrightTimeout:
        # Say where it stood: which cells waited, what the kernel was doing, what dialog was up.
        prompts = page.locator(PROMPTS).all_inner_texts()
        waiting = [i for i, prompt in enumerate(prompts) if "*" in prompt]
        never = [i for i, prompt in enumerate(prompts) if not re.search(r"\[\d+\]", prompt)]
        status = page.locator(f"{SHOWN} .jp-Notebook-ExecutionIndicator").get_attribute(
            "data-status"
        )
        pytest.fail(
            f"Run All of {name} did not end within 180 s: kernel {status}, code cells "
            f"waiting {waiting}, never run {never} of {len(prompts)}; dialogs "
            f"{page.locator('.jp-Dialog').all_inner_texts() or 'none'}"
        )


def test_run_all_in_jupyterlab_runs_notebook_07_without_an_error(student_lab, browser):
    # Notebook 07 once raised in 9 cells under Run All while every other check passed.
    root, port = student_lab
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.goto(f"http://127.0.0.1:{port}/lab?reset&token={TOKEN}")
    page.wait_for_selector(".jp-DirListing-item", timeout=60_000)
    menus = page.locator(".lm-MenuBar-itemLabel").all_inner_texts()
    assert "Nbgrader" not in menus  # no instructor tools, no assignment list
    run_all_in_the_browser(page, port, "07_control")
    assert page.locator(STDERR).all_inner_texts() == [], "cells of 07_control showed errors"
    # Validate, as a student clicks it: the whole notebook, every cell, passes.
    page.locator(".jp-NotebookPanel-toolbar").get_by_text("Validate").click()
    dialog = page.locator(".jp-Dialog")
    dialog.wait_for(timeout=180_000)
    assert "Success! Your notebook passes all the tests." in dialog.inner_text()
    dialog.get_by_role("button", name="Ok").click()
    # What JupyterLab ran, saved as the student would save it: every cell, no error.
    page.keyboard.press("Control+s")
    path = root / "course" / "07_control" / "07_control.ipynb"
    deadline = time.monotonic() + 30
    saved = _saved(path)
    while not any(cell.get("outputs") for cell in saved["cells"]):
        assert time.monotonic() < deadline, "the notebook was not saved within 30 s"
        time.sleep(0.5)
        saved = _saved(path)
    code = [c for c in saved["cells"] if c["cell_type"] == "code"]
    assert [i for i, c in enumerate(code) if c["execution_count"] is None] == []
    raised = [o["ename"] for c in code for o in c["outputs"] if o["output_type"] == "error"]
    assert raised == []

    # Notebook 01 links the README: it opens in JupyterLab from the notebook.
    page.goto(
        f"http://127.0.0.1:{port}/lab/tree/course/01_getting_started/"
        f"01_getting_started.ipynb?token={TOKEN}"
    )
    page.locator(".jp-RenderedMarkdown a", has_text="README").first.click()
    page.wait_for_selector(".lm-TabBar-tabLabel:text-is('README.md')", timeout=30_000)
    page.close()


def _saved(path):
    """The notebook at ``path`` as JSON; no cells while JupyterLab is still writing it."""
    try:
        return json.loads(path.read_text())
    except ValueError:  # caught half-written
        return {"cells": []}


def test_validate_for_students_reports_any_cell_that_raises_not_only_the_tests(tmp_path):
    # nbgrader's Validate looks at the test cells only, unless told otherwise: the students'
    # configuration (duckielib/lab/, which `make lab` starts with) tells it to look at all.
    from nbgrader.validator import Validator
    from traitlets.config.loader import JSONFileConfigLoader

    notebook = nbformat.v4.new_notebook()
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    test = nbformat.v4.new_code_cell("assert 1 + 1 == 2")
    test.metadata["nbgrader"] = {
        "grade": True,
        "grade_id": "test_sum",
        "locked": True,
        "points": 1,
        "solution": False,
        "schema_version": 3,
    }
    notebook.cells = [nbformat.v4.new_code_cell("open_straight[0]"), test]
    path = tmp_path / "07_control.ipynb"
    nbformat.write(notebook, path)
    assert Validator().validate(str(path)) == {}  # nbgrader's own default: "Success!"
    config = JSONFileConfigLoader(
        "nbgrader_config.json", str(ROOT / "duckielib" / "lab")
    ).load_config()
    (failed,) = Validator(config=config).validate(str(path))["failed"]
    assert failed["source"] == "open_straight[0]"
    assert "NameError" in failed["error"]


#: The widgets each notebook shows: the run player, the camera's image view.
WIDGETS = {
    "02_ros_concepts": (".duckie-image-view", ".duckie-player"),
    "09_mission": (".duckie-player",),
    "10_bag_analysis": (".duckie-player",),
}


def test_a_student_runs_the_lab_report_notebooks_and_writes_an_answer(
    student_lab, tmp_path, browser
):
    # The notebooks with answers in words, as a student who finished the code meets them: Run
    # All shows no error; an answer typed into YOUR ANSWER HERE is saved into its answer cell
    # and waits for a person when the student is graded.
    root, port = student_lab
    typed = "My odometry ended 3.1 cm and 2 deg from the truth on the realistic robot."
    for name in ("02_ros_concepts", "06_driving", "09_mission", "10_bag_analysis"):
        # A page of its own for each notebook, as a student who opens one at a time.
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        try:
            run_all_in_the_browser(page, port, name)
        except PlaywrightTimeout:
            page.screenshot(path=str(tmp_path / f"{name}.png"), full_page=True)
            pytest.fail(f"Run All of {name} did not end; see {tmp_path / name}.png")
        assert page.locator(STDERR).all_inner_texts() == [], f"cells of {name} showed errors"
        for widget in WIDGETS.get(name, ()):  # the players and views drew their pictures
            shown = page.locator(f"{SHOWN} {widget} img").first
            assert shown.get_attribute("src"), f"{name} shows no picture in its {widget}"
        if name != "10_bag_analysis":
            page.close()
    # Still in 10_bag_analysis: double-click the answer cell, type, render, save.
    cell = page.locator(f"{SHOWN} .jp-MarkdownCell", has_text="YOUR ANSWER HERE").first
    cell.scroll_into_view_if_needed()
    cell.dblclick()
    editor = cell.locator(".cm-content")
    editor.click()
    page.keyboard.press("Control+a")
    page.keyboard.type(typed)
    page.keyboard.press("Shift+Enter")
    page.keyboard.press("Control+s")
    path = root / "course" / "10_bag_analysis" / "10_bag_analysis.ipynb"
    deadline = time.monotonic() + 30
    saved = _saved(path)
    while typed not in json.dumps(saved):
        assert time.monotonic() < deadline, "the answer was not saved within 30 s"
        time.sleep(0.5)
        saved = _saved(path)
    page.close()
    (answer,) = [
        cell
        for cell in saved["cells"]
        if cell["metadata"].get("nbgrader", {}).get("grade_id") == "answer_bag_final"
    ]
    assert (answer["cell_type"], "".join(answer["source"])) == ("markdown", typed)

    from autograder.grade import grade_class
    from autograder.sandbox import Limits

    submissions = tmp_path / "submissions"
    shutil.copytree(root / "course", submissions / "ada")
    names = ["10_bag_analysis"]
    (result,) = grade_class(
        submissions, tmp_path / "out", names=names, driving=False, limits=Limits()
    )
    assert result.to_grade == [("10_bag_analysis", "answer_bag_final")]
    assert result.cells[("10_bag_analysis", "answer_theta_wrap")] == (0.0, 2.0)  # unanswered


#: A laptop's screen, 1366 by 768 pixels, leaves about 1366 by 650 to the page.
LAPTOP = {"width": 1366, "height": 650}

#: The run player's caption: "t = 12.3 s · state: square · LEDs: GREEN".
CAPTION = ".duckie-player .widget-html-content"


def test_a_student_plays_a_run_in_the_player_and_sees_the_robot_its_lights_and_its_state(
    student_lab, tmp_path, browser
):
    import io

    import numpy as np
    from PIL import Image

    from duckielib.leds import pattern_colors, pattern_named

    root, port = student_lab
    kernel = {"name": "python3", "display_name": "Python 3", "language": "python"}
    notebook = nbformat.v4.new_notebook(metadata={"kernelspec": kernel})
    notebook.cells = [
        nbformat.v4.new_code_cell(
            "from duckielib.bags import sample_bag\n"
            "from duckielib.plots import RunPlayer\n\n"
            "RunPlayer(sample_bag('square_then_circle_realistic'))"
        )
    ]
    (root / "course" / "watch").mkdir(parents=True)
    nbformat.write(notebook, root / "course" / "watch" / "watch.ipynb")
    page = browser.new_page(viewport=LAPTOP)
    run_all_in_the_browser(page, port, "watch")
    player = page.locator(f"{SHOWN} .duckie-player")
    player.wait_for(timeout=60_000)
    caption = page.locator(CAPTION)
    assert caption.inner_text().startswith("t = 0.0 s")
    play_pause = player.locator(".widget-play button").first  # ▶, then ⏸ while playing
    # On a laptop the ▶ button and the whole picture (the mat in it) are in view at once: with
    # the player scrolled to the top of the notebook, both lie inside the notebook's view.
    picture = player.locator("img").first
    page.wait_for_function(
        "(img) => img.complete && img.naturalHeight > 0", arg=picture.element_handle()
    )
    player.evaluate("(box) => box.scrollIntoView({block: 'start'})")
    view = page.locator(f"{SHOWN} .jp-WindowedPanel-outer").bounding_box()
    for what, box in (
        ("the ▶ button", play_pause.bounding_box()),
        ("the picture", picture.bounding_box()),
    ):
        inside = (
            view["x"] <= box["x"]
            and box["x"] + box["width"] <= view["x"] + view["width"]
            and view["y"] <= box["y"]
            and box["y"] + box["height"] <= view["y"] + view["height"]
        )
        assert inside, (
            f"{what} {box} is not inside the notebook's view {view} on a laptop "
            f"(the player: {player.bounding_box()})"
        )
    play_pause.click()
    # The square's first leg: green LEDs. Playing moves the slider; the kernel draws.
    page.wait_for_function(
        "(selector) => document.querySelector(selector).textContent.includes('square')",
        arg=CAPTION,
        polling=POLL_MS,
        timeout=60_000,
    )
    play_pause.click()
    page.wait_for_timeout(1500)  # the last frames asked for arrive
    paused = caption.inner_text()
    page.wait_for_timeout(1500)
    assert caption.inner_text() == paused, "the player went on after pause"
    shot = player.screenshot(path=str(tmp_path / "player.png"))
    page.close()
    t, state, lights = re.fullmatch(r"t = ([\d.]+) s · state: (\S+) · LEDs: (\S+)", paused).groups()
    assert float(t) > 0
    assert state == "square"
    assert lights == "GREEN"
    pixels = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int)
    green = np.round(np.asarray(pattern_colors(pattern_named(lights))[0]) * 255)
    chassis = np.array([0xF2, 0xC2, 0x00])
    # The chassis is drawn to scale in a view that spans the whole path: the realistic robot
    # drives a little beyond the mat, so it is about 300 pixels here.
    for color, least in ((green, 2000), (chassis, 250)):
        assert np.all(np.abs(pixels - color) <= 24, axis=2).sum() >= least, (
            f"the screenshot ({tmp_path / 'player.png'}) lacks the colour {color}"
        )
