"""YAML configs → validated, frozen dataclasses.

An experiment config names its ``base`` (usually ``paper.yaml``, which holds the paper's
parameters) and overrides keys of it; ``KEY=VALUE`` overrides (the command line's ``--set``)
go on top. Every leaf remembers which file (or the overrides) gave it, so an error names
the file, the key, what was given and what was expected, in one line.

The dataclasses carry no defaults on purpose: the paper's values live in one place,
``configs/paper.yaml``, and a config that misses a key says so instead of silently
picking up a second copy of a default. The YAML-to-dataclass machinery and its messages
are :mod:`curiosity_cli.schema`'s; the maps a config names, :mod:`curiosity_cli.maps.datasets`'.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import re
import typing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from curiosity_cli.errors import ConfigError
from curiosity_cli.files import atomic_path, display_path, resolved
from curiosity_cli.maps.datasets import DATASET_CONFIG_DIR, dataset_path, load_dataset_config
from curiosity_cli.paths import SHIPPED_CONFIGS, SHIPPED_DATA
from curiosity_cli.config_yaml import SAVED_BASE, to_dict, to_yaml
from curiosity_cli.schema import NAME_PATTERN, NAME_RULE, OVERRIDES, Raw, build, invalid, spec
from curiosity_cli.yamlfile import dump_yaml, parse_yaml, read_yaml, shown

#: The shipped configs, which a command or a ``base:`` may name without a path (``quick``, ``paper.yaml``).
CONFIG_DIR = SHIPPED_CONFIGS
#: The vocabularies shipped with the package, which a config names ``shipped`` (a saved
#: config too, so that an experiment folder copied to another machine finds them there).
SHIPPED_VOCABULARIES = {"shipped": SHIPPED_DATA / "vocab"}

#: The top-level key of an experiment config that declares a sweep over its other keys
#: (:func:`curiosity_cli.study.sweep.declared_sweeps`); an experiment never sees it.
SWEEP_KEY = "sweep"
#: The top-level key of a study config that declares named specifications, each a set of
#: overrides run on every map and replicate seed (:mod:`curiosity_cli.study.specifications`); an
#: experiment never sees it either.
SPECIFICATIONS_KEY = "specifications"
#: The top-level key of a study config that declares hypotheses, each tested on some of its specifications'
#: seeds (:mod:`curiosity_cli.study.hypotheses`); an experiment never sees it either.
HYPOTHESES_KEY = "hypotheses"

#: The largest ORB or texton vocabulary a config may name and ``vocab build`` may learn.
MAX_VOCABULARY = 30000
#: Bounds on the counts a config names: far above any run that finishes on one machine (the paper:
#: 20 restarts, 320 steps; this project: 100,000 samples a step, 64-256 label sweeps, 200 batch
#: sweeps), so that a typo (1e12) is refused by name before anything runs, never a run that does
#: not end or a count beyond what the kernels' 64-bit integers hold.
MAX_RESTARTS = 10_000
MAX_PATH_LENGTH = 100_000
MAX_SAMPLES = 100_000_000  # word samples of refinement per step or frame: 1,000 times the default
MAX_SWEEPS = 100_000  # Gibbs sweeps of a labelling chain or of the batch reference
MAX_CANDIDATE_SWEEPS = 1_000  # passes over a candidate's temporary labels
#: Bounds on the other numbers a config names, each far above any defensible setting and below what overflows,
#: hangs or fails inside a library, so that a typo is refused by name (issue 63).
MAX_PRIOR = 1_000.0  # α, β: Dirichlet priors, the paper's 0.1; 1e308 made every log-likelihood -inf
MAX_PIXELS = 16_384  # a length in pixels: an ORB tile or grid step, a frame's width, the simulated camera's view
MAX_CELLS_SIDE = 256  # image cells along a frame's side
MAX_FEATURES = 10_000_000  # ORB keypoints of a map or of one of its tiles
MAX_STEP_SECONDS = 3_600.0  # a walker's time budget per step; 1e308 never ended
MAX_DISTANCE2 = 1e9  # a squared distance in cells: a map of 30,000 cells a side
MAX_FRAMES = 100_000_000  # frames the live model remembers: a year at 3 frames a second
MAX_SPEED = 10.0  # m/s forward: twenty times the paper robot's fastest; the robot never backs up (0 at least)
MAX_RATE = 6.283  # rad/s yaw or pitch: a turn a second
MAX_GAIN = 100.0  # m/s or rad/s per unit of target offset (offsets run -1..1)
MAX_BAUD = 12_000_000  # the fastest USB serial adapters
MAX_WAIT = 3_600.0  # s: a timeout, a watchdog, a simulated frame's interval
KEEPALIVE_MAX = 0.2  # s: the wire protocol wants a host frame at least every 200 ms (drive/PROTOCOL.md)
MAX_RATE_HZ = 1_000.0  # Hz: telemetry, a video's frames
MAX_RESENDS = 100
MAX_METRES_PER_PIXEL = 1_000.0

#: The walkers a config may name in ``explore.weight_functions``, in the order reports list
#: them: the paper's four weight functions in its order, the lawnmower, the ceilings, then the
#: validation walkers (:data:`VALIDATION_WALKERS`).
#: The one list of walkers: names are the config's vocabulary, checked here under every
#: entry point without importing the explore stage;
#: :data:`curiosity_cli.explore.weights.WEIGHT_FUNCTIONS` gives each its walker, in this order.
WALKER_NAMES = (
    "random-walk",
    "stochastic-coverage",
    "word-perplexity",
    "topic-perplexity",
    "lawnmower",
    "scattered-cells",
    "compact-block",
    "oracle-0.1",
    "oracle-0.2",
    "oracle-0.3",
    "sham",
)
#: Walkers that test the measures, not curiosity (issue 58): oracles with a planted advantage (they read the
#: map's truth, so they run only on maps with labels) and a sham that steers on information-free scores. Never
#: compared in the paper's verdict (:mod:`curiosity_cli.explore.weights`).
VALIDATION_WALKERS = ("oracle-0.1", "oracle-0.2", "oracle-0.3", "sham")
#: The walkers that read a map's truth (its human labels), so that their runs' recipes hold the labels' digest.
READS_TRUTH = ("oracle-0.1", "oracle-0.2", "oracle-0.3")

#: The paper's own walkers (its four weight functions): what a specification curve compares.
PAPER_WALKERS = ("random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity")


@dataclass(frozen=True)
class CoverageReading:
    """A reading of eq. 8: what a visited candidate's own term (``d = 0``) is.

    Attributes
    ----------
    name : str
        What ``explore.coverage`` names it.
    meaning : str
        The own term, in words.
    reads_min_d2 : bool
        Whether its potential reads ``explore.min_d2``, the floor on ``d²``: a config
        naming it must give the floor, and a run's settings record the floor only then.
    infinite_when_visited : bool
        Whether a visited candidate's potential is ``∞`` (weight 0): a walker whose
        neighbours are all visited then has nothing to weigh, and draws its step by the
        candidates' own visit counts instead (:func:`curiosity_cli.explore.walker.explore`).
    """

    name: str
    meaning: str
    reads_min_d2: bool
    infinite_when_visited: bool


#: The readings of eq. 8 a config may name in ``explore.coverage``, by name, the default
#: (``configs/paper.yaml``) first: what a visited candidate's own term (``d = 0``) means,
#: which the paper leaves undefined. The one table of readings: the config's rules and the
#: walker read its flags, and :func:`curiosity_cli.explore.weights.coverage_potential`
#: computes each by its name.
COVERAGE_READINGS: dict[str, CoverageReading] = {
    reading.name: reading
    for reading in (
        CoverageReading(
            "literal", "n / 0 = ∞, as eq. 8 is written", reads_min_d2=False, infinite_when_visited=True,
        ),
        CoverageReading(
            "clamp", "d² clamped from below at explore.min_d2", reads_min_d2=True, infinite_when_visited=False,
        ),
        CoverageReading(
            "others", "left out of the candidate's sum", reads_min_d2=False, infinite_when_visited=False,
        ),
    )
}

#: Where labelling runs (``label.device``): the CPU, a CUDA GPU (the extra ``curiosity-cli[cuda]``),
#: or a GPU when one is there; the same bytes on each (``topics/chains.py``). The one list of
#: names: configs are checked here under every entry point without importing the topics stage,
#: and :data:`curiosity_cli.topics.devices.DEVICES`, the table of devices, holds exactly these
#: and ``auto`` (checked when it loads).
LABEL_DEVICES = ("cpu", "cuda", "auto")
#: How a path's frozen Φ_p labels the whole map (``label.reading``; curiosity_cli/label/readings.py says what each
#: does); the first is the default, which a label recipe leaves out.
LABEL_READINGS = ("frozen", "unseen-topic", "used-topics", "thawed")
#: How surprising a camera frame's image cells are to the drive (``drive.surprise``; curiosity_cli/drive/surprise.py
#: says what each is), the paper's eq. 12 as the drive computed it first.
DRIVE_SURPRISES = ("paper", "predictive", "recent", "bayesian")

#: The other open choices of the paper's exploration, each a key of ``explore`` with the
#: values a config may name, today's reading first (``configs/paper.yaml`` gives each the
#: paper's sentence and what the authors' ROST code does):
#:
#: - ``candidates``: the cells ``G(c)`` a walker scores, 4 (up, down, left, right) or 8;
#: - ``candidate_context``: the counts eq. 12's temporary labels of a candidate are drawn
#:   against, ``neighbourhood`` (the model's ``n_Gk`` of the candidate) or ``own`` (its
#:   own temporary labels only), and ``candidate_sweeps`` the passes over them;
#: - ``candidate_labels``: each temporary label drawn from eq. 5 (``sample``) or its most
#:   likely topic under eq. 5 (``argmax``, as the authors' ``estimate()``);
#: - ``candidate_words``: the candidate's words ``held-out`` of the model while it is scored
#:   (the paper's "without adding") or ``added`` to it, in Φ and the path's topics too, as
#:   the authors' code scores words it has already added;
#: - ``path_topics``: P(k | path), ``smoothed`` ``(n_k + α) / (N + Kα)`` or ``counts`` ``n_k / N``;
#: - ``revisits``: a revisited cell's words enter the model ``once`` or ``again`` each visit;
#: - ``refine_picks``: which observations realtime refinement picks, ``uniform`` (eq. 6),
#:   ``recent`` (the authors' refinery) or ``recent-64-ours`` (our earlier translation of
#:   it: :data:`RECENT_NEWEST`).
EXPLORE_READINGS = {
    "candidates": (4, 8),
    "candidate_context": ("neighbourhood", "own"),
    "candidate_labels": ("sample", "argmax"),
    "candidate_words": ("held-out", "added"),
    "path_topics": ("smoothed", "counts"),
    "revisits": ("once", "again"),
    "refine_picks": ("uniform", "recent", "recent-64-ours"),
}
#: What a run recipe leaves out: each reading at what every run did before its key existed
#: (the first value of each, and one pass over the temporary labels), so that the runs of
#: older experiments stay current (a run's recipe names a reading only when it is another).
UNRECORDED_READINGS = {key: values[0] for key, values in EXPLORE_READINGS.items()} | {"candidate_sweeps": 1}

#: For each ``refine_picks`` reading after ``uniform``: how many of the newest observation
#: times its η branch picks among, uniformly (else it draws a time by age from Beta(τ = 2,
#: 1)). The authors' refinery (rost-ros ``refinery.hpp``, ``dowork_parallel_refine_online2``)
#: picks among the cells of the last observation, ``observation_size`` = 64 cells of a
#: camera frame; a step of the map walker observes one cell, so ``recent`` picks the newest
#: time. ``recent-64-ours`` is our earlier translation, 64 observation times, not the
#: authors'. A run's recipe records the number (:meth:`ExploreConfig.run_settings`): the
#: runs made when ``recent`` meant 64 recorded none, so they are made again, never taken as
#: current.
RECENT_NEWEST = {"recent": 1, "recent-64-ours": 64}

#: Where a config's ORB words are (``words.orb_detector``): at ORB's keypoints, or at every
#: point of a regular grid (:mod:`curiosity_cli.words.orb_grid`), as near the density of the
#: paper's Table 1 as one scale gets.
ORB_DETECTORS = ("keypoints", "grid")


@dataclass(frozen=True)
class ModelConfig:
    """The ROST topic model (paper section 3)."""

    topics: int = spec(min=2, max=127)
    alpha: float = spec(min=0, min_exclusive=True, max=MAX_PRIOR)
    beta: float = spec(min=0, min_exclusive=True, max=MAX_PRIOR)
    eta: float = spec(min=0, max=1)
    spatial_neighbours: int = spec(choices=(0, 4))


@dataclass(frozen=True)
class WordsConfig:
    """Visual words (paper section 5.1)."""

    vocabulary_dir: Path = spec(must_exist=True, named=SHIPPED_VOCABULARIES)
    orb_vocabulary: int = spec(min=2, max=MAX_VOCABULARY)
    texton_vocabulary: int = spec(min=2, max=MAX_VOCABULARY)
    orb_detector: str = spec(choices=ORB_DETECTORS)
    # read by the grid detector only (store_settings)
    orb_grid_step: int = spec(min=1, max=MAX_PIXELS)
    # read by the keypoints detector only (store_settings)
    orb_tile: int = spec(min=1, max=MAX_PIXELS)
    orb_per_tile: int | None = spec(min=1, max=MAX_FEATURES)
    orb_max_features: int | None = spec(min=1, max=MAX_FEATURES)
    orb_fast_threshold: int = spec(min=1, max=255)
    orb_fill_threshold: int | None = spec(min=1, max=255)
    # hue words, whichever the ORB detector
    colour_words: bool = spec()

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

    def read_settings(self) -> dict:
        """The keys that change a map's words: :meth:`store_settings` and the vocabularies' keys
        (two configs that differ only outside these make the same words)."""
        return {**{key: getattr(self, key) for key in _VOCABULARY_KEYS}, **self.store_settings()}


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


@functools.lru_cache(maxsize=1)
def _shipped_words() -> dict:
    """The shipped ``words`` section (``configs/paper.yaml``), read once."""
    return read_yaml(CONFIG_DIR / "paper.yaml", "config file")["words"]


def _check_words(words: WordsConfig, raw: Raw) -> None:
    """ORB keys that tie together: the grid takes no keypoint cap, and the keypoints detector no grid step other
    than the shipped one (it reads none: a step set for it would be taken in silence); a top-up fills capped
    tiles, below the FAST threshold."""
    if words.orb_detector == "keypoints" and words.orb_grid_step != (shipped := _shipped_words()["orb_grid_step"]):
        raise invalid(
            raw, ("words", "orb_grid_step"),
            f"got {words.orb_grid_step}, but words.orb_detector keypoints reads no grid step; expected {shipped} "
            "(the shipped value), or words.orb_detector: grid",
        )
    if words.orb_detector == "grid":
        for key in ("orb_per_tile", "orb_max_features"):
            value = getattr(words, key)
            if value is not None:
                raise invalid(
                    raw, ("words", key),
                    f"got {value}, expected null when words.orb_detector is grid (a word at every grid point; "
                    "the cap is the keypoints detector's)",
                )
    fill = words.orb_fill_threshold
    if fill is None:
        return
    if words.orb_per_tile is None:
        raise invalid(
            raw, ("words", "orb_fill_threshold"),
            f"got {fill}, expected null when words.orb_per_tile is null (the top-up only fills tiles capped by "
            "orb_per_tile)",
        )
    if fill > words.orb_fast_threshold:
        raise invalid(
            raw, ("words", "orb_fill_threshold"),
            f"got {fill}, expected an integer between 1 and words.orb_fast_threshold ({words.orb_fast_threshold})",
        )


@dataclass(frozen=True)
class ExploreConfig:
    """Exploration runs on the simulated 2-D grid (paper sections 4 and 5.1)."""

    # names in WALKER_NAMES, checked when loading
    weight_functions: tuple[str, ...] = spec()
    restarts: int = spec(min=1, max=MAX_RESTARTS)
    path_length: int = spec(min=1, max=MAX_PATH_LENGTH)
    checkpoints: tuple[int, ...] = spec(min=1, max=MAX_PATH_LENGTH)
    samples_per_step: int = spec(min=1, max=MAX_SAMPLES)
    step_seconds: float | None = spec(min=0, min_exclusive=True, max=MAX_STEP_SECONDS)
    coverage: str = spec(choices=tuple(COVERAGE_READINGS))
    # read only by a reading whose reads_min_d2 says so (run_settings)
    min_d2: float | None = spec(min=0, min_exclusive=True, max=MAX_DISTANCE2)
    candidates: int = spec(choices=EXPLORE_READINGS["candidates"])
    candidate_context: str = spec(choices=EXPLORE_READINGS["candidate_context"])
    candidate_sweeps: int = spec(min=1, max=MAX_CANDIDATE_SWEEPS)
    candidate_labels: str = spec(choices=EXPLORE_READINGS["candidate_labels"])
    candidate_words: str = spec(choices=EXPLORE_READINGS["candidate_words"])
    path_topics: str = spec(choices=EXPLORE_READINGS["path_topics"])
    revisits: str = spec(choices=EXPLORE_READINGS["revisits"])
    refine_picks: str = spec(choices=EXPLORE_READINGS["refine_picks"])

    def run_settings(self) -> dict:
        """The keys a run's numbers depend on.

        Every key but ``min_d2`` unless the reading reads it (the clamp), and but a reading of
        :data:`UNRECORDED_READINGS` at the value every run had before its key existed; and,
        with a ``refine_picks`` of :data:`RECENT_NEWEST`, ``refine_newest``: its number of
        newest times, which a run made when ``recent`` picked among 64 lacks.
        """
        settings = {
            key: value for key, value in to_dict(self).items()
            if (key != "min_d2" or COVERAGE_READINGS[self.coverage].reads_min_d2)
            and UNRECORDED_READINGS.get(key, _NO_DEFAULT) != value
        }
        if self.refine_picks in RECENT_NEWEST:
            settings["refine_newest"] = RECENT_NEWEST[self.refine_picks]
        return settings


@dataclass(frozen=True)
class LabelConfig:
    """Labelling whole maps: with a path's model (Z_p) and in batch mode (Z_b) (paper section 5.1)."""

    sweeps: int = spec(min=1, max=MAX_SWEEPS)
    warm_sweeps: int | None = spec(min=1, max=MAX_SWEEPS)
    check_restarts: int = spec(min=0, max=MAX_RESTARTS)
    batch_sweeps: int = spec(min=1, max=MAX_SWEEPS)
    device: str = spec(choices=LABEL_DEVICES)
    reading: str = spec(choices=LABEL_READINGS)
    used_share: float = spec(min=0, max=1, min_exclusive=True)
    thaw_sweeps: int = spec(min=1, max=MAX_SWEEPS)


@dataclass(frozen=True)
class DriveConfig:
    """The live robot driver (paper section 5.2), its wire protocol and the simulated robot."""
    #: Keys no longer read: the value every config saved before holds, and what replaced
    #: them. :func:`~curiosity_cli.schema.build` drops that value and refuses any other,
    #: since a run could not do what it says.
    RETIRED: typing.ClassVar[dict] = {
        key: (value, "the live model no longer restarts every window_frames frames; "
              "drive.memory_frames bounds what it remembers, forgetting one frame at a time")
        for key, value in (("window_frames", 150), ("carry_frames", 50), ("carry_sweeps", 2))
    }

    surprise: str = spec(choices=DRIVE_SURPRISES)
    gamma: float = spec(min=0, max=1, max_exclusive=True)
    temporal_neighbours: int = spec(choices=(0, 2))
    frame_width: int = spec(min=16, max=MAX_PIXELS)
    grid_rows: int = spec(min=1, max=MAX_CELLS_SIDE)
    grid_cols: int = spec(min=1, max=MAX_CELLS_SIDE)
    texton_stride: int = spec(min=1, max=MAX_PIXELS)
    orb_levels: int = spec(min=1, max=16)
    orb_per_tile: int = spec(min=1, max=MAX_FEATURES)
    orb_fill_threshold: int | None = spec(min=1, max=19)
    samples_per_frame: int = spec(min=0, max=MAX_SAMPLES)
    newest_share: float | None = spec(min=0, max=1)
    memory_frames: int | None = spec(min=2, max=MAX_FRAMES)
    surge_cruise: float = spec(min=0, max=MAX_SPEED)
    surge_gain: float = spec(min=0, max=MAX_GAIN)
    surge_min: float = spec(min=0, max=MAX_SPEED)
    surge_max: float = spec(min=0, max=MAX_SPEED)
    yaw_gain: float = spec(min=0, max=MAX_GAIN)
    yaw_rate_max: float = spec(min=0, max=MAX_RATE)
    pitch_gain: float = spec(min=0, max=MAX_GAIN)
    pitch_rate_max: float = spec(min=0, max=MAX_RATE)
    port: str | None = spec()
    baud: int = spec(min=1, max=MAX_BAUD)
    hello_timeout: float = spec(min=0, min_exclusive=True, max=MAX_WAIT)
    ack_timeout: float = spec(min=0, min_exclusive=True, max=MAX_WAIT)
    resends: int = spec(min=0, max=MAX_RESENDS)
    keepalive: float = spec(min=0, min_exclusive=True, max=KEEPALIVE_MAX)
    watchdog: float = spec(min=0, min_exclusive=True, max=MAX_WAIT)
    state_rate: float = spec(min=0, min_exclusive=True, max=MAX_RATE_HZ)
    sim_metres_per_pixel: float = spec(min=0, min_exclusive=True, max=MAX_METRES_PER_PIXEL)
    sim_view_rows: int = spec(min=16, max=MAX_PIXELS)
    sim_view_cols: int = spec(min=16, max=MAX_PIXELS)
    sim_frame_interval: float = spec(min=0, max=MAX_WAIT)
    video_fps: float = spec(min=0, min_exclusive=True, max=MAX_RATE_HZ)


@dataclass(frozen=True)
class ExperimentConfig:
    """One experiment: which maps, which seed, and every parameter of the pipeline."""

    name: str = spec(file_name=True)
    seed: int = spec(min=0, max=2**32 - 1)
    datasets: tuple[str, ...] = spec()
    model: ModelConfig = spec()
    words: WordsConfig = spec()
    explore: ExploreConfig = spec()
    label: LabelConfig = spec()
    drive: DriveConfig = spec()


# --------------------------------------------------------------------------- loading


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
        Neither a file nor a shipped config, naming the shipped ones; or a folder (an
        experiment folder: naming its ``config.yaml``).
    """
    path = Path(name_or_path)
    expected = f"expected a path to a YAML config or the name of a shipped one ({', '.join(shipped_configs())})"
    if path.is_dir():
        saved = path / "config.yaml"
        if saved.is_file():
            raise ConfigError(
                f"{display_path(path)}: an experiment folder, not a config; its saved config is {display_path(saved)}"
            )
        raise ConfigError(f"{display_path(path)}: a folder, not a config; {expected}")
    if os.path.lexists(path):
        return path
    if (shipped := shipped_config(str(name_or_path))) is not None:
        return shipped
    raise ConfigError(f"{display_path(path)}: config file not found; {expected}")


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
    if not NAME_PATTERN.match(name) or name.endswith((".yaml", ".yml")):
        raise ConfigError(f"name: got {shown(name)}, expected {NAME_RULE}", parameter="name")
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


def _load_chain(path: Path, raw: Raw, seen: tuple[Path, ...] = ()) -> None:
    """Merge ``path`` and, first, the chain of ``base`` files it names."""
    path = resolved(path)
    if path in seen:
        raise ConfigError(f"{display_path(path)}: base: the chain of base configs loops back here")
    data = read_yaml(path, "config file")
    if not data:  # else every section would be reported missing, the first as "model: got None"
        raise ConfigError(
            f"{display_path(path)}: empty; expected a YAML config, e.g. base: paper.yaml and the keys that differ from it"
        )
    for key, what in ((SWEEP_KEY, "a sweep"), (SPECIFICATIONS_KEY, "specifications"), (HYPOTHESES_KEY, "hypotheses")):
        if key in data and seen:
            raise ConfigError(f"{display_path(path)}: {key}: only the experiment config itself may declare {what}")
        # the sweep's, not an experiment's (curiosity_cli.study.sweep.declared_sweeps, curiosity_cli.study.specifications)
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


def _apply_overrides(raw: Raw, overrides: typing.Iterable[str]) -> None:
    given: dict[tuple, str] = {}
    for text in overrides:
        keys, value = _parse_override(text)
        for earlier, shown_text in given.items():  # the last would win in silence: refuse it by name
            if earlier[: len(keys)] == keys or keys[: len(earlier)] == earlier:
                raise ConfigError(
                    f"{OVERRIDES}: {'.'.join(keys)} is given twice ({shown_text}, {text}); give each key once",
                    parameter=OVERRIDES,
                )
        given[keys] = text
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
    return _experiment(_read_chain(path, overrides))


#: What an experiment config adds to the base it builds on (``paper.yaml`` has none of them).
_EXPERIMENT_KEYS = ("name", "seed", "datasets")
#: An example of each, for the message of one left out.
_EXPERIMENT_EXAMPLES = {"name": "name: my-experiment", "seed": "seed: 0", "datasets": "datasets: [aerial-mosaic]"}


def _experiment(raw: Raw) -> ExperimentConfig:
    """The experiment a merged chain of configs makes, every rule checked."""
    # the base holds the paper's parameters, never these: say what is expected (an unknown key is named first)
    missing = [key for key in _EXPERIMENT_KEYS if key not in raw.data]
    if missing and raw.data.keys() <= {f.name for f in dataclasses.fields(ExperimentConfig)}:
        raise invalid(
            raw, (missing[0],), f"missing key; an experiment config names its {', '.join(_EXPERIMENT_KEYS)} (its base "
            f"holds only parameters), e.g. {_EXPERIMENT_EXAMPLES[missing[0]]}",
        )
    return _check_experiment(build(ExperimentConfig, raw.data, (), raw), raw)


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
        return to_yaml(_experiment(raw))
    hints = typing.get_type_hints(ExperimentConfig)
    sections = {
        f.name: to_dict(build(hints[f.name], raw.data.get(f.name), (f.name,), raw))
        for f in dataclasses.fields(ExperimentConfig) if f.name not in _EXPERIMENT_KEYS
    }
    return dump_yaml(sections)


def _read_chain(path: str | Path, overrides: typing.Iterable[str]) -> Raw:
    """A config file (or a shipped config's name), its chain of bases and ``overrides``, merged."""
    path = config_file(path)
    raw = Raw(str(resolved(path)))
    _load_chain(path, raw)
    _apply_overrides(raw, overrides)
    return raw


#: The converged labelling schedule (docs/GUIDE.md, "Reproducing the paper"): 256 sweeps from
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
    raw = Raw(str(resolved(path)))
    _load_chain(path, raw)
    for text in overrides:
        if not _parse_override(text)[0][0] == "words":
            raise ConfigError(
                f"{OVERRIDES} {shown(text)}: expected a words.* key; this command reads only words", parameter=OVERRIDES
            )
    _apply_overrides(raw, overrides)
    words = build(WordsConfig, raw.data.get("words"), ("words",), raw)
    _check_words(words, raw)
    return words


# --------------------------------------------------------------------------- validation


def _check_experiment(config: ExperimentConfig, raw: Raw) -> ExperimentConfig:
    """Rules that tie keys together; dataset paths become absolute so a saved config travels."""
    _check_words(config.words, raw)
    datasets, names = [], {}
    for i, entry in enumerate(config.datasets):
        source = raw.origin(("datasets", i))
        relative_to = None if source == OVERRIDES else Path(source).parent
        try:
            path = dataset_path(entry, relative_to)
        except ConfigError as exc:
            raise invalid(raw, ("datasets", i), str(exc)) from None
        datasets.append(entry if path.parent == DATASET_CONFIG_DIR else str(path))
        try:
            name = load_dataset_config(path).name
        except ConfigError:  # a map that does not load is named by the stage that loads it
            continue
        if name in names:
            raise invalid(
                raw, ("datasets", i), f"got {shown(entry)}, a second map named {name!r} (datasets[{names[name]}]); "
                "runs are filed by map name",
            )
        names[name] = i
    explore = config.explore
    for i, name in enumerate(explore.weight_functions):
        if name not in WALKER_NAMES:
            raise invalid(
                raw, ("explore", "weight_functions", i), f"got {shown(name)}, expected one of {', '.join(WALKER_NAMES)}"
            )
    if len(set(explore.weight_functions)) != len(explore.weight_functions):
        raise invalid(
            raw, ("explore", "weight_functions"), f"got {list(explore.weight_functions)}, expected each weight function once"
        )
    checkpoints = list(explore.checkpoints)
    if checkpoints != sorted(set(checkpoints)) or checkpoints[-1] > explore.path_length:
        raise invalid(
            raw, ("explore", "checkpoints"),
            f"got {checkpoints}, expected increasing path lengths no longer than explore.path_length "
            f"({explore.path_length})",
        )
    _check_coverage(explore, raw)
    _check_drive(config.drive, raw)
    return dataclasses.replace(config, datasets=tuple(datasets))


def _check_coverage(explore: ExploreConfig, raw: Raw) -> None:
    """The clamp needs its floor; a floor set without naming a reading is the old syntax."""
    if COVERAGE_READINGS[explore.coverage].reads_min_d2 and explore.min_d2 is None:
        raise invalid(raw, ("explore", "min_d2"), "got null, expected a number > 0: the clamp reading's floor on d^2")
    paper = str((CONFIG_DIR / SAVED_BASE).resolve())
    if explore.min_d2 is not None and raw.origin(("explore", "min_d2")) != paper and (
        raw.origin(("explore", "coverage")) == paper
    ):
        # min_d2 alone once meant the clamp; read now as literal it would be silently ignored
        raise invalid(
            raw, ("explore", "min_d2"),
            f"got {explore.min_d2} without explore.coverage; the reading of eq. 8 is now named there "
            f"(one of {', '.join(COVERAGE_READINGS)}): add explore.coverage: clamp to clamp d^2 at {explore.min_d2}",
        )


def _check_drive(drive: DriveConfig, raw: Raw) -> None:
    """Rules that tie ``drive`` keys together: the first broken one, where its key was set."""
    # the grid is named, not frame_width: a grid too fine is what a user mistypes, and a run would meet it
    # only at its first frame, after loading the model
    fits = f"at most frame_width ({drive.frame_width}): a frame is resized to {drive.frame_width} px wide"
    rules = [
        (drive.grid_cols <= drive.frame_width, "grid_cols", f"{fits}, a pixel at least to each column of cells"),
        (drive.grid_rows <= drive.frame_width, "grid_rows", f"{fits}, and stretched no taller than that to give each "
         "row of cells a pixel"),
        (drive.surge_min <= drive.surge_max, "surge_min", f"at most surge_max ({drive.surge_max})"),
        (drive.keepalive < drive.watchdog, "keepalive", f"shorter than the robot's watchdog ({drive.watchdog} s)"),
        (drive.ack_timeout < drive.watchdog, "ack_timeout", f"shorter than the robot's watchdog ({drive.watchdog} s): "
         "a frame is resent before the robot stops for want of one"),
    ]
    for ok, key, expected in rules:
        if not ok:
            raise invalid(raw, ("drive", key), f"got {getattr(drive, key)}, expected {expected}")
