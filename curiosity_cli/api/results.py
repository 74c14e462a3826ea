"""An explored, labelled and evaluated experiment folder, read from Python: its tables as pandas frames, its runs."""

from __future__ import annotations

import typing
from pathlib import Path

from curiosity_cli.api.arguments import folder_argument, name_or_path
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
        ParameterError
            ``name`` is none of the tables ``evaluate`` wrote, naming them.
        """
        import pandas as pd

        from curiosity_cli.errors import ParameterError

        written = sorted(Path(file).stem for file in self.experiment.check_tables() if Path(file).suffix == ".csv")
        if name not in written:
            raise ParameterError(f"name: got {name!r}, expected one of {', '.join(written)}")
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
        ParameterError
            ``restart`` is not an int >= 0, or a name is not a string.
        """
        from curiosity_cli.checks import check_int
        from curiosity_cli.explore.runs import read_run

        dataset, weight_function = name_or_path(dataset, "dataset"), name_or_path(weight_function, "weight_function")
        return read_run(self.experiment.folder.run(dataset, weight_function, check_int("restart", restart, 0)))


def open_experiment(folder: Path | str | None = None, *, name: str = "quick", results_dir: Path = DEFAULT_RESULTS) -> Results:
    """The results of an experiment folder (default ``results_dir/name``).

    Raises
    ------
    ConfigError
        No ``config.yaml`` there (explore it first), or one that does not validate.
    """
    from curiosity_cli.experiment.experiment import Experiment

    if folder is None:
        folder = experiment_root(folder_argument(results_dir, "results_dir"), name_or_path(name, "name"))
    return Results(Experiment.open(folder_argument(folder)))
