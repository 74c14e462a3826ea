"""Reading ``evaluate``'s tables back: the one way every reader reads an evaluation table
(:func:`read_table`), an experiment's ``maps.csv`` (:func:`read_maps`), and the error of
results that cannot be evaluated (:class:`EvaluationError`). What each table holds: the
evaluation stage, :mod:`~curiosity_cli.evaluate.stage`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import display_path


class EvaluationError(CuriosityError):
    """Results that cannot be evaluated: missing, corrupt, or not from the same maps."""


#: :func:`read_table`'s ``absent`` when a missing table is an error.
_RAISE = object()


def read_table(path: Path, columns: Sequence[str] = (), *, absent=_RAISE, error: type = EvaluationError, **options):
    """An evaluation table, the one way every reader reads one back.

    Parameters
    ----------
    path : Path
        The CSV file ``evaluate`` wrote.
    columns : sequence of str
        Columns it must have (others are kept).
    absent : optional
        What a missing file gives; without it, a missing file is an error.
    error : type
        The :class:`~curiosity_cli.errors.CuriosityError` to raise (a figure's reader raises its own).
    **options
        For :func:`pandas.read_csv` (a table whose empty cells mean "" rather than missing).

    Returns
    -------
    pandas.DataFrame
        Empty, without columns, for a table written without any (no run was labelled twice).

    Raises
    ------
    error
        Missing, unreadable, or without one of ``columns``; naming the file and that ``evaluate``
        makes it.
    """
    import pandas as pd

    path = Path(path)
    again = {"rerun": "evaluate", "force": False}
    if not path.is_file():
        if absent is not _RAISE:
            return absent
        raise error(f"{display_path(path)}: not found; {RERUN} makes it", **again)
    try:
        table = pd.read_csv(path, **options)
    except pd.errors.EmptyDataError:
        table = pd.DataFrame()
    except (OSError, ValueError) as exc:  # pandas' parser errors are ValueErrors, a bad encoding a UnicodeDecodeError
        raise error(f"{display_path(path)}: not a readable CSV table ({exc}); {RERUN} makes it again", **again) from None
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise error(
            f"{display_path(path)}: no column {missing[0]!r}; expected {', '.join(columns)} ({RERUN} makes it again)",
            **again,
        )
    return table


def read_maps(folder: Path):
    """``maps.csv`` of an experiment (each map's words and the paper map it stands in
    for, written by ``explore``), or None for a folder from before it existed.

    Raises
    ------
    EvaluationError
        It is not as ``explore`` wrote it (``provenance.yaml`` records its size and digest), or cannot be read.
    """
    import pandas as pd

    import yaml

    from curiosity_cli.experiment.wholeness import FILES_KEY, changed

    layout = ExperimentFolder(folder)
    path = layout.maps_csv
    if not path.is_file():
        return None
    try:  # what explore recorded of it (nothing in a folder from before it did)
        written = yaml.safe_load(layout.provenance.read_text()).get(FILES_KEY, {})
    except (OSError, yaml.YAMLError, AttributeError):
        written = {}
    if path.name in written and (change := changed(layout.root, {path.name: written[path.name]})) is not None:
        raise EvaluationError(
            f"{display_path(path)}: {change[1]} (explore wrote it); {RERUN} writes it again, keeping the runs",
            rerun="explore", force=False,
        )
    try:
        return pd.read_csv(path, keep_default_na=False, na_values=[""])
    except (ValueError, OSError) as exc:
        raise EvaluationError(f"{display_path(path)}: cannot read the table of maps: {exc}") from None
