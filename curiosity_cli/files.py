"""File helpers shared by every stage: reading YAML, writing atomically, showing paths."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

from curiosity_cli.errors import ConfigError


def display_path(path: Path) -> str:
    """A path as a user would type it: relative to the current directory when inside it."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def read_yaml(path: Path, what: str) -> dict:
    """Read a YAML file whose top level is a mapping.

    Raises
    ------
    ConfigError
        Missing file, not YAML, not text, or not a mapping; the message names the file.
    """
    import yaml

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{display_path(path)}: {what} not found")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "not valid YAML"
        raise ConfigError(f"{display_path(path)}: not valid YAML{where}: {problem}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{display_path(path)}: not a text file; expected YAML") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(
            f"{display_path(path)}: expected a mapping of keys at the top level, "
            f"got {type(data).__name__}"
        )
    return data


@contextlib.contextmanager
def atomic_path(path: Path):
    """Yield a temporary path beside ``path``; it replaces ``path`` only if the block succeeds.

    A reader never sees a half-written file, and a killed writer leaves at most a stray
    ``.tmp`` file, never a truncated result under the real name.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}")
    os.close(fd)
    # mkstemp makes the file private (0600); a result should get the permissions of any new file
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def user_cache_dir() -> Path:
    """The user's cache of downloads and derived data: ``$CURIOSITY_CACHE``, else
    ``$XDG_CACHE_HOME/curiosity``, else ``~/.cache/curiosity``.

    Source archives go to its ``sources/`` folder, maps made from them to ``maps/<name>/``.
    Nothing here is committed; deleting it costs only a download.
    """
    env = os.environ.get("CURIOSITY_CACHE")
    if env:
        return Path(env).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "curiosity"
