"""curiosity from Python: the commands as functions a notebook can call, and an experiment's results as pandas frames.

Every ``curiosity`` command wraps the library function these call, so a notebook and a
terminal make the same files, byte for byte::

    from curiosity_cli import api as cur

    folder = cur.explore("quick", overrides=["explore.restarts=4"])
    cur.label(folder)
    cur.evaluate(folder)
    results = cur.open_experiment(folder)
    results.headline                     # pandas.DataFrame
    results.run("zurich-zh17", "topic-perplexity", 0).path

A config is a shipped config's name (``quick``, ``paper-grid``), a path to a YAML file or
an :class:`~curiosity_cli.config.ExperimentConfig`; folders default to the paths table of
:mod:`curiosity_cli.paths`. Errors are :class:`~curiosity_cli.errors.CuriosityError`\\ s,
whose messages name the argument at fault.
"""

from __future__ import annotations

import typing
from pathlib import Path

from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS, experiment_root

if typing.TYPE_CHECKING:
    import pandas as pd

    from curiosity_cli.config import ExperimentConfig
    from curiosity_cli.evaluate.tables import Evaluation
    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.explore.runs import Run
    from curiosity_cli.words.store import WordStore

Config = typing.Union[str, Path, "ExperimentConfig"]


def load(config: Config, overrides: typing.Iterable[str] = ()) -> ExperimentConfig:
    """An experiment config: a shipped config's name or a YAML path, with ``overrides``; or a config as it is.

    Parameters
    ----------
    config : str, Path or ExperimentConfig
    overrides : iterable of str
        ``KEY=VALUE`` with dotted keys, e.g. ``explore.restarts=4``.

    Raises
    ------
    ConfigError
        The file does not validate, naming the key; or ``overrides`` with an
        ``ExperimentConfig``, which is already resolved (change it with ``dataclasses.replace``).
    """
    from curiosity_cli.config import OVERRIDES, ExperimentConfig, load_config
    from curiosity_cli.errors import ConfigError

    overrides = list(overrides)
    if isinstance(config, ExperimentConfig):
        if overrides:
            raise ConfigError(
                f"{OVERRIDES}: got {overrides}, but the config is already resolved; give its name or path, "
                "or change it with dataclasses.replace", parameter=OVERRIDES,
            )
        return config
    return load_config(config, overrides)


def explore(
    config: Config, *, overrides: typing.Iterable[str] = (), results_dir: Path = DEFAULT_RESULTS,
    cache_dir: Path = DEFAULT_CACHE, jobs: int | None = None, force: bool = False,
) -> Path:
    """``curiosity explore``: every missing run of the grid; returns the experiment folder.

    As :func:`~curiosity_cli.explore.grid.run_grid`, which says what is checked and raised.
    """
    from curiosity_cli.explore.grid import run_grid

    return run_grid(load(config, overrides), results_dir=results_dir, cache_dir=cache_dir, jobs=jobs, force=force).folder


def label(
    folder: Path, *, overrides: typing.Iterable[str] = (), converged: bool = False, cache_dir: Path = DEFAULT_CACHE,
    jobs: int | None = None, force: bool = False,
) -> dict:
    """``curiosity label``: Z_b per map and Z_p per run; returns what was done (``labelled``, ``skipped``, ...).

    ``overrides`` may change only ``label.*`` keys, which the folder's ``config.yaml`` then
    records; ``converged`` is the converged schedule. As
    :func:`~curiosity_cli.evaluate.label_stage.label_experiment`.
    """
    from curiosity_cli.config import with_converged_labels
    from curiosity_cli.evaluate.label_stage import label_experiment
    from curiosity_cli.experiment.saved_config import load_saved_config

    config = load_saved_config(folder, with_converged_labels(overrides) if converged else overrides)
    return label_experiment(config, Path(folder), cache_dir=cache_dir, jobs=jobs, force=force)


def evaluate(folder: Path, *, partial: bool = False) -> Evaluation:
    """``curiosity evaluate``: MI, statistics and tables of a labelled experiment. As
    :func:`~curiosity_cli.evaluate.tables.evaluate_experiment`."""
    from curiosity_cli.evaluate.tables import evaluate_experiment

    return evaluate_experiment(Path(folder), partial=partial)


def plot(folder: Path) -> list[Path]:
    """``curiosity plot``: the figures of an evaluated experiment; returns the files written. As
    :func:`~curiosity_cli.plots.figures.write_figures`."""
    from curiosity_cli.plots.figures import write_figures

    return list(write_figures(Path(folder)))


def reproduce(
    config: Config = "quick", *, overrides: typing.Iterable[str] = (), results_dir: Path = DEFAULT_RESULTS,
    cache_dir: Path = DEFAULT_CACHE, jobs: int | None = None, force: bool = False,
) -> Path:
    """``curiosity reproduce``: explore, label, evaluate and plot; returns the path of ``REPORT.md``."""
    from curiosity_cli.reproduce import reproduce as run_pipeline

    return run_pipeline(load(config, overrides), results_dir=results_dir, cache_dir=cache_dir, jobs=jobs, force=force)


def word_store(dataset: str, config: Config = "paper", *, cache_dir: Path = DEFAULT_CACHE) -> WordStore:
    """A map's word store under ``config``'s word settings, from the cache or extracted now (``curiosity extract``).

    Parameters
    ----------
    dataset : str
        A registered map's name or a dataset YAML.
    """
    from curiosity_cli.config import load_words_config
    from curiosity_cli.data import load_map
    from curiosity_cli.words.extract import extract_words

    words = load(config).words if not isinstance(config, (str, Path)) else load_words_config(config)
    return extract_words(load_map(dataset), words, cache_dir=cache_dir).store


class Results:
    """An explored, labelled and evaluated experiment folder, read: its tables as pandas frames, its runs.

    Attributes
    ----------
    experiment : Experiment
        The folder, its saved config (``experiment.config``) and its maps.
    """

    def __init__(self, experiment: Experiment):
        self.experiment = experiment

    def table(self, name: str) -> pd.DataFrame:
        """An evaluation table by name (``mi``, ``summary``, ``headline``, ``tests``, ``effects``, ``classes``, ...).

        Raises
        ------
        StaleTablesError
            The tables are not one set made from the folder's files as they are now.
        """
        import pandas as pd

        self.experiment.check_tables()
        return pd.read_csv(self.experiment.folder.table(name))

    @property
    def mi(self) -> pd.DataFrame:
        """One row per run and checkpoint: MI against the human and the batch labels, classes found, revisits."""
        return self.table("mi")

    @property
    def summary(self) -> pd.DataFrame:
        """Mean MI with its 95 % CI per map, walker, path length and reference."""
        return self.table("summary")

    @property
    def headline(self) -> pd.DataFrame:
        """Per map: topic perplexity's lead at 80 steps, its test and how sure it is."""
        return self.table("headline")

    def run(self, dataset: str, weight_function: str, restart: int) -> Run:
        """A run: its ``meta`` (run.json), ``path`` ((L,) cells) and ``phi(length)`` ((V, K) counts at a checkpoint).

        Raises
        ------
        RunError
            A missing, incomplete or altered run, naming the file.
        """
        from curiosity_cli.explore.runs import read_run

        return read_run(self.experiment.folder.run(dataset, weight_function, restart))


def open_experiment(folder: Path | str | None = None, *, name: str = "quick", results_dir: Path = DEFAULT_RESULTS) -> Results:
    """The results of an experiment folder (default ``results_dir/name``).

    Raises
    ------
    ConfigError
        No ``config.yaml`` there (explore it first), or one that does not validate.
    """
    from curiosity_cli.experiment.experiment import Experiment

    return Results(Experiment.open(experiment_root(results_dir, name) if folder is None else folder))
