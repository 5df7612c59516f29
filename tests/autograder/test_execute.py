"""Tests of the sandbox's server: a notebook run as the sandbox runs it, with a forked kernel.

The server (``autograder/sandbox/inside``) runs here outside the sandbox, with the sandbox's
thread settings. Each case runs with the kernel forked from the zygote and, where the two must
agree, also launched the usual way (``DUCKIE_KERNEL_ZYGOTE=0``), and compares what the notebook
shows.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import nbformat
import pytest
from pace import seconds as paced

from autograder.sandbox.inside.notebook import METADATA_KEY, NOT_RUN
from autograder.sandbox.inside.zygote import ZYGOTE_VARIABLE
from autograder.sandbox.server import RUNNER

pytestmark = pytest.mark.notebook

#: Printed by a first cell: whether the kernel was forked (the zygote imported duckielib.plots).
FORKED = "import sys\nprint('duckielib.plots' in sys.modules)"
DIED = "the kernel died"


def _notebook(cells: Sequence[str], tests: Sequence[int] = ()) -> str:
    """A notebook of code cells; those whose index is in ``tests`` are graded test cells."""
    notebook = nbformat.v4.new_notebook()
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    for index, source in enumerate(cells):
        cell = nbformat.v4.new_code_cell(source)
        if index in tests:
            cell.metadata["nbgrader"] = {
                "grade": True,
                "grade_id": f"test_{index}",
                "points": 1,
                "solution": False,
                "locked": True,
            }
        notebook.cells.append(cell)
    return nbformat.writes(notebook)


def _run(
    folder: Path,
    cells: Sequence[str],
    forked: bool = True,
    seconds: int = paced(10),
    tests: Sequence[int] = (),
    backend: Optional[str] = "Agg",
) -> nbformat.NotebookNode:
    """Run the server on the notebook of ``cells`` in ``folder``; the executed notebook."""
    env = {key: value for key, value in os.environ.items() if key != "MPLBACKEND"}
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env[ZYGOTE_VARIABLE] = "1" if forked else "0"
    if backend is not None:
        env["MPLBACKEND"] = backend
    result = subprocess.run(
        [sys.executable, str(RUNNER), str(seconds)],
        input=_notebook(cells, tests),
        capture_output=True,
        text=True,
        cwd=folder,
        env=env,
        timeout=120,
        check=True,
    )
    return nbformat.reads(result.stdout, as_version=4)


def _texts(notebook: nbformat.NotebookNode) -> List[str]:
    """Each cell's printed text."""
    return [
        "".join(out.get("text", "") for out in cell.outputs if out.output_type == "stream")
        for cell in notebook.cells
    ]


def _shape(notebook: nbformat.NotebookNode) -> Tuple[List[str], List[List[Tuple[str, str]]]]:
    """The grader's problems, and each cell's outputs as (type, error name or stream text)."""
    cells = [
        [(out.output_type, out.get("ename") or out.get("text", "")) for out in cell.outputs]
        for cell in notebook.cells
    ]
    return notebook.metadata[METADATA_KEY]["problems"], cells


def _outputs(notebook: nbformat.NotebookNode) -> List[List[Dict[str, object]]]:
    """Each cell's outputs without their metadata (display ids, and so on)."""
    return [
        [{key: value for key, value in out.items() if key != "metadata"} for out in cell.outputs]
        for cell in notebook.cells
    ]


@pytest.mark.parametrize("forked", [True, False])
def test_the_zygote_is_used_unless_turned_off(tmp_path: Path, forked: bool) -> None:
    notebook = _run(tmp_path, [FORKED], forked=forked)
    assert _texts(notebook) == [f"{forked}\n"]


def test_a_forked_kernel_starts_as_a_new_one(tmp_path: Path) -> None:
    probe = [
        "import os, sys\nprint(__name__)\nprint(os.getcwd())",
        "print(sys.path)\nprint(sys.argv[0], sys.argv[1], sys.argv[3:], sys.orig_argv[1:3])",
        "print(sorted(name for name in dir() if not name.startswith('_')))",
        "print(os.getpgid(0) == os.getpid(), os.environ['JPY_PARENT_PID'] == str(os.getppid()))",
        "import stat\nprint(stat.S_ISFIFO(os.fstat(0).st_mode), sys.stdin.read())",
        "print(sorted(os.listdir('/proc/self/fd'), key=int))",
        "import signal\nprint(signal.getsignal(signal.SIGCHLD), signal.getsignal(signal.SIGTERM))",
        "import matplotlib\nprint(matplotlib.rcParams['backend'])",
    ]
    forked = _texts(_run(tmp_path, [FORKED, *probe], forked=True))
    usual = _texts(_run(tmp_path, [FORKED, *probe], forked=False))
    assert forked[0] == "True\n"
    assert usual[0] == "False\n"
    assert forked[1] == f"__main__\n{tmp_path}\n"
    assert forked[2].startswith("[")
    assert str(RUNNER) not in forked[2]
    assert str(RUNNER.parent) not in forked[2]
    assert forked[4] == "True True\n"
    assert forked[1:] == usual[1:]


def test_the_guard_works_in_a_forked_kernel(tmp_path: Path) -> None:
    cells = [
        FORKED,
        "import numpy as np\nnp.allclose = lambda *a, **k: True",
        "assert not np.allclose(1, 2)\nprint('tested')",
    ]
    notebook = _run(tmp_path, cells, tests=[2])
    assert _texts(notebook) == ["True\n", "", "tested\n"]
    (problem,) = notebook.metadata[METADATA_KEY]["problems"]
    assert "before test_2" in problem
    assert "numpy.allclose" in problem


def test_a_student_numpy_does_not_stand_in_for_numpy(tmp_path: Path) -> None:
    (tmp_path / "numpy.py").write_text("allclose = lambda *a, **k: True\n")
    cells = [FORKED, "import numpy as np\nprint(np.allclose(1, 2), np.__file__ != 'numpy.py')"]
    assert _texts(_run(tmp_path, cells)) == ["True\n", "False True\n"]


@pytest.mark.parametrize(
    "death",
    [
        "import os\nos._exit(0)",
        "import ctypes\nctypes.string_at(0)",
        "import sys\nsys.exit(3)",
        "exit()",
    ],
    ids=["os._exit", "segfault", "sys.exit", "exit"],
)
def test_a_kernel_that_ends_is_reported_as_with_the_usual_launch(
    tmp_path: Path, death: str
) -> None:
    cells = ["print(1)", death, "print(2)", "print(3)"]
    forked = _shape(_run(tmp_path, [FORKED, *cells], forked=True))
    usual = _shape(_run(tmp_path, [FORKED, *cells], forked=False))
    assert forked[1][0] == [("stream", "True\n")]
    assert forked[0] == usual[0]
    assert forked[1][1] == usual[1][1]
    assert forked[1][3:] == usual[1][3:]
    # A kernel that dies at once may do so before it says it started the cell (either launch).
    unsure = ([], [("error", NOT_RUN)])
    assert forked[1][2] == usual[1][2] or (forked[1][2] in unsure and usual[1][2] in unsure)


@pytest.mark.parametrize("death", ["import os\nos._exit(0)", "import ctypes\nctypes.string_at(0)"])
def test_a_dead_kernel_marks_the_cells_after_it_not_run(tmp_path: Path, death: str) -> None:
    problems, cells = _shape(_run(tmp_path, [FORKED, "print(1)", death, "print(2)"]))
    assert len(problems) == 1
    assert problems[0].startswith(DIED)
    assert cells[:2] == [[("stream", "True\n")], [("stream", "1\n")]]
    assert cells[2] in ([], [("error", NOT_RUN)])  # it may die before it says it started
    assert cells[3] == [("error", NOT_RUN)]


def test_an_endless_cell_is_interrupted_and_the_next_one_runs(tmp_path: Path) -> None:
    cells = [FORKED, "while True:\n    pass", "print('after')"]
    forked = _shape(_run(tmp_path, cells, seconds=paced(2)))
    usual = _shape(_run(tmp_path, cells, seconds=paced(2), forked=False))
    assert forked[0] == []
    assert ("error", "CellTimeoutError") in forked[1][1]
    assert forked[1][2] == [("stream", "after\n")]
    assert forked[1][1:] == usual[1][1:]


def test_the_kernel_ends_with_the_script(tmp_path: Path) -> None:
    cells = [FORKED, "import os\nprint(os.getpid())"]
    pid = int(_texts(_run(tmp_path, cells))[1])
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


@pytest.mark.parametrize("backend", [None, "Agg"], ids=["inline", "Agg"])
def test_figures_show_as_with_the_usual_launch(tmp_path: Path, backend: Optional[str]) -> None:
    cells = [
        FORKED,
        "import matplotlib.pyplot as plt\nplt.plot([0, 1], [1, 0])\nplt.show()",
        "from IPython.display import display\nfig, ax = plt.subplots()\nax.plot([0, 1])\n"
        "display(fig)\nplt.close(fig)",
        "import io\nfrom IPython.display import Image\nbuffer = io.BytesIO()\n"
        "fig.savefig(buffer, format='png')\ndisplay(Image(buffer.getvalue()))",
        "from duckielib.plots import plot_path\nprint(plot_path.__module__)",
    ]
    forked = _outputs(_run(tmp_path, cells, forked=True, backend=backend))
    usual = _outputs(_run(tmp_path, cells, forked=False, backend=backend))
    assert forked[0] != usual[0]
    assert forked[1:] == usual[1:]
    shown = [[sorted(out.get("data", {})) for out in cell] for cell in forked[1:4]]
    picture = [["image/png", "text/plain"]]
    if backend is None:  # ipykernel's inline backend shows every figure
        assert shown == [picture, picture, picture]
    else:
        assert shown == [[], [["text/plain"]], picture]


def test_the_zygote_refuses_a_kernel_of_another_environment() -> None:
    script = (
        "from autograder.sandbox.inside.zygote import Zygote\n"
        "zygote = Zygote.start()\n"
        "print(zygote.launch(['python'], None, {'ONLY': 'this'}))\n"
        "zygote.close()\n"
        "print(zygote.launch(['python'], None, {}))\n"
    )
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    result = subprocess.run(
        [sys.executable, "-c", script],
        check=False,
        capture_output=True,
        text=True,
        env=env,
        cwd=RUNNER.parents[2],
        timeout=120,
    )
    assert result.stdout.split() == ["None", "None"], result.stderr


def _serve(tmp_path: Path, notebooks: Sequence[Tuple[str, str]], sandboxed: bool) -> List[dict]:
    """Run ``(folder, notebook text)`` pairs through one server (``--serve``); its replies."""
    from autograder.sandbox import NOBODY, Limits, sandboxed_command
    from autograder.sandbox.inside.wire import frame, read_frame

    command = [sys.executable, str(RUNNER), "--serve", "20"]
    for folder, _ in notebooks:
        (tmp_path / folder).mkdir(exist_ok=True)
    if sandboxed:
        for path in [tmp_path, *tmp_path.iterdir()]:
            os.chown(path, NOBODY, NOBODY)
        command = sandboxed_command([*command, "--sandboxed"], tmp_path, Limits(), course=tmp_path)
    requests = b"".join(
        frame(json.dumps({"folder": folder, "notebook": text}).encode())
        for folder, text in notebooks
    )
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    done = subprocess.run(
        command,
        input=requests,
        capture_output=True,
        timeout=180,
        cwd=tmp_path,
        env=env,
        check=False,
    )
    stream = io.BytesIO(done.stdout)
    replies = []
    while (data := read_frame(stream)) is not None:
        replies.append(json.loads(data))
    assert len(replies) == len(notebooks), done.stderr.decode()
    return replies


def _printed(reply: dict) -> List[str]:
    notebook = nbformat.reads(reply["notebook"], as_version=4)
    return [
        "".join(output.get("text", "") for output in cell.outputs if output.output_type == "stream")
        for cell in notebook.cells
    ]


def test_one_server_runs_each_notebook_in_a_new_kernel_in_its_own_folder(tmp_path):
    first = _notebook([FORKED, "import os\nsecret = 42\nprint(os.getcwd())"])
    second = _notebook([FORKED, "import os\nprint(os.getcwd(), 'secret' in globals())"])
    replies = _serve(tmp_path, [("05_odometry", first), ("06_driving", second)], sandboxed=False)
    assert _printed(replies[0]) == ["True\n", f"{tmp_path / '05_odometry'}\n"]
    assert _printed(replies[1]) == ["True\n", f"{tmp_path / '06_driving'} False\n"]


@pytest.mark.slow
def test_in_the_sandbox_what_a_notebook_leaves_running_is_gone_before_the_next(sandbox, tmp_path):
    leave = _notebook(
        ["import subprocess\nchild = subprocess.Popen(['sleep', '600'], start_new_session=True)\n"
         "open('../pid.txt', 'w').write(str(child.pid))\nprint('started')"]
    )  # fmt: skip
    look = _notebook(
        ["import os\npid = int(open('../pid.txt').read())\n"
         "try:\n    os.kill(pid, 0)\n    print('still there')\n"
         "except ProcessLookupError:\n    print('gone')"]
    )  # fmt: skip
    replies = _serve(tmp_path, [("01_a", leave), ("02_b", look)], sandboxed=True)
    assert _printed(replies[0]) == ["started\n"]
    assert _printed(replies[1]) == ["gone\n"]


def test_a_notebook_that_blocks_the_guards_note_is_still_run_and_graded(sandbox, tmp_path):
    # The note lives in the sandbox's /tmp, where the student's code may put anything: a folder
    # in its place must not cost the notebook its run.
    block = _notebook(
        ["import os\nos.mkdir('/tmp/.grader-writes')\nprint('blocked')", "print('graded')"],
        tests=[1],
    )
    (reply,) = _serve(tmp_path, [("01_a", block)], sandboxed=True)
    assert "notebook" in reply, reply
    assert _printed(reply) == ["blocked\n", "graded\n"]
    notebook = nbformat.reads(reply["notebook"], as_version=4)
    assert notebook.metadata[METADATA_KEY]["problems"] == []
