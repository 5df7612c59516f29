"""The calls between the grader's tests and the student's kernel: plain data only, read strictly.

The kernel's side is driven here through the same ``answer`` function the sandbox calls in a
kernel, with the "kernel" a namespace of this process: what crosses is the JSON text alone.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from autograder import calls, verdict
from autograder.calls import CallsBroken, Link, Remote, decode, encode
from autograder.verdict import run_test


class FakeKernel:
    """The kernel's side of the calls, with ``names`` as the student's globals."""

    def __init__(self, names):
        self.names = names
        self.requests = []

    def send(self, request):
        self.requests.append(request)
        if request["op"] == "get":
            if request["name"] not in self.names:
                return json.dumps(
                    {"raised": {"type": "NameError", "message": "no", "traceback": []}}
                )
            value = self.names[request["name"]]
            return json.dumps({"value": encode(value, calls._keep)})
        return calls.answer(json.dumps(request))


def _link(names):
    kernel = FakeKernel(names)
    return Link(kernel.send, {}), kernel


def test_plain_values_cross_as_themselves():
    values = [
        None, True, 3, -(10**40), 2.5, math.inf, complex(1, -2), "θ", b"\x00\xff",
        [1, (2.0, "x")], {"a": [1], 2: None}, {1, 2},
    ]  # fmt: skip
    for value in values:
        assert decode(json.loads(json.dumps(encode(value, calls._keep))), None) == value
    nan = decode(encode(math.nan, calls._keep), None)
    assert math.isnan(nan)


def test_arrays_come_back_as_plain_numpy_arrays_of_their_dtype():
    class AlwaysEqual(np.ndarray):
        __hash__ = None

        def __eq__(self, other):
            return np.ones(np.shape(self), dtype=bool)

    sneaky = np.arange(6, dtype=np.float32).reshape(2, 3).view(AlwaysEqual)
    got = decode(json.loads(json.dumps(encode(sneaky, calls._keep))), None)
    assert type(got) is np.ndarray
    assert (got.dtype, got.shape) == (np.float32, (2, 3))
    assert not np.array_equal(got, np.zeros((2, 3)))
    big_endian = np.array([1.5, -2.0], dtype=">f8")
    assert decode(encode(big_endian, calls._keep), None).tolist() == [1.5, -2.0]
    scalar = decode(encode(np.float64(0.25), calls._keep), None)
    assert type(scalar) is np.float64
    assert scalar == 0.25


@pytest.mark.parametrize(
    "data",
    [
        "not a list",
        [],
        ["i", "12x"],
        ["i", "1" * 5000],
        ["f", "1" * 100],
        ["a", "<f8", [2], "AAAA"],  # 3 bytes for two doubles
        ["a", "|O", [1], ""],  # objects are never data
        ["d", [["s", "k"]]],
        ["q", 1],
        ["l", [["l", [["l", []]]]] * 2, "extra"],
    ],
)
def test_anything_else_is_refused(data):
    with pytest.raises(calls.DecodeError):
        decode(data, lambda number, kind: None)


def test_nesting_past_the_limit_is_refused():
    data = ["n"]
    for _ in range(calls.MAX_DEPTH + 5):
        data = ["l", [data]]
    with pytest.raises(calls.DecodeError, match="deeply"):
        decode(data, None)


def test_a_students_object_stays_in_the_kernel_and_never_claims_to_equal_anything():
    class Liar:
        __hash__ = None

        def __eq__(self, other):
            return True

        def value(self):
            return 7

    link, kernel = _link({"make": Liar})
    made = link.get("make")()
    assert isinstance(made, Remote)
    assert type(made).__name__ == "Liar"
    assert made != 7
    assert (made == 7) is False
    assert made.value() == 7
    # Nothing the grader compared with was sent to the kernel.
    assert all("7" not in json.dumps(request.get("args", [])) for request in kernel.requests)


def test_a_test_fails_on_a_wrong_answer_whatever_the_kernel_patched_there():
    link, _ = _link({"double": lambda x: x + 1})
    outputs = run_test(
        "import math\nassert math.isclose(double(2), 4), 'double(2) should be 4'\n",
        "test_double",
        {},
        link,
    )
    assert outputs[-1]["ename"] == "AssertionError"
    assert outputs[-1]["traceback"] == ["AssertionError: double(2) should be 4"]


def test_a_passing_test_prints_what_it_printed_and_nothing_else():
    link, _ = _link({"double": lambda x: 2 * x})
    outputs = run_test("print('checked', double(21))\n", "test_double", {}, link)
    assert outputs == [{"output_type": "stream", "name": "stdout", "text": "checked 42\n"}]


def test_the_students_error_is_raised_as_its_kind_with_the_students_traceback_only():
    def refuse(wheel):
        raise ValueError(f"no wheel {wheel!r}")

    link, _ = _link({"refuse": refuse})
    source = (
        "try:\n    refuse('middle')\nexcept ValueError:\n    pass\n"
        "else:\n    raise AssertionError('should raise')\n"
        "### BEGIN HIDDEN TESTS\nrefuse('secret input 42')\n### END HIDDEN TESTS\n"
    )
    outputs = run_test(source, "test_refuse", {}, link)
    error = outputs[-1]
    assert (error["ename"], error["evalue"]) == ("ValueError", "no wheel 'secret input 42'")
    text = "\n".join(error["traceback"])
    assert "raise ValueError" in text  # the student's own line
    assert "HIDDEN" not in text  # never the test's code
    assert "refuse('secret" not in text


def test_a_missing_function_is_a_name_error_and_a_kernel_that_answers_nonsense_fails_the_test():
    link, _ = _link({})
    outputs = run_test("wrap_angle(1.0)\n", "test_wrap", {}, link)
    assert outputs[-1]["ename"] == "NameError"

    forged = Link(lambda request: '{"value": ["h", "1", "x"], "extra": 1}', {})
    outputs = run_test("assert f(1) == 2\n", "test_f", {}, forged)
    assert outputs[-1]["ename"] == "KernelError"
    with pytest.raises(CallsBroken):
        Link(lambda request: "[1, 2", {}).get("f")
    # An answer nested a million deep is refused before any JSON reader recurses into it.
    with pytest.raises(CallsBroken, match="nests more than 64 levels deep"):
        Link(lambda request: '{"value": ' + "[" * 1_000_000, {}).get("f")


def test_the_tests_imports_and_definitions_are_the_graders():
    cells = [
        {"cell_type": "code", "metadata": {}, "source": "%matplotlib inline\nimport math as m\n"},
        {"cell_type": "code", "metadata": {"nbgrader": {"solution": True}}, "source": "import os"},
    ]
    space = verdict.prelude(cells)
    assert space["m"] is math
    assert "os" not in space
    link, kernel = _link({"m": "the student's m"})
    run_test("def helper():\n    return m.pi\n", "test_a", space, link)
    outputs = run_test("assert helper() == m.pi\n", "test_b", space, link)
    assert outputs == []
    assert kernel.requests == []  # nothing was asked of the kernel


def test_the_robots_name_a_test_sets_is_the_one_the_students_code_reads(monkeypatch):
    import os

    link, kernel = _link({"robot_topic": lambda name: f"/{os.environ['VEHICLE_NAME']}/{name}"})
    monkeypatch.setenv("VEHICLE_NAME", "outside")
    source = (
        "import os\n"
        "os.environ['VEHICLE_NAME'] = 'autobot07'\n"
        "assert robot_topic('chatter') == '/autobot07/chatter'\n"
        "del os.environ['VEHICLE_NAME']\n"
        "try:\n    robot_topic('chatter')\nexcept KeyError:\n    pass\n"
        "else:\n    raise AssertionError('should raise KeyError')\n"
        "os.environ['VEHICLE_NAME'] = 'outside'\n"
    )
    assert run_test(source, "test_robot_topic", {}, link) == []
    calls = [request for request in kernel.requests if request["op"] == "call"]
    assert [request["environment"] for request in calls] == [
        {"VEHICLE_NAME": "autobot07"},
        {"VEHICLE_NAME": None},
    ]


def test_the_kernel_serves_a_test_over_its_socket_and_keeps_its_own_robot_name(
    tmp_path, monkeypatch
):
    import os
    import socket
    import threading
    import types

    import IPython

    from autograder.sandbox.inside import wire

    space = {"robot_topic": lambda name: f"/{os.environ['VEHICLE_NAME']}/{name}"}
    monkeypatch.setattr(IPython, "get_ipython", lambda: types.SimpleNamespace(user_ns=space))
    monkeypatch.setenv("VEHICLE_NAME", "kernels_own")
    path = str(tmp_path / "socket")
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(path)
    listener.listen(1)
    serving = threading.Thread(target=calls.serve, args=(path,))
    serving.start()
    connection, _ = listener.accept()
    stream = connection.makefile("rb")

    # The relay's frames (the wire's), which the kernel's side reads with a copy of its own.
    def ask(request):
        connection.sendall(wire.frame(json.dumps(request).encode()))
        return json.loads(wire.read_frame(stream))

    handle = ask({"op": "get", "name": "robot_topic"})["value"]
    got = ask({"op": "call", "target": handle[1], "args": ["l", [["s", "chatter"]]],
               "kwargs": ["d", []], "environment": {"VEHICLE_NAME": "db21"}})  # fmt: skip
    assert got == {"value": ["s", "/db21/chatter"]}
    connection.sendall(wire.frame(b"end"))
    serving.join(timeout=10)
    assert not serving.is_alive()
    assert os.environ["VEHICLE_NAME"] == "kernels_own"
    connection.close()
    listener.close()


def test_only_the_grader_marks_the_tests_it_runs_and_none_of_their_code_is_sent():
    import nbformat

    from autograder.unit import _remote_tests

    test = {"grade": True, "solution": False, "grade_id": "test_f", "points": 1}
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [
        nbformat.v4.new_code_cell("def f(x):\n    return x", metadata={}),
        # A student's cell that claims to be a test the grader runs.
        nbformat.v4.new_code_cell("print('mine')", metadata={"duckie_grading": {"remote": True}}),
        nbformat.v4.new_code_cell("assert f(1) == 1  # SECRET", metadata={"nbgrader": test}),
        nbformat.v4.new_code_cell("assert f(2) == 2  # SECRET", metadata={"nbgrader": test}),
        nbformat.v4.new_code_cell(
            "assert f(3) == 3\n### BEGIN HIDDEN TESTS\nassert f(4) == 4  # SECRET\n",
            metadata={"nbgrader": {**test, "grade_id": "test_g"}},
        ),
    ]
    sent, tests = _remote_tests(notebook)
    assert tests == {2: "test_f", 4: "test_g"}
    assert "SECRET" not in nbformat.writes(sent)
    assert "f(3)" not in nbformat.writes(sent)
    # The sandbox learns which tests have a hidden part (it runs after the last cell).
    assert [cell.metadata.get("duckie_grading") for cell in sent.cells] == [
        None, None, {"remote": True, "hidden": False}, None, {"remote": True, "hidden": True},
    ]  # fmt: skip
    assert "SECRET" in notebook.cells[2].source  # the grader's own copy keeps the test
