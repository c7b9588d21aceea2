"""Intake of a course website's download through nbgrader's ``zip_collect``.

An LMS download of one lab (one zip, or a folder of files named by student) goes through nbgrader's
ZipCollectApp: its extractor unpacks the archives, and our collector, a FileNameCollectorPlugin,
reads the LMS's name for the student (and the submission time, if the file name carries one) from
the name the LMS wrote (a file's path, or for a file unpacked from a student's upload, the upload's
name: nothing inside an upload can claim another student or another time), and maps the name to our student id with a CSV (``lms_name,student_id``). The
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
from traitlets import Float, Int, List, Unicode
from traitlets.config import Config

from autograder.labs import ROOT, Lab, get_lab
from autograder.pipeline.archives import RATIO_FLOOR, Limits, Refusal, Unpacker
from autograder.pipeline.intake import STUDENT_ID

DEFAULT_PATTERN = r"(?:^|/)(?P<student_id>[^/_]+)_[^/]*\.ipynb$"
"""A file ``<lms name>_<anything>.ipynb`` anywhere in the download (but inside a student's upload: see
StudentIdCollector). No time is read: after the LMS's name comes the student's own name for the file,
which could begin with a time of the student's choosing (a fourth review dated a late file so)."""
TIMED_PATTERN = (
    r"(?:^|/)(?P<student_id>[^/_]+)_"
    r"(?:(?P<timestamp>\d{4}-\d\d-\d\d[-_T ]\d\d[-:]\d\d(?:[-:]\d\d)?)_)?[^/]*\.ipynb$"
)
"""``collect --times-in-names``: also ``<lms name>_<YYYY-MM-DD-HH-MM-SS>_<anything>.ipynb``, with the
submission time, for an LMS that writes its own time there."""


def unpacked_folder(relative: PurePosixPath) -> str:
    """Where SafeExtractor unpacks the archive at ``relative`` (in the download), relative to the
    extracted download: a folder of its name without the archive's suffix (``.tar.gz`` both)."""
    return (relative.parent / relative.stem.removesuffix(".tar")).as_posix()


def _as_notebook(path: str) -> str | None:
    """An archive's path as the pattern reads it: with ``.ipynb`` for its suffix (None: it cannot take one)."""
    try:
        return PurePosixPath(path).with_suffix(".ipynb").as_posix()
    except ValueError:  # a path whose last part cannot take a suffix ("..")
        return None


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
                raise IntakeError(f"{path}, line {line}: {student!r} is not a valid student id (letters, digits, _ . @ -, beginning with a letter or a digit).")
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
                    folder = unpacked_folder(PurePosixPath(relative.as_posix()))
                    unpacker.unpack(source, Path(extracted_path) / folder, folder, relative.as_posix())
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

    ``named_regexp`` is searched in the name the LMS wrote (``/`` separators): its group
    ``student_id`` is the LMS's name, and its optional group ``timestamp`` the submission time in
    ``timezone``. That name is a file's path relative to the extracted download, unless the file
    was unpacked from a student's upload: an archive of the download (not one of ``lms_archives``)
    whose own path, read with ``.ipynb`` for its suffix, the pattern matches. Then the student and
    the time are the archive's; a member whose own path names another student, or gives a time, is
    not collected, with the reason (refused, not read as the uploader's: it is either an attempt to
    submit as someone else or at another time, or a mix-up the instructor should see). A lab has
    one notebook, so whatever name the student gave the file, it is collected as ``<lab>.ipynb``.
    Of a student's several notebooks the newest is collected (a later path wins a tie, as in
    nbgrader); when one of them has no time, none is, with the reason: that student's refusal,
    never an error for the class. The whole download is planned at the first file nbgrader asks
    about, so that nbgrader only ever sees one notebook per student.
    """

    named_regexp = Unicode(DEFAULT_PATTERN, help="Regular expression with the groups student_id and, optionally, timestamp.").tag(config=True)
    students_file = Unicode("", help="CSV with the columns lms_name and student_id.").tag(config=True)
    timezone = Unicode("UTC", help="The time zone of the submission times in file names (IANA name).").tag(config=True)
    lms_archives = List(Unicode(), help="Archives of the archive folder that the LMS wrote, holding many students' files "
                        "(their members' names are the LMS's). An archive the pattern does not name is one too; any "
                        "other archive is the upload of the student its name gives.").tag(config=True)

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        if not self.students_file:
            raise IntakeError("StudentIdCollector needs students_file, a CSV with the columns lms_name and student_id.")
        self.students = read_students(Path(self.students_file))
        self.collected: list[Collected] = []
        self.skipped: list[tuple[str, str]] = []
        """(file, reason) for every file that is not collected."""
        self.superseded: list[tuple[str, str]] = []
        """(file, student): a student's older notebook, not collected for a newer one."""
        self._plan: dict[str, dict] | None = None
        self._upload_names: dict[str, tuple[str, re.Match]] | None = None

    def _relative(self, path: str) -> str:
        extracted = self.parent._format_collect_path(self.parent.extracted_directory)
        return Path(path).relative_to(extracted).as_posix()

    def collect(self, submitted_file: str) -> dict | None:
        if self._plan is None:
            self._plan = self._make_plan()
        return self._plan.get(self._relative(submitted_file))

    def _uploads(self) -> dict[str, tuple[str, re.Match]]:
        """Unpacked folder (relative to the extracted download) -> (its archive's path in the download,
        the pattern's match on it), for each archive that is a student's upload."""
        if self._upload_names is None:
            top = Path(self.parent._format_collect_path(self.parent.archive_directory))
            zip_ext = getattr(getattr(self.parent, "extractor_plugin_inst", None), "zip_ext", None) or [".zip", ".gz"]
            self._upload_names = {}
            for root, _, files in os.walk(top):
                for name in files:
                    relative = PurePosixPath((Path(root) / name).relative_to(top).as_posix())
                    if relative.suffix not in zip_ext or relative.as_posix() in self.lms_archives:
                        continue
                    path = _as_notebook(relative.as_posix())
                    match = path and re.search(self.named_regexp, path)
                    if match:
                        self._upload_names[unpacked_folder(relative)] = (relative.as_posix(), match)
        return self._upload_names

    def _upload_of(self, relative: str) -> tuple[str, str, re.Match] | None:
        """(folder, archive, match) of the student's upload a file was unpacked from, or None."""
        uploads = self._uploads()
        for folder in PurePosixPath(relative).parents:
            if folder.as_posix() in uploads:
                return (folder.as_posix(), *uploads[folder.as_posix()])
        return None

    def _label(self, name: str) -> str:
        return f"{name} ({self.students[name]})" if name in self.students else f"{name!r}, not in the student list"

    def _candidate(self, relative: str) -> Collected | str:
        """The student and time of one notebook, or why it is not collected."""
        upload = self._upload_of(relative)
        if upload:
            folder, archive, match = upload
            name = match.group("student_id")
            inner = re.search(self.named_regexp, PurePosixPath(relative).relative_to(folder).as_posix())
            where = f"it is in {self._label(name)}'s upload {_shown(archive)}, but its name"
            if inner and inner.group("student_id") != name:
                return (f"{where} says it is {inner.group('student_id')!r}'s: a file in an upload is the uploader's, "
                        "so it is not collected")
            if inner and inner.groupdict().get("timestamp"):
                return f"{where} gives its own submission time: the time is the upload's, so it is not collected"
            if name not in self.students:
                return f"unknown student {name!r}: not in the student list (its upload {_shown(archive)})"
        else:
            match = re.search(self.named_regexp, relative)
            if not match:
                return "the file name does not match the LMS pattern"
            name = match.group("student_id")
            if name not in self.students:
                return f"unknown student {name!r}: not in the student list"
        stamp = match.groupdict().get("timestamp")
        try:
            time = parse_time(stamp, self.timezone) if stamp else None
        except (ValueError, TypeError, OverflowError):
            # a student's own file name after the LMS's name can look like a time that is no date: that file is
            # this student's refusal, never the whole class's (it stopped collect for everyone)
            return f"{self._label(name)}: the submission time its name gives, {stamp!r}, is not a date, so it is not collected"
        return Collected(relative, self.students[name], time)

    def _make_plan(self) -> dict[str, dict]:
        """Every file of the extracted download, as nbgrader walks it: the collected notebooks' infos
        by path; the other files go to ``skipped`` or ``superseded``."""
        extracted = Path(self.parent._format_collect_path(self.parent.extracted_directory))
        files = sorted(os.path.join(root, name) for root, _, names in os.walk(extracted) for name in names)
        by_student: dict[str, list[Collected]] = {}
        for path in files:
            relative = Path(path).relative_to(extracted).as_posix()
            if Path(path).suffix not in self.valid_ext:
                self.skipped.append((relative, "not a notebook"))
                continue
            found = self._candidate(relative)
            if isinstance(found, str):
                self.skipped.append((relative, found))
            else:
                by_student.setdefault(found.student, []).append(found)
        plan = {}
        for student, items in by_student.items():
            if len(items) > 1 and any(item.time is None for item in items):
                listed = ", ".join(_shown(item.path) for item in items)
                reason = (f"{student} has {len(items)} notebooks here ({listed}) and no submission time in each name "
                          "to choose the newest: none is collected (keep one)")
                self.skipped += [(item.path, reason) for item in items]
                continue
            kept = items[0]
            for item in items[1:]:  # in path order: a later file wins a tie, as in nbgrader
                if item.time >= kept.time:
                    kept = item
            self.superseded += [(item.path, student) for item in items if item is not kept]
            self.collected.append(kept)
            info = {"student_id": student, "file_id": f"{self.parent.coursedir.assignment_id}.ipynb"}
            if kept.time:
                info["timestamp"] = kept.time.isoformat()
            plan[kept.path] = info
        return plan

    def owner(self, refusal: Refusal) -> str | None:
        """Whose a refused file is, as ``lms name (student id)``: for a member of a student's upload,
        the upload's student; else the LMS name the pattern finds in its path, read as if it were a
        notebook; None if it says none."""
        upload = refusal.archive and self._uploads().get(refusal.archive)
        if upload:
            return self._label(upload[1].group("student_id"))
        if refusal.archive is None and refusal.path in self.lms_archives:
            return None
        path = _as_notebook(refusal.path)
        match = path and re.search(self.named_regexp, path)
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


def collect(lab: Lab, download: Path, students_file: Path, out: Path, pattern: str | None = None,
            zone: str = "UTC", limits: Limits = Limits(), times_in_names: bool = False) -> IntakeReport:
    """Collect an LMS download of ``lab`` (a zip or a folder) into ``out/<student>/<lab>/<lab>.ipynb``.
    The file names are read with ``pattern``, or by default DEFAULT_PATTERN (TIMED_PATTERN with
    ``times_in_names``: the LMS writes each upload's time after the student's LMS name).

    nbgrader's ZipCollectApp does the work in a scratch course folder whose ``submitted/`` is
    ``out``, its archives unpacked within ``limits`` (SafeExtractor). A student's folder
    in ``out`` is replaced by the newest file of this download.
    Raises IntakeError when nbgrader refuses; a student's own several notebooks without times are
    that student's refusal, in the report.
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
        if not download.is_dir():
            config.StudentIdCollector.lms_archives = [download.name]  # the LMS's own zip, whatever its name
        if pattern or times_in_names:
            config.StudentIdCollector.named_regexp = pattern or TIMED_PATTERN
        app = ZipCollectApp(coursedir=CourseDirectory(config=config), config=config)
        result = capture_log(app)
        collector: StudentIdCollector | None = app.collector_plugin_inst
        extractor: SafeExtractor | None = app.extractor_plugin_inst
        if not result["success"]:
            errors = "\n".join(line for line in result.get("log", "").splitlines() if line.startswith("[ERROR]"))
            raise IntakeError(f"nbgrader zip_collect could not collect {download}:\n{errors or result['error']}")
    students = sorted({c.student for c in collector.collected})
    return IntakeReport(
        lab.id,
        students,
        collector.skipped,
        collector.superseded,
        sorted(set(collector.students.values()) - set(students)),
        [(c.path, c.student) for c in collector.collected if not c.path.endswith(lab.notebook_name)],
        [(r.path, collector.owner(r), r.reason) for r in extractor.refused],
    )


def run_collect(lab_id: str, download: Path, students_file: Path, out: Path, pattern: str | None = None,
                zone: str = "UTC", limits: Limits = Limits(), times_in_names: bool = False) -> int:
    """``python -m autograder collect``: collect and print the report. Exit status 1 if a file was
    refused or not collected, 2 if nothing could be collected."""
    try:
        report = collect(get_lab(lab_id), download, students_file, out, pattern, zone, limits, times_in_names)
    except (IntakeError, ValueError, OSError) as error:
        print(f"collect: {error}")
        return 2
    print("\n".join(report.lines()))
    print(f"Submissions: {out}. Grade them with: python -m autograder grade {out}")
    return 1 if report.skipped or report.refused else 0
