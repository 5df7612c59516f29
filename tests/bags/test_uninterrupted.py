"""Ctrl-C while a bag is written waits until the write is whole, then stops as it would have."""

from __future__ import annotations

import os
import signal

import pytest

from duckielib.bags import Bag, BagWriter
from duckielib.bags.writer import uninterrupted
from duckielib.messages import String


def test_ctrl_c_inside_a_write_comes_once_the_write_is_whole(tmp_path):
    before = signal.getsignal(signal.SIGINT)
    writer = BagWriter(tmp_path / "talk.bag")
    written = []

    def write_three_and_close():
        with uninterrupted():
            os.kill(os.getpid(), signal.SIGINT)  # arrives now, in the middle of the block
            for index in range(3):
                writer.write("/chatter", String(data=f"hello {index}"), 1_000_000_000 * index)
                written.append(index)
            writer.close()

    with pytest.raises(KeyboardInterrupt):
        write_three_and_close()
    assert written == [0, 1, 2]
    assert signal.getsignal(signal.SIGINT) is before
    bag = Bag(tmp_path / "talk.bag")
    assert bag.check() is None
    assert [item.message.data for item in bag.read("/chatter")] == [
        "hello 0",
        "hello 1",
        "hello 2",
    ]


def test_without_a_signal_nothing_is_raised_and_the_handler_is_back(tmp_path):
    before = signal.getsignal(signal.SIGINT)
    with uninterrupted():
        assert signal.getsignal(signal.SIGINT) is not before
    assert signal.getsignal(signal.SIGINT) is before
