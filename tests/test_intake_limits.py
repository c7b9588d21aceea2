"""Intake within limits: `collect` reads each archive's directory before it unpacks anything, and
refuses a zip bomb, an archive inside an archive, too many files, a path that leaves the folder and a
link, naming the student and the reason; the honest student beside it is collected, and the refused
upload is still in the download."""

import gzip
import io
import os
import subprocess
import sys
import tarfile
import time
import zipfile

import nbformat
import pytest

from autograder.__main__ import main
from autograder.catalogues import submissions
from autograder.labs import ROOT, get_lab
from autograder.pipeline import intake
from autograder.pipeline.archives import Limits
from autograder.pipeline.collect import collect

LAB = get_lab("train-kf")
STUDENTS = "lms_name,student_id\nalice,s001\nbob,s002\n"
HONEST = "export/alice_train-kf.ipynb"


@pytest.fixture(scope="module")
def notebook() -> str:
    return nbformat.writes(submissions.solved(LAB))


def class_zip(path, notebook, bob: dict[str, bytes]) -> None:
    """The LMS's zip of the class: alice's honest notebook and bob's files, each compressed."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr(HONEST, notebook)
        for name, data in bob.items():
            archive.writestr(name, data)


def zip_bytes(files: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in files.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def run(tmp_path, download, limits=Limits()):
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    out = tmp_path / "SUBMISSIONS"
    report = collect(LAB, download, students, out, limits=limits)
    assert report.students == ["s001"], "the honest student is collected"
    assert (out / "s001/train-kf/train-kf.ipynb").read_text() == nbformat.writes(submissions.solved(LAB))
    return report, out


def test_a_zip_bomb_member_is_refused_before_it_is_written(tmp_path, notebook):
    """bob's notebook is 60 MB of zeros, 60 kB compressed: more than a file may hold."""
    download = tmp_path / "lms.zip"
    class_zip(download, notebook, {"export/bob_train-kf.ipynb": bytes(60_000_000)})
    assert download.stat().st_size < 200_000
    report, out = run(tmp_path, download)
    assert report.refused == [("lms/export/bob_train-kf.ipynb", "bob (s002)",
                               "it unpacks to 60,000,000 bytes, more than the 50,000,000 a file may")]
    assert report.missing == ["s002"] and not (out / "s002").exists()
    assert zipfile.ZipFile(download).getinfo("export/bob_train-kf.ipynb").file_size == 60_000_000


def test_a_member_too_compressed_is_refused(tmp_path, notebook):
    """Under the size of a file, but 20 MB from 20 kB: more than 100 times its compressed size."""
    download = tmp_path / "lms.zip"
    class_zip(download, notebook, {"export/bob_train-kf.ipynb": bytes(20_000_000)})
    report, _ = run(tmp_path, download)
    [(path, whose, reason)] = report.refused
    assert (path, whose) == ("lms/export/bob_train-kf.ipynb", "bob (s002)")
    assert reason.startswith("it unpacks to 20,000,000 bytes from ") and "more than 100 times" in reason
    assert zipfile.ZipFile(download).read("export/bob_train-kf.ipynb") == bytes(20_000_000)


def test_a_member_larger_than_it_declares_is_refused(tmp_path, notebook):
    """A zip whose directory says 1,000 bytes for a member of 5 MB: no more than 1,000 bytes are read
    (zipfile stops there, and so does the extractor's count), and the member fails its checksum."""
    download = tmp_path / "lms.zip"
    class_zip(download, notebook, {"export/bob_train-kf.ipynb": b"x" * 5_000_000})
    data = bytearray(download.read_bytes())
    with zipfile.ZipFile(download) as archive:
        info = archive.getinfo("export/bob_train-kf.ipynb")
    for offset in (info.header_offset + 22, data.rindex(b"PK\x01\x02") + 24):  # local header, central directory
        data[offset:offset + 4] = (1000).to_bytes(4, "little")
    download.write_bytes(bytes(data))
    report, out = run(tmp_path, download)
    assert report.refused == [("lms/export/bob_train-kf.ipynb", "bob (s002)", "it could not be unpacked "
                               "(BadZipFile: Bad CRC-32 for file 'export/bob_train-kf.ipynb')")]
    assert not (out / "s002").exists() and download.read_bytes() == bytes(data)


def test_an_archive_inside_the_archive_is_not_unpacked(tmp_path, notebook):
    inner = zip_bytes({"bob_deeper.zip": zip_bytes({"bob_train-kf.ipynb": notebook.encode()})})
    download = tmp_path / "lms.zip"
    class_zip(download, notebook, {"export/bob_upload.zip": inner})
    report, out = run(tmp_path, download)
    assert report.refused == [("lms/export/bob_upload.zip", "bob (s002)",
                               "it is an archive inside an archive, which is not unpacked")]
    assert [p.name for p in out.rglob("*")] == ["s001", "train-kf", "train-kf.ipynb"]
    assert zipfile.ZipFile(download).read("export/bob_upload.zip") == inner


def test_an_upload_of_too_many_files_is_refused_whole(tmp_path, notebook):
    """A folder download: alice's notebook and bob's zip of 30 files, with at most 20 files unpacked;
    refused from the zip's end record, and from its directory when the end record says 1 entry."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    upload = zip_bytes({f"bob/{i}.txt": b"" for i in range(30)})
    (download / "bob_upload.zip").write_bytes(upload)
    report, out = run(tmp_path, download, Limits(max_files=20))
    assert report.refused == [("bob_upload.zip", "bob (s002)",
                               "it holds 30 entries, more than the 20 files left of the limit of 20")]
    assert (download / "bob_upload.zip").read_bytes() == upload

    end = upload.rindex(b"PK\x05\x06")
    (download / "bob_upload.zip").write_bytes(upload[:end + 8] + b"\x01\x00\x01\x00" + upload[end + 12:])
    report, out = run(tmp_path, download, Limits(max_files=20))
    assert report.refused == [("bob_upload.zip", "bob (s002)", "it holds 30 files, more than the 20 left of the limit of 20")]


def test_an_upload_past_the_total_is_refused_whole(tmp_path, notebook):
    """A folder download: bob's tar.gz (6 files of 1 MB) would take the download past 5 MB in all."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    with tarfile.open(download / "bob_upload.tar.gz", "w:gz") as archive:
        for i in range(6):
            info = tarfile.TarInfo(f"part{i}.bin")
            info.size = 1_000_000
            archive.addfile(info, io.BytesIO(bytes(range(256)) * 3907 + bytes(208)))
    report, out = run(tmp_path, download, Limits(max_bytes=5_000_000))
    assert report.refused == [("bob_upload.tar.gz", "bob (s002)",
                               "it unpacks to more than the 5,000,000 bytes left of the limit of 5,000,000")]
    assert (download / "bob_upload.tar.gz").exists()


@pytest.mark.parametrize("member, reason", [
    ("../../bob_train-kf.ipynb", "its path '../../bob_train-kf.ipynb' leaves the folder (..)"),
    ("/tmp/bob_train-kf.ipynb", "its path '/tmp/bob_train-kf.ipynb' is absolute"),
])
def test_a_path_that_leaves_the_folder_is_refused(tmp_path, notebook, member, reason):
    """bob's own upload, a zip in a folder download, names a file outside it."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    with zipfile.ZipFile(download / "bob_upload.zip", "w") as archive:
        archive.writestr(zipfile.ZipInfo(member), notebook)  # ZipInfo keeps the name as it is
    report, out = run(tmp_path, download)
    assert report.refused == [(f"bob_upload/{member}", "bob (s002)", reason)]
    assert not list(tmp_path.glob("**/bob_train-kf.ipynb")) and not (out / "s002").exists()
    assert zipfile.ZipFile(download / "bob_upload.zip").namelist() == [member]


def test_links_in_a_zip_and_in_a_tar_are_refused(tmp_path, notebook):
    """bob's zip holds a symbolic link to the course's solved notebook, his tar a symbolic and a hard link."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    with zipfile.ZipFile(download / "bob_zipped.zip", "w") as archive:
        link = zipfile.ZipInfo("bob_train-kf.ipynb")
        link.external_attr = (0o120777 << 16)
        archive.writestr(link, str(LAB.source_notebook))
    with tarfile.open(download / "bob_tarred.tar.gz", "w:gz") as archive:
        for name, kind in (("bob_soft.ipynb", tarfile.SYMTYPE), ("bob_hard.ipynb", tarfile.LNKTYPE)):
            info = tarfile.TarInfo(name)
            info.type, info.linkname = kind, str(LAB.source_notebook)
            archive.addfile(info)
    report, out = run(tmp_path, download)
    assert report.refused == [
        ("bob_tarred/bob_soft.ipynb", "bob (s002)", "it is a symbolic link"),
        ("bob_tarred/bob_hard.ipynb", "bob (s002)", "it is a hard link"),
        ("bob_zipped/bob_train-kf.ipynb", "bob (s002)", "it is a symbolic link"),
    ]
    assert not [p for p in tmp_path.rglob("*") if p.is_symlink()]
    assert tarfile.open(download / "bob_tarred.tar.gz").getnames() == ["bob_soft.ipynb", "bob_hard.ipynb"]
    assert zipfile.ZipFile(download / "bob_zipped.zip").namelist() == ["bob_train-kf.ipynb"]


def test_the_command_names_the_student_and_exits_nonzero(tmp_path, notebook, capsys):
    """The refusal on the terminal, and a file name with an escape sequence shown quoted, not acted on."""
    download = tmp_path / "lms.zip"
    class_zip(download, notebook, {"export/bob_upload.zip": zip_bytes({"x.ipynb": b"{}"}),
                                   "export/\x1b[2Jbob_evil.zip": b""})
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    argv = ["collect", "train-kf", str(download), "--students", str(students), "--out", str(tmp_path / "out")]
    assert main(argv) == 1
    printed = capsys.readouterr().out
    assert ("REFUSED lms/export/bob_upload.zip from bob (s002): it is an archive inside an archive, which is not "
            "unpacked; it is left in the download") in printed
    assert "REFUSED 'lms/export/\\x1b[2Jbob_evil.zip' from '\\x1b[2Jbob, not in the student list'" in printed
    assert "\x1b" not in printed
    assert main([*argv, "--max-file-mb", "0.001"]) == 1
    assert "more than the 1,000 a file may" in capsys.readouterr().out


def test_the_largest_file_unpacked_is_the_largest_notebook_graded():
    assert Limits().max_file_bytes == intake.MAX_SUBMISSION_BYTES


def ext_header(kind: bytes, size: int) -> bytes:
    """One ustar header block of type ``kind`` (pax ``x``, global ``g``, GNU longname ``L``, longlink
    ``K``) declaring ``size`` bytes of body."""
    info = tarfile.TarInfo("././@PaxHeader" if kind in b"xg" else "././@LongLink")
    info.type, info.size = kind, size
    return info.tobuf(tarfile.USTAR_FORMAT)


@pytest.mark.parametrize("kind, what", [(b"x", "a pax header"), (b"g", "a pax global header"),
                                        (b"L", "a GNU long name"), (b"K", "a GNU long link name")])
def test_a_tar_whose_extended_header_declares_too_much_is_refused_before_it_is_read(tmp_path, notebook, kind, what):
    """tarfile reads a pax or GNU long-name header's whole body into memory and parses it (quadratic on
    some Pythons: CVE-2024-6232) before any limit applies: the raw headers are scanned first, and one
    that declares more than 64 KiB is refused. The body here is 10 kB: what it declares is enough."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    with gzip.open(download / "bob_upload.tar.gz", "wb") as handle:
        handle.write(ext_header(kind, 400_000_000) + b"0" * 10_000)
    report, out = run(tmp_path, download)
    assert report.refused == [("bob_upload.tar.gz", "bob (s002)",
                               f"its header at byte 0 is {what} of 400,000,000 bytes, more than the 65,536 one may hold")]
    assert not (out / "s002").exists()


def test_a_tar_with_a_malformed_header_is_refused(tmp_path, notebook):
    """A member, then a header whose checksum is wrong (one byte of its name changed): refused whole
    (tarfile would end the archive there and unpack the member before it)."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    info = tarfile.TarInfo("bob_train-kf.ipynb")
    data = notebook.encode()
    info.size = len(data)
    body = data + bytes(-len(data) % 512)
    with gzip.open(download / "bob_upload.tar.gz", "wb") as handle:
        header = info.tobuf(tarfile.USTAR_FORMAT)
        handle.write(header + body + b"c" + header[1:] + body + bytes(1024))
    report, _ = run(tmp_path, download)
    assert report.refused == [("bob_upload.tar.gz", "bob (s002)",
                               f"its header at byte {512 + len(body):,} is malformed (bad checksum)")]


def test_a_tar_of_a_few_megabytes_in_a_pax_header_is_refused_quickly(tmp_path, notebook):
    """The review's archive, smaller: a pax header of 3 MB of ASCII zeros, which took this Python's
    tarfile (quadratic) far longer than a minute. `collect` refuses it in seconds."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_train-kf.ipynb").write_text(notebook)
    with gzip.open(download / "bob_upload.tar.gz", "wb") as handle:
        handle.write(ext_header(b"x", 3_000_000) + b"0" * 3_000_000 + bytes(1024))
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "autograder", "collect", "train-kf", str(download),
                           "--students", str(students), "--out", str(tmp_path / "out")],
                          cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1, done.stdout + done.stderr
    assert ("REFUSED bob_upload.tar.gz from bob (s002): its header at byte 0 is a pax header of 3,000,000 bytes, "
            "more than the 65,536 one may hold") in done.stdout
    assert time.monotonic() - started < 60
