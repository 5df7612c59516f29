"""Reading a student's folder without trusting it: links, FIFOs, sparse files, unsafe zips."""

from __future__ import annotations

import os
import stat
import zipfile

import pytest

from autograder.files import UnsafeFile, collect_folder, read_regular, unpack_zip

pytestmark = pytest.mark.timeout(30)  # a FIFO opened for reading would block for ever


def test_a_regular_file_is_read_and_everything_else_is_refused_in_a_sentence(tmp_path):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "mission.bag").write_bytes(b"#ROSBAG V2.0\n")
    assert read_regular(tmp_path, "run/mission.bag") == b"#ROSBAG V2.0\n"
    secret = tmp_path / "secret.txt"
    secret.write_text("the reference solution")
    (tmp_path / "run" / "link.bag").symlink_to(secret)
    (tmp_path / "elsewhere").symlink_to(tmp_path / "run")
    os.mkfifo(tmp_path / "run" / "fifo.bag")
    with (tmp_path / "run" / "sparse.bag").open("wb") as handle:
        handle.truncate(100 * 1024**3)  # 100 GB of nothing, on no disk
    for relative, words in (
        ("run/link.bag", "run/link.bag is a symbolic link."),
        ("elsewhere/mission.bag", "elsewhere/mission.bag: elsewhere is not a folder."),
        ("run/fifo.bag", "run/fifo.bag is a FIFO, not a file."),
        ("run/sparse.bag", "run/sparse.bag is 102400.0 MB; at most 50.0 MB is read."),
        ("run/none.bag", "run/none.bag does not exist."),
        ("../secret.txt", "../secret.txt is not a path inside the folder."),
    ):
        with pytest.raises(UnsafeFile) as raised:
            read_regular(tmp_path, relative)
        assert str(raised.value) == words


def test_a_students_folder_gives_its_files_and_says_what_it_left_out(tmp_path):
    folder = tmp_path / "03_frames"
    (folder / "data").mkdir(parents=True)
    (folder / "03_frames.ipynb").write_text("{}")
    (folder / "data" / "ticks.csv").write_text("1,2\n")
    (folder / ".ipynb_checkpoints").mkdir()
    (folder / ".ipynb_checkpoints" / "03_frames-checkpoint.ipynb").write_text("{}")
    (folder / "zz_05_odometry.ipynb").symlink_to("/etc/passwd")
    os.mkfifo(folder / "zz_scratch.ipynb")
    with (folder / "zz_big.ipynb").open("wb") as handle:
        handle.truncate(100 * 1024**3)
    (folder / "half.bin").write_bytes(b"x" * 1000)
    collected = collect_folder(folder, skip=(".*",), file_limit=1000, folder_limit=1000)
    assert collected.files == {"03_frames.ipynb": b"{}", "data/ticks.csv": b"1,2\n"}
    assert collected.left_out == [
        "half.bin was left out: the folder's files passed 1000 bytes.",
        "zz_05_odometry.ipynb is a symbolic link; it was left out.",
        "zz_big.ipynb is 102400.0 MB; at most 1000 bytes is read. It was left out.",
        "zz_scratch.ipynb is a FIFO; it was left out.",
    ]


def test_a_zip_is_read_in_memory_and_refused_when_it_points_outside(tmp_path):
    good = tmp_path / "ada.zip"
    with zipfile.ZipFile(good, "w") as archive:
        archive.writestr("03_frames/03_frames.ipynb", "{}")
        link = zipfile.ZipInfo("03_frames/zz_link.ipynb")
        link.external_attr = (stat.S_IFLNK | 0o777) << 16
        archive.writestr(link, "/etc/passwd")
        archive.writestr("03_frames/big.bin", "y" * 5000)
    collected = unpack_zip(good, folder_limit=1000)
    assert collected.files == {"03_frames/03_frames.ipynb": b"{}"}
    assert collected.left_out == [
        "03_frames/zz_link.ipynb is a symbolic link; it was left out.",
        "03_frames/big.bin was left out: the archive's files passed 1000 bytes.",
    ]
    bad = tmp_path / "eve.zip"
    with zipfile.ZipFile(bad, "w") as archive:
        archive.writestr("../../gradebook.db", "overwritten")
    with pytest.raises(UnsafeFile, match=r"it holds the unsafe path '\.\./\.\./gradebook\.db'"):
        unpack_zip(bad)
    (tmp_path / "junk.zip").write_bytes(b"not a zip")
    with pytest.raises(UnsafeFile, match="it is not a readable zip"):
        unpack_zip(tmp_path / "junk.zip")


def test_a_hidden_students_folder_or_zip_is_said_and_a_hidden_file_is_not(tmp_path):
    from autograder.grade import find_submissions

    (tmp_path / "ada").mkdir()
    (tmp_path / ".hidden_student").mkdir()
    (tmp_path / ".ben.zip").write_bytes(b"PK\x05\x06" + bytes(18))
    (tmp_path / ".DS_Store").write_bytes(b"\0")
    found, skipped = find_submissions(tmp_path)
    assert sorted(found) == ["ada"]
    assert skipped == [
        ".ben.zip: hidden (its name starts with a dot), so not graded; rename it without the dot "
        "to grade it",
        ".hidden_student: hidden (its name starts with a dot), so not graded; rename it without "
        "the dot to grade it",
    ]


def test_grades_csv_keeps_a_name_a_spreadsheet_would_take_for_a_formula_as_text(tmp_path):
    import csv

    from autograder.grade import _Writer
    from autograder.results import StudentResult

    writer = _Writer(out=tmp_path, names=[], cells={}, db_url="")
    for name in ('=HYPERLINK("evil.invalid","click")', "+1", "ada", "o'neil"):
        writer.results[name] = StudentResult(name, problems=["-x"] if name == "ada" else [])
    writer.write_csv()
    with (tmp_path / "grades.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [(row["student"], row["problems"]) for row in rows] == [
        ("'+1", ""),
        ('\'=HYPERLINK("evil.invalid","click")', ""),
        ("ada", "'-x"),
        ("o'neil", ""),
    ]


def test_a_folder_of_many_files_is_read_up_to_the_limit_and_said_in_one_sentence(tmp_path):
    folder = tmp_path / "many"
    folder.mkdir()
    for number in range(60):
        (folder / f"f{number:03d}.txt").write_bytes(b"x")
    collected = collect_folder(folder, count_limit=5)
    assert sorted(collected.files) == [f"f{number:03d}.txt" for number in range(5)]
    assert collected.size == 5
    # 55 left out: 50 said one by one (the limit of sentences), then one sentence for the rest.
    assert len(collected.left_out) == 51
    assert collected.left_out[0] == "f005.txt was left out: at most 5 files are read from a folder."
    assert collected.left_out[-1] == "5 more files were left out (not listed one by one)."


def test_names_too_long_for_a_file_system_are_left_out_of_a_zip_and_the_rest_is_read(tmp_path):
    archive = tmp_path / "long.zip"
    long = "a" * 300 + ".txt"
    with zipfile.ZipFile(archive, "w") as zipped:
        zipped.writestr(f"03_frames/{long}", b"x")
        zipped.writestr("03_frames/03_frames.ipynb", b"{}")
    collected = unpack_zip(archive)
    assert sorted(collected.files) == ["03_frames/03_frames.ipynb"]
    (said,) = collected.left_out
    assert said.startswith("03_frames/aaaa")
    assert said.endswith("has a name longer than a file system takes; it was left out.")


def test_a_refused_zip_says_why_and_names_no_notebook_it_never_opened(tmp_path):
    from autograder.grade import _left_out

    refused = "the submission was not graded: it holds the unsafe path '../../etc/passwd'"
    said = _left_out([refused, "03_frames/x.bin is a FIFO; it was left out.",
                      "05_odometry/y is a FIFO; it was left out."], ["03_frames"])  # fmt: skip
    assert said == [
        refused[:1].upper() + refused[1:],
        "03_frames: x.bin is a FIFO; it was left out.",
    ]


@pytest.mark.parametrize(
    "name", ["alice ", "new\nline", "st[1]", "l" * 250, " lead", "dots.", "=HYPERLINK(1)"]
)
def test_any_folder_name_gets_an_id_nbgrader_and_file_systems_take(name):
    import re

    from autograder.grade import student_id

    made = student_id(name)
    assert re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_-]{0,40}-[0-9a-f]{8}", made), made
    assert student_id(name) == made  # the same at every run
    assert student_id(name + "x") != made
    assert student_id("ada") == "ada"
    assert student_id("ada.lovelace_2") == "ada.lovelace_2"
