"""The rows of an experiment's tables, read from its runs and label files (:func:`label_rows`),
each checked against the recipe the experiment makes it by now; the evaluation stage
(:mod:`~curiosity_cli.evaluate.stage`) puts them in tables."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.evaluate.tables import EvaluationError
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import first_of
from curiosity_cli.files import CorruptFileError, display_path, open_npz

if TYPE_CHECKING:
    from curiosity_cli.config import ExperimentConfig


@dataclass(frozen=True)
class LabelRows:
    """What the label files hold, as table rows (:func:`label_rows`)."""

    mi: list[dict]  # one per run and checkpoint
    classes: list[dict]  # one per run, checkpoint and class with pixels
    left_out: list[str]  # runs of the grid without usable labels, each naming the file at fault and why
    notes: list[str]  # label files of runs outside the grid, which change no number
    steering: list[dict]  # one per run that scored its moves and checkpoint (steering.csv)
    mechanism: list[dict]  # likewise (mechanism.csv)


def run_rows(
    meta: dict, arrays: dict, class_names: dict[int, str] | None = None, steps: tuple | None = None,
) -> tuple[list[dict], list[dict]]:
    """The mi.csv rows (one per checkpoint) and classes.csv rows of one run's label file.

    Parameters
    ----------
    meta : dict
        The label file's ``meta``.
    arrays : dict of str to ndarray
        ``lengths`` (n,), ``batch`` (n, K, K), optionally ``human`` (n, K, C),
        ``class_first_step`` (C,), the visited cells' ``visited_batch`` and ``visited_human``,
        the held-out log-likelihood's ``heldout_bits`` and ``heldout_words`` (n, 2) and the
        second chain's ``placed_batch`` and ``placed_human``, as
        :func:`~curiosity_cli.label.stage.label_block` writes them.
    class_names : dict of int to str, optional
        The map's legend.
    steps : ((L,) int ndarray, (L,) bool ndarray), optional
        The run's path and ``boxed_in`` flags, for the revisit columns
        (:func:`~curiosity_cli.evaluate.revisits.revisit_counts`); NaN without.

    Returns
    -------
    (list of dict, list of dict)
    """
    from curiosity_cli.evaluate.information import matched_recall, mutual_information
    from curiosity_cli.evaluate.measures import Checkpoint, measure_values
    from curiosity_cli.evaluate.revisits import REVISIT_COLUMNS, revisit_counts
    from curiosity_cli.label.label_files import HELDOUT_BITS, HELDOUT_WORDS, SECOND_PREFIX, VISITED_PREFIX

    human, batch = arrays.get("human"), arrays["batch"]
    first = arrays.get("class_first_step")
    run = {"dataset": meta["dataset"], "weight_function": meta["weight_function"], "restart": meta["restart"]}
    rows, class_rows = [], []
    for i, length in enumerate(arrays["lengths"].tolist()):
        point = Checkpoint(
            length, batch[i], None if human is None else human[i], first,
            *(arrays[name][i] if name in arrays else None
              for name in (VISITED_PREFIX + "batch", VISITED_PREFIX + "human", HELDOUT_BITS, HELDOUT_WORDS)),
        )
        row = {
            **run, "path_length": length, **measure_values(point),
            "seed": " ".join(map(str, meta["run_seed"])), "replicate": meta["run_seed"][0],
            "placed_mi_human": np.nan, "placed_mi_batch": np.nan,
            **(revisit_counts(*steps, length) if steps is not None else dict.fromkeys(REVISIT_COLUMNS, np.nan)),
        }
        for against in ("human", "batch"):
            if SECOND_PREFIX + against in arrays:
                row[f"placed_mi_{against}"] = mutual_information(arrays[SECOND_PREFIX + against][i])
        if human is not None:
            pixels = human[i].sum(axis=0)
            recall, topic = matched_recall(human[i])
            for h in np.flatnonzero(pixels > 0).tolist():
                reached = first is not None and 0 <= first[h] < length
                class_rows.append({
                    **run, "path_length": length, "class_id": h, "class_name": (class_names or {}).get(h, ""),
                    "pixels": int(pixels[h]), "found": bool(reached) if first is not None else np.nan,
                    "first_step": float(first[h]) if reached else np.nan,
                    "topic": int(topic[h]), "recall": float(recall[h]),
                })
        rows.append(row)
    return rows, class_rows


def label_rows(experiment: Experiment, cache_dir: Path | None = None) -> LabelRows:
    """The table rows of every label file of an experiment, and the files left out, with why.

    Every label file must have been made from its run and its map's batch reference as
    the experiment's ``config.yaml`` and its maps as they are now make them, human labels
    included, and every run likewise (:meth:`~curiosity_cli.experiment.experiment.Experiment.run_recipe`);
    their files and example maps must be as they were written.

    Parameters
    ----------
    experiment : Experiment
    cache_dir : Path, optional
        Where the maps' word stores are cached (for ``mechanism.csv``); default the user cache.

    Raises
    ------
    EvaluationError
        No label files at all, or label files or runs made otherwise or altered since
        (naming them and what changed).
    CuriosityError
        A map of the config that cannot be loaded, naming it.
    """
    from curiosity_cli.label.label_files import examples_changed, read_label_file
    from curiosity_cli.evaluate.mechanism import mechanism_rows
    from curiosity_cli.evaluate.steering import steering_rows
    from curiosity_cli.explore.runs import RunError, read_run

    layout = experiment.folder
    files = layout.label_files()
    if not files:
        raise EvaluationError(f"{display_path(layout.labels)}: no label files; {RERUN} makes them", rerun="label", force=False)
    class_names = read_class_names(experiment.config)
    planned = _planned_label_files(experiment)
    files, notes = _in_grid(layout, files, planned)
    skipped = []
    rows, class_rows, steering, mechanism, otherwise = [], [], [], [], []
    batches = {}  # per map: what is wrong with its batch reference, None if nothing
    surroundings = {}  # per map: its classes per cell and its words per cell, for mechanism.csv
    for path in files:
        try:
            meta, arrays = read_label_file(path)
        except CorruptFileError as exc:
            skipped.append(f"{exc}; label the experiment again to redo it")
            continue
        if layout.label_file(meta["dataset"], meta["weight_function"], meta["restart"]) != path:
            # a file copied or moved over another run's: it would count its own run twice
            skipped.append(
                f"{display_path(path)}: holds the labels of {meta['dataset']} / {meta['weight_function']} / restart "
                f"{meta['restart']}, not of the run it is named after; label the experiment again to redo it"
            )
            continue
        if meta["dataset"] not in experiment.maps:
            skipped.append(f"{display_path(path)}: {meta['dataset']} is not a map of {display_path(layout.config)}")
            continue
        run_path = layout.run(meta["dataset"], meta["weight_function"], meta["restart"])
        try:
            run = read_run(run_path)
        except RunError as exc:
            skipped.append(str(exc))
            continue
        run_change = experiment.run_recipe(meta["dataset"], meta["weight_function"], meta["restart"]).changes(run.meta)
        if run_change is not None:
            otherwise.append(f"{display_path(run_path / 'run.json')}: {run_change}")
            continue
        if meta["dataset"] not in batches:
            batches[meta["dataset"]] = _batch_change(layout.batch(meta["dataset"]), experiment.batch_recipe(meta["dataset"]))
        if batches[meta["dataset"]] is not None:
            otherwise.append(batches[meta["dataset"]])
            continue
        change = experiment.label_recipe(run.meta).changes(meta)
        if change is not None:
            otherwise.append(f"{display_path(path)}: {change}")
            continue
        if (change := examples_changed(path, meta)) is not None:
            otherwise.append(change)
            continue
        try:
            steps = (run.path, run.boxed_in())
            candidates = run.candidates()
        except RunError as exc:
            skipped.append(str(exc))
            continue
        mi, classes = run_rows(meta, arrays, class_names.get(meta["dataset"]), steps)
        rows += mi
        class_rows += classes
        if mi:
            lengths = arrays["lengths"].tolist()
            steering += steering_rows(mi[0], candidates, lengths)
            if meta["dataset"] not in surroundings:
                surroundings[meta["dataset"]] = _surroundings(experiment, meta["dataset"], cache_dir)
            mechanism += mechanism_rows(mi[0], run.path, candidates, *surroundings[meta["dataset"]], lengths)
    if otherwise:
        raise EvaluationError(
            f"{len(otherwise)} label files or runs were made otherwise than {display_path(layout.config)} "
            f"and the maps make them now, or changed since ({first_of(otherwise)}); {RERUN} makes the label files "
            "again (explore first, for runs made otherwise)",
            rerun="label", force=False,
        )
    skipped += _unlabelled_runs(layout, files, planned)
    return LabelRows(rows, class_rows, skipped, notes, steering, mechanism)


def _surroundings(experiment: Experiment, dataset: str, cache_dir: Path | None) -> tuple:
    """A map's human classes present per cell ((n_cells, C) bool, C = 0 without labels) and
    its words per cell (the word store's ``cell_words``), for :func:`~curiosity_cli.evaluate.mechanism.mechanism_rows`."""
    from curiosity_cli.evaluate.mechanism import class_presence
    from curiosity_cli.maps.cell_classes import map_class_pixels
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.paths import DEFAULT_CACHE
    from curiosity_cli.words.extract import extract_words

    map_data = load_map(experiment.maps[dataset].entry)
    store = extract_words(map_data, experiment.config.words, cache_dir=cache_dir or DEFAULT_CACHE).store
    cell_classes = map_class_pixels(map_data)
    if cell_classes is None:
        return np.zeros((store.n_cells, 0), bool), store.cell_words
    return class_presence(cell_classes), store.cell_words


def _batch_change(path: Path, recipe) -> str | None:
    """What is wrong with a map's batch reference (missing, corrupt, or made otherwise than
    ``recipe``), in words; None if nothing. Its label files were compared with it, and the
    figures draw it."""
    from curiosity_cli.files import read_meta

    try:
        with open_npz(path) as npz:
            change = recipe.changes(read_meta(npz))
    except FileNotFoundError:
        return f"{display_path(path)}: not found"
    except CorruptFileError as exc:
        return str(exc)
    return None if change is None else f"{display_path(path)}: {change}"


def _planned_label_files(experiment: Experiment) -> list[Path]:
    """The label file of each run of the grid."""
    return [experiment.folder.label_file(r.dataset, r.weight_function, r.restart) for r in experiment.planned()]


def _in_grid(layout: ExperimentFolder, files: list[Path], planned: list[Path]) -> tuple[list[Path], list[str]]:
    """``files`` of runs in the grid (``planned``: :func:`_planned_label_files`), and a line
    for those of runs outside it (a config narrowed since)."""
    keep = set(planned)
    outside = [path for path in files if path not in keep]
    if not outside:
        return files, []
    note = (
        f"{len(outside)} label files of runs outside the grid of {display_path(layout.config)} "
        f"(explore.weight_functions or explore.restarts narrowed since), e.g. {display_path(outside[0])}"
    )
    return [path for path in files if path in keep], [note]


def _unlabelled_runs(layout: ExperimentFolder, files: list[Path], planned: list[Path]) -> list[str]:
    """A line for each run of the grid (``planned``) that has no label file, naming the file it lacks, or the run
    folder when the run is not explored (as ``label`` names it)."""
    from curiosity_cli.label.stage import unexplored

    lines = []
    for path in planned:
        if path not in files:
            run = layout.run(*layout.run_of_label_file(path))
            if (run / ExperimentFolder.RUN_META).is_file():
                lines.append(f"{display_path(path)}: not found; label the experiment to make it")
            else:
                lines.append(unexplored(run, layout))
    return lines


def read_class_names(config: ExperimentConfig) -> dict[str, dict[int, str]]:
    """Per dataset of an experiment, its legend's class names by id; none for a map whose legend cannot be read.

    Best effort from the datasets' YAML and legend files (no images): the names only
    label ``classes.csv`` rows.
    """
    from curiosity_cli.maps.datasets import dataset_path, load_dataset_config
    from curiosity_cli.maps.map_data import load_legend

    names = {}
    for entry in config.datasets:
        try:
            dataset = load_dataset_config(dataset_path(entry))
            if dataset.legend is not None:
                names[dataset.name] = {c.id: c.name for c in load_legend(dataset.legend)}
        except (CuriosityError, OSError):
            continue
    return names
