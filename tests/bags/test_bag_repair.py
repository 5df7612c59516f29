"""Repairing bags cut short: every complete message is recovered, nothing else."""

from __future__ import annotations

import pytest

from duckielib.bags import Bag, BagWriter, repair_bag
from duckielib.bags.records import scan
from duckielib.errors import BagError
from duckielib.messages import String


def chunked_bag(path, compression="none", chunks=4, per_chunk=25):
    """A closed bag of ``chunks`` flushed chunks; returns the file offsets where each ends."""
    ends = []
    with BagWriter(path, compression) as writer:
        for chunk in range(chunks):
            for k in range(per_chunk):
                index = chunk * per_chunk + k
                writer.write("/count", String(f"message {index}"), index * 1_000_000)
            writer.flush()
            ends.append(path.stat().st_size)
    return ends


@pytest.mark.parametrize("compression", ["none", "bz2"])
def test_cut_inside_the_last_chunk_keeps_the_chunks_before(tmp_path, compression):
    bag = tmp_path / "whole.bag"
    ends = chunked_bag(bag, compression)
    broken = tmp_path / "broken.bag.active"
    broken.write_bytes(bag.read_bytes()[: ends[2] + 40])  # into the fourth chunk
    report = repair_bag(broken, tmp_path / "fixed.bag", compression=compression)
    assert report.counts == {"/count": 75}
    assert report.damage is not None
    assert not report.was_indexed
    fixed = Bag(tmp_path / "fixed.bag")
    assert [m.message.data for m in fixed.read("/count")] == [f"message {i}" for i in range(75)]
    assert fixed.start_ns == 1  # recorded at 0, written as ROS's smallest valid time
    assert fixed.end_ns == 74_000_000
    assert "Recovered 75 messages on 1 topics" in str(report)


def test_an_uncompressed_chunk_cut_short_gives_its_complete_messages(tmp_path):
    bag = tmp_path / "whole.bag"
    ends = chunked_bag(bag)
    broken = tmp_path / "broken.bag"
    middle = (ends[2] + ends[3]) // 2
    broken.write_bytes(bag.read_bytes()[:middle])
    report = repair_bag(broken, tmp_path / "fixed.bag")
    assert 75 < report.messages < 100
    assert "cut short" in report.damage
    messages = Bag(tmp_path / "fixed.bag").read("/count")
    assert [m.message.data for m in messages] == [f"message {i}" for i in range(report.messages)]


def test_an_undamaged_bag_is_copied_whole(tmp_path):
    bag = tmp_path / "whole.bag"
    chunked_bag(bag)
    report = repair_bag(bag, tmp_path / "copy.bag")
    assert report.messages == 100
    assert report.was_indexed
    assert report.damage is None
    assert "was not damaged" in str(report)
    assert len(scan(tmp_path / "copy.bag").messages) == 100


def test_repair_errors(tmp_path):
    bag = tmp_path / "whole.bag"
    ends = chunked_bag(bag)
    with pytest.raises(BagError, match="There is no file"):
        repair_bag(tmp_path / "missing.bag", tmp_path / "out.bag")
    with pytest.raises(BagError, match="exists already"):
        repair_bag(bag, bag)
    header_only = tmp_path / "header.bag"
    header_only.write_bytes(bag.read_bytes()[: 4096 + 13])
    with pytest.raises(BagError, match="No complete message could be recovered"):
        repair_bag(header_only, tmp_path / "out.bag")
    assert not (tmp_path / "out.bag").exists()
    text = tmp_path / "notes.txt"
    text.write_text("not a bag at all")
    with pytest.raises(BagError, match="is not a ROS 1 bag"):
        repair_bag(text, tmp_path / "out.bag")
    assert ends
