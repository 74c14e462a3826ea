"""YAML configs → validated, frozen dataclasses.

An experiment config names its ``base`` (usually ``paper.yaml``, which holds the paper's
parameters) and overrides keys of it; ``KEY=VALUE`` overrides (the command line's ``--set``)
go on top. Every leaf remembers which file (or the overrides) gave it, so an error names
the file, the key, what was given and what was expected, in one line.

The dataclasses carry no defaults on purpose: the paper's values live in one place,
``configs/paper.yaml``, and a config that misses a key says so instead of silently
picking up a second copy of a default.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from curiosity_cli.errors import ConfigError
from curiosity_cli.files import atomic_path, display_path, resolved
from curiosity_cli.paths import SHIPPED_CONFIGS, SHIPPED_DATA
from curiosity_cli.yamlfile import SHOWN_CHARS, dump_yaml, parse_yaml, read_yaml, shown

#: The shipped configs, which a command or a ``base:`` may name without a path (``quick``, ``paper.yaml``).
CONFIG_DIR = SHIPPED_CONFIGS
DATASET_CONFIG_DIR = CONFIG_DIR / "datasets"
#: The vocabularies shipped with the package, which a config names ``shipped`` (a saved
#: config too, so that an experiment folder copied to another machine finds them there).
SHIPPED_VOCABULARIES = {"shipped": SHIPPED_DATA / "vocab"}

#: The shipped config a saved experiment config builds on (:func:`saved_yaml`).
_SAVED_BASE = "paper.yaml"
#: Where a value given in :func:`load_config`'s ``overrides`` "comes from": the name of
#: that argument, which begins the message of any error about it.
OVERRIDES = "overrides"

#: The top-level key of an experiment config that declares a sweep over its other keys
#: (:func:`curiosity_cli.sweep.declared_sweeps`); an experiment never sees it.
SWEEP_KEY = "sweep"
#: The top-level key of a study config that declares named specifications, each a set of
#: overrides run on every map and replicate seed (:mod:`curiosity_cli.specifications`); an
#: experiment never sees it either.
SPECIFICATIONS_KEY = "specifications"

#: The longest experiment or dataset name; a sweep names its experiments in up to this many.
MAX_NAME = 120
# Names become file and folder names: no separators, no leading dot, no path of '..'.
_NAME_PATTERN = re.compile(rf"^[A-Za-z0-9][A-Za-z0-9_.-]{{0,{MAX_NAME - 1}}}$")
_NAME_RULE = f"1 to {MAX_NAME} letters, digits, '-', '_' or '.', starting with a letter or digit"

#: The largest ORB or texton vocabulary a config may name and ``vocab build`` may learn.
MAX_VOCABULARY = 30000

#: The walkers a config may name in ``explore.weight_functions``, in the order reports list
#: them: the paper's four weight functions in its order, the lawnmower, then the ceilings.
#: The one list of walkers: names are the config's vocabulary, checked here under every
#: entry point without importing the explore stage, and
#: :data:`curiosity_cli.explore.weights.WEIGHT_FUNCTIONS` finds each name's walker in that
#: module by the name (``random-walk``: ``random_walk``).
WALKER_NAMES = (
    "random-walk",
    "stochastic-coverage",
    "word-perplexity",
    "topic-perplexity",
    "lawnmower",
    "scattered-cells",
    "compact-block",
)

#: The paper's own walkers (its four weight functions): what a specification curve compares.
PAPER_WALKERS = WALKER_NAMES[:4]

#: The readings of eq. 8 a config may name in ``explore.coverage``: what a visited
#: candidate's own term (``d = 0``) means, which the paper leaves undefined.
#: :func:`curiosity_cli.explore.weights.coverage_potential` gives each its meaning.
COVERAGE_READINGS = ("literal", "clamp", "others")
#: Where labelling runs (``label.device``): the CPU, a CUDA GPU (the extra ``curiosity[cuda]``),
#: or a GPU when one is there; the same bytes on each (``topics/chains.py``).
LABEL_DEVICES = ("cpu", "cuda", "auto")

#: The other open choices of the paper's exploration, each a key of ``explore`` with the
#: values a config may name, today's reading first (``configs/paper.yaml`` gives each the
#: paper's sentence and what the authors' ROST code does):
#:
#: - ``candidates``: the cells ``G(c)`` a walker scores, 4 (up, down, left, right) or 8;
#: - ``candidate_context``: the counts eq. 12's temporary labels of a candidate are drawn
#:   against, ``neighbourhood`` (the model's ``n_Gk`` of the candidate) or ``own`` (its
#:   own temporary labels only), and ``candidate_sweeps`` the Gibbs passes over them;
#: - ``path_topics``: P(k | path), ``smoothed`` ``(n_k + α) / (N + Kα)`` or ``counts`` ``n_k / N``;
#: - ``revisits``: a revisited cell's words enter the model ``once`` or ``again`` each visit;
#: - ``refine_picks``: which observations realtime refinement picks, ``uniform`` (eq. 6) or
#:   ``recent`` (the authors' refinery).
EXPLORE_READINGS = {
    "candidates": (4, 8),
    "candidate_context": ("neighbourhood", "own"),
    "path_topics": ("smoothed", "counts"),
    "revisits": ("once", "again"),
    "refine_picks": ("uniform", "recent"),
}
#: What a run recipe leaves out: each reading at what every run did before its key existed
#: (the first value of each, and one pass over the temporary labels), so that the runs of
#: older experiments stay current (a run's recipe names a reading only when it is another).
UNRECORDED_READINGS = {key: values[0] for key, values in EXPLORE_READINGS.items()} | {"candidate_sweeps": 1}

#: Where a config's ORB words are (``words.orb_detector``): at ORB's keypoints, or at every
#: point of a regular grid (:mod:`curiosity_cli.words.orb_grid`), as near the density of the
#: paper's Table 1 as one scale gets.
ORB_DETECTORS = ("keypoints", "grid")


def _spec(
    *,
    min: float | None = None,
    max: float | None = None,
    min_exclusive: bool = False,
    max_exclusive: bool = False,
    choices: tuple | None = None,
    must_exist: bool = False,
    file_name: bool = False,
    named: dict[str, Path] | None = None,
    default: Any = dataclasses.MISSING,
):
    """A dataclass field with the checks the validator applies to it.

    ``file_name`` marks a string that becomes a file or folder name (:data:`MAX_NAME`).
    ``named`` gives a path field names for paths of this checkout (e.g.
    :data:`SHIPPED_VOCABULARIES`): a config may use the name, and a saved config does.

    Only dataset YAMLs, which a user writes per map, have optional keys (``default``);
    experiment configs name every key, their values coming from ``configs/paper.yaml``.
    """
    return field(
        default=default,
        metadata=dict(
            min=min,
            max=max,
            min_exclusive=min_exclusive,
            max_exclusive=max_exclusive,
            choices=choices,
            must_exist=must_exist,
            file_name=file_name,
            named=named,
        )
    )


@dataclass(frozen=True)
class ModelConfig:
    """The ROST topic model (paper section 3)."""

    topics: int = _spec(min=2, max=127)
    alpha: float = _spec(min=0, min_exclusive=True)
    beta: float = _spec(min=0, min_exclusive=True)
    eta: float = _spec(min=0, max=1)
    spatial_neighbours: int = _spec(choices=(0, 4))


@dataclass(frozen=True)
class WordsConfig:
    """Visual words (paper section 5.1)."""

    vocabulary_dir: Path = _spec(must_exist=True, named=SHIPPED_VOCABULARIES)
    orb_vocabulary: int = _spec(min=2, max=MAX_VOCABULARY)
    texton_vocabulary: int = _spec(min=2, max=MAX_VOCABULARY)
    orb_detector: str = _spec(choices=ORB_DETECTORS)
    # read by the grid detector only (store_settings)
    orb_grid_step: int = _spec(min=1)
    # read by the keypoints detector only (store_settings)
    orb_tile: int = _spec(min=1)
    orb_per_tile: int | None = _spec(min=1)
    orb_max_features: int | None = _spec(min=1)
    orb_fast_threshold: int = _spec(min=1, max=255)
    orb_fill_threshold: int | None = _spec(min=1, max=255)
    # hue words, whichever the ORB detector
    colour_words: bool = _spec()

    def store_settings(self) -> dict:
        """The keys a map's words depend on besides its vocabularies: what names its word store.

        Every key (so that a key added here changes the store's name unless it is left
        out below), but:

        - the vocabularies' keys (:data:`_VOCABULARY_KEYS`): the store's name covers each
          vocabulary by its name, size and content hash instead, so a vocabulary folder
          moved elsewhere keeps its stores;
        - a key that the chosen ``orb_detector`` does not read (:data:`_READ_BY`);
        - a key at the value that was the behaviour before the key existed
          (:data:`_NAMED_UNLESS`), so stores made before it keep their names.
        """
        return {
            key: value
            for key, value in to_dict(self).items()
            if key not in _VOCABULARY_KEYS
            and _READ_BY.get(key, self.orb_detector) == self.orb_detector
            and _NAMED_UNLESS.get(key, _NO_DEFAULT) != value
        }


#: Words keys that the word store records by their vocabularies' content hashes instead.
_VOCABULARY_KEYS = ("vocabulary_dir", "orb_vocabulary", "texton_vocabulary")
#: Words keys read by one ORB detector only: under the other they change no word.
_READ_BY = {
    "orb_grid_step": "grid",
    **dict.fromkeys(("orb_tile", "orb_per_tile", "orb_max_features", "orb_fast_threshold", "orb_fill_threshold"),
                    "keypoints"),
}
#: Words keys added after word stores existed, and the value that was the behaviour before:
#: at it they leave the store's name as it was.
_NAMED_UNLESS = {"orb_detector": "keypoints"}
_NO_DEFAULT = object()


def _check_words(words: WordsConfig, raw: _Raw) -> None:
    """ORB keys that tie together: the grid takes no keypoint cap; a top-up fills capped
    tiles, below the FAST threshold."""
    if words.orb_detector == "grid":
        for key in ("orb_per_tile", "orb_max_features"):
            value = getattr(words, key)
            if value is not None:
                raise _invalid(
                    raw, ("words", key),
                    f"got {value}, expected null when words.orb_detector is grid (a word at every grid point; "
                    "the cap is the keypoints detector's)",
                )
    fill = words.orb_fill_threshold
    if fill is None:
        return
    if words.orb_per_tile is None:
        raise _invalid(
            raw, ("words", "orb_fill_threshold"),
            f"got {fill}, expected null when words.orb_per_tile is null (the top-up only fills tiles capped by "
            "orb_per_tile)",
        )
    if fill > words.orb_fast_threshold:
        raise _invalid(
            raw, ("words", "orb_fill_threshold"),
            f"got {fill}, expected an integer between 1 and words.orb_fast_threshold ({words.orb_fast_threshold})",
        )


@dataclass(frozen=True)
class ExploreConfig:
    """Exploration runs on the simulated 2-D grid (paper sections 4 and 5.1)."""

    # names in WALKER_NAMES, checked when loading
    weight_functions: tuple[str, ...] = _spec()
    restarts: int = _spec(min=1)
    path_length: int = _spec(min=1)
    checkpoints: tuple[int, ...] = _spec(min=1)
    samples_per_step: int = _spec(min=1)
    step_seconds: float | None = _spec(min=0, min_exclusive=True)
    coverage: str = _spec(choices=COVERAGE_READINGS)
    # read by the clamp reading only (run_settings)
    min_d2: float | None = _spec(min=0, min_exclusive=True)
    candidates: int = _spec(choices=EXPLORE_READINGS["candidates"])
    candidate_context: str = _spec(choices=EXPLORE_READINGS["candidate_context"])
    candidate_sweeps: int = _spec(min=1)
    path_topics: str = _spec(choices=EXPLORE_READINGS["path_topics"])
    revisits: str = _spec(choices=EXPLORE_READINGS["revisits"])
    refine_picks: str = _spec(choices=EXPLORE_READINGS["refine_picks"])

    def run_settings(self) -> dict:
        """The keys a run's numbers depend on.

        Every key but ``min_d2`` unless the reading is clamp, and but a reading of
        :data:`UNRECORDED_READINGS` at the value every run had before its key existed.
        """
        return {
            key: value for key, value in to_dict(self).items()
            if (key != "min_d2" or self.coverage == "clamp") and UNRECORDED_READINGS.get(key, _NO_DEFAULT) != value
        }


@dataclass(frozen=True)
class LabelConfig:
    """Labelling whole maps: with a path's model (Z_p) and in batch mode (Z_b) (paper section 5.1)."""

    sweeps: int = _spec(min=1)
    warm_sweeps: int | None = _spec(min=1)
    check_restarts: int = _spec(min=0)
    batch_sweeps: int = _spec(min=1)
    device: str = _spec(choices=LABEL_DEVICES)


@dataclass(frozen=True)
class DriveConfig:
    """The live robot driver (paper section 5.2), its wire protocol and the simulated robot."""

    gamma: float = _spec(min=0, max=1, max_exclusive=True)
    temporal_neighbours: int = _spec(choices=(0, 2))
    frame_width: int = _spec(min=16)
    grid_rows: int = _spec(min=1)
    grid_cols: int = _spec(min=1)
    texton_stride: int = _spec(min=1)
    orb_levels: int = _spec(min=1, max=16)
    orb_per_tile: int = _spec(min=1)
    orb_fill_threshold: int | None = _spec(min=1, max=19)
    samples_per_frame: int = _spec(min=0)
    window_frames: int = _spec(min=2)
    carry_frames: int = _spec(min=0)
    carry_sweeps: int = _spec(min=0)
    surge_cruise: float = _spec()
    surge_gain: float = _spec(min=0)
    surge_min: float = _spec()
    surge_max: float = _spec()
    yaw_gain: float = _spec(min=0)
    yaw_rate_max: float = _spec(min=0)
    pitch_gain: float = _spec(min=0)
    pitch_rate_max: float = _spec(min=0)
    port: str | None = _spec()
    baud: int = _spec(min=1)
    hello_timeout: float = _spec(min=0, min_exclusive=True)
    ack_timeout: float = _spec(min=0, min_exclusive=True)
    resends: int = _spec(min=0)
    keepalive: float = _spec(min=0, min_exclusive=True)
    watchdog: float = _spec(min=0, min_exclusive=True)
    state_rate: float = _spec(min=0, min_exclusive=True)
    sim_metres_per_pixel: float = _spec(min=0, min_exclusive=True)
    sim_view_rows: int = _spec(min=16)
    sim_view_cols: int = _spec(min=16)
    sim_frame_interval: float = _spec(min=0)
    video_fps: float = _spec(min=0, min_exclusive=True)


@dataclass(frozen=True)
class ExperimentConfig:
    """One experiment: which maps, which seed, and every parameter of the pipeline."""

    name: str = _spec(file_name=True)
    seed: int = _spec(min=0, max=2**32 - 1)
    datasets: tuple[str, ...] = _spec()
    model: ModelConfig = _spec()
    words: WordsConfig = _spec()
    explore: ExploreConfig = _spec()
    label: LabelConfig = _spec()
    drive: DriveConfig = _spec()


@dataclass(frozen=True)
class DatasetConfig:
    """A map: an image, optional ground-truth labels with their legend, and its grid.

    ``image`` is required unless ``fetch`` names a map made on first use from a pinned
    source archive (:mod:`curiosity_cli.fetched`); then image, labels and legend are the
    files it makes. Every key with a default may be left out of the YAML.
    """

    name: str = _spec(file_name=True)
    cell_width: int = _spec(min=1)
    word_stride: int = _spec(min=1)
    image: Path | None = _spec(must_exist=True, default=None)
    labels: Path | None = _spec(must_exist=True, default=None)
    legend: Path | None = _spec(must_exist=True, default=None)
    fetch: str | None = _spec(default=None)
    bands: tuple[int, ...] | None = _spec(min=0, default=None)
    stretch: tuple[float, ...] = _spec(min=0, max=100, default=(2.0, 98.0))
    size: tuple[int, ...] | None = _spec(min=1, default=None)
    description: str = _spec(default="")
    source: str = _spec(default="")
    licence: str = _spec(default="")
    stands_in_for: str | None = _spec(default=None)


# --------------------------------------------------------------------------- loading


class _Raw:
    """A merged YAML mapping plus, for every key path, the file (or option) that set it."""

    def __init__(self, top: str):
        self.data: dict = {}
        self.origins: dict[tuple, str] = {}
        self.top = top

    def origin(self, keys: tuple) -> str:
        # The deepest recorded prefix: a whole section set by one file names that file.
        for n in range(len(keys), 0, -1):
            if keys[:n] in self.origins:
                return self.origins[keys[:n]]
        return self.top

    def merge(self, mapping: dict, source: str, prefix: tuple = ()) -> None:
        target = self.data
        for key in prefix:
            target = target.setdefault(key, {})
        for key, value in mapping.items():
            keys = prefix + (key,)
            if isinstance(value, dict) and isinstance(target.get(key), dict):
                self.merge(value, source, keys)
            else:
                target[key] = value
                self.origins[keys] = source


def shipped_configs() -> list[str]:
    """The names of the shipped experiment configs (``quick``, ``paper``, ...)."""
    return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))


def shipped_config(name: str) -> Path | None:
    """The shipped config a bare name means (``quick``, ``paper.yaml``), or None."""
    shipped = CONFIG_DIR / (name if name.endswith((".yaml", ".yml")) else f"{name}.yaml")
    return shipped if Path(name).name == name and shipped.is_file() else None


def config_file(name_or_path: str | Path) -> Path:
    """The config a command line names: a path, else a shipped config by its name.

    A path that exists means that file (or what is wrong with it, a folder or a symlink
    loop, for its reader to name); a bare name that is no file (``quick``, ``paper.yaml``)
    means the shipped config of that name, wherever the command runs.

    Raises
    ------
    ConfigError
        Neither a file nor a shipped config, naming the shipped ones.
    """
    path = Path(name_or_path)
    if os.path.lexists(path):
        return path
    if (shipped := shipped_config(str(name_or_path))) is not None:
        return shipped
    raise ConfigError(
        f"{display_path(path)}: config file not found; expected a path to a YAML config or the name of a shipped one "
        f"({', '.join(shipped_configs())})"
    )


def init_config(name: str, source: str = "quick", folder: Path = Path(".")) -> Path:
    """Write ``folder/<name>.yaml``: an editable copy of the shipped experiment config ``source``, comments and all,
    named ``name``; returns its path.

    Its ``base:`` names a shipped config, which resolves wherever the copy is.

    Raises
    ------
    ConfigError
        ``name`` is not a valid experiment name, ``source`` no shipped experiment config
        (``paper`` is the base the others build on, not an experiment), or the file exists.
    """
    if not _NAME_PATTERN.match(name) or name.endswith((".yaml", ".yml")):
        raise ConfigError(f"name: got {shown(name)}, expected {_NAME_RULE}", parameter="name")
    experiments = [n for n in shipped_configs() if re.search(r"^name:", (CONFIG_DIR / f"{n}.yaml").read_text(), re.M)]
    if source not in experiments:
        raise ConfigError(
            f"source: got {shown(source)}, expected a shipped experiment config: {', '.join(experiments)}",
            parameter="source",
        )
    path = Path(folder) / f"{name}.yaml"
    if path.exists():
        raise ConfigError(f"{display_path(path)}: already exists; choose another name or edit that file")
    text = re.sub(
        r"^name:( *)(\S+)( *)", lambda m: f"name:{m[1]}{name}{' ' * max(len(m[2]) + len(m[3]) - len(name), 1)}",
        (CONFIG_DIR / f"{source}.yaml").read_text(), count=1, flags=re.M,
    )  # the comment after the name stays in its column
    with atomic_path(path) as tmp:
        tmp.write_text(text)
        load_config(tmp)  # a copy that would not load is never left behind
    return path


def _load_chain(path: Path, raw: _Raw, seen: tuple[Path, ...] = ()) -> None:
    """Merge ``path`` and, first, the chain of ``base`` files it names."""
    path = resolved(path)
    if path in seen:
        raise ConfigError(f"{display_path(path)}: base: the chain of base configs loops back here")
    data = read_yaml(path, "config file")
    for key, what in ((SWEEP_KEY, "a sweep"), (SPECIFICATIONS_KEY, "specifications")):
        if key in data and seen:
            raise ConfigError(f"{display_path(path)}: {key}: only the experiment config itself may declare {what}")
        # the sweep's, not an experiment's (curiosity_cli.sweep.declared_sweeps, curiosity_cli.specifications)
        data.pop(key, None)
    base = data.pop("base", None)
    if base is not None:
        if not isinstance(base, str):
            raise ConfigError(
                f"{display_path(path)}: base: got {shown(base)}, expected a path to a YAML config"
            )
        base_path = path.parent / base
        if not base_path.is_file():  # a shipped config may be named from anywhere (a saved config does)
            base_path = shipped_config(base)
        if base_path is None:
            raise ConfigError(f"{display_path(path)}: base: file not found: {display_path(path.parent / base)}")
        _load_chain(base_path, raw, seen + (path,))
    raw.merge(data, str(path))


def _parse_override(text: str) -> tuple[tuple[str, ...], Any]:
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise ConfigError(
            f"{OVERRIDES} {shown(text)}: expected KEY=VALUE, e.g. explore.restarts=5", parameter=OVERRIDES
        )
    key = key.strip()
    try:
        return tuple(key.split(".")), parse_yaml(value, f"{OVERRIDES} {shown(key)}")
    except ConfigError as exc:
        raise ConfigError(str(exc), parameter=OVERRIDES) from None


def _apply_overrides(raw: _Raw, overrides: typing.Iterable[str]) -> None:
    for text in overrides:
        keys, value = _parse_override(text)
        nested: Any = value
        for key in reversed(keys[1:]):
            nested = {key: nested}
        raw.merge({keys[0]: nested}, OVERRIDES)


def load_config(path: str | Path, overrides: typing.Iterable[str] = ()) -> ExperimentConfig:
    """Load an experiment config, its chain of ``base`` configs and ``overrides``.

    Parameters
    ----------
    path : str or Path
        The experiment YAML, e.g. ``my-experiment.yaml``, or a shipped config's name
        (``quick``, ``paper-grid``: :func:`config_file`).
    overrides : iterable of str
        ``KEY=VALUE`` strings with dotted keys (``explore.restarts=5``); values are YAML.

    Returns
    -------
    ExperimentConfig

    Raises
    ------
    ConfigError
        One line naming the file (or ``overrides``), the key, the value and what was expected.
    """
    raw = _read_chain(path, overrides)
    return _check_experiment(_build(ExperimentConfig, raw.data, (), raw), raw)


#: What an experiment config adds to the base it builds on (``paper.yaml`` has none of them).
_EXPERIMENT_KEYS = ("name", "seed", "datasets")


def show_config(path: str | Path, overrides: typing.Iterable[str] = ()) -> str:
    """What ``config show`` prints: an experiment config resolved, every key; or, for a base
    config that names no experiment (``paper``), its parameter sections, each checked.

    Raises
    ------
    ConfigError
        As :func:`load_config`.
    """
    raw = _read_chain(path, overrides)
    sections = {f.name for f in dataclasses.fields(ExperimentConfig) if f.name not in _EXPERIMENT_KEYS}
    if not raw.data.keys() <= sections:  # an experiment, or a key of neither: refused as an experiment's
        return to_yaml(_check_experiment(_build(ExperimentConfig, raw.data, (), raw), raw))
    hints = typing.get_type_hints(ExperimentConfig)
    sections = {
        f.name: to_dict(_build(hints[f.name], raw.data.get(f.name), (f.name,), raw))
        for f in dataclasses.fields(ExperimentConfig) if f.name not in _EXPERIMENT_KEYS
    }
    return dump_yaml(sections)


def _read_chain(path: str | Path, overrides: typing.Iterable[str]) -> _Raw:
    """A config file (or a shipped config's name), its chain of bases and ``overrides``, merged."""
    path = config_file(path)
    raw = _Raw(str(resolved(path)))
    _load_chain(path, raw)
    _apply_overrides(raw, overrides)
    return raw


#: The converged labelling schedule (README, "Reproducing the paper"): 256 sweeps from
#: random topics at every checkpoint, which brought chains from two starts together in 35
#: of the 36 map-length-target cells of the paper's grid. ``--converged`` of ``label`` and
#: ``reproduce``; the experiment's config.yaml records the two keys it sets.
CONVERGED_LABELS = ("label.sweeps=256", "label.warm_sweeps=null")


def with_converged_labels(overrides: typing.Iterable[str]) -> list[str]:
    """``overrides`` and then :data:`CONVERGED_LABELS`.

    Raises
    ------
    ConfigError
        An override of a key the converged schedule sets (it would be silently replaced).
    """
    overrides = list(overrides)
    fixed = {_parse_override(text)[0] for text in CONVERGED_LABELS}
    for text in overrides:
        if _parse_override(text)[0] in fixed:
            raise ConfigError(
                f"{OVERRIDES} {shown(text)}: the converged schedule sets {' and '.join(CONVERGED_LABELS)}; "
                "give either, not both", parameter=OVERRIDES,
            )
    return [*overrides, *CONVERGED_LABELS]


def load_words_config(path: str | Path, overrides: typing.Iterable[str] = ()) -> WordsConfig:
    """Load only the ``words`` section of a config (and its base chain), for ``extract``.

    Raises
    ------
    ConfigError
        As :func:`load_config`; also for an override outside ``words``.
    """
    path = config_file(path)
    raw = _Raw(str(resolved(path)))
    _load_chain(path, raw)
    for text in overrides:
        if not _parse_override(text)[0][0] == "words":
            raise ConfigError(
                f"{OVERRIDES} {shown(text)}: expected a words.* key; this command reads only words", parameter=OVERRIDES
            )
    _apply_overrides(raw, overrides)
    words = _build(WordsConfig, raw.data.get("words"), ("words",), raw)
    _check_words(words, raw)
    return words


def load_dataset_config(path: str | Path) -> DatasetConfig:
    """Load a dataset YAML; relative paths in it are relative to the YAML file.

    A fetched map's ``image``, ``labels`` and ``legend`` become the files it is made into
    (:func:`curiosity_cli.fetched.fetched_files`); they need not exist yet.

    Raises
    ------
    ConfigError
        The file, key, value and expectation, in one line.
    """
    from curiosity_cli.fetched import FETCHED_MAPS, fetched_files
    from curiosity_cli.paper import PAPER_MAPS

    path = Path(path)
    where = display_path(path)
    raw = _Raw(str(resolved(path)))
    raw.merge(read_yaml(path, "dataset file"), str(resolved(path)))
    config = _build(DatasetConfig, raw.data, (), raw)
    if config.fetch is not None:
        if config.fetch not in FETCHED_MAPS:
            raise ConfigError(
                f"{where}: fetch: got {shown(config.fetch)}, expected one of {', '.join(sorted(FETCHED_MAPS))}"
            )
        given = [key for key in ("image", "labels", "legend") if key in raw.data]
        if given:
            raise ConfigError(f"{where}: {given[0]}: a fetched map's files are made on first use; leave {given[0]} out")
        config = dataclasses.replace(config, **fetched_files(config.fetch))
    elif config.image is None:
        raise ConfigError(f"{where}: image: missing key; expected the path of the map's image")
    if config.word_stride > config.cell_width:
        raise ConfigError(
            f"{where}: word_stride: got {config.word_stride}, expected at most cell_width ({config.cell_width}): "
            "a wider stride leaves cells without texton words"
        )
    if config.labels is not None and config.legend is None:
        raise ConfigError(f"{where}: legend: missing; a dataset with labels needs a legend YAML")
    if config.size is not None and len(config.size) != 2:
        raise ConfigError(f"{where}: size: got {shown(list(config.size))}, expected [rows, cols]")
    if config.bands is not None and len(config.bands) not in (1, 3):
        raise ConfigError(
            f"{where}: bands: got {shown(list(config.bands))}, expected [r, g, b] (0-based band indices) or [k] for grey"
        )
    if len(config.stretch) != 2 or config.stretch[0] >= config.stretch[1]:
        raise ConfigError(
            f"{where}: stretch: got {shown(list(config.stretch))}, expected [low, high] percentiles with 0 <= low < high <= 100"
        )
    if config.stands_in_for is not None and config.stands_in_for not in PAPER_MAPS:
        raise ConfigError(
            f"{where}: stands_in_for: got {shown(config.stands_in_for)}, expected one of {', '.join(PAPER_MAPS)} or null"
        )
    return config


def dataset_names() -> list[str]:
    """Names of the datasets in ``configs/datasets/``, sorted."""
    return sorted(p.stem for p in DATASET_CONFIG_DIR.glob("*.yaml"))


def dataset_path(name_or_path: str | Path, relative_to: Path | None = None) -> Path:
    """The dataset YAML for a registered name or a path to a YAML file.

    Raises
    ------
    ConfigError
        When it is neither.
    """
    text = str(name_or_path)
    registered = DATASET_CONFIG_DIR / f"{text}.yaml"
    if _NAME_PATTERN.match(text) and not text.endswith((".yaml", ".yml")) and registered.is_file():
        return registered
    candidate = (relative_to or Path.cwd()) / text
    if candidate.is_file():
        return resolved(candidate)
    raise ConfigError(
        f"no dataset {shown(text)}: expected one of {', '.join(dataset_names())} "
        "or a path to a dataset YAML"
    )


def to_dict(config) -> dict:
    """A config as plain YAML-ready data (paths as strings or their names, tuples as lists)."""

    def plain(value, named=None):
        if dataclasses.is_dataclass(value):
            return {f.name: plain(getattr(value, f.name), f.metadata.get("named")) for f in dataclasses.fields(value)}
        if isinstance(value, tuple):
            return [plain(v) for v in value]
        if isinstance(value, Path):
            return next((name for name, path in (named or {}).items() if value == path), str(value))
        return value

    return plain(config)


def to_yaml(config) -> str:
    """The resolved config as YAML: every key."""
    return dump_yaml(to_dict(config))


def saved_yaml(config) -> str:
    """The config as an experiment folder saves it: every key, on top of the shipped ``paper.yaml``.

    Every key is written, so the file says what the experiment ran with; the ``base``
    gives a key added to the project after the file was saved its default from
    ``configs/paper.yaml``, so the folder still loads. A file made with another value
    than that default is then refused or made again by its recipe
    (:mod:`curiosity_cli.experiment.recipes`), never taken as made with it.
    """
    return f"base: {_SAVED_BASE}  # the shipped configs/{_SAVED_BASE}: defaults for keys added after saving\n" + to_yaml(config)


# --------------------------------------------------------------------------- validation


def _invalid(raw: _Raw, keys: tuple, problem: str) -> ConfigError:
    """The error of the value at ``keys``, named by where it was set: a file, or the overrides."""
    parameter = OVERRIDES if raw.origin(keys) == OVERRIDES else None
    return ConfigError(f"{_where(raw, keys)}: {problem}", parameter=parameter)


def _where(raw: _Raw, keys: tuple) -> str:
    source = raw.origin(keys)
    label = source if source == OVERRIDES else display_path(Path(source))
    key = "".join(_key_text(k) for k in keys).lstrip(".")
    # a key is user input too: an unknown one may be of any length
    key = key if len(key) <= SHOWN_CHARS else key[: SHOWN_CHARS - 3] + "..."
    return f"{label}: {key}" if key else label


def _key_text(key) -> str:
    """One step of a key path: ``[0]`` for a list index, ``.name`` for a plain key."""
    if isinstance(key, int):
        return f"[{key}]"
    # an unknown key may be empty, hold a newline or not be a string at all: show its repr
    plain = isinstance(key, str) and key.isprintable() and key
    return f".{key}" if plain else f".{shown(key)}"


#: What a value of each leaf type is called in a message: one, and a list of them.
_NOUNS = {
    int: ("an integer", "integers"),
    float: ("a number", "numbers"),
    bool: ("true or false", "true or false values"),
    str: ("a string", "strings"),
    Path: ("a file path", "file paths"),
}


def _expected(tp) -> str:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        return f"{_expected(inner[0])} or null"
    if origin is tuple:
        return f"a list of {_NOUNS[typing.get_args(tp)[0]][1]}"
    return _NOUNS.get(tp, ("a mapping",))[0]


def _bound_text(bound: float) -> str:
    """A bound as a person writes it: whole numbers in full (4294967295, not 4.29497e+09)."""
    return str(int(bound)) if float(bound).is_integer() else f"{bound:g}"


def _range_text(meta: dict) -> str:
    parts = []
    if meta["min"] is not None:
        parts.append(f"{'>' if meta['min_exclusive'] else '>='} {_bound_text(meta['min'])}")
    if meta["max"] is not None:
        parts.append(f"{'<' if meta['max_exclusive'] else '<='} {_bound_text(meta['max'])}")
    return " and ".join(parts)


def _build(cls, data: Any, keys: tuple, raw: _Raw):
    if not isinstance(data, dict):
        raise _invalid(raw, keys, f"got {shown(data)} ({type(data).__name__}), expected a mapping of keys")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    for key in data:
        if key not in names:
            raise _invalid(raw, keys + (key,), f"unknown key; expected one of {', '.join(names)}")
    values = {}
    for f in dataclasses.fields(cls):
        if f.name not in data:
            if f.default is not dataclasses.MISSING:
                values[f.name] = f.default
                continue
            raise _invalid(raw, keys + (f.name,), "missing key")
        values[f.name] = _convert(hints[f.name], f.metadata, data[f.name], keys + (f.name,), raw)
    return cls(**values)


def _convert(tp, meta: dict, value: Any, keys: tuple, raw: _Raw):
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None:
            return None
        (inner,) = [a for a in typing.get_args(tp) if a is not type(None)]
        tp, origin = inner, typing.get_origin(inner)

    def refuse(expected: str):
        given = f"{shown(value)} ({type(value).__name__})" if not isinstance(value, dict) else "a mapping"
        raise _invalid(raw, keys, f"got {given}, expected {expected}")

    if dataclasses.is_dataclass(tp):
        return _build(tp, value, keys, raw)
    if origin is tuple:
        if not isinstance(value, list) or not value:
            refuse(f"a non-empty {_expected(tp)[2:]}")
        item_type = typing.get_args(tp)[0]
        return tuple(
            _convert(item_type, meta, item, keys + (i,), raw) for i, item in enumerate(value)
        )
    if tp is bool:
        if not isinstance(value, bool):
            refuse("true or false")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            refuse(_expected(int) + (f" {_range_text(meta)}" if _range_text(meta) else ""))
        result = value
    elif tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            refuse("a finite number" + (f" {_range_text(meta)}" if _range_text(meta) else ""))
        result = float(value)
    elif tp is str:
        if not isinstance(value, str):
            refuse("a string")
        if meta["file_name"] and not _NAME_PATTERN.match(value):
            refuse(f"{_NAME_RULE} (it names files and folders)")
        result = value
    elif tp is Path:
        if not isinstance(value, str) or not value or "\0" in value:
            refuse("a file path")
        named = meta["named"] or {}
        result = named[value] if value in named else _resolve_path(value, keys, raw)
        if meta["must_exist"] and not result.exists():
            raise _invalid(raw, keys, f"file not found: {display_path(result)}")
        return result
    else:  # pragma: no cover - a field type the validator does not know is a bug here
        raise TypeError(f"unsupported config field type {tp!r}")

    if meta["choices"] is not None and result not in meta["choices"]:
        refuse(f"one of {', '.join(str(c) for c in meta['choices'])}")
    if isinstance(result, (int, float)):
        low, high = meta["min"], meta["max"]
        too_low = low is not None and (result <= low if meta["min_exclusive"] else result < low)
        too_high = high is not None and (result >= high if meta["max_exclusive"] else result > high)
        if too_low or too_high:
            refuse(f"{'an integer' if tp is int else 'a number'} {_range_text(meta)}")
    return result


def _resolve_path(value: str, keys: tuple, raw: _Raw) -> Path:
    """Relative paths count from the YAML file that wrote them (from the cwd for overrides)."""
    try:
        path = Path(value).expanduser()
    except RuntimeError:  # ~user of a user this machine does not know
        raise _invalid(raw, keys, f"got {shown(value)}, expected a file path; no such home folder") from None
    if path.is_absolute():
        return path
    source = raw.origin(keys)
    base = Path.cwd() if source == OVERRIDES else Path(source).parent
    return resolved(base / path)


def _check_experiment(config: ExperimentConfig, raw: _Raw) -> ExperimentConfig:
    """Rules that tie keys together; dataset paths become absolute so a saved config travels."""
    _check_words(config.words, raw)
    datasets = []
    for i, entry in enumerate(config.datasets):
        source = raw.origin(("datasets", i))
        relative_to = None if source == OVERRIDES else Path(source).parent
        try:
            path = dataset_path(entry, relative_to)
        except ConfigError as exc:
            raise _invalid(raw, ("datasets", i), str(exc)) from None
        datasets.append(entry if path.parent == DATASET_CONFIG_DIR else str(path))
    explore = config.explore
    for i, name in enumerate(explore.weight_functions):
        if name not in WALKER_NAMES:
            raise _invalid(
                raw, ("explore", "weight_functions", i), f"got {shown(name)}, expected one of {', '.join(WALKER_NAMES)}"
            )
    if len(set(explore.weight_functions)) != len(explore.weight_functions):
        raise _invalid(
            raw, ("explore", "weight_functions"), f"got {list(explore.weight_functions)}, expected each weight function once"
        )
    checkpoints = list(explore.checkpoints)
    if checkpoints != sorted(set(checkpoints)) or checkpoints[-1] > explore.path_length:
        raise _invalid(
            raw, ("explore", "checkpoints"),
            f"got {checkpoints}, expected increasing path lengths no longer than explore.path_length "
            f"({explore.path_length})",
        )
    _check_coverage(explore, raw)
    _check_drive(config.drive, raw)
    return dataclasses.replace(config, datasets=tuple(datasets))


def _check_coverage(explore: ExploreConfig, raw: _Raw) -> None:
    """The clamp needs its floor; a floor set without naming a reading is the old syntax."""
    if explore.coverage == "clamp" and explore.min_d2 is None:
        raise _invalid(raw, ("explore", "min_d2"), "got null, expected a number > 0: the clamp reading's floor on d^2")
    paper = str((CONFIG_DIR / _SAVED_BASE).resolve())
    if explore.min_d2 is not None and raw.origin(("explore", "min_d2")) != paper and (
        raw.origin(("explore", "coverage")) == paper
    ):
        # min_d2 alone once meant the clamp; read now as literal it would be silently ignored
        raise _invalid(
            raw, ("explore", "min_d2"),
            f"got {explore.min_d2} without explore.coverage; the reading of eq. 8 is now named there "
            f"(one of {', '.join(COVERAGE_READINGS)}): add explore.coverage: clamp to clamp d^2 at {explore.min_d2}",
        )


def _check_drive(drive: DriveConfig, raw: _Raw) -> None:
    """Rules that tie ``drive`` keys together: the first broken one, where its key was set."""
    rules = [
        (drive.frame_width >= drive.grid_cols, "frame_width", f"at least grid_cols ({drive.grid_cols})"),
        (drive.carry_frames < drive.window_frames, "carry_frames", f"fewer than window_frames ({drive.window_frames})"),
        (drive.surge_min <= drive.surge_max, "surge_min", f"at most surge_max ({drive.surge_max})"),
        (drive.keepalive < drive.watchdog, "keepalive", f"shorter than the robot's watchdog ({drive.watchdog} s)"),
    ]
    for ok, key, expected in rules:
        if not ok:
            raise _invalid(raw, ("drive", key), f"got {getattr(drive, key)}, expected {expected}")
