"""Intake of a course website's download through nbgrader's ``zip_collect``.

An LMS download of one lab (one zip, or a folder of files named by student) goes through nbgrader's
ZipCollectApp: its extractor unpacks the archives, and our collector, a FileNameCollectorPlugin,
reads the LMS's name for the student (and the submission time, if the file name carries one) from
each file's path, and maps the name to our student id with a CSV (``lms_name,student_id``). The
result is the layout ``python -m autograder grade`` takes:
``SUBMISSIONS/<student>/<lab>/<lab>.ipynb``, with nbgrader's ``timestamp.txt`` beside it when the
LMS gives a submission time. Every file that is not collected is reported with the reason.
The download is unpacked within limits (SafeExtractor, in place of nbgrader's extractor): a refused
file is reported with the student it belongs to, where its name says, and stays in the download.

Plain nbgrader works too, into the course's ``submitted/``:
``nbgrader zip_collect <lab> --collector=autograder.pipeline.collect.StudentIdCollector
--StudentIdCollector.students_file=students.csv --extractor=autograder.pipeline.collect.SafeExtractor``.
"""

from __future__ import annotations

import csv
import os
import re
import shutil
import tempfile
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path, PurePosixPath
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from nbgrader.apps import ZipCollectApp
from nbgrader.coursedir import CourseDirectory
from nbgrader.plugins import ExtractorPlugin, FileNameCollectorPlugin
from nbgrader.utils import capture_log
from traitlets import Float, Int, Unicode
from traitlets.config import Config

from autograder.labs import ROOT, Lab, get_lab
from autograder.pipeline.archives import RATIO_FLOOR, Limits, Refusal, Unpacker
from autograder.pipeline.intake import STUDENT_ID

DEFAULT_PATTERN = (
    r"(?:^|/)(?P<student_id>[^/_]+)_"
    r"(?:(?P<timestamp>\d{4}-\d\d-\d\d[-_T ]\d\d[-:]\d\d(?:[-:]\d\d)?)_)?[^/]*\.ipynb$"
)
"""A file ``<lms name>_<anything>.ipynb``, or ``<lms name>_<YYYY-MM-DD-HH-MM-SS>_<anything>.ipynb``
with the submission time, anywhere in the download."""


class IntakeError(RuntimeError):
    """The download or the student list cannot be collected; the message says why."""


def read_students(path: Path) -> dict[str, str]:
    """The student-id mapping: a CSV with the columns ``lms_name`` and ``student_id``."""
    with open(path, newline="") as handle:
        reader = csv.DictReader(handle)
        if not {"lms_name", "student_id"} <= set(reader.fieldnames or ()):
            raise IntakeError(f"{path} must have the columns lms_name and student_id (it has {reader.fieldnames}).")
        students: dict[str, str] = {}
        for line, record in enumerate(reader, start=2):
            name, student = record["lms_name"].strip(), record["student_id"].strip()
            if not STUDENT_ID.fullmatch(student):
                raise IntakeError(f"{path}, line {line}: {student!r} is not a valid student id (letters, digits, _ . -).")
            if students.get(name, student) != student:
                raise IntakeError(f"{path}, line {line}: {name!r} is mapped to both {students[name]} and {student}.")
            students[name] = student
    return students


def parse_time(text: str, zone: str) -> datetime:
    """A submission time from a file name (``2026-10-02-23-59-00``, ``2026-10-02T23:59``), read in
    the LMS's time zone, in UTC."""
    fields = [int(part) for part in re.findall(r"\d+", text)]
    return datetime(*fields[:6], tzinfo=ZoneInfo(zone)).astimezone(timezone.utc)


class SafeExtractor(ExtractorPlugin):
    """nbgrader's extractor within limits (archives.Unpacker): each archive of the archive folder (by
    nbgrader's ``zip_ext``) is unpacked into a folder of its name, and any other file copied, as
    nbgrader does; a symbolic link is refused. ``refused`` lists what was not unpacked or copied."""

    max_bytes = Int(Limits.max_bytes, help="Bytes unpacked from all the download's archives together.").tag(config=True)
    max_file_bytes = Int(Limits.max_file_bytes, help="Bytes of one unpacked file.").tag(config=True)
    max_files = Int(Limits.max_files, help="Files unpacked from all the download's archives together.").tag(config=True)
    max_ratio = Float(Limits.max_ratio, help=f"Unpacked over compressed size, for what unpacks to more than "
                      f"{RATIO_FLOOR:,} bytes.").tag(config=True)

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.refused: list[Refusal] = []

    def extract(self, archive_path: str, extracted_path: str) -> None:
        unpacker = Unpacker(Limits(self.max_bytes, self.max_file_bytes, self.max_files, self.max_ratio))
        top = Path(archive_path)
        for root, folders, files in os.walk(top):
            links = [name for name in folders if (Path(root) / name).is_symlink()]
            for name in sorted(files + links):
                source = Path(root) / name
                relative = source.relative_to(top)
                target = Path(extracted_path) / relative.parent
                target.mkdir(parents=True, exist_ok=True)
                if source.is_symlink():
                    unpacker.refused.append(Refusal(relative.as_posix(), "it is a symbolic link"))
                elif source.suffix in self.zip_ext:
                    stem = source.stem.removesuffix(".tar")
                    unpacker.unpack(source, target / stem, (relative.parent / stem).as_posix(), relative.as_posix())
                else:
                    shutil.copy(source, target / name)
        self.refused = unpacker.refused
        for refusal in self.refused:
            self.log.warning("Refused %s: %s", refusal.path, refusal.reason)


@dataclass
class Collected:
    """One file the collector matched to a student."""

    path: str
    student: str
    time: datetime | None


class StudentIdCollector(FileNameCollectorPlugin):
    """nbgrader's file-name collector, mapping the LMS's name for a student to our student id.

    ``named_regexp`` is searched in each file's path relative to the extracted download (``/``
    separators); its group ``student_id`` is the LMS's name, and its optional group ``timestamp``
    the submission time in ``timezone``. A lab has one notebook, so whatever name the student gave
    the file, it is collected as ``<lab>.ipynb``.
    """

    named_regexp = Unicode(DEFAULT_PATTERN, help="Regular expression with the groups student_id and, optionally, timestamp.").tag(config=True)
    students_file = Unicode("", help="CSV with the columns lms_name and student_id.").tag(config=True)
    timezone = Unicode("UTC", help="The time zone of the submission times in file names (IANA name).").tag(config=True)

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        if not self.students_file:
            raise IntakeError("StudentIdCollector needs students_file, a CSV with the columns lms_name and student_id.")
        self.students = read_students(Path(self.students_file))
        self.collected: list[Collected] = []
        self.skipped: list[tuple[str, str]] = []
        """(file, reason) for every file that is not collected."""

    def _relative(self, path: str) -> str:
        extracted = self.parent._format_collect_path(self.parent.extracted_directory)
        return Path(path).relative_to(extracted).as_posix()

    def collect(self, submitted_file: str) -> dict | None:
        relative = self._relative(submitted_file)
        if Path(submitted_file).suffix not in self.valid_ext:
            self.skipped.append((relative, "not a notebook"))
            return None
        match = re.search(self.named_regexp, relative)
        if not match:
            self.skipped.append((relative, "the file name does not match the LMS pattern"))
            return None
        name = match.group("student_id")
        if name not in self.students:
            self.skipped.append((relative, f"unknown student {name!r}: not in the student list"))
            return None
        info = {"student_id": self.students[name], "file_id": f"{self.parent.coursedir.assignment_id}.ipynb"}
        stamp = match.groupdict().get("timestamp")
        time = parse_time(stamp, self.timezone) if stamp else None
        if time:
            info["timestamp"] = time.isoformat()
        self.collected.append(Collected(relative, info["student_id"], time))
        return info

    def owner(self, refusal: Refusal) -> str | None:
        """Whose a refused file is, as ``lms name (student id)``: the LMS name the pattern finds in its
        path, or else in its archive's, read as if it were a notebook; None if neither says."""
        for path in (refusal.path, refusal.archive):
            try:
                match = path and re.search(self.named_regexp, PurePosixPath(path).with_suffix(".ipynb").as_posix())
            except ValueError:  # a path whose last part cannot take a suffix ("..")
                match = None
            if match:
                name = match.group("student_id")
                return f"{name} ({self.students[name]})" if name in self.students else f"{name}, not in the student list"
        return None


@dataclass
class IntakeReport:
    """What ``collect`` did: the students collected, and every file it did not collect."""

    lab: str
    students: list[str]
    skipped: list[tuple[str, str]]
    """(file, reason): the files not collected."""
    superseded: list[tuple[str, str]]
    """(file, student): a student's older file, replaced by a newer submission."""
    missing: list[str]
    """Students in the student list who submitted nothing."""
    renamed: list[tuple[str, str]]
    """(file, student): a notebook collected under the lab's name although named differently."""
    refused: list[tuple[str, str | None, str]] = field(default_factory=list)
    """(file, whose, reason): what the download's limits kept from being unpacked (SafeExtractor)."""

    def lines(self) -> list[str]:
        out = [f"{self.lab}: collected {len(self.students)} submission(s)."]
        out += [f"REFUSED {_shown(path)}{f' from {_shown(whose)}' if whose else ''}: {reason}; it is left in the download"
                for path, whose, reason in self.refused]
        out += [f"NOT COLLECTED {_shown(path)}: {reason}" for path, reason in self.skipped]
        out += [f"superseded {_shown(path)}: {student} submitted a newer file" for path, student in self.superseded]
        out += [f"renamed {_shown(path)}: collected as {student}'s {self.lab}.ipynb" for path, student in self.renamed]
        if self.missing:
            out.append(f"no submission from: {', '.join(self.missing)}")
        return out


def _shown(path: str) -> str:
    """A path from the download as the terminal shows it: quoted as Python writes it if it holds a
    character that is not printable (an escape sequence in a file name would act on the terminal)."""
    return path if path.isprintable() else repr(path)


def _superseded(collected: list[Collected]) -> list[tuple[str, str]]:
    """The files nbgrader replaced: for each student all but the newest (later files win ties, as in
    ZipCollectApp, which sees the files in sorted order). nbgrader refuses a student's second file
    without a time, so here every student with two files has times."""
    kept: dict[str, Collected] = {}
    for item in sorted(collected, key=lambda c: c.path):
        if item.student not in kept or item.time >= kept[item.student].time:
            kept[item.student] = item
    return [(c.path, c.student) for c in collected if kept[c.student] is not c]


def collect(lab: Lab, download: Path, students_file: Path, out: Path, pattern: str | None = None,
            zone: str = "UTC", limits: Limits = Limits()) -> IntakeReport:
    """Collect an LMS download of ``lab`` (a zip or a folder) into ``out/<student>/<lab>/<lab>.ipynb``.

    nbgrader's ZipCollectApp does the work in a scratch course folder whose ``submitted/`` is
    ``out``, its archives unpacked within ``limits`` (SafeExtractor). A student's folder
    in ``out`` is replaced by the newest file of this download.
    Raises IntakeError when nbgrader refuses (e.g. two files of one student and no times to
    choose between them).
    """
    if not download.exists():
        raise IntakeError(f"There is no download {download}.")
    read_students(students_file)  # its errors, before nbgrader starts
    try:
        ZoneInfo(zone)
    except (ZoneInfoNotFoundError, ValueError):
        raise IntakeError(f"Unknown time zone {zone!r}: give an IANA name such as Europe/London.") from None
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        archive = Path(scratch) / "downloaded" / lab.id / "archive"
        if download.is_dir():
            shutil.copytree(download, archive, symlinks=True)  # a link is refused, not followed
        else:
            archive.mkdir(parents=True)
            shutil.copy2(download, archive)
        config = Config()
        config.CourseDirectory.root = scratch
        config.CourseDirectory.assignment_id = lab.id
        config.CourseDirectory.release_directory = str(ROOT / "release")
        config.CourseDirectory.submitted_directory = str(out.resolve())
        config.ZipCollectApp.force = True
        config.ZipCollectApp.log_level = "ERROR"  # every file not collected is in the report
        config.ExtractorPlugin.force = True
        config.ZipCollectApp.extractor_plugin = SafeExtractor
        config.SafeExtractor.max_bytes = limits.max_bytes
        config.SafeExtractor.max_file_bytes = limits.max_file_bytes
        config.SafeExtractor.max_files = limits.max_files
        config.SafeExtractor.max_ratio = limits.max_ratio
        config.ZipCollectApp.collector_plugin = StudentIdCollector
        config.StudentIdCollector.students_file = str(students_file)
        config.StudentIdCollector.timezone = zone
        if pattern:
            config.StudentIdCollector.named_regexp = pattern
        app = ZipCollectApp(coursedir=CourseDirectory(config=config), config=config)
        result = capture_log(app)
        collector: StudentIdCollector | None = app.collector_plugin_inst
        extractor: SafeExtractor | None = app.extractor_plugin_inst
        if not result["success"]:
            errors = "\n".join(line for line in result.get("log", "").splitlines() if line.startswith("[ERROR]"))
            files: dict[str, list[str]] = {}
            for item in collector.collected if collector else []:
                files.setdefault(item.student, []).append(item.path)
            twice = "".join(f"\n{student}: {', '.join(paths)}" for student, paths in files.items() if len(paths) > 1)
            raise IntakeError(f"nbgrader zip_collect could not collect {download}:\n{errors or result['error']}"
                              + (f"\nStudents with several files and no submission times (keep one each):{twice}" if twice else ""))
    students = sorted({c.student for c in collector.collected})
    return IntakeReport(
        lab.id,
        students,
        collector.skipped,
        _superseded(collector.collected),
        sorted(set(collector.students.values()) - set(students)),
        [(c.path, c.student) for c in collector.collected if not c.path.endswith(lab.notebook_name)],
        [(r.path, collector.owner(r), r.reason) for r in extractor.refused],
    )


def run_collect(lab_id: str, download: Path, students_file: Path, out: Path, pattern: str | None = None,
                zone: str = "UTC", limits: Limits = Limits()) -> int:
    """``python -m autograder collect``: collect and print the report. Exit status 1 if a file was
    refused or not collected, 2 if nothing could be collected."""
    try:
        report = collect(get_lab(lab_id), download, students_file, out, pattern, zone, limits)
    except (IntakeError, ValueError, OSError) as error:
        print(f"collect: {error}")
        return 2
    print("\n".join(report.lines()))
    print(f"Submissions: {out}. Grade them with: python -m autograder grade {out}")
    return 1 if report.skipped or report.refused else 0
