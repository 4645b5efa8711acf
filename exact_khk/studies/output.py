"""Output files written atomically, and destinations checked before the work starts.

A reader never sees a truncated file: every file is written to a temporary
name in its target folder and renamed into place (``os.replace`` is atomic on
one file system).  :func:`check_writable` is called before a long computation,
so that a bad destination fails at once, not after the work.
"""

from __future__ import annotations

import os
import tempfile

from exact_khk.errors import OutputError


def check_writable(path, what: str = "output", trial: bool = True) -> str:
    """``path`` as a string if a file can be written there; else :class:`OutputError`
    naming the problem (missing folder, a folder in the way, no permission).  ``trial``:
    also create and remove a temporary file beside it, as :func:`write_atomic` will
    (/proc, /sys or a read-only file system pass the permission test)."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise OutputError(f"{what}: {path!r} is a folder, not a file")
    if not os.path.isdir(folder):
        raise OutputError(f"{what}: the folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"{what}: no permission to write in {folder!r}")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise OutputError(f"{what}: no permission to overwrite {path!r}")
    if trial and (not os.path.exists(path) or os.path.isfile(path)):
        fd, tmp = _temporary(path, folder, what)
        os.close(fd)
        os.unlink(tmp)
    return path


def _temporary(path, folder, what):
    """``(fd, name)`` of a new temporary file beside ``path`` (OutputError naming ``path``)."""
    try:
        return tempfile.mkstemp(prefix=".tmp-", suffix=os.path.basename(path), dir=folder)
    except OSError as exc:
        raise OutputError(f"{what}: cannot write {path!r} (a file cannot be created in {folder!r}: "
                          f"{exc.strerror or exc})") from None


#: the folders :func:`prepare_folder` created in this process (see :func:`settle_new_folders`)
_CREATED: list = []


def prepare_folder(path, what: str = "--out"):
    """The output folder ``path`` (a Path), created if missing; :class:`OutputError` if a
    file is in the way or it cannot be created (called before the work starts)."""
    from pathlib import Path

    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{what}: {str(folder)!r} exists and is not a folder")
    missing = [p for p in (folder, *folder.absolute().parents) if not p.exists()]
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{what}: cannot create the folder {str(folder)!r}: {exc.strerror or exc}") from None
    _CREATED.extend(missing)
    return folder


def settle_new_folders(failed: bool) -> None:
    """Forget the folders :func:`prepare_folder` created; when the work ``failed`` (the
    command line: an error or Ctrl-C), first remove those still empty, deepest first.
    A folder with anything in it stays."""
    for folder in sorted(_CREATED, key=lambda p: len(p.absolute().parts), reverse=True) if failed else ():
        try:
            folder.rmdir()  # only an empty folder
        except OSError:
            pass
    _CREATED.clear()


def write_atomic(path, data, what: str = "output") -> None:
    """Write ``data`` — a str (UTF-8 text), bytes, or a function that writes to a
    binary file object (e.g. ``lambda fh: fig.savefig(fh, format="png")``) — to
    ``path`` through a temporary file renamed into place (a path that exists and is
    not a regular file — a device such as /dev/stdout, a pipe — is written directly:
    renaming over it would replace it)."""
    path = check_writable(path, what, trial=False)  # the temporary file below is the trial

    def fill(fh):
        if callable(data):
            data(fh)
        else:
            fh.write(data.encode("utf-8") if isinstance(data, str) else data)

    if os.path.exists(path) and not os.path.isfile(path):
        try:
            with open(path, "wb") as fh:
                fill(fh)
        except OSError as exc:
            raise OutputError(f"{what}: cannot write {path!r}: {exc.strerror or exc}") from None
        return
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = _temporary(path, folder, what)
    try:
        with os.fdopen(fd, "wb") as fh:
            fill(fh)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a plain open() would honour the umask
        os.replace(tmp, path)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise OutputError(f"{what}: cannot write {path!r}: {exc.strerror or exc}") from None
        raise
