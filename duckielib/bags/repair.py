"""Recovering the messages of a bag whose recording was killed.

A recorder that is killed leaves a bag with no index, often with a chunk cut short. Such a
bag cannot be opened (and ``rosbag reindex`` damages bags written by rosbags), so the repair
reads the file record by record (:mod:`duckielib.bags.records`), keeps every complete
message, and writes them, with their connections, to a new bag.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional

from duckielib.bags import records
from duckielib.bags.io import BagWriter, PathLike
from duckielib.errors import BagError
from duckielib.rostime import NS_PER_S

__all__ = ["RepairReport", "copy_scanned", "repair_bag"]


@dataclass
class RepairReport:
    """What a repair recovered.

    Attributes:
        source: the damaged bag.
        output: the repaired bag.
        counts: messages recovered, by topic.
        damage: where reading stopped, or None if the bag ended cleanly.
        was_indexed: whether the source still has its index (it was closed properly).
        bytes_unread: bytes at the end of the source that held no complete record.
        start_ns, end_ns: record times of the first and last message recovered.
    """

    source: Path
    output: Path
    counts: Dict[str, int] = field(default_factory=dict)
    damage: Optional[str] = None
    was_indexed: bool = False
    bytes_unread: int = 0
    start_ns: int = 0
    end_ns: int = 0

    @property
    def messages(self) -> int:
        """How many messages were recovered."""
        return sum(self.counts.values())

    def __str__(self) -> str:
        lines = [
            f"Recovered {self.messages} messages on {len(self.counts)} topics "
            f"from {self.source} into {self.output}.",
        ]
        if self.messages:
            lines.append(
                f"Record times: {self.start_ns / NS_PER_S:.3f} s to {self.end_ns / NS_PER_S:.3f} s."
            )
        for topic, count in sorted(self.counts.items()):
            lines.append(f"  {topic}: {count} messages")
        if self.was_indexed and self.damage is None:
            lines.append("The bag was not damaged: it was closed properly.")
        elif self.damage is not None:
            lines.append(f"Reading stopped early: {self.damage}.")
        if self.bytes_unread:
            lines.append(f"{self.bytes_unread} bytes at the end held no complete message.")
        return "\n".join(lines)


def copy_scanned(scan: records.ScanResult, writer: BagWriter) -> None:
    """Write every whole message a scan found, with its connection, into ``writer``."""
    for connection_id, time_ns, data in scan.messages:
        connection = scan.connections[connection_id]
        writer.write_raw(
            connection.topic,
            connection.type,
            connection.md5sum,
            connection.message_definition,
            time_ns,
            data,
            callerid=connection.callerid,
            latching=connection.latching,
        )


def repair_bag(source: PathLike, output: PathLike, compression: str = "none") -> RepairReport:
    """Write every complete message of a damaged bag to a new bag.

    Args:
        source: the damaged bag (for example ``run.bag.active`` from a killed recording).
        output: the new bag; it must not exist. It appears only when it is complete.
        compression: the new bag's compression, ``"none"`` or ``"bz2"``.

    Returns:
        A report of what was recovered.

    Raises:
        BagError: if the source is missing or not a bag, the output exists, or no complete
            message could be recovered.
    """
    source, output = Path(source), Path(output)
    if not source.exists():
        raise BagError(f"There is no file {source}.")
    if output.exists():
        raise BagError(f"{output} exists already; choose another name for the repaired bag.")
    scan = records.scan(source)
    if not scan.messages:
        reason = f" ({scan.damage})" if scan.damage else ""
        raise BagError(f"No complete message could be recovered from {source}{reason}.")
    report = RepairReport(
        source=source,
        output=output,
        damage=scan.damage,
        was_indexed=0 < scan.index_pos < scan.size,
        bytes_unread=scan.size - scan.end,
    )
    partial = output.with_name(output.name + ".partial")
    if partial.exists():
        partial.unlink()
    try:
        with BagWriter(partial, compression) as writer:
            copy_scanned(scan, writer)
        partial.replace(output)
    finally:
        if partial.exists():
            partial.unlink()
    for connection_id, _, _ in scan.messages:
        topic = scan.connections[connection_id].topic
        report.counts[topic] = report.counts.get(topic, 0) + 1
    times = [time_ns for _, time_ns, _ in scan.messages]
    report.start_ns, report.end_ns = min(times), max(times)
    return report
