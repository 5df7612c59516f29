"""What runs inside the sandbox, piece by piece: the wire, the Jupyter seam, the guard's code.

The server as a whole runs in ``test_execute.py``; here, the parts that need no kernel.
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest

from autograder.sandbox.inside import seam, wire
from autograder.sandbox.inside.guard import WRITES_FILE, writes_outside
from autograder.sandbox.inside.notebook import module_code
from autograder.sandbox.inside.zygote import ZYGOTE_VARIABLE


def test_a_frame_carries_a_message_whole_and_ends_cleanly():
    messages = [{"folder": "01", "notebook": "é" * 300}, {"call": "{}"}, {"end": True}]
    stream = io.BytesIO(b"".join(wire.encode(message) for message in messages))
    heard = wire.Channel(stream, io.BytesIO())
    assert [heard.hear(), heard.hear(), heard.hear(), heard.hear()] == [*messages, None]
    assert wire.frame(b"abc") == b"\x00\x00\x00\x00\x00\x00\x00\x03abc"
    assert wire.size(b"\x00\x00\x00\x00\x00\x00\x01\x00") == 256


def test_a_frame_cut_short_is_the_end_of_the_stream():
    whole = wire.encode({"notebook": "x" * 100})
    assert wire.read_frame(io.BytesIO(whole[:50])) is None
    assert wire.read_frame(io.BytesIO(whole[:5])) is None


def test_a_message_must_be_an_object():
    with pytest.raises(ValueError, match="not a message"):
        wire.decode(b"[1, 2]")


def test_the_channel_says_each_message_as_one_frame():
    said = io.BytesIO()
    wire.Channel(io.BytesIO(), said).say({"answer": "42"})
    assert wire.read_frame(io.BytesIO(said.getvalue())) == b'{"answer": "42"}'


@pytest.mark.parametrize("package", sorted(seam.CHECKED))
def test_the_installed_jupyter_packages_are_the_checked_ones(package):
    # A new version may move a private part: read the seam's list against it, then add it.
    assert version(package) in seam.CHECKED[package], (
        f"{package} {version(package)} is not among the versions autograder/sandbox/inside/"
        f"seam.py was checked with ({', '.join(seam.CHECKED[package])})"
    )


def test_every_private_part_the_seam_lists_is_there():
    assert seam.missing() == []
    seam.check()


def test_a_missing_private_part_is_named_with_the_versions_to_install(monkeypatch):
    lacking = (
        ("jupyter_client.manager", "AsyncKernelManager", "_async_gone", "calls", "a test"),
        ("jupyter_client.nowhere", "Manager", "start", "calls", "a test"),
        ("nbclient", "NotebookClient", "nb", "reads", "a test"),
        # Only set, as the usual launch sets it: a version without it does not read it.
        ("jupyter_client.provisioning", "LocalProvisioner", "gone", "sets", "a test"),
        ("jupyter_client.provisioning", "GoneProvisioner", "pid", "sets", "a test"),
    )
    assert seam.missing(lacking) == [
        "jupyter_client.manager.AsyncKernelManager._async_gone",
        "jupyter_client.nowhere.Manager",
        "jupyter_client.provisioning.GoneProvisioner",
    ]
    monkeypatch.setattr(seam, "PRIVATE", lacking)
    with pytest.raises(seam.SeamError) as raised:
        seam.check()
    said = str(raised.value)
    assert "AsyncKernelManager._async_gone" in said
    assert f"jupyter_client=={seam.CHECKED['jupyter_client'][-1]}" in said
    assert f"nbclient=={seam.CHECKED['nbclient'][-1]}" in said


def test_every_listed_use_is_one_the_seam_knows():
    assert {entry[3] for entry in seam.PRIVATE} <= {"overrides", "calls", "reads", "sets"}
    # Every private method the seam's classes override is listed as overridden.
    manager = seam.forking_manager_class(zygote=None)  # type: ignore[arg-type]
    provisioner = seam._forked_provisioner_class(zygote=None)  # type: ignore[arg-type]
    private = {
        name
        for cls in (manager, manager.client_factory, provisioner)
        for name, value in vars(cls).items()
        if name.startswith("_") and not name.startswith("__") and callable(value)
    }
    listed = {entry[2] for entry in seam.PRIVATE if entry[3] == "overrides"}
    assert private == listed == {"_async_pre_start_kernel", "_async_wait"}


def test_module_code_makes_a_module_and_leaves_the_namespace_alone():
    namespace: dict = {}
    code = module_code("__probe_module__", "VALUE = 41\ndef more():\n    return VALUE + 1\n",
                       "module.seen = module.more()")  # fmt: skip
    try:
        exec(code, namespace)
        probe = sys.modules["__probe_module__"]
        assert (probe.VALUE, probe.seen) == (41, 42)
        assert [name for name in namespace if name != "__builtins__"] == []
    finally:
        sys.modules.pop("__probe_module__", None)


def test_the_guards_note_is_read_once_and_only_from_a_plain_file(tmp_path):
    note = tmp_path / "writes"
    note.write_text("/etc/passwd\n/etc/passwd\n" + "".join(f"/x/{n}\n" for n in range(6)))
    assert writes_outside(str(note)) == [
        "the notebook tried to write outside the student's folders: /etc/passwd, /x/0, /x/1, "
        "/x/2, /x/3 and 2 more"
    ]
    assert not note.exists()
    assert writes_outside(str(note)) == []
    note.mkdir()
    assert writes_outside(str(note)) == []
    assert WRITES_FILE.startswith("/tmp/")


def test_a_server_whose_seam_is_broken_says_so_for_every_notebook(tmp_path):
    # The server as the sandbox starts it, with one private part listed that nbclient lacks.
    inside = Path(seam.__file__).parent
    script = (
        "import sys\n"
        f"sys.path[0] = {str(inside.parent)!r}\n"
        "sys.argv[1:] = ['--serve', '10']\n"
        "from inside import seam\n"
        "seam.PRIVATE += (('nbclient', 'NotebookClient', 'gone', 'reads', 'a test'),)\n"
        "from inside.serve import main\n"
        "main()\n"
    )
    notebook = '{"cells": [], "metadata": {}, "nbformat": 4, "nbformat_minor": 5}'
    requests = b"".join(wire.encode({"folder": ".", "notebook": notebook}) for _ in range(2))
    done = subprocess.run(
        [sys.executable, "-c", script],
        input=requests,
        capture_output=True,
        cwd=tmp_path,
        env={**os.environ, ZYGOTE_VARIABLE: "0"},
        timeout=120,
        check=True,
    )
    stream = io.BytesIO(done.stdout)
    replies = [wire.decode(data) for data in iter(lambda: wire.read_frame(stream), None)]
    assert len(replies) == 2
    for reply in replies:
        assert list(reply) == ["problem"]
        assert "SeamError" in reply["problem"]
        assert "nbclient.NotebookClient.gone" in reply["problem"]
        assert f"nbclient=={seam.CHECKED['nbclient'][-1]}" in reply["problem"]
