"""File helpers shared by every stage: writing atomically, reading ``.npz`` files and their meta,
digests of files and arrays, showing paths and naming OS errors (YAML: :mod:`curiosity_cli.yamlfile`)."""

from __future__ import annotations

import contextlib
import errno
import os
import sys
import tempfile
from pathlib import Path

from curiosity_cli.errors import ConfigError, CuriosityError


#: The first bytes of a zip archive, and so of every ``.npz`` file.
_ZIP_MAGIC = b"PK\x03\x04"


class CorruptFileError(CuriosityError):
    """A file that exists but cannot be read as what it should be: truncated, empty, or another format."""


def resolved(path: str | Path) -> Path:
    """``Path(path).resolve()``, a symlink loop raised as the OS error it is, which the CLI
    reports by its path (Python 3.11's ``resolve`` raises ``RuntimeError`` for it)."""
    try:
        return Path(path).resolve()
    except RuntimeError:
        raise OSError(errno.ELOOP, os.strerror(errno.ELOOP), str(path)) from None


def display_path(path: Path) -> str:
    """A path as a user would type it: relative to the current directory when inside it."""
    try:
        return str(resolved(path).relative_to(Path.cwd()))
    except (ValueError, OSError):
        return str(path)


def os_error_message(exc: OSError) -> str:
    """One line for an operating-system error: the path it concerns and what went wrong.

    A folder that cannot be made because a file is in its way (``ENOTDIR``, ``EEXIST``)
    names that file, not the deeper path being made, and says a folder was expected.

    Parameters
    ----------
    exc : OSError
        As raised by any file operation, here or in a worker.
    """
    reason = exc.strerror or str(exc) or type(exc).__name__
    if exc.filename is None:
        return reason
    path = Path(os.fsdecode(exc.filename))
    if exc.errno in (errno.ENOTDIR, errno.EEXIST, errno.ELOOP):
        # a file that is itself a loop keeps the system's words; a folder above it in the way is named
        blocking = _in_the_way(path if exc.errno != errno.ELOOP else path.parent)
        if blocking is not None:
            where, what = blocking
            return f"{display_path(where)}: {what}; expected a folder"
    return f"{display_path(path)}: {reason}"


def _in_the_way(path: Path) -> tuple[Path, str] | None:
    """The nearest of ``path`` and its parents that is not a folder, and what it is instead: a file, or a symbolic
    link that leads nowhere (a loop, or a missing target: "File exists" said of it named no cause)."""
    for candidate in (path, *path.parents):
        if candidate.is_symlink() and not candidate.exists():
            return candidate, "a symbolic link that leads nowhere (a loop, or its target is missing)"
        if candidate.exists() and not candidate.is_dir():
            return candidate, "is a file"
    return None


def unwritable(folder: Path) -> str | None:
    """None when files can be written in ``folder`` (made if missing); else why not, as :func:`os_error_message`
    words it. A stage that writes there after its work asks first, so that a read-only folder, one under a file or
    a link that leads nowhere is found before the work, not after it."""
    try:
        Path(folder).mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=_PROBE):
            pass
    except OSError as exc:
        if exc.filename is not None and Path(os.fsdecode(exc.filename)).name.startswith(_PROBE):
            exc.filename = os.fspath(folder)  # the folder refused the file: name it, not the probe's random name
        return os_error_message(exc)
    return None


_PROBE = ".writable-"


def note(line: str) -> None:
    """Tell the user, in one line on stderr, something the command did that they did not ask for."""
    print(line, file=sys.stderr, flush=True)


@contextlib.contextmanager
def open_npz(path: Path):
    """``np.load(path)`` of a ``.npz`` file whose reading, inside the block too, fails as one error.

    A truncated, empty or foreign file fails in many ways (a bad zip, a short stream, a
    missing member, zlib's own error) and some only when a member is read, so the block
    is covered as well. An operating-system error (no such file, no permission) is not
    corruption and passes through as it is.

    Raises
    ------
    FileNotFoundError, OSError
        No such file (the caller decides whether that is a mistake or work still to do),
        or one that cannot be opened.
    CorruptFileError
        The file exists but is not the ``.npz`` expected; the message names it.
    """
    import zipfile
    import zlib

    import numpy as np

    def corrupt(reason: str) -> CorruptFileError:
        return CorruptFileError(f"{display_path(Path(path))}: corrupt or truncated ({reason})")

    # opened here: np.load leaves the file it opened open when the zip in it is bad
    with open(path, "rb") as handle:
        start = handle.read(len(_ZIP_MAGIC))
        if start != _ZIP_MAGIC:  # else numpy tries it as a pickle, and says so
            raise corrupt("not a .npz archive" if start else "empty")
        handle.seek(0)
        try:
            with np.load(handle, allow_pickle=False) as npz:
                yield npz
        except (ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise corrupt(_reason(exc)) from None


def file_sha256(path: Path) -> str:
    """Hex SHA-256 of a file's bytes, read in blocks of 1 MiB."""
    import hashlib

    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def arrays_digest(arrays: dict) -> str:
    """SHA-256 of named arrays (each one's name, dtype, shape and bytes, in the dict's order): what a
    ``.npz`` file's meta records of its arrays when written, so that arrays altered since are found."""
    import hashlib

    import numpy as np

    digest = hashlib.sha256()
    for name, array in arrays.items():
        array = np.ascontiguousarray(array)
        digest.update(f"{name}:{array.dtype.str}:{array.shape};".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def read_meta(npz, required: tuple[str, ...] = ()) -> dict:
    """The JSON ``meta`` of an ``.npz`` file this package wrote (a batch reference, a label file), with the ``required`` keys.

    Raises
    ------
    KeyError, ValueError
        No meta, not a JSON object, or a required key missing: read inside
        :func:`open_npz`, the file is reported as corrupt.
    """
    import json

    meta = json.loads(str(npz["meta"]))
    if not isinstance(meta, dict):
        raise ValueError("its meta is not a JSON object")
    missing = [key for key in required if key not in meta]
    if missing:
        raise KeyError(f"its meta lacks {', '.join(missing)}")
    return meta


def _reason(exc: Exception) -> str:
    """An exception's message without the quotes a KeyError adds, or its type if it has none."""
    text = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    return str(text) or type(exc).__name__


#: The name of :func:`atomic_path`'s temporary files.
LEFTOVER = ".*.tmp*"


def remove_leftovers(folder: Path) -> int:
    """Delete the temporary files writers killed inside :func:`atomic_path` left below ``folder``; how many.

    For a stage that starts over in a folder it alone writes: a file being written by
    another command at the same time would go too.
    """
    removed = 0
    for path in Path(folder).rglob(LEFTOVER):
        if path.is_file():
            path.unlink(missing_ok=True)
            removed += 1
    return removed


@contextlib.contextmanager
def atomic_path(path: Path):
    """Yield a temporary path beside ``path``; it replaces ``path`` only if the block succeeds.

    A reader never sees a half-written file, and a killed writer leaves at most a stray
    ``.tmp`` file (:data:`LEFTOVER`, which :func:`remove_leftovers` deletes), never a
    truncated result under the real name.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}")
    except OSError as exc:  # a read-only folder: name the file to be written, not its temporary twin
        raise OSError(exc.errno, exc.strerror, os.fspath(path)) from None
    os.close(fd)
    # mkstemp makes the file private (0600); a result should get the permissions of any new file
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        with naming_os_errors(path, tmp):
            yield Path(tmp)
        try:
            os.replace(tmp, path)
        except OSError as exc:  # e.g. a folder where the file belongs: name it, not the temporary file
            raise OSError(exc.errno, exc.strerror, os.fspath(path)) from None
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


@contextlib.contextmanager
def naming_os_errors(path: Path, stand_in: str | None = None):
    """Give an OS error raised in the block the name ``path`` when it has no file name, or names ``stand_in``.

    A write to a file already open (a full disk: ``ENOSPC``) fails without saying which
    file, and one to a temporary file (``stand_in``, :func:`atomic_path`) names a file the
    user never asked for; the user is told the result it was writing instead.
    """
    try:
        yield
    except OSError as exc:
        named = exc.filename is not None and not (stand_in is not None and os.fsdecode(exc.filename) == stand_in)
        if named or exc.errno is None:
            raise
        raise OSError(exc.errno, exc.strerror, os.fspath(path)) from None


def check_inside(path: Path, root: Path, what: str) -> None:
    """Refuse a ``path`` built from names that does not resolve to somewhere below ``root``.

    Names are validated when a config is loaded; this second line of defence keeps a name
    that slipped through from writing outside the results or the cache.
    """
    inside, top = resolved(path), resolved(root)
    if top not in inside.parents:
        raise ConfigError(
            f"{what}: {display_path(path)} is not inside {display_path(root)}; "
            "expected a name without '/' or '..'"
        )
