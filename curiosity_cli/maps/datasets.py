"""The maps a config may name: dataset YAMLs, shipped (``configs/datasets/``, by name) or a user's own (by path).

A dataset YAML (schema: :class:`DatasetConfig`) gives a map's image, its human labels and
their legend, and the grid it is cut into; a fetched map's names ``fetch:`` instead
(:mod:`curiosity_cli.maps.fetched`), and a generated map's ``generate:``, the generative
model its words are drawn from (:mod:`curiosity_cli.maps.generative_spec`), instead of files.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from curiosity_cli.errors import ConfigError
from curiosity_cli.files import display_path, resolved
from curiosity_cli.maps.generative_spec import GenerativeSpec
from curiosity_cli.paths import SHIPPED_CONFIGS
from curiosity_cli.schema import NAME_PATTERN, Raw, build, spec
from curiosity_cli.yamlfile import read_yaml, shown

#: The shipped dataset YAMLs, which a config names without a path.
DATASET_CONFIG_DIR = SHIPPED_CONFIGS / "datasets"


@dataclass(frozen=True)
class DatasetConfig:
    """A map: an image, optional ground-truth labels with their legend, and its grid.

    ``image`` is required unless ``fetch`` names a map made on first use from a pinned
    source archive (:mod:`curiosity_cli.maps.fetched`); then image, labels and legend are the
    files it makes. A generated map gives ``generate`` and none of the image's keys
    (:data:`IMAGE_KEYS`): its words are drawn one every ``word_stride`` px, its truth is the
    generating topics. Every key with a default may be left out of the YAML.
    """

    name: str = spec(file_name=True)
    cell_width: int = spec(min=1)
    word_stride: int = spec(min=1)
    image: Path | None = spec(must_exist=True, default=None)
    labels: Path | None = spec(must_exist=True, default=None)
    legend: Path | None = spec(must_exist=True, default=None)
    fetch: str | None = spec(default=None)
    bands: tuple[int, ...] | None = spec(min=0, default=None)
    stretch: tuple[float, ...] = spec(min=0, max=100, default=(2.0, 98.0))
    size: tuple[int, ...] | None = spec(min=1, default=None)
    description: str = spec(default="")
    source: str = spec(default="")
    licence: str = spec(default="")
    stands_in_for: str | None = spec(default=None)
    generate: GenerativeSpec | None = spec(default=None)


#: The keys of a map made from an image, which a generated map leaves out.
IMAGE_KEYS = ("image", "labels", "legend", "fetch", "bands", "stretch", "size")


def load_dataset_config(path: str | Path) -> DatasetConfig:
    """Load a dataset YAML; relative paths in it are relative to the YAML file.

    A fetched map's ``image``, ``labels`` and ``legend`` become the files it is made into
    (:func:`curiosity_cli.maps.fetched.fetched_files`); they need not exist yet.

    Raises
    ------
    ConfigError
        The file, key, value and expectation, in one line.
    """
    from curiosity_cli.maps.fetched import FETCHED_MAPS, fetched_files
    from curiosity_cli.paper import PAPER_MAPS

    path = Path(path)
    where = display_path(path)
    raw = Raw(str(resolved(path)))
    raw.merge(read_yaml(path, "dataset file"), str(resolved(path)))
    # before the keys are built: an image a generated map names is refused as named, not as a file not there
    given = [key for key in IMAGE_KEYS if key in raw.data] if isinstance(raw.data, dict) and "generate" in raw.data else []
    if given:
        raise ConfigError(f"{where}: {given[0]}: a generated map draws its words and truth; leave {given[0]} out")
    config = build(DatasetConfig, raw.data, (), raw)
    if config.generate is not None:
        from curiosity_cli.maps.generated import generation_problem  # numpy: not for the CLI's help

        problem = generation_problem(config.generate, config.cell_width, config.word_stride)
        if problem is not None:
            raise ConfigError(f"{where}: {problem[0]}: {problem[1]}")
    elif config.fetch is not None:
        if config.fetch not in FETCHED_MAPS:
            raise ConfigError(
                f"{where}: fetch: got {shown(config.fetch)}, expected one of {', '.join(sorted(FETCHED_MAPS))}"
            )
        given = [key for key in ("image", "labels", "legend") if key in raw.data]
        if given:
            raise ConfigError(f"{where}: {given[0]}: a fetched map's files are made on first use; leave {given[0]} out")
        config = dataclasses.replace(config, **fetched_files(config.fetch))
    elif config.image is None:
        raise ConfigError(
            f"{where}: image: missing key; expected the path of the map's image (or `generate:`, a generated map's model)"
        )
    problem = stride_problem(config.word_stride, config.cell_width)
    if problem is not None:
        raise ConfigError(f"{where}: word_stride: {problem}")
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


def stride_problem(stride: int, cell_width: int) -> str | None:
    """What is wrong with texton words every ``stride`` px in cells ``cell_width`` px wide, or None.

    Said of a dataset's ``word_stride`` and of the stride and cell width ``extract`` is
    given instead (:func:`~curiosity_cli.words.extract.extract_words`).
    """
    if stride > cell_width:
        return (
            f"got a stride of {stride} px with cells of {cell_width} px, expected a stride of at most the cell width: "
            "a wider stride leaves cells without texton words"
        )
    return None


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
    if NAME_PATTERN.match(text) and not text.endswith((".yaml", ".yml")) and registered.is_file():
        return registered
    candidate = (relative_to or Path.cwd()) / text
    if candidate.is_file():
        return resolved(candidate)
    raise ConfigError(
        f"no dataset {shown(text)}: expected one of {', '.join(dataset_names())} "
        "or a path to a dataset YAML"
    )
