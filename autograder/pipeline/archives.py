"""Unpacking an LMS download within limits, for ``collect`` (nbgrader's ZipCollectApp's extractor).

nbgrader's own extractor unpacks every zip and tar it finds, archives inside archives too, with no
limit: one student's upload of zeros fills the disk, and nested archives make that unbounded.
Unpacker, which ``collect.SafeExtractor`` uses in its place, reads each archive's directory before
it writes anything, and refuses, with the reason:
- a member whose path leaves the folder (``..``, an absolute path), a link (symbolic or hard), a
  device or pipe, and an archive inside the archive (it is not unpacked, so nesting never goes deeper);
- a member that would unpack to more than ``max_file_bytes``, or to more than RATIO_FLOOR bytes at
  more than ``max_ratio`` times its compressed size (a tar: the whole archive's ratio);
- a whole archive whose members would take the download past ``max_files`` files or
  ``max_bytes`` bytes unpacked, and one that is not a readable zip or tar; a zip already from its
  end record, before zipfile reads its directory into memory, when that record declares too many
  entries or a directory larger than DIRECTORY_BYTES_PER_FILE for each file allowed.
A tar's raw 512-byte headers are scanned first, through its decompressor, each body skipped by its
declared size and not kept, before tarfile sees the tar: tarfile reads a pax header's (or a GNU long
name's) whole body into memory and parses it, quadratically in Python 3.11.7 (CVE-2024-6232), before
any limit here applies. The scan refuses the whole tar for a malformed header, an extended header
declaring more than MAX_TAR_EXTENSION bytes, a sparse member, and for the file-count, size, total and
ratio limits (the ratio over every byte it decompresses).
It reads each member through a count that stops, and refuses the member, once it holds more than
its declared size (zipfile and tarfile stop there too). A tar is read in order, so a member of a tar
that is too large refuses the whole tar (skipping it would mean decompressing it). Nothing of the
download is changed: a refused file is still where it was.
"""

from __future__ import annotations

import bz2
import gzip
import lzma
import os
import re
import shutil
import stat
import tarfile
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

ARCHIVE_SUFFIXES = (".zip", ".gz", ".tgz", ".tar", ".bz2", ".tbz2", ".xz", ".txz", ".7z", ".rar", ".jar")
"""Names of members that are archives themselves: refused, never unpacked."""
RATIO_FLOOR = 10_000_000
"""The compression ratio is checked only for what unpacks to more than this many bytes: a smaller file
cannot be a bomb, and a notebook of repeated output compresses several hundred times."""
DIRECTORY_BYTES_PER_FILE = 1024
"""The most a zip's central directory may take per file allowed: zipfile holds the whole directory in
memory (a 17 MB zip of 200,000 empty files took 200 MB), so a larger one is refused before it is read."""
CHUNK = 1 << 20
MAX_TAR_EXTENSION = 64 * 1024
"""The most bytes a tar's pax header (``x``, global ``g``) or GNU long name (``L``, ``K``) may declare:
tarfile reads such a body whole into memory and parses it (quadratic in Python 3.11.7: CVE-2024-6232),
before any other limit applies. A path of 4,096 bytes and its pax records fit many times over."""
MAX_TAR_EXTENSIONS_IN_A_ROW = 8
"""The most extended headers (pax, global, long name, long link) one member may come after."""
BLOCK = 512
_EXTENSIONS = {b"x": "a pax header", b"X": "a pax header", b"g": "a pax global header",
               b"L": "a GNU long name", b"K": "a GNU long link name"}
_PAX_RECORD = re.compile(rb"(\d{1,20}) ")


@dataclass(frozen=True)
class Limits:
    """What ``collect`` unpacks from one download at most."""

    max_bytes: int = 2_000_000_000
    """Bytes unpacked from all the download's archives together."""
    max_file_bytes: int = 50_000_000
    """Bytes of one unpacked file: the grader reads no larger notebook (intake.MAX_SUBMISSION_BYTES)."""
    max_files: int = 10_000
    """Files unpacked from all the download's archives together."""
    max_ratio: float = 100.0
    """Unpacked size over compressed size, for what unpacks to more than RATIO_FLOOR bytes."""


@dataclass
class Refusal:
    """A file of the download that was not unpacked or copied."""

    path: str
    """Where it would have been, relative to the extracted download (``<archive>/<member>``)."""
    reason: str
    archive: str | None = None
    """The archive it is a member of, relative to the extracted download (None: a file of the download itself)."""


class Refused(Exception):
    """A whole archive is refused; the message says why."""


@dataclass
class _Member:
    name: str
    size: int
    packed: int | None
    """Compressed size (a zip's member); None in a tar."""
    kind: str
    """file, dir, symlink, hardlink or special."""
    entry: zipfile.ZipInfo | tarfile.TarInfo


def _zip_directory(path: Path) -> tuple[int, int]:
    """The number of entries and the size in bytes of a zip's central directory, as its end record
    says (zip64's too), read before zipfile reads the directory."""
    with open(path, "rb") as handle:
        size = handle.seek(0, os.SEEK_END)
        handle.seek(max(0, size - 22 - 65_535))  # the end record, after at most a 65,535-byte comment
        tail = handle.read()
        at = tail.rfind(b"PK\x05\x06")
        entries = int.from_bytes(tail[at + 10:at + 12], "little")
        directory = int.from_bytes(tail[at + 12:at + 16], "little")
        if (entries == 0xFFFF or directory == 0xFFFFFFFF) and tail[max(at - 20, 0):at - 16] == b"PK\x06\x07":
            handle.seek(int.from_bytes(tail[at - 12:at - 4], "little"))  # zip64's end record
            record = handle.read(56)
            entries, directory = int.from_bytes(record[32:40], "little"), int.from_bytes(record[40:48], "little")
    return entries, directory


def _zip_kind(info: zipfile.ZipInfo) -> str:
    mode = info.external_attr >> 16
    if stat.S_ISLNK(mode):
        return "symlink"
    if info.is_dir():
        return "dir"
    return "file" if stat.S_IFMT(mode) in (0, stat.S_IFREG) else "special"  # no type bits: a file, as most zips say


def _tar_kind(info: tarfile.TarInfo) -> str:
    if info.issym():
        return "symlink"
    if info.islnk():
        return "hardlink"
    return "dir" if info.isdir() else "file" if info.isfile() else "special"


def _path_problem(name: str) -> str | None:
    """Why a member's path is refused: it is absolute or leaves the folder."""
    parts = name.replace("\\", "/").split("/")
    if name.startswith(("/", "\\")) or (len(name) > 1 and name[1] == ":"):
        return f"its path {name!r} is absolute"
    if ".." in parts:
        return f"its path {name!r} leaves the folder (..)"
    return None


def _member_problem(member: _Member, limits: Limits) -> str | None:
    """Why one member is refused, from the archive's directory alone."""
    problem = _path_problem(member.name)
    if problem:
        return problem
    if member.kind == "symlink":
        return "it is a symbolic link"
    if member.kind == "hardlink":
        return "it is a hard link"
    if member.kind == "special":
        return "it is a device or a pipe, not a file"
    if member.kind == "file" and member.name.lower().endswith(ARCHIVE_SUFFIXES):
        return "it is an archive inside an archive, which is not unpacked"
    if member.kind == "file" and member.size > limits.max_file_bytes:
        return f"it unpacks to {member.size:,} bytes, more than the {limits.max_file_bytes:,} a file may"
    if (member.packed is not None and member.size > RATIO_FLOOR
            and member.size > limits.max_ratio * max(member.packed, 1)):
        return (f"it unpacks to {member.size:,} bytes from {member.packed:,}, more than {limits.max_ratio:g} "
                "times its compressed size")
    return None


class Unpacker:
    """Unpacks the archives of one download within ``limits``, which all its archives share; what it
    refuses is in ``refused``."""

    def __init__(self, limits: Limits) -> None:
        self.limits = limits
        self.refused: list[Refusal] = []
        self._bytes_left = limits.max_bytes
        self._files_left = limits.max_files

    def unpack(self, source: Path, dest: Path, folder: str, relative: str) -> None:
        """Unpack the archive ``source`` (``relative`` to the download) into the new folder ``dest``
        (``folder`` relative to the extracted download), refusing what the limits do not allow."""
        try:
            self._unpack(source, dest, folder)
        except Refused as why:
            shutil.rmtree(dest, ignore_errors=True)
            self.refused.append(Refusal(relative, str(why)))

    def _unpack(self, source: Path, dest: Path, folder: str) -> None:
        """Unpack the archive ``source`` into ``dest`` (``folder`` relative to the extracted download),
        member by member, within the limits left; raises Refused to refuse it whole."""
        try:
            if zipfile.is_zipfile(source):
                entries, directory = _zip_directory(source)
                if entries > self._files_left:
                    raise Refused(f"it holds {entries:,} entries, more than the {self._files_left:,} files left of the "
                                  f"limit of {self.limits.max_files:,}")
                if directory > DIRECTORY_BYTES_PER_FILE * self._files_left:
                    raise Refused(f"its directory takes {directory:,} bytes, more than {DIRECTORY_BYTES_PER_FILE:,} for "
                                  f"each of the {self._files_left:,} files left of the limit of {self.limits.max_files:,}")
                with zipfile.ZipFile(source) as archive:
                    members = [_Member(i.filename, i.file_size, i.compress_size, _zip_kind(i), i)
                               for i in archive.infolist()]
                    for member in self._check(members, folder):
                        self._write(lambda m=member: archive.open(m.entry), member, dest, folder)
            else:
                self._scan_tar(source)  # before tarfile reads a header's body
                with tarfile.open(source, tarinfo=_CappedTarInfo) as archive:
                    for member in self._check(self._tar_members(archive, source.stat().st_size), folder):
                        self._write(lambda m=member: archive.extractfile(m.entry), member, dest, folder)
        except (zipfile.BadZipFile, tarfile.TarError, EOFError, OSError, ValueError) as error:
            # tarfile's ReadError lists every compression it tried: it only means "not a tar"
            detail = "" if isinstance(error, tarfile.ReadError) else f" ({type(error).__name__}: {error})"
            raise Refused(f"it is not a readable zip or tar archive{detail}") from None

    def _scan_tar(self, source: Path) -> None:
        """Read a tar's raw 512-byte headers through its decompressor, skipping each body by its declared
        size without keeping it, as tarfile would walk them; raise Refused for a malformed header, an
        extended header (pax, global, GNU long name) that declares more than MAX_TAR_EXTENSION bytes,
        a sparse member, and for the limits that ``_tar_members`` applies after: too many entries, a
        file too large, too much unpacked in all or at too high a ratio (here every byte decompressed
        counts towards the ratio). A first block that is not a header: not a tar."""
        packed = source.stat().st_size
        limits = self.limits
        with _open_stream(source) as stream:
            offset = entries = total = extensions = 0
            pax_size: int | None = None
            global_size: int | None = None
            name = b""
            while True:
                header = _read_exactly(stream, BLOCK)
                if not header or header == bytes(BLOCK):
                    return  # the end, as tarfile reads it: no more data, or a block of zeros
                problem = _header_problem(header)
                if problem:
                    if offset == 0:
                        raise Refused("it is not a readable zip or tar archive")
                    raise Refused(f"its header at byte {offset:,} is malformed ({problem})")
                size, kind = tarfile.nti(header[124:136]), header[156:157]
                at, offset = offset, offset + BLOCK
                if kind in _EXTENSIONS:
                    if size > MAX_TAR_EXTENSION:
                        raise Refused(f"its header at byte {at:,} is {_EXTENSIONS[kind]} of {size:,} bytes, more than "
                                      f"the {MAX_TAR_EXTENSION:,} one may hold")
                    extensions += 1
                    if extensions > MAX_TAR_EXTENSIONS_IN_A_ROW:
                        raise Refused(f"its header at byte {at:,} is the {extensions}th extended header in a row, more "
                                      f"than the {MAX_TAR_EXTENSIONS_IN_A_ROW} a member may have")
                    body = _read_exactly(stream, tarfile.BLOCKSIZE * -(-size // BLOCK))
                    if len(body) < size:
                        raise Refused(f"its header at byte {at:,} is malformed (its body is cut short)")
                    offset += len(body)
                    if kind in b"xXg":
                        records = _pax_records(body[:size])
                        if records is None:
                            raise Refused(f"its header at byte {at:,} is malformed (its pax records cannot be read)")
                        if b"size" in records:
                            if kind == b"g":
                                global_size = records[b"size"]
                            else:
                                pax_size = records[b"size"]
                        elif kind != b"g" and global_size is not None:
                            pax_size = global_size  # tarfile merges the global records into a local header's
                        if b"path" in records:
                            name = records[b"path"]
                    elif kind == b"L":
                        name = body[:size].rstrip(b"\0")
                    continue
                if kind == tarfile.GNUTYPE_SPARSE:
                    raise Refused(f"its header at byte {at:,} is a sparse file (GNU), which is not unpacked")
                entries += 1
                if entries > self._files_left:
                    raise Refused(f"it holds more than the {self._files_left:,} files left of the limit "
                                  f"of {limits.max_files:,}")
                if pax_size is not None:
                    size = pax_size
                ustar_name = header[0:100].split(b"\0", 1)[0]
                is_file = kind in tarfile.REGULAR_TYPES and not (kind == tarfile.AREGTYPE and ustar_name.endswith(b"/"))
                has_body = is_file or kind not in tarfile.SUPPORTED_TYPES
                member = (name or ustar_name).decode("utf-8", "replace")
                pax_size, name, extensions = None, b"", 0
                if is_file:
                    total += size
                    if size > limits.max_file_bytes:
                        raise Refused(f"its member {member!r} unpacks to {size:,} bytes, more than the "
                                      f"{limits.max_file_bytes:,} a file may")
                    if total > self._bytes_left:
                        raise Refused(f"it unpacks to more than the {self._bytes_left:,} bytes left of the limit "
                                      f"of {limits.max_bytes:,}")
                elif has_body and size > limits.max_file_bytes:
                    raise Refused(f"its header at byte {at:,} declares {size:,} bytes, more than the "
                                  f"{limits.max_file_bytes:,} a file may")
                if has_body:
                    offset += _skip(stream, tarfile.BLOCKSIZE * -(-size // BLOCK))
                if offset > RATIO_FLOOR and offset > limits.max_ratio * max(packed, 1):
                    raise Refused(f"it unpacks to more than {offset:,} bytes from {packed:,}, more than "
                                  f"{limits.max_ratio:g} times its compressed size")

    def _tar_members(self, archive: tarfile.TarFile, packed: int) -> list[_Member]:
        """A tar's directory, read header by header and given up (refusing the tar) as soon as it
        has too many entries, a file too large, or unpacks to too much or at too high a ratio."""
        members: list[_Member] = []
        total = 0
        limits = self.limits
        while (info := archive.next()) is not None:
            member = _Member(info.name, info.size, None, _tar_kind(info), info)
            members.append(member)
            if len(members) > self._files_left:  # folders and links count too: each header costs a read
                raise Refused(f"it holds more than the {self._files_left:,} files left of the limit "
                              f"of {limits.max_files:,}")
            if member.kind != "file":
                continue
            total += member.size
            if member.size > limits.max_file_bytes:
                raise Refused(f"its member {member.name!r} unpacks to {member.size:,} bytes, more than the "
                              f"{limits.max_file_bytes:,} a file may")
            if total > self._bytes_left:
                raise Refused(f"it unpacks to more than the {self._bytes_left:,} bytes left of the limit "
                              f"of {limits.max_bytes:,}")
            if total > RATIO_FLOOR and total > limits.max_ratio * max(packed, 1):
                raise Refused(f"it unpacks to more than {total:,} bytes from {packed:,}, more than {limits.max_ratio:g} "
                              "times its compressed size")
        return members

    def _check(self, members: list[_Member], folder: str) -> list[_Member]:
        """The files of an archive that may be unpacked; the others refused one by one. Raises Refused
        if they are too many or unpack to too much for what is left of the limits."""
        accepted = []
        for member in members:
            problem = _member_problem(member, self.limits)
            if problem:
                self.refused.append(Refusal(f"{folder}/{member.name}", problem, folder))
            elif member.kind == "file":
                accepted.append(member)
        if len(accepted) > self._files_left:
            raise Refused(f"it holds {len(accepted):,} files, more than the {self._files_left:,} left of the limit "
                          f"of {self.limits.max_files:,}")
        size = sum(m.size for m in accepted)
        if size > self._bytes_left:
            raise Refused(f"it unpacks to {size:,} bytes, more than the {self._bytes_left:,} left of the limit "
                          f"of {self.limits.max_bytes:,}")
        return accepted

    def _write(self, open_member, member: _Member, dest: Path, folder: str) -> None:
        """Write one member under ``dest``, counting its bytes: past its declared size it is removed
        and refused."""
        target = dest.joinpath(*PurePosixPath(member.name.replace("\\", "/")).parts)
        written, opened = 0, False
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            with open_member() as data, open(target, "wb") as out:
                opened = True
                while chunk := data.read(min(CHUNK, member.size + 1 - written)):
                    written += len(chunk)
                    if written > member.size:
                        raise Refused(f"it holds more than its declared {member.size:,} bytes")
                    out.write(chunk)
        except Exception as error:  # Refused, or any of the archive's or the disk's errors (corrupt, encrypted, ...)
            if opened:
                target.unlink(missing_ok=True)
            reason = str(error) if isinstance(error, Refused) else \
                f"it could not be unpacked ({type(error).__name__}: {error})"
            self.refused.append(Refusal(f"{folder}/{member.name}", reason, folder))
            return
        finally:
            self._bytes_left -= written
        self._files_left -= 1


class _CappedTarInfo(tarfile.TarInfo):
    """tarfile's TarInfo that refuses an extended header (pax, GNU long name) declaring more than
    MAX_TAR_EXTENSION bytes before tarfile reads its body: a second guard behind ``_scan_tar``."""

    def _proc_member(self, tarfile_):
        if self.type in _EXTENSIONS and self.size > MAX_TAR_EXTENSION:
            raise Refused(f"it has {_EXTENSIONS[self.type]} of {self.size:,} bytes, more than the "
                          f"{MAX_TAR_EXTENSION:,} one may hold")
        return super()._proc_member(tarfile_)


def _open_stream(source: Path):
    """The tar inside ``source``, decompressed as it is read (gzip, bzip2, xz, or none), as
    ``tarfile.open`` would find it."""
    with open(source, "rb") as handle:
        magic = handle.read(6)
    if magic.startswith(b"\x1f\x8b"):
        return gzip.open(source, "rb")
    if magic.startswith(b"BZh"):
        return bz2.open(source, "rb")
    if magic.startswith(b"\xfd7zXZ\x00"):
        return lzma.open(source, "rb")
    return open(source, "rb")


def _read_exactly(stream, size: int) -> bytes:
    """Up to ``size`` bytes (fewer only at the end of the stream)."""
    parts, left = [], size
    while left > 0 and (part := stream.read(left)):
        parts.append(part)
        left -= len(part)
    return b"".join(parts)


def _skip(stream, size: int) -> int:
    """Read and drop ``size`` bytes, a chunk at a time; Refused if the stream ends first."""
    left = size
    while left > 0:
        part = stream.read(min(CHUNK, left))
        if not part:
            raise Refused(f"it is cut short: a member's body ends {left:,} bytes before its declared size")
        left -= len(part)
    return size


def _header_problem(header: bytes) -> str | None:
    """Why a 512-byte block is not a tar header (tarfile's checks: length, checksum, numbers)."""
    if len(header) < BLOCK:
        return "it is cut short"
    try:
        if tarfile.nti(header[148:156]) not in tarfile.calc_chksums(header):
            return "bad checksum"
        size = tarfile.nti(header[124:136])
    except (tarfile.HeaderError, ValueError):
        return "a number field cannot be read"
    return "negative size" if size < 0 else None


def _pax_records(body: bytes) -> dict[bytes, object] | None:
    """The ``size`` (an int) and ``path`` records of a pax header's body (``<length> <key>=<value>\\n``
    each), or None if the body is not such records. A later record wins, as in tarfile."""
    records: dict[bytes, object] = {}
    pos = 0
    while pos < len(body) and body[pos:pos + 1] != b"\0":
        match = _PAX_RECORD.match(body, pos)
        if not match:
            return None
        length = int(match.group(1))
        record = body[match.end():pos + length]
        if length < match.end() - pos + 2 or pos + length > len(body) or not record.endswith(b"\n") or b"=" not in record:
            return None
        key, value = record[:-1].split(b"=", 1)
        if key == b"size":
            try:
                records[key] = int(value)
            except ValueError:
                return None
            if records[key] < 0:
                return None
        elif key == b"path":
            records[key] = value
        pos += length
    return records
