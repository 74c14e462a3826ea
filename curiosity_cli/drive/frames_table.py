"""A drive's frames as one flat table: ``frames.parquet`` and ``frames.csv``, one row per frame.

The table is made from the run's ``log.jsonl`` (the record of the run), so it says what
the log says: a frame's times as integer nanoseconds, its surprise (the mean of its
image cells' topic perplexity, the paper's, section 5.2) and its parts, the refinement
it got, the command it gave and its pose. The mission file
(:mod:`~curiosity_cli.drive.mission`) takes its numbers from the same rows through
:func:`frame_summary`, so the two agree value for value.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: The table's files in a run folder.
FRAMES_PARQUET, FRAMES_CSV = "frames.parquet", "frames.csv"
#: Where ``frames.parquet``'s schema metadata records what it was made from: the SHA-256 of the run's log and its
#: frames, so that a table edited, or another run's, is never read as this run's.
MADE_FROM = b"curiosity.made_from"

#: Its columns, in order; the integer ones that may be missing are pandas' nullable Int64.
COLUMNS = (
    "frame", "time_ns", "bag_time_ns", "header_time_ns", "surprise", "perplexity_max", "score_max", "refined",
    "words", "target_row", "target_col", "surge", "yaw_rate", "pitch_rate", "latency_ms",
    "pose_source", "pose_frame", "x", "y", "z", "yaw", "pose_gap_ms",
)
_NULLABLE_INTS = ("bag_time_ns", "header_time_ns")


def frame_summary(row: dict) -> dict:
    """A frame record's surprise and its parts.

    Parameters
    ----------
    row : dict
        A ``frame`` record of a drive's log.

    Returns
    -------
    dict
        ``surprise`` (mean cell perplexity), ``perplexity_max``, ``score_max`` (the decayed
        score that steered), ``refined`` (word samples of its own refinement), ``words``.
    """
    perplexity = np.asarray(row["perplexity"], np.float64)
    return {
        "surprise": round(float(perplexity.mean()), 6),
        "perplexity_max": float(perplexity.max()),
        "score_max": float(np.max(row["scores"])),
        "refined": int(row.get("refined", 0)),
        "words": int(row["words"]),
    }


def frames_table(log: Path):
    """The frames of a drive's log as a DataFrame with :data:`COLUMNS`.

    Raises
    ------
    CuriosityError
        A line before the last that is not a JSON object, or a frame record without a
        field the table reads, naming the line.
    """
    import pandas as pd

    from curiosity_cli.drive.jsonlines import frame_records

    rows = []
    for record in frame_records(Path(log), ("frame", "time_ns", "perplexity", "scores", "words", "target", "command")):
        pose = record.get("pose") or {}
        command = record["command"]
        rows.append({
            "frame": record["frame"],
            "time_ns": record["time_ns"],
            "bag_time_ns": record.get("bag_time_ns"),
            "header_time_ns": record.get("header_time_ns"),
            **frame_summary(record),
            "target_row": record["target"][0],
            "target_col": record["target"][1],
            "surge": command["surge"],
            "yaw_rate": command["yaw_rate"],
            "pitch_rate": command["pitch_rate"],
            "latency_ms": record.get("latency_ms"),
            "pose_source": pose.get("source"),
            "pose_frame": pose.get("frame_id"),
            "x": pose.get("x"),
            "y": pose.get("y"),
            "z": pose.get("z"),
            "yaw": pose.get("yaw"),
            "pose_gap_ms": pose.get("gap_ms"),
        })
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    for name in _NULLABLE_INTS:
        table[name] = table[name].astype("Int64")
    for name in ("frame", "time_ns", "refined", "words", "target_row", "target_col"):
        table[name] = table[name].astype(np.int64)
    for name in ("pose_source", "pose_frame"):
        table[name] = table[name].astype("string")
    for name in ("latency_ms", "x", "y", "z", "yaw", "pose_gap_ms"):
        table[name] = table[name].astype(np.float64)
    return table


def write_frames_table(folder: Path):
    """Write :data:`FRAMES_PARQUET` and :data:`FRAMES_CSV` from ``folder``'s log; the table written.

    Each is written whole under a temporary name and renamed into place.

    Raises
    ------
    CuriosityError
        As :func:`frames_table`.
    """
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from curiosity_cli.drive.driver import RUN_LOG
    from curiosity_cli.files import atomic_path, file_sha256

    folder = Path(folder)
    table = frames_table(folder / RUN_LOG)
    made_from = json.dumps({"log_sha256": file_sha256(folder / RUN_LOG), "frames": len(table)}).encode()
    arrow = pa.Table.from_pandas(table, preserve_index=False)
    arrow = arrow.replace_schema_metadata({**(arrow.schema.metadata or {}), MADE_FROM: made_from})
    with atomic_path(folder / FRAMES_PARQUET) as tmp:
        pq.write_table(arrow, tmp)
    with atomic_path(folder / FRAMES_CSV) as tmp:
        table.to_csv(tmp, index=False)
    return table


def read_frames_table(folder: Path):
    """A run's frames: its ``frames.parquet`` where that was made from the run's log as the log is now (the
    log's SHA-256 and frame count it records), else the log's own (:func:`frames_table`), with a note saying why:
    a table edited, another run's, or one of a run stopped before writing it.

    Raises
    ------
    CuriosityError
        A table that is no parquet file, or a log that cannot be read, naming the file.
    """
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from curiosity_cli.drive.driver import RUN_LOG
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.files import display_path, file_sha256, note

    folder = Path(folder)
    path, log = folder / FRAMES_PARQUET, folder / RUN_LOG
    if not path.is_file():
        return frames_table(log)
    try:
        arrow = pq.read_table(path)
    except (OSError, ValueError, pa.ArrowException) as exc:
        raise CuriosityError(f"{display_path(path)}: cannot be read ({' '.join(str(exc).split())})") from None
    try:
        made_from = json.loads((arrow.schema.metadata or {}).get(MADE_FROM, b"null"))
    except ValueError:
        made_from = None
    if not isinstance(made_from, dict):
        why = "it does not say which log it was made from (written by another tool, or before tables said)"
    elif made_from.get("log_sha256") != file_sha256(log):
        why = "it was made from another log than this run's (another run's table, or the log changed since)"
    elif made_from.get("frames") != arrow.num_rows:
        why = f"it holds {arrow.num_rows} frames where the log it was made from has {made_from.get('frames')}"
    else:
        return arrow.to_pandas()
    note(f"{display_path(path)}: {why}; the frames are read from {display_path(log)}")
    return frames_table(log)
