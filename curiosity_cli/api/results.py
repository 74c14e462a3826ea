"""An explored, labelled and evaluated experiment folder, read from Python: its tables as pandas frames, its runs."""

from __future__ import annotations

import typing
from pathlib import Path

from curiosity_cli.paths import DEFAULT_RESULTS, experiment_root

if typing.TYPE_CHECKING:
    import pandas as pd

    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.explore.runs import Run


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
