# SPDX-License-Identifier: Apache-2.0
"""The files canola's tools read and write, through two doors that a hostile file system
cannot turn.

- :func:`write_file` puts bytes or text in place whole or not at all: a temporary with a
  fresh random name in the target's folder, created with ``O_CREAT|O_EXCL|O_NOFOLLOW``
  (a name or symlink planted there is never opened, never followed), written, fsynced,
  then renamed over the target. A symlink at the target is replaced by the file, not
  followed. A target that already exists keeps its permission bits.
- :func:`read_file` reads a regular file of at most ``limit`` bytes: a FIFO, a device
  (``/dev/zero``, ``/dev/urandom``), a folder or a socket is refused before a byte is read
  (the file is opened non-blocking, so a FIFO without a writer cannot block it), and so is
  a file larger than the limit, even one that grows while it is read.

Both raise :class:`FileError` (an ``OSError``) with a one-line message naming the file.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat

__all__ = ["EDS_MAX_BYTES", "FileError", "read_file", "write_file"]

#: The largest EDS/DCF the tools read (the largest real one known is about 174 KiB).
EDS_MAX_BYTES = 64 * 1024 * 1024

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR,
          "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


class FileError(OSError):
    """A file that cannot be read or written as asked; ``str()`` is one line."""

    def __init__(self, path: str | os.PathLike[str], why: str) -> None:
        super().__init__(f"{os.fspath(path)}: {why}")
        self.why = why
        self.path = os.fspath(path)

    def __str__(self) -> str:
        return f"{self.path}: {self.why}"


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def read_file(path: str | os.PathLike[str], limit: int) -> bytes:
    """The bytes of the regular file ``path``, of at most ``limit`` bytes. Raises
    :class:`FileError` for anything else (missing, unreadable, not a regular file, too
    large). Cost: one open, one fstat, reads of the file's size."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as exc:
        raise FileError(path, f"cannot read file: {exc.strerror}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise FileError(path, f"not a regular file ({_kind(info.st_mode)})")
        data = b""
        if info.st_size <= limit:
            data = os.read(fd, info.st_size + 1)
            while data and len(data) <= limit:  # it grew since fstat: on to the limit
                more = os.read(fd, min(1 << 20, limit + 1 - len(data)))
                if not more:
                    break
                data += more
    except OSError as exc:
        if isinstance(exc, FileError):
            raise
        raise FileError(path, f"cannot read file: {exc.strerror}") from None
    finally:
        os.close(fd)
    if info.st_size > limit or len(data) > limit:
        raise FileError(path, f"larger than {limit // (1024 * 1024)} MiB, the most "
                                "canola reads")
    return data


def write_file(path: str | os.PathLike[str], data: bytes | str,
               encoding: str = "utf-8") -> None:
    """Replace ``path`` with ``data`` (text is encoded with ``encoding``, line ends as
    given) in one rename: readers see the old file or the new one, never a part. Raises
    :class:`FileError` (and leaves no temporary behind) when it cannot."""
    raw = data.encode(encoding) if isinstance(data, str) else data
    target = os.fspath(path)
    folder = os.path.dirname(target) or "."
    mode = 0o666
    with contextlib.suppress(OSError):
        info = os.stat(target, follow_symlinks=False)
        if stat.S_ISREG(info.st_mode):
            mode = stat.S_IMODE(info.st_mode)
    fd, tmp = _create_temporary(folder, os.path.basename(target), path)
    try:
        try:
            view = memoryview(raw)
            while view:
                view = view[os.write(fd, view):]
            os.fsync(fd)
        finally:
            os.close(fd)
        if mode != 0o666:
            os.chmod(tmp, mode)
        os.replace(tmp, target)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise FileError(path, f"cannot write: {exc.strerror or exc}") from None
    _sync_folder(folder)


def _create_temporary(folder: str, name: str,
                      path: str | os.PathLike[str]) -> tuple[int, str]:
    """A new file beside the target that nobody else made: (fd, its path)."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC
    for _ in range(16):
        tmp = os.path.join(folder, f".{name}.{secrets.token_hex(8)}.part")
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:
            continue  # someone's file (or link) has this name: never touch it
        except OSError as exc:
            raise FileError(path, f"cannot write: {exc.strerror}") from None
    raise FileError(path, f"cannot write: {os.strerror(errno.EEXIST)}")


def _sync_folder(folder: str) -> None:
    """The rename itself on disk (best effort: not every file system allows it)."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
