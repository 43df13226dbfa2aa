"""Files on disk, the one way fitbench opens and writes them (readers, CLI outputs, results, figures, the
method manifest): only regular files, written atomically.

* :func:`write_atomic` / :func:`atomic_path`: the new content goes to a temporary file beside the target and
  replaces it with ``os.replace``, so a reader sees the old file or the whole new one, never a partial one,
  and a failed write leaves no temporary file. A symlink is written *through*: its regular target is
  replaced and the link stays. A target that exists and is not a regular file (a FIFO, a device such as
  ``/dev/null``, a folder) is refused in one line (:class:`NotRegularFileError`). A new file gets the mode
  ``open()`` would give it (0666 less the umask); an existing file keeps its mode.
* :class:`StagedFiles`: the same for several files written together (a command's outputs): no target is
  replaced before every one was written.
* :func:`open_regular`: a file opened for reading after checking, on the open descriptor, that it is a
  regular file: a FIFO or a device is refused without blocking (``O_NONBLOCK`` on the open).

This is the lowest layer that writes a file (``python -m methods._manifest``), so every package above
uses it; it imports nothing but the standard library.
"""
from __future__ import annotations

import contextlib
import io
import os
import stat
import tempfile
from pathlib import Path

from methods._errors import InvalidInputError

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISDIR, "a folder"), (stat.S_ISSOCK, "a socket"))


class NotRegularFileError(InvalidInputError):
    """A path that names a FIFO, a device, a folder or a socket where a regular file is needed."""


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _refuse(path, mode: int, verb: str) -> NotRegularFileError:
    return NotRegularFileError(f"{path}: is {_kind(mode)}, not a regular file; {verb} a regular file")


def _new_file_mode() -> int:
    """0666 less the process umask: the mode ``open(path, 'w')`` gives a new file."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def writable_target(path) -> Path:
    """The file a write to ``path`` replaces: ``path`` itself, or the final target of a symlink chain.
    Raises :class:`NotRegularFileError` when that target exists and is not a regular file."""
    path = Path(path)
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    try:
        st = os.stat(target)
    except FileNotFoundError:
        return target
    except OSError:
        return target  # the write below reports it
    if not stat.S_ISREG(st.st_mode):
        raise _refuse(path, st.st_mode, "write to")
    return target


def _temporary_beside(path, make_parents: bool) -> tuple[Path, Path, int]:
    """(a new empty temporary file in the target's folder with the target's suffix, the target
    (:func:`writable_target`), the mode the target gets: its own if it exists, else the umask's)."""
    target = writable_target(path)
    folder = target.parent if str(target.parent) else Path(".")
    if make_parents:
        folder.mkdir(parents=True, exist_ok=True)
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        mode = _new_file_mode()
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{target.name}.", suffix=f".tmp{target.suffix}")
    os.close(fd)
    return Path(tmp), target, mode


def _remove(tmp) -> None:
    if os.path.lexists(tmp):
        os.unlink(tmp)


@contextlib.contextmanager
def atomic_path(path, *, make_parents: bool = False):
    """``with atomic_path(p) as tmp:`` write the new file to ``tmp`` (a path in the target's folder with the
    target's suffix, for writers that take a file name such as ``savefig``); when the block ends without
    error ``tmp`` replaces the target (:func:`writable_target`), else it is removed."""
    tmp, target, mode = _temporary_beside(path, make_parents)
    try:
        yield tmp
        os.chmod(tmp, mode)
        os.replace(tmp, target)
    finally:
        _remove(tmp)


class StagedFiles:
    """Several files replaced together (a command's outputs), as :func:`atomic_path` replaces one:
    ``with staged.path(p) as tmp:`` write ``p``'s new content to ``tmp``; nothing replaces a target until
    :meth:`commit`, which moves every temporary onto its target once all were written; :meth:`discard`
    removes the temporaries, leaving every target as it was. ``written`` lists the paths committed."""

    def __init__(self):
        self._staged: list[tuple[str, Path, Path, int]] = []   # (path as given, temporary, target, mode)
        self._writing: list[Path] = []   # temporaries being written: :meth:`discard` removes them too
        self.written: list[str] = []

    @contextlib.contextmanager
    def path(self, path, *, make_parents: bool = False):
        tmp, target, mode = _temporary_beside(path, make_parents)
        self._writing.append(tmp)   # known from now on: an exception anywhere (a signal's) cannot lose it
        try:
            yield tmp
            for i, (_, old, t, _) in enumerate(self._staged):   # written again: the last content counts
                if t == target:
                    _remove(old)
                    del self._staged[i]
                    break
            self._staged.append((str(path), tmp, target, mode))
        except BaseException:
            _remove(tmp)
            raise
        finally:
            self._writing.remove(tmp)

    def pending(self) -> list[str]:
        """The paths written to temporaries and not yet moved onto their targets."""
        return [given for given, *_ in self._staged]

    def commit(self) -> None:
        """Move every temporary onto its target, in the order written; an OSError names the path it failed on
        in ``filename`` and leaves ``written`` (the paths replaced before it) and :meth:`pending` (it and the
        rest) for the caller to say."""
        while self._staged:
            given, tmp, target, mode = self._staged[0]
            try:
                os.chmod(tmp, mode)
                os.replace(tmp, target)
            except OSError as exc:
                exc.filename = given
                raise
            self._staged.pop(0)
            self.written.append(given)

    def discard(self) -> None:
        """Remove the temporaries not committed, those still being written included (every target stays as it was)."""
        for tmp in [t for _, t, _, _ in self._staged] + self._writing:
            _remove(tmp)
        self._staged.clear()


def write_atomic(path, data, *, make_parents: bool = True, fsync: bool = True) -> None:
    """Write ``data`` (str as UTF-8, or bytes) to ``path`` atomically (see the module docstring); the
    folder is created unless ``make_parents`` is false (then a missing folder is an OSError)."""
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    with atomic_path(path, make_parents=make_parents) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(payload)
            if fsync:
                fh.flush()
                os.fsync(fh.fileno())


def open_regular(path, *, encoding: str | None = "utf-8-sig", errors: str | None = None, newline=None):
    """``path`` opened for reading (text with ``encoding``, binary when it is None), refusing without
    blocking anything that is not a regular file (:class:`NotRegularFileError`). Other failures are the
    usual OSError (FileNotFoundError, PermissionError, ...)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _refuse(path, st.st_mode, "read")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        raw = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    if encoding is None:
        return raw
    return io.TextIOWrapper(raw, encoding=encoding, errors=errors, newline=newline)


def check_regular(path) -> None:
    """Refuse (:class:`NotRegularFileError`) a path that exists and is not a regular file, without opening it."""
    try:
        st = os.stat(path)
    except OSError:
        return
    if not stat.S_ISREG(st.st_mode):
        raise _refuse(path, st.st_mode, "read")
