"""A map loaded from its dataset YAML (:mod:`curiosity_cli.maps.datasets` finds it): its image,
human labels and legend, and the digest of its labels (:func:`load_map`). A generated map's
are drawn (:mod:`curiosity_cli.maps.generated`): its truth as labels, the truth in the
legend's colours as its image.

Loading checks everything a later stage would trip over, and says what is wrong in one
line naming the file.
"""

from __future__ import annotations

import hashlib
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid, map_grid
from curiosity_cli.maps.datasets import DatasetConfig, dataset_names, dataset_path, load_dataset_config
from curiosity_cli.errors import ConfigError, DatasetError
from curiosity_cli.files import display_path, note
from curiosity_cli.maps.images import Rendering
from curiosity_cli.yamlfile import read_yaml

_COLOUR = re.compile(r"^#[0-9a-fA-F]{6}$")


@dataclass(frozen=True)
class MapClass:
    """One class of a label map."""

    id: int
    name: str
    colour: tuple[int, int, int]
    description: str


@dataclass(frozen=True)
class MapData:
    """A loaded map.

    Attributes
    ----------
    config : DatasetConfig
    image : (H, W, 3) uint8 ndarray
        RGB.
    labels : (H, W) integer ndarray or None
        Class ids, each one of ``legend``'s.
    legend : tuple of MapClass
        Empty when the dataset has no labels.
    rendering : Rendering
        How the image file's bands and values became ``image``.
    """

    config: DatasetConfig
    image: np.ndarray
    labels: np.ndarray | None
    legend: tuple[MapClass, ...]
    rendering: Rendering

    @property
    def grid(self) -> SquareGrid:
        """The map's cells: its ``cell_width`` grid over the image."""
        return map_grid(self.image.shape[:2], self.config.cell_width)

    @property
    def n_classes(self) -> int:
        """The classes the human labels may hold: the legend's largest id + 1; 0 without labels."""
        return max(c.id for c in self.legend) + 1 if self.labels is not None else 0

    @property
    def labels_digest(self) -> str | None:
        """A digest of the human labels as evaluation reads them (class ids and their count); None without labels."""
        if self.labels is None:
            return None
        head = f"{self.labels.dtype.str}{self.labels.shape}{self.n_classes}{self.config.cell_width}".encode()
        return hashlib.sha256(head + np.ascontiguousarray(self.labels).tobytes()).hexdigest()[:16]


def load_legend(path: Path) -> tuple[MapClass, ...]:
    """Read a legend YAML: ``classes: [{id, name, colour: "#rrggbb", description}, …]``.

    Raises
    ------
    DatasetError
        A missing or malformed key, a duplicate id or name, a colour not in ``#rrggbb``.
    """
    try:
        data = read_yaml(path, "legend file")
    except ConfigError as exc:
        raise DatasetError(str(exc)) from None
    where = display_path(path)
    entries = data.get("classes")
    if not isinstance(entries, list) or not entries:
        raise DatasetError(f"{where}: classes: expected a non-empty list of classes")
    classes = []
    for i, entry in enumerate(entries):
        key = f"classes[{i}]"
        if not isinstance(entry, dict):
            raise DatasetError(f"{where}: {key}: got {entry!r}, expected a mapping with id, name, colour")
        unknown = set(entry) - {"id", "name", "colour", "description"}
        if unknown:
            raise DatasetError(
                f"{where}: {key}.{sorted(unknown)[0]}: unknown key; expected id, name, colour, description"
            )
        class_id, name, colour = entry.get("id"), entry.get("name"), entry.get("colour")
        if isinstance(class_id, bool) or not isinstance(class_id, int) or not 0 <= class_id <= 65535:
            raise DatasetError(f"{where}: {key}.id: got {class_id!r}, expected an integer 0..65535")
        if not isinstance(name, str) or not name:
            raise DatasetError(f"{where}: {key}.name: got {name!r}, expected a non-empty string")
        if not isinstance(colour, str) or not _COLOUR.match(colour):
            raise DatasetError(f"{where}: {key}.colour: got {colour!r}, expected \"#rrggbb\"")
        description = entry.get("description", "")
        if not isinstance(description, str):
            raise DatasetError(f"{where}: {key}.description: got {description!r}, expected a string")
        rgb = tuple(int(colour[j : j + 2], 16) for j in (1, 3, 5))
        classes.append(MapClass(class_id, name, rgb, description))
    for attr in ("id", "name"):
        values = [getattr(c, attr) for c in classes]
        duplicates = sorted({v for v in values if values.count(v) > 1}, key=str)
        if duplicates:
            raise DatasetError(f"{where}: classes: {attr} {duplicates[0]!r} appears more than once")
    return tuple(sorted(classes, key=lambda c: c.id))


def _to_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def load_map(name_or_path: str | Path, *, announce=_to_stderr) -> MapData:
    """Load a dataset by registered name or YAML path, and check it is usable.

    A fetched map (``fetch:`` in its YAML) is downloaded and made on first use, and made
    again when a file of it in the cache does not read.

    Parameters
    ----------
    name_or_path : str or Path
        ``aerial-mosaic`` or ``path/to/my-map.yaml``.
    announce : callable, optional
        Called with a line of text before a fetched map is downloaded or made; by
        default the line goes to stderr, so a first run says why it waits.

    Returns
    -------
    MapData

    Raises
    ------
    ConfigError
        The YAML itself does not validate.
    DatasetError
        Unreadable or empty image, a multi-band image without ``bands``, labels of another
        size or not single-channel, label ids missing from the legend, a cell wider than
        the image, a size other than declared, a fetch that fails.
    """
    yaml_path = dataset_path(name_or_path)
    config = load_dataset_config(yaml_path)
    where = display_path(yaml_path)
    if config.generate is not None:
        return _generated_map(config)
    if config.fetch is None:
        return _read_map(config, where)
    _fetch(config.fetch, where, announce)
    try:
        return _read_map(config, where)
    except DatasetError as exc:
        # the files are the cache's, made from the archive: a damaged one is made again, as a word store is
        note(f"{exc}; the cache made it for the fetched map {config.fetch}, which is made again")
        _fetch(config.fetch, where, announce, force=True)
        return _read_map(config, where)


def _fetch(name: str, where: str, announce, *, force: bool = False) -> None:
    """:func:`~curiosity_cli.maps.fetched.ensure_fetched`; its error names the dataset YAML ``where``, and the
    maps that need no network."""
    from curiosity_cli.maps.fetched import ensure_fetched

    try:
        ensure_fetched(name, announce=announce, force=force)
    except DatasetError as exc:
        local = [n for n in dataset_names() if load_dataset_config(dataset_path(n)).fetch is None]
        raise DatasetError(f"{where}: {exc}; the embedded and generated maps {', '.join(local)} need no network") from None


def _generated_map(config: DatasetConfig) -> MapData:
    """The map a ``generate:`` section draws: its truth as labels and image (:mod:`curiosity_cli.maps.generated`)."""
    from curiosity_cli.maps.generated import generate_map

    drawn = generate_map(config.generate, config.cell_width, config.word_stride)
    legend = tuple(
        MapClass(class_id, name, colour, description) for class_id, (name, colour, description) in enumerate(drawn.legend)
    )
    # the image is made here in 8-bit RGB: nothing to stretch
    rendering = Rendering(bands=(0, 1, 2), dtype="uint8", low=None, high=None, percentiles=None)
    return MapData(config=config, image=drawn.image, labels=drawn.labels, legend=legend, rendering=rendering)


def _read_map(config: DatasetConfig, where: str) -> MapData:
    """The map ``config`` describes, read from its files and checked (:func:`load_map`); ``where`` names the YAML."""
    from curiosity_cli.maps.images import read_raster, render_rgb

    image, rendering = render_rgb(read_raster(config.image, f"{where}: image"), config.bands, config.stretch, where)
    rows, cols = image.shape[:2]
    if config.size is not None and tuple(config.size) != (rows, cols):
        raise DatasetError(
            f"{where}: size: declared {list(config.size)} [rows, cols], "
            f"but {display_path(config.image)} is [{rows}, {cols}]"
        )
    if config.cell_width > min(rows, cols):
        raise DatasetError(
            f"{where}: cell_width: got {config.cell_width}, expected at most the image's "
            f"smaller side ({min(rows, cols)} px)"
        )

    labels, legend = None, ()
    if config.labels is not None:
        legend = load_legend(config.legend)
        pixels = read_raster(config.labels, f"{where}: labels").pixels
        if pixels.shape[2] != 1 or pixels.dtype not in (np.uint8, np.uint16):
            raise DatasetError(
                f"{where}: labels: {display_path(config.labels)} is {pixels.dtype} with "
                f"{pixels.shape[2]} channels; expected a single-channel 8- or 16-bit image of class ids"
            )
        labels = pixels[:, :, 0]
        if labels.shape != (rows, cols):
            raise DatasetError(
                f"{where}: labels: {display_path(config.labels)} is [{labels.shape[0]}, {labels.shape[1]}] "
                f"[rows, cols]; expected the image's size [{rows}, {cols}]"
            )
        missing = np.setdiff1d(np.unique(labels), [c.id for c in legend])
        if missing.size:
            raise DatasetError(
                f"{where}: labels: class ids {missing.tolist()} in {display_path(config.labels)} "
                f"are missing from the legend {display_path(config.legend)}"
            )
    return MapData(config=config, image=image, labels=labels, legend=legend, rendering=rendering)


__all__ = ["MapClass", "MapData", "dataset_names", "load_legend", "load_map"]
