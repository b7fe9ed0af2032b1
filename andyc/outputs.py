"""Files andyc writes: never over an input, always whole.

Every output is checked before the work that produces it (`check_output`):
it must not be one of the files the command reads (the model, a table, a
controller, the jumps file), not a folder, and its folder must be creatable and
writable. It is then written under a temporary name in the same folder and
renamed into place (`write_atomic`), so an interrupted or failed write leaves
the old file or none, never a truncated one, and two processes writing the
same file each leave a whole one. The user's jumps file is created only where
none exists (`create_once`), even when two builds race.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


class OutputError(ValueError):
    """An output path that cannot or must not be written; the message says which and why."""


def check_output(path, inputs=(), what: str = "output") -> Path:
    """`path` as given, after checking that it may be written; OutputError otherwise.

    inputs: the files the command reads (paths; missing ones are ignored), none of which may be overwritten.
    """
    path = Path(path)
    for source in inputs:
        if source is not None and _same_file(path, Path(source)):
            raise OutputError(f"{path}: the {what} would overwrite {source}, which this command reads; "
                              f"write the {what} elsewhere")
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; give a file name for the {what}")
    check_folder(path.parent)
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputError(f"{path}: the file is read-only; write the {what} elsewhere, or make it writable")
    return path


def check_folder(folder, inputs=(), write: bool = True) -> Path:
    """`folder`, after checking that it is a folder (or can be made one) that can be written in (`write`:
    False for a build folder, which an up-to-date build only reads: a write it needs fails where it is made,
    with OutputError)."""
    folder = Path(folder)
    for source in inputs:
        if source is not None and _same_file(folder, Path(source)):
            raise OutputError(f"{folder}: is the file {source}, which this command reads; give a folder")
    existing = folder
    while not existing.exists():
        if existing.parent == existing:
            break
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise OutputError(f"{folder}: {existing} is a file, not a folder; choose another folder")
    if write and existing.exists() and not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError(f"{folder}: cannot write in {existing} (permission denied); choose a folder you can "
                          f"write in")
    return folder


def _same_file(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.abspath(a) == os.path.abspath(b) or a.resolve() == b.resolve()


@contextmanager
def _temporary(path: Path):
    """A new, empty file beside `path` (its folder made if missing), removed on leaving unless renamed away."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".tmp{path.suffix}")
    except OSError as exc:
        raise OutputError(f"{path}: cannot write it ({exc.strerror}); choose another place") from None
    os.close(fd)
    os.chmod(name, _MODE)           # mkstemp makes it private; the result should be as any new file
    tmp = Path(name)
    try:
        yield tmp
    finally:
        tmp.unlink(missing_ok=True)


@contextmanager
def write_atomic(path):
    """`with write_atomic(path) as tmp:` write the file at tmp (a new name in path's folder); on leaving the
    block without an error, tmp is renamed to path in one step. OutputError when it cannot be written."""
    path = Path(path)
    with _temporary(path) as tmp:
        try:
            yield tmp
            os.replace(tmp, path)
        except OSError as exc:
            raise OutputError(f"{path}: cannot write it ({exc.strerror}); choose another place") from None


@contextmanager
def new_folder_atomic(path):
    """`with new_folder_atomic(path) as tmp:` fill the new folder tmp (beside path); on leaving the block
    without an error it is renamed to path in one step (a result store is made whole or not at all: its
    later updates are the chunk files its library writes, each atomically). OutputError when path exists
    by then or cannot be written."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp"))
    except OSError as exc:
        raise OutputError(f"{path}: cannot write it ({exc.strerror}); choose another place") from None
    try:
        yield tmp
        os.rename(tmp, path)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write it ({exc.strerror}); choose another place") from None
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def write_text(path, text: str) -> Path:
    """Write `text` (UTF-8) to path, atomically."""
    with write_atomic(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def update_text(path, text: str) -> bool:
    """write_text, unless the file holds `text` already (then it is not touched: its time stamp is
    what Numba's cache checks); True when written."""
    try:
        if Path(path).read_text(encoding="utf-8") == text:
            return False
    except (OSError, UnicodeDecodeError):
        pass
    write_text(path, text)
    return True


def create_once(path, text: str) -> bool:
    """Write `text` to path only if no file is there, even against a concurrent writer: the whole file is
    written under a temporary name, then linked to path, which fails when path exists. True when written."""
    path = Path(path)
    with _temporary(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
        try:
            os.link(tmp, path)
        except FileExistsError:
            return False
        except OSError:             # a file system without hard links: an exclusive create, written in place
            try:
                with open(path, "x", encoding="utf-8") as fh:
                    fh.write(text)
            except FileExistsError:
                return False
            except OSError as exc:
                raise OutputError(f"{path}: cannot write it ({exc.strerror}); choose another place") from None
    return True


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_MODE = 0o666 & ~_umask()
