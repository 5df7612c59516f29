"""The seam with rosbags' undocumented internals: what it needs, and the error when it is gone."""

from __future__ import annotations

import struct
from importlib import metadata

import pytest
import rosbags.rosbag1.writer as rosbags_writer
from bagtools import LEFT, encoder
from rosbags.rosbag1 import Reader, Writer

from duckielib.bags import Bag, BagWriter
from duckielib.bags import seam as bag_seam
from duckielib.bags.records import scan
from duckielib.bags.seam import ROSBAGS_CHECKED, RosbagsSeam
from duckielib.errors import BagError

VERSION = metadata.version("rosbags")


@pytest.fixture
def unchecked(monkeypatch):
    """As if no bag had been written or opened yet in this process."""
    monkeypatch.setattr(RosbagsSeam, "writer_checked", False)
    monkeypatch.setattr(RosbagsSeam, "reader_checked", False)


def _several_chunks(path):
    with BagWriter(path) as writer:
        writer._writer.chunk_threshold = 4096
        for i in range(300):
            writer.write(LEFT, encoder(i, i * 10_000_000), i * 10_000_000)
    return path


def _assert_names(message, missing, action="write"):
    assert message.startswith(f"duckielib cannot {action} bags with rosbags {VERSION}: ")
    assert f"it lacks {missing}, which duckielib.bags.seam relies on" in message
    assert message.endswith(
        f"install rosbags=={ROSBAGS_CHECKED[-1]} "
        f"(duckielib was checked with rosbags {', '.join(ROSBAGS_CHECKED)})."
    )


def test_the_installed_rosbags_is_one_the_seam_was_checked_with():
    assert VERSION in ROSBAGS_CHECKED, (
        f"rosbags {VERSION} is installed, but the seam in duckielib/bags/seam.py was checked with "
        f"rosbags {', '.join(ROSBAGS_CHECKED)}: check what RosbagsSeam relies on against the "
        "new version, then add it to ROSBAGS_CHECKED."
    )


def test_the_installed_rosbags_has_what_the_writer_side_relies_on(unchecked, tmp_path):
    probe = tmp_path / "probe.bag"
    assert bag_seam._missing_from_writer(probe) == []
    writer = Writer(probe)
    chunk = writer.chunks[-1]
    assert isinstance(writer.chunk_threshold, int)
    assert writer.bio is None
    assert chunk.data.tell() == 0
    assert (chunk.start, chunk.end) == (rosbags_writer.MAXSIZE, 0)
    assert chunk.connections[3] == []  # a defaultdict(list)
    RosbagsSeam.check_writer(probe)  # the same messages, the same bytes
    assert RosbagsSeam.writer_checked
    assert not probe.exists()


def test_the_installed_rosbags_has_what_the_reader_side_relies_on(unchecked, tmp_path):
    path = _several_chunks(tmp_path / "chunks.bag")
    bag = Bag(path)
    assert RosbagsSeam.reader_checked
    assert bag.chunk_count == scan(path).chunks > 1
    assert bag.compression == "none"


@pytest.mark.parametrize(
    "missing",
    [
        "Writer.chunks",
        "Writer.chunk_threshold",
        "Writer.bio",
        "WriteChunk.data",
        "WriteChunk.connections",
        "WriteChunk.start",
        "WriteChunk.end",
    ],
)
def test_a_rosbags_writer_without_an_attribute_is_refused_with_its_name(
    unchecked, monkeypatch, tmp_path, missing
):
    owner, name = missing.split(".")
    original = Writer.__init__

    def changed(self, path):
        original(self, path)
        delattr(self if owner == "Writer" else self.chunks[-1], name)

    monkeypatch.setattr(Writer, "__init__", changed)
    with pytest.raises(BagError) as caught:
        BagWriter(tmp_path / "run.bag")
    _assert_names(str(caught.value), missing)
    assert not (tmp_path / "run.bag").exists()
    assert not RosbagsSeam.writer_checked


def test_a_rosbags_writer_without_write_chunk_is_refused_with_its_name(
    unchecked, monkeypatch, tmp_path
):
    monkeypatch.delattr(Writer, "write_chunk")
    with pytest.raises(BagError) as caught:
        BagWriter(tmp_path / "run.bag")
    _assert_names(str(caught.value), "Writer.write_chunk")


def test_a_rosbags_writing_other_bytes_is_refused(unchecked, monkeypatch, tmp_path):
    # As if rosbags wrote record times as one 64-bit number of nanoseconds.
    monkeypatch.setattr(rosbags_writer, "serialize_time", struct.Struct("<Q").pack)
    with pytest.raises(BagError) as caught:
        BagWriter(tmp_path / "run.bag")
    assert str(caught.value) == (
        f"duckielib cannot write bags with rosbags {VERSION}: its Writer.write writes other "
        f"bytes than duckielib.bags.seam does; install rosbags=={ROSBAGS_CHECKED[-1]} "
        f"(duckielib was checked with rosbags {', '.join(ROSBAGS_CHECKED)})."
    )


def test_a_rosbags_writer_that_fails_the_probe_is_refused(unchecked, monkeypatch, tmp_path):
    def changed(self, connection, timestamp, data):
        raise TypeError("write() takes 3 positional arguments but 4 were given")

    monkeypatch.setattr(Writer, "write", changed)
    with pytest.raises(BagError, match=r"writing test messages .* failed \(TypeError: write"):
        BagWriter(tmp_path / "run.bag")


def test_the_writer_is_checked_once(unchecked, monkeypatch, tmp_path):
    BagWriter(tmp_path / "first.bag").close()
    monkeypatch.delattr(Writer, "write_chunk")  # no longer looked for
    BagWriter(tmp_path / "second.bag").abandon()


@pytest.mark.parametrize("missing", ["Reader.chunk_infos", "ChunkInfo.pos"])
def test_a_rosbags_reader_without_chunk_positions_is_refused_with_its_name(
    unchecked, monkeypatch, tmp_path, missing
):
    path = _several_chunks(tmp_path / "chunks.bag")
    original_open, original_close = Reader.open, Reader.close

    def changed_open(self):
        original_open(self)
        if missing == "Reader.chunk_infos":
            self.chunk_list = self.chunk_infos  # as if renamed
            del self.chunk_infos
        else:
            self.chunk_infos = [info[1:] for info in self.chunk_infos]  # tuples without pos

    def changed_close(self):
        self.chunk_infos = getattr(self, "chunk_list", [])
        original_close(self)

    monkeypatch.setattr(Reader, "open", changed_open)
    monkeypatch.setattr(Reader, "close", changed_close)
    with pytest.raises(BagError) as caught:
        Bag(path)
    _assert_names(str(caught.value), missing, action="read")


def test_a_rosbags_reader_whose_positions_point_elsewhere_is_refused(
    unchecked, monkeypatch, tmp_path
):
    path = _several_chunks(tmp_path / "chunks.bag")
    original = Reader.open

    def changed(self):
        original(self)
        self.chunk_infos = [info._replace(pos=info.pos + 1) for info in self.chunk_infos]

    monkeypatch.setattr(Reader, "open", changed)
    with pytest.raises(BagError, match=r"its ChunkInfo\.pos no longer points at a chunk"):
        Bag(path)
