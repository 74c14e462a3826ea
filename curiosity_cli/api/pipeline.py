"""The experiment's commands as functions: ``extract``, ``explore``, ``label``, ``evaluate``, ``plot`` and ``reproduce``.

Each takes the arguments its command takes, under the same names and with the same
defaults; the command line only parses its options into them and reports what they
return. Arguments that do not go together raise :class:`~curiosity_cli.errors.UsageError`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import typing
from collections.abc import Callable, Sequence
from pathlib import Path

from curiosity_cli.api.arguments import (
    boolean, callback, config_argument, folder_argument, name_or_path, name_text, optional_count, optional_path,
    overrides_argument, strings,
)
from curiosity_cli.errors import UsageError
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS

if typing.TYPE_CHECKING:
    from curiosity_cli.config import ExperimentConfig
    from curiosity_cli.evaluate.stage import Evaluation
    from curiosity_cli.explore.grid import GridSummary
    from curiosity_cli.plots.figures import WrittenFigures
    from curiosity_cli.words.extract import Extraction
    from curiosity_cli.words.store import WordStore

Config = typing.Union[str, Path, "ExperimentConfig"]
#: Where a command's tasks run (:data:`curiosity_cli.workers.BACKENDS`).
BACKEND = "loky"
#: The experiment folder the stages after ``explore`` work in by default: the quick job's.
DEFAULT_EXPERIMENT = DEFAULT_RESULTS / "quick"


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
        The file does not validate, naming the key; ``overrides`` with an
        ``ExperimentConfig``, which is already resolved (change it with
        ``dataclasses.replace``); or a file that declares a sweep whose swept keys
        ``overrides`` do not all set, or specifications: many experiments, not one
        (:func:`reproduce` runs them).
    """
    from curiosity_cli.config import ExperimentConfig, load_config
    from curiosity_cli.errors import ConfigError
    from curiosity_cli.schema import OVERRIDES

    config, overrides = config_argument(config), overrides_argument(overrides)
    if isinstance(config, ExperimentConfig):
        if overrides:
            raise ConfigError(
                f"{OVERRIDES}: got {overrides}, but the config is already resolved; give its name or path, "
                "or change it with dataclasses.replace", parameter=OVERRIDES,
            )
        return config
    _refuse_many(config, overrides)
    return load_config(config, overrides)


def _refuse_many(config: str | Path, overrides: Sequence[str]) -> None:
    """A config that declares a sweep (whose keys ``overrides`` leave open) or specifications is many experiments."""
    from curiosity_cli.config import config_file
    from curiosity_cli.errors import ConfigError
    from curiosity_cli.files import display_path
    from curiosity_cli.study.specifications import declared_specifications
    from curiosity_cli.study.sweep import declared_sweeps, split_values

    fixed = {text.split("=", 1)[0] for text in overrides}
    swept = [text.split("=", 1) for text in declared_sweeps(config)]
    open_axes = [(key, values) for key, values in swept if key not in fixed]
    specifications = declared_specifications(config)
    if open_axes or specifications:
        what = f"a sweep over {', '.join(key for key, _ in open_axes)}" if open_axes else f"{len(specifications)} specifications"
        one = "; to load one, set each swept key, e.g. " + " ".join(
            f"{key}={split_values(values)[0]}" for key, values in open_axes
        ) if open_axes else ""
        raise ConfigError(
            f"config: {display_path(config_file(config))} declares {what}, which is many experiments (reproduce runs "
            f"them all){one}", parameter="config",
        )


def _is_config(config: Config) -> bool:
    from curiosity_cli.config import ExperimentConfig

    return isinstance(config, ExperimentConfig)


def _check_scheduler(backend: str, scheduler: str | None) -> None:
    from curiosity_cli.checks import check_choice
    from curiosity_cli.workers import BACKENDS

    check_choice("backend", backend, BACKENDS)
    if scheduler is not None:
        name_text(scheduler, "scheduler")
    if scheduler is not None and backend != "dask":
        raise UsageError("scheduler: needs `backend` dask", parameter="scheduler")


def extract(
    dataset: str, *, config: Config = "paper", overrides: typing.Iterable[str] = (), stride: int | None = None,
    cell_width: int | None = None, cache_dir: Path = DEFAULT_CACHE, force: bool = False, density: Path | None = None,
) -> Extraction:
    """``curiosity extract``: a map's word store under ``config``'s word settings, from the cache or made now.

    Parameters
    ----------
    dataset : str
        A registered map's name or a dataset YAML.
    config : str, Path or ExperimentConfig
        Whose ``words`` section to use; ``overrides`` may change only ``words.*`` keys.
    stride, cell_width : int, optional
        Texton words every ``stride`` pixels in cells of ``cell_width``; default the dataset's.
    density : Path, optional
        Also write a PNG of words per cell and a sample of words there.

    Returns
    -------
    Extraction
        The store, its path, whether it was reused, and the seconds of each stage.
        As :func:`~curiosity_cli.words.extract.extract_words`.
    """
    from curiosity_cli.config import load_words_config
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.words.extract import extract_words

    dataset, config, overrides = name_or_path(dataset, "dataset"), config_argument(config), overrides_argument(overrides)
    density, cache_dir = optional_path(density, "density"), folder_argument(cache_dir, "cache_dir")
    stride, cell_width = optional_count(stride, "stride"), optional_count(cell_width, "cell_width")
    force = boolean(force, "force")
    if density is not None and density.suffix.lower() != ".png":
        raise UsageError(f"density: got {density}, expected a path ending in .png (the figure is a PNG)", parameter="density")
    words = load(config, overrides).words if _is_config(config) else load_words_config(config, overrides)
    map_data = load_map(dataset)
    result = extract_words(map_data, words, stride=stride, cell_width=cell_width, cache_dir=cache_dir, force=force)
    if density is not None:
        from curiosity_cli.plots.words import write_word_density

        write_word_density(map_data, result.store, density)
    return result


def word_store(dataset: str, config: Config = "paper", *, cache_dir: Path = DEFAULT_CACHE) -> WordStore:
    """A map's word store under ``config``'s word settings (:func:`extract`'s store).

    Parameters
    ----------
    dataset : str
        A registered map's name or a dataset YAML.
    """
    return extract(dataset, config=config, cache_dir=cache_dir).store


@contextlib.contextmanager
def _shown(on_stage, on_done):
    """The progress callbacks given; in a notebook, where none are, a :class:`~curiosity_cli.progress.Progress`'s, so
    a cell shows its stages as the command line does."""
    from curiosity_cli.progress import Progress, in_notebook

    if on_stage is not None or on_done is not None or not in_notebook():
        yield on_stage, on_done
        return
    with Progress() as progress:
        yield progress.stage, progress.advance


def explore(
    config: Config = "quick", *, maps: Sequence[str] = (), weights: Sequence[str] | None = None,
    restarts: int | None = None, steps: int | None = None, overrides: typing.Iterable[str] = (),
    jobs: int | None = None, force: bool = False, results_dir: Path = DEFAULT_RESULTS, cache_dir: Path = DEFAULT_CACHE,
    backend: str = BACKEND, scheduler: str | None = None,
    on_prepared: Callable[[str, int, int], None] | None = None, on_run: Callable[..., None] | None = None,
) -> GridSummary:
    """``curiosity explore``: every missing run of the grid.

    Parameters
    ----------
    config : str, Path or ExperimentConfig
    maps : sequence of str
        Only these maps (names or dataset YAMLs); default the config's datasets.
    weights : sequence of str, optional
        Only these weight functions (walkers).
    restarts : int, optional
        Restarts per weight function.
    steps : int, optional
        The path length; checkpoints beyond it are dropped, and it becomes the last.
    overrides : iterable of str
        ``KEY=VALUE``, under ``maps``, ``weights`` and ``restarts``.
    on_prepared : callable, optional
        ``on_prepared(name, to_run, skipped)``: the experiment's name and its runs to do and
        already done, before any runs.
    on_run : callable, optional
        As :func:`~curiosity_cli.explore.grid.run_grid`, which says what is checked and raised.

    Returns
    -------
    GridSummary
        The experiment folder (``folder``) and what was run, skipped and written.
    """
    from curiosity_cli.errors import ConfigError
    from curiosity_cli.explore.grid import run_grid
    from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS
    from curiosity_cli.maps.datasets import DATASET_CONFIG_DIR, dataset_path

    _check_scheduler(backend, scheduler)
    on_prepared, on_run = callback(on_prepared, "on_prepared"), callback(on_run, "on_run")
    maps = strings(maps, "maps", "aerial-mosaic")
    weights = None if weights is None else strings(weights, "weights", "topic-perplexity")
    restarts, steps, jobs = optional_count(restarts, "restarts"), optional_count(steps, "steps"), optional_count(jobs, "jobs")
    results_dir, cache_dir = folder_argument(results_dir, "results_dir"), folder_argument(cache_dir, "cache_dir")
    force = boolean(force, "force")
    options = []
    # a map or walker given twice is refused here, where the user's words are known: the config would
    # refuse it too, but as an override the user never wrote
    if maps:
        try:
            found = [dataset_path(name) for name in maps]
        except ConfigError as exc:
            raise UsageError(f"maps: {exc}", parameter="maps") from None
        files = [path.resolve() for path in found]
        twice = next((name for i, name in enumerate(maps) if files[i] in files[:i]), None)
        if twice is not None:
            raise UsageError(f"maps: got {twice!r} twice, expected each map once", parameter="maps")
        # a registered map by its name, as a config names it (a copied experiment folder still finds it);
        # a dataset YAML by its absolute path, which no working folder changes
        paths = [name if path.parent == DATASET_CONFIG_DIR else str(file) for name, path, file in zip(maps, found, files)]
        options.append(f"datasets={paths}")
    if weights is not None:
        for i, name in enumerate(weights):
            if name not in WEIGHT_FUNCTIONS:
                raise UsageError(f"weights: got {name!r}, expected one of {', '.join(WEIGHT_FUNCTIONS)}", parameter="weights")
            if name in weights[:i]:
                raise UsageError(f"weights: got {name!r} twice, expected each weight function once", parameter="weights")
        options.append(f"explore.weight_functions={weights}")
    if restarts is not None:
        options.append(f"explore.restarts={restarts}")
    resolved = load(config, [*overrides_argument(overrides), *options])
    if steps is not None:
        kept = tuple(c for c in resolved.explore.checkpoints if c < steps) + (steps,)
        resolved = dataclasses.replace(
            resolved, explore=dataclasses.replace(resolved.explore, path_length=steps, checkpoints=kept)
        )
    from curiosity_cli.progress import Progress, in_notebook

    grid = functools.partial(
        run_grid, resolved, results_dir=results_dir, cache_dir=cache_dir, jobs=jobs, force=force, backend=backend,
        scheduler=scheduler,
    )
    if on_prepared is None and on_run is None and in_notebook():  # a cell shows the runs as the command line does
        with Progress() as progress:
            return grid(
                on_prepared=lambda to_run, skipped: progress.stage(f"exploring ({skipped} runs already finished)", to_run),
                on_run=progress.advance,
            )
    return grid(on_prepared=None if on_prepared is None else functools.partial(on_prepared, resolved.name), on_run=on_run)


def label(
    folder: Path = DEFAULT_EXPERIMENT, *, overrides: typing.Iterable[str] = (), jobs: int | None = None,
    force: bool = False, cache_dir: Path = DEFAULT_CACHE, backend: str = BACKEND, scheduler: str | None = None,
    converged: bool = False, on_stage: Callable[[str, int], None] | None = None, on_done: Callable[[], None] | None = None,
    reuse: bool = True,
) -> dict:
    """``curiosity label``: Z_b per map and Z_p per run of an explored experiment folder.

    ``overrides`` may change only ``label.*`` keys, which the folder's ``config.yaml`` then
    records; ``converged`` is the converged schedule (``label.sweeps=256``,
    ``label.warm_sweeps=null``); ``reuse=False`` computes the label files and batch
    references that another experiment already computed from the same inputs
    (:mod:`~curiosity_cli.label.shared_items`). As
    :func:`~curiosity_cli.label.stage.label_experiment`, which says what is returned and raised.
    """
    from curiosity_cli.config import with_converged_labels
    from curiosity_cli.experiment.saved_config import load_saved_config
    from curiosity_cli.label.stage import label_experiment

    _check_scheduler(backend, scheduler)
    on_stage, on_done = callback(on_stage, "on_stage"), callback(on_done, "on_done")
    folder, overrides = folder_argument(folder), overrides_argument(overrides)
    jobs, cache_dir = optional_count(jobs, "jobs"), folder_argument(cache_dir, "cache_dir")
    force, converged, reuse = boolean(force, "force"), boolean(converged, "converged"), boolean(reuse, "reuse")
    config = load_saved_config(folder, with_converged_labels(overrides) if converged else overrides)
    with _shown(on_stage, on_done) as (on_stage, on_done):
        return label_experiment(
            config, folder, cache_dir=cache_dir, jobs=jobs, force=force, on_stage=on_stage, on_done=on_done,
            backend=backend, scheduler=scheduler, reuse=reuse,
        )


def evaluate(folder: Path = DEFAULT_EXPERIMENT, *, partial: bool = False, cache_dir: Path = DEFAULT_CACHE) -> Evaluation:
    """``curiosity evaluate``: MI, statistics and tables of a labelled experiment; ``partial`` leaves out (and
    lists) the runs without usable labels; ``cache_dir`` holds the word stores (the mechanism table reads
    each cell's words). As :func:`~curiosity_cli.evaluate.stage.evaluate_experiment`."""
    from curiosity_cli.evaluate.stage import evaluate_experiment

    return evaluate_experiment(
        folder_argument(folder), partial=boolean(partial, "partial"), cache_dir=folder_argument(cache_dir, "cache_dir"),
    )


def plot(folder: Path = DEFAULT_EXPERIMENT) -> WrittenFigures:
    """``curiosity plot``: the figures of an evaluated experiment; the files written, and (``skipped``) what was
    not drawn and why. As :func:`~curiosity_cli.plots.figures.write_figures`."""
    from curiosity_cli.plots.figures import write_figures

    return write_figures(folder_argument(folder))


def run_named(text: str, parameter: str = "run") -> tuple[str, str, int]:
    """A run named ``MAP/WALKER/RESTART`` (as ``curiosity plot --animate`` takes it) as (dataset, weight_function,
    restart).

    Raises
    ------
    UsageError
        Not three parts with a restart number, naming ``parameter``.
    """
    parameter = name_text(parameter, "parameter")
    parts = text.split("/") if isinstance(text, str) else []
    if len(parts) != 3 or not parts[2].isdigit():
        raise UsageError(
            f"{parameter}: got {text!r}, expected MAP/WALKER/RESTART, e.g. aerial-mosaic/topic-perplexity/0",
            parameter=parameter,
        )
    return parts[0], parts[1], int(parts[2])


def animate(
    folder: Path, dataset: str, weight_function: str, restart: int, *, out: Path | None = None,
    cache_dir: Path | None = None,
) -> Path:
    """``curiosity plot --animate``: one run's path growing over its map beside Z_p at each checkpoint; returns
    the file written. As :func:`~curiosity_cli.plots.animation.animate_run`."""
    from curiosity_cli.checks import check_int
    from curiosity_cli.plots.animation import animate_run

    return animate_run(
        folder_argument(folder), name_or_path(dataset, "dataset"), name_or_path(weight_function, "weight_function"),
        check_int("restart", restart, 0),
        out=optional_path(out, "out"), cache_dir=optional_path(cache_dir, "cache_dir"),
    )


def reproduce(
    config: Config = "quick", *, overrides: typing.Iterable[str] = (), sweeps: Sequence[str] = (),
    jobs: int | None = None, force: bool = False, backend: str = BACKEND, scheduler: str | None = None,
    results_dir: Path = DEFAULT_RESULTS, cache_dir: Path = DEFAULT_CACHE, converged: bool = False,
    on_stage: Callable[[str, int], None] | None = None, on_done: Callable[[], None] | None = None,
    on_status: Callable[[str], None] | None = None, reuse: bool = True, record: Path | None = None,
    measure: str = "mi",
) -> Path:
    """``curiosity reproduce``: explore, label, evaluate and plot; returns the path of ``REPORT.md``.

    A config that declares a sweep (or specifications), or ``sweeps``, runs once per
    combination of values, each as its own experiment under ``results_dir/<name>-sweep/``,
    and returns the path of that folder's ``SWEEP.md``.

    Parameters
    ----------
    config : str, Path or ExperimentConfig
        Default ``quick``, as :func:`explore`'s: minutes on a laptop; the paper's full grid is ``paper-grid``.
    sweeps : sequence of str
        ``KEY=V1,V2,...``, each an axis of the sweep; one replaces the values of a key the
        config's ``sweep:`` declares.
    converged : bool
        The converged label schedule (``label.sweeps=256``, ``label.warm_sweeps=null``).
    on_stage, on_done : callable, optional
        ``on_stage(description, units)`` when a stage starts, ``on_done()`` after each unit.
    on_status : callable, optional
        ``on_status(line)`` with a sweep's size and folder before it runs.
    reuse : bool
        Take label files and batch references another experiment computed from the same
        inputs (:mod:`~curiosity_cli.label.shared_items`); False computes them all.
    record : Path, optional
        A study's record, e.g. ``studies/multiverse`` (:mod:`~curiosity_cli.study.record`):
        the seeds and specifications recorded there are taken, not computed; each one
        computed is recorded there. Only for a config that declares specifications and
        sweeps only ``seed``.
    measure : str
        A study's specification curve is drawn for this measure too (one of
        :func:`measures`; MI's is always drawn). Only for a config that declares specifications.

    Raises
    ------
    UsageError
        ``sweeps`` not in the ``KEY=V1,V2,...`` form; ``scheduler`` without ``backend="dask"``;
        ``record`` or another ``measure`` than MI for a config that is not a study; a
        ``measure`` that is none.
    RecordError
        A recorded combination made from other recipes than the study gives now, or edited.
    """
    from curiosity_cli.config import load_config, with_converged_labels
    from curiosity_cli.study.hypotheses import declared_hypotheses
    from curiosity_cli.study.pipeline import reproduce as run_pipeline
    from curiosity_cli.study.specifications import declared_specifications
    from curiosity_cli.study.sweep import declared_sweeps, merge_sweeps

    _check_scheduler(backend, scheduler)
    on_stage, on_done, on_status = callback(on_stage, "on_stage"), callback(on_done, "on_done"), callback(on_status, "on_status")
    config, overrides, sweeps = config_argument(config), overrides_argument(overrides), strings(sweeps, "sweeps", "seed=0,1")
    jobs, reuse = optional_count(jobs, "jobs"), boolean(reuse, "reuse")
    force, converged = boolean(force, "force"), boolean(converged, "converged")
    results_dir, cache_dir = folder_argument(results_dir, "results_dir"), folder_argument(cache_dir, "cache_dir")
    record = optional_path(record, "record")
    if measure not in measures():
        raise UsageError(f"measure: got {measure!r}, expected one of {', '.join(measures())}", parameter="measure")
    with _shown(on_stage, on_done) as (on_stage, on_done):
        if converged:
            overrides = with_converged_labels(overrides)
        if _is_config(config):
            if sweeps:
                raise UsageError("sweeps: a resolved config is one experiment; give the config's name or path to sweep it", parameter="sweeps")
            resolved = load(config, overrides)  # refuses overrides of a resolved config
        else:
            declared = declared_sweeps(config)
            # the keys whose values only the file gives: an error in one names the file, not --sweep
            from_file = {text.partition("=")[0] for text in declared} - {text.partition("=")[0].strip() for text in sweeps}
            sweeps = merge_sweeps(declared, sweeps)
            specifications = declared_specifications(config)
            if sweeps or specifications:
                return _reproduce_sweep(
                    config, overrides, sweeps, specifications, from_file, on_stage=on_stage, on_done=on_done, on_status=on_status,
                    results_dir=results_dir, cache_dir=cache_dir, jobs=jobs, force=force, backend=backend, scheduler=scheduler,
                    reuse=reuse, record=record, measure=measure,
                )
            declared_hypotheses(config, (), ())  # refuses hypotheses without the specifications they name
            resolved = load_config(config, overrides)  # neither a sweep nor specifications, just read: one experiment
        if record is not None:
            raise UsageError(
                "record: keeps a study's seeds (a config that declares specifications and sweeps seed); this is one experiment",
                parameter="record",
            )
        if measure != "mi":
            raise UsageError(
                "measure: draws a study's specification curve (a config that declares specifications); this is one "
                "experiment, whose REPORT.md compares every measure", parameter="measure",
            )
        return run_pipeline(
            resolved, results_dir=results_dir, cache_dir=cache_dir, jobs=jobs, force=force,
            backend=backend, scheduler=scheduler, on_stage=on_stage, on_done=on_done, reuse=reuse,
        )


def measures() -> list[str]:
    """The names of the measures a study's curve can be drawn for (``reproduce(measure=...)``), MI first."""
    from curiosity_cli.evaluate.measures import MEASURES

    return [m.name for m in MEASURES if m.name == "mi" or m.found]


def _reproduce_sweep(config, overrides, sweeps, specifications, from_file, *, on_status, **options) -> Path:
    """A sweep, or a study's specifications: every option and combination checked, then all run."""
    from curiosity_cli.files import display_path
    from curiosity_cli.study.specifications import study_size
    from curiosity_cli.study.sweep import parse_sweeps, plan_sweep, run_sweep
    from curiosity_cli.study.types import SweepSyntaxError, count

    try:
        axes = parse_sweeps(sweeps, overrides)
    except SweepSyntaxError as exc:
        raise UsageError(f"sweeps: {exc}", parameter="sweeps") from None
    sweep = plan_sweep(config, axes, overrides, specifications, from_file)
    if options["measure"] != "mi" and not specifications:
        raise UsageError("measure: draws a study's specification curve; this config declares no specifications",
                         parameter="measure")
    if on_status is not None:
        of = f" ({study_size(sweep)})" if specifications else ""
        on_status(f"{count(len(sweep.combinations), 'combination')}{of}, in {display_path(sweep.folder(options['results_dir']))}")
    return run_sweep(sweep, **options)
