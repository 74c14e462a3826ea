"""Event logs as JSON Lines, written line by line, and read back."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path


class JsonLines:
    """A JSON Lines file written line by line (each line flushed, so a killed run keeps its log).

    ``write(event, **fields)`` adds ``{"event": ..., "time": <s since open>, ...}``, and
    raises ValueError for a field that is not finite (every line is valid JSON);
    :attr:`ended` tells whether an ``end`` event was written. ``path`` must be new: a file
    there is never emptied (FileExistsError), whoever made it since its caller looked.
    """

    def __init__(self, path: Path):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        self._file = open(path, "x", encoding="utf-8")
        self._lock = threading.Lock()
        self._start = time.monotonic()
        self.ended = False

    def write(self, event: str, **fields) -> None:
        record = {"event": event, "time": round(time.monotonic() - self._start, 4), **fields}
        # NaN and Infinity are not JSON: a record holding one is a bug where it was made, not a line to write
        text = json.dumps(record, separators=(",", ":"), allow_nan=False)
        with self._lock:
            if not self._file.closed:
                self._file.write(text + "\n")
                self._file.flush()
            self.ended = self.ended or event == "end"

    def close(self) -> None:
        with self._lock:
            self._file.close()


def read_records(log: Path) -> list[dict]:
    """The records of a drive's log, each with its line number (``_line``); a last line cut short left out, noted.

    Raises
    ------
    CuriosityError
        A line before the last that is not a JSON object, naming it.
    """
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.files import display_path, note

    try:
        lines = log.read_text().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise CuriosityError(f"{display_path(log)}: cannot be read ({exc})") from None
    records = []
    for number, line in enumerate(lines, start=1):
        try:
            record = json.loads(line)
        except ValueError:
            if number == len(lines):
                note(f"{display_path(log)}: its last line is cut short (a run stopped while writing it?); it is left out")
                break
            raise CuriosityError(f"{display_path(log)}: line {number}: not a JSON record") from None
        if not isinstance(record, dict):
            raise CuriosityError(f"{display_path(log)}: line {number}: expected a JSON object, got {type(record).__name__}")
        records.append({**record, "_line": number})
    return records


def frame_records(log: Path, fields: tuple[str, ...], keep=lambda record: True) -> list[dict]:
    """The ``frame`` records of a drive's log that ``keep`` takes, each checked to hold ``fields``
    (:func:`read_records`).

    Raises
    ------
    CuriosityError
        As :func:`read_records`; a frame record without one of ``fields``, naming its line and the field.
    """
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.files import display_path

    records = [r for r in read_records(Path(log)) if r.get("event") == "frame" and keep(r)]
    for record in records:
        missing = [k for k in fields if k not in record]
        if missing:
            raise CuriosityError(f"{display_path(Path(log))}: line {record['_line']}: a frame record without {missing[0]!r}")
    return records
