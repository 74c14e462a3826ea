"""An explored, labelled and evaluated experiment folder, read from Python: its tables as pandas frames, its runs."""

from __future__ import annotations

import typing
from pathlib import Path

from curiosity_cli.api.arguments import folder_argument, name_or_path, path_argument
from curiosity_cli.paths import DEFAULT_RESULTS, experiment_root

if typing.TYPE_CHECKING:
    import pandas as pd

    from curiosity_cli.evaluate.stage import Evaluation
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
        from curiosity_cli.errors import ParameterError
        from curiosity_cli.evaluate.tables import read_table

        written = sorted(Path(file).stem for file in self.experiment.check_tables() if Path(file).suffix == ".csv")
        if name not in written:
            raise ParameterError(f"name: got {name!r}, expected one of {', '.join(written)}")
        return read_table(self.experiment.folder.table(name))

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
            A missing, incomplete or altered run of the grid, naming the file.
        ParameterError
            ``restart`` is not an int >= 0, or a name is not a string; a map, walker or
            restart the experiment's grid does not hold.
        """
        from curiosity_cli.checks import check_int
        from curiosity_cli.explore.runs import read_run

        dataset, weight_function = name_or_path(dataset, "dataset"), name_or_path(weight_function, "weight_function")
        restart = check_int("restart", restart, 0)
        self._check_in_grid(dataset, weight_function, restart)
        return read_run(self.experiment.folder.run(dataset, weight_function, restart))

    def _check_in_grid(self, dataset: str, weight_function: str, restart: int) -> None:
        """Refuse a run outside the grid: explore never makes it, so its folder's absence is no unfinished run."""
        from curiosity_cli.errors import ConfigError, ParameterError
        from curiosity_cli.files import display_path
        from curiosity_cli.maps.datasets import dataset_path, load_dataset_config

        config = self.experiment.config
        where = display_path(self.experiment.folder.config)
        walkers = config.explore.weight_functions
        if weight_function not in walkers:
            raise ParameterError(
                f"weight_function: got {weight_function!r}, expected a walker of {where}: {', '.join(walkers)}",
                parameter="weight_function",
            )
        if restart >= config.explore.restarts:
            raise ParameterError(
                f"restart: got {restart}, expected a restart of {where}: 0 to {config.explore.restarts - 1}",
                parameter="restart",
            )
        try:
            # the maps' names from their YAMLs: loading every map's image to name it would take long
            maps = [load_dataset_config(dataset_path(entry)).name for entry in config.datasets]
        except ConfigError:  # a map's YAML that does not load now: which maps there are is unknown; the run is read
            return
        if dataset not in maps:
            raise ParameterError(f"dataset: got {dataset!r}, expected a map of {where}: {', '.join(maps)}", parameter="dataset")


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


def verdict(source: Evaluation | Path | str) -> list[str]:
    """The verdict, a line per map, each its answer and then the evidence (after the first ``;``): of the tables
    :func:`~curiosity_cli.api.evaluate` returned, or of an experiment's ``REPORT.md`` (empty for a sweep's
    ``SWEEP.md``, which has none).

    Raises
    ------
    CuriosityError
        A report that cannot be read, naming it.
    """
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.evaluate.report import read_verdict
    from curiosity_cli.evaluate.report import verdict as map_verdict
    from curiosity_cli.evaluate.stage import Evaluation
    from curiosity_cli.files import display_path

    if isinstance(source, Evaluation):
        return [map_verdict(row, source.effects) for row in source.headline.to_dict("records")]
    report = path_argument(source, "source", "a REPORT.md or SWEEP.md, or the folder holding one")
    try:
        return read_verdict(report)
    except (OSError, UnicodeDecodeError) as exc:
        raise CuriosityError(f"{display_path(report)}: cannot be read ({exc})") from None
