"""Event logs as JSON Lines, written line by line."""

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
