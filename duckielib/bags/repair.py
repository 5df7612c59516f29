"""Recovering the messages of a bag whose recording was killed, or whose file was damaged.

A recorder that is killed leaves a bag with no index, often with a chunk cut short. Such a
bag cannot be opened (and ``rosbag reindex`` damages bags written by rosbags), so the repair
reads the file record by record (:mod:`duckielib.bags.records`), keeps every complete
message, and writes them, with their connections, to a new bag. Damage in the middle of the
file (its header, a chunk, the index) is skipped: reading resumes at the next record that can
be read, and the report says how many bytes were skipped and where.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional

from duckielib.bags import records
from duckielib.bags.writer import BagWriter, PathLike
from duckielib.errors import BagError
from duckielib.rostime import NS_PER_S

__all__ = ["RepairReport", "copy_scanned", "repair_bag"]

#: How many damaged stretches a report lists one by one.
_LISTED_DAMAGES = 5


@dataclass
class RepairReport:
    """What a repair recovered, and what state the source was in.

    Attributes:
        source: the damaged bag.
        output: the repaired bag.
        counts: messages recovered, by topic.
        damage: the first problem found (damage or the file's cut end), or None if there was
            none.
        damages: every damaged stretch that was skipped, as a sentence each, in file order.
        bytes_skipped: how many bytes the damaged stretches held.
        was_indexed: whether the source was closed properly: its header, index and records
            all agree (then the repair is only a copy).
        index_lists_chunks: whether the source's header and index list exactly the chunks
            the file holds (its messages may still be damaged).
        header_damaged: whether the bag header (the file's first 4 KB) could not be read.
        index_pos: where the source's header says its index is; 0 if it has none, or its
            header is damaged.
        listed: how many messages the source's index lists (0 without an index).
        found: how many complete messages the source holds, recovered or not.
        header_chunks: how many chunks the source's header says its index lists.
        indexed_chunks: how many chunks its index lists.
        chunks: how many chunks the file holds, whole or in part.
        size: the source's size in bytes.
        orphans: messages that could not be recovered because their connection record (topic
            and type) was lost in the damage.
        suspects: messages left out because damage starts right after them (the damage may
            begin in their data).
        cut: a sentence saying where the file ends inside a record, or None.
        bytes_unread: bytes at the end of the source that held no complete record.
        start_ns, end_ns: record times of the first and last message recovered.
        format: the source's format, ``"ros1"`` or ``"mcap"`` (whose index is its summary,
            and whose damage is said chunk by chunk).
    """

    source: Path
    output: Path
    counts: Dict[str, int] = field(default_factory=dict)
    damage: Optional[str] = None
    damages: List[str] = field(default_factory=list)
    bytes_skipped: int = 0
    was_indexed: bool = False
    index_lists_chunks: bool = False
    header_damaged: bool = False
    index_pos: int = 0
    listed: int = 0
    found: int = 0
    header_chunks: int = 0
    indexed_chunks: int = 0
    chunks: int = 0
    size: int = 0
    orphans: int = 0
    suspects: int = 0
    cut: Optional[str] = None
    bytes_unread: int = 0
    start_ns: int = 0
    end_ns: int = 0
    format: str = "ros1"

    @property
    def messages(self) -> int:
        """How many messages were recovered."""
        return sum(self.counts.values())

    @property
    def damaged(self) -> bool:
        """Whether the source was anything but a properly closed, sound bag."""
        return not self.was_indexed or bool(self.damages) or self.cut is not None

    def _index_state(self) -> List[str]:
        """A sentence on the source's index: missing, lost, not matching, or short."""
        lines: List[str] = []
        if self.format == "mcap":
            if not self.was_indexed:
                lines.append(
                    "It had no summary (an MCAP file's index): it was cut short or never "
                    "closed; it was read from its start up to its damage."
                )
            elif self.found < self.listed:
                lines.append(
                    f"{self.listed - self.found} of the {_count(self.listed, 'message')} its "
                    "summary lists were lost in the damage."
                )
            return lines
        if self.header_damaged:
            lines.append(
                "Its bag header (the first record, in the file's first 4 KB) was damaged, so "
                "its index could not be used; the messages were found record by record."
            )
        elif self.index_pos == 0:
            lines.append("It had no index: its recording was interrupted before it was closed.")
        elif self.index_pos >= self.size:
            lines.append(
                f"Its index was lost: its header says the index starts at byte "
                f"{self.index_pos}, but the file ends at byte {self.size}."
            )
        elif not self.index_lists_chunks:
            lines.append(
                "Its index did not match its records: its header lists "
                f"{_count(self.header_chunks, 'chunk')}, its index "
                f"{_count(self.indexed_chunks, 'chunk')} with "
                f"{_count(self.listed, 'message')}, and the file holds "
                f"{_count(self.chunks, 'chunk')} with {_count(self.found, 'complete message')}, "
                "so readers that go by the index could not read it whole."
            )
        elif self.found < self.listed:
            lines.append(
                f"{self.listed - self.found} of the {_count(self.listed, 'message')} its index "
                "lists were lost in the damage or left out next to it."
            )
        elif self.found > self.listed:
            lines.append(
                f"It holds {self.found - self.listed} more messages than the {self.listed} its "
                "index lists."
            )
        return lines

    def state(self) -> List[str]:
        """Sentences on the state the source was in: its index, its damage, its end."""
        if not self.damaged:
            return ["The bag was not damaged: it was closed properly, and the copy is whole."]
        lines = self._index_state()
        if self.damages and self.format == "mcap":
            lines += [f"  {text}." for text in self.damages[:_LISTED_DAMAGES]]
        elif self.damages:
            count = len(self.damages)
            stretches = "stretch was" if count == 1 else "stretches were"
            after = "it" if count == 1 else "each"
            lines.append(
                f"{count} damaged {stretches} skipped ({self.bytes_skipped} bytes in all); "
                f"reading resumed after {after} at the next record that could be read:"
            )
            lines += [f"  {text}" for text in self.damages[:_LISTED_DAMAGES]]
            if count > _LISTED_DAMAGES:
                lines.append(f"  and {count - _LISTED_DAMAGES} more.")
        if self.suspects:
            lines.append(
                f"{_count(self.suspects, 'message')} just before damage "
                f"{'was' if self.suspects == 1 else 'were'} left out: the damage may begin in "
                "their data."
            )
        if self.orphans:
            lines.append(
                f"{self.orphans} messages were left out: the damage took their connection "
                "record, which says their topic and type."
            )
        if self.cut is not None:
            lines.append(f"The file was cut short: {self.cut}.")
        if self.bytes_unread:
            lines.append(f"{self.bytes_unread} bytes at its end held no complete message.")
        return lines

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
        return "\n".join(lines + self.state())


def _repair_mcap(source: Path, output: Path, compression: str) -> RepairReport:
    """Every message of a damaged MCAP file (ROS 1 schemas) that can be read, into a ROS 1 bag.

    The chunks the file's summary lists are read one by one, each checked by its CRC, so a
    damaged chunk costs only its own messages; a file without its summary is read from its
    start up to its damage.
    """
    from duckielib.bags.convert import _mcap_to_ros1

    partial = output.with_name(output.name + ".partial")
    partial.unlink(missing_ok=True)
    try:
        found = _mcap_to_ros1(source, partial, keep_going=True, compression=compression)
        report = RepairReport(source, output, was_indexed=found.summarised, format="mcap")
        report.damages = list(found.damages)
        report.listed, report.found = found.listed, found.count
        if not found.count:
            state = " ".join(report.state()) if report.damaged else "It holds no message."
            raise BagError(f"No complete message could be recovered from {source}. {state}")
        partial.replace(output)
    finally:
        partial.unlink(missing_ok=True)
    report.counts = dict(found.counts)
    report.start_ns, report.end_ns = found.start_ns, found.end_ns
    return report


def _count(number: int, noun: str) -> str:
    """``1 chunk``, ``2 chunks``."""
    return f"{number} {noun}{'' if number == 1 else 's'}"


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


def _report(source: Path, output: Path, scan: records.ScanResult) -> RepairReport:
    """What a scan of ``source`` found, as a report (without the counts of what is copied)."""
    return RepairReport(
        source=source,
        output=output,
        damage=scan.damage,
        damages=[str(damage) for damage in scan.damages],
        bytes_skipped=scan.bytes_skipped,
        was_indexed=scan.index_matches,
        index_lists_chunks=scan.index_lists_chunks,
        header_damaged=not scan.header_ok,
        index_pos=scan.index_pos,
        listed=sum(scan.index_counts.values()),
        found=sum(scan.counts.values()),
        header_chunks=scan.chunk_count,
        indexed_chunks=len(scan.indexed_chunks),
        chunks=scan.chunks,
        size=scan.size,
        orphans=scan.orphans,
        suspects=scan.suspects,
        cut=scan.cut,
        bytes_unread=scan.size - scan.end,
    )


def repair_bag(source: PathLike, output: PathLike, compression: str = "none") -> RepairReport:
    """Write every complete message of a damaged bag to a new bag.

    Damaged stretches are skipped: reading resumes at the next record that passes every
    check, so a damaged header or chunk costs only the messages it held.

    Args:
        source: the damaged bag (for example ``run.bag.active`` from a killed recording).
        output: the new bag; it must not exist. It appears only when it is complete.
        compression: the new bag's compression, ``"none"`` or ``"bz2"``.

    Returns:
        A report of what was recovered and of the state the source was in.

    Raises:
        BagError: if the source is missing or not a bag, the output exists, or no complete
            message could be recovered (the message says what was found instead).
    """
    source, output = Path(source), Path(output)
    why = records.not_a_file(source)
    if why is not None:
        raise BagError(why)
    if output.exists():
        raise BagError(f"{output} exists already; choose another name for the repaired bag.")
    if records.bag_format(source) == "mcap":
        return _repair_mcap(source, output, compression)
    scan = records.scan(source, check_index=True)
    report = _report(source, output, scan)
    if not scan.messages:
        found = " ".join(report.state()) if report.damaged else "The bag holds no message."
        raise BagError(f"No complete message could be recovered from {source}. {found}")
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
