"""The seconds each stage of an experiment took, whether it ran in one ``reproduce`` or one command at a time.

``stage_seconds.json`` holds, per stage, the time of the calls that made its results: the
resumable stages (extract and explore, label) add each call's time to the last, so a
resumed stage reports all the work it did, not the few seconds of its last call; a call
that recomputes everything (``force``, and always ``evaluate`` and ``plot``) replaces it.
The report's time table reads it (:func:`read_stage_seconds`).
"""

from __future__ import annotations

import json
from pathlib import Path

from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import atomic_path, display_path, note

#: The stages, in the order they run and the report lists them.
STAGES = ("extract and explore", "label", "evaluate", "plot")


def record_stage_seconds(folder: Path, stage: str, seconds: float, *, add: bool) -> None:
    """Record that ``stage`` took ``seconds`` in the experiment ``folder``: added to its time so far, or in its place.

    The stage holds the folder's lock (:mod:`~curiosity_cli.experiment.lock`) while it
    records, so no two stages write the file at once.
    """
    if stage not in STAGES:
        raise ValueError(f"stage: got {stage!r}, expected one of {', '.join(STAGES)}")
    path = ExperimentFolder(folder).stage_seconds
    times, problem = _read(folder)
    if problem is not None:
        note(f"{problem}; the stage times it held are lost: {stage}'s is recorded alone")
    times[stage] = (times.get(stage, 0.0) if add else 0.0) + float(seconds)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({name: times[name] for name in STAGES if name in times}, indent=1) + "\n")


def stage_seconds_problem(folder: Path) -> str | None:
    """Why ``stage_seconds.json`` of ``folder`` cannot be read, naming it; None when it is missing or fine."""
    return _read(folder)[1]


def read_stage_seconds(folder: Path) -> dict[str, float]:
    """The seconds of each stage recorded in ``folder``, in :data:`STAGES` order; none for a file missing or unreadable.

    The times are a report's footnote, never a reason to refuse one: a file that cannot
    be read counts as no times at all (:func:`stage_seconds_problem` says why, for the
    report and the next stage to say so).
    """
    return _read(folder)[0]


def _read(folder: Path) -> tuple[dict[str, float], str | None]:
    """The stages' seconds a file holds (the readable ones, in :data:`STAGES` order), and what is wrong with it."""
    path = ExperimentFolder(folder).stage_seconds
    try:
        recorded = json.loads(path.read_text())
    except FileNotFoundError:
        return {}, None
    except (OSError, ValueError) as exc:
        return {}, f"{display_path(path)}: cannot be read ({exc})"
    malformed = f"{display_path(path)}: expected a mapping of stage names to seconds"
    if not isinstance(recorded, dict):
        return {}, malformed

    def seconds(value) -> bool:
        return isinstance(value, (int, float)) and not isinstance(value, bool)

    times = {name: float(recorded[name]) for name in STAGES if seconds(recorded.get(name))}
    return times, None if all(map(seconds, recorded.values())) else malformed
