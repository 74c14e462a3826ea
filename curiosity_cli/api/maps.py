"""The maps' and vocabularies' commands as functions: ``datasets list``, ``datasets show`` and ``vocab build``."""

from __future__ import annotations

import typing
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NamedTuple

from curiosity_cli.config import MAX_VOCABULARY  # the bound `vocab build` takes and its options show
from curiosity_cli.paths import DEFAULT_RESULTS

if typing.TYPE_CHECKING:
    from curiosity_cli.maps.map_data import MapData
    from curiosity_cli.words.vocab import Vocabulary

#: Where ``datasets show`` writes its preview by default.
PREVIEWS = DEFAULT_RESULTS / "datasets"


class DatasetRow(NamedTuple):
    """A registered map as :func:`list_datasets` lists it; None where only its pixels would say, and they are not here."""

    name: str
    size: tuple[int, int] | None  # (rows, cols) px
    cell_width: int
    grid: tuple[int, int] | None  # (rows, cols) of cells
    classes: int | None
    pixels: str  # embedded, cached, fetched on first use, or generated
    source: str
    licence: str


def list_datasets() -> list[DatasetRow]:
    """``curiosity datasets list``: the maps registered in ``configs/datasets/``, sorted by name.

    A fetched map that is not cached yet is listed from its YAML; nothing is downloaded.
    """
    from curiosity_cli.maps.cell_grid import map_grid
    from curiosity_cli.maps.datasets import dataset_names, dataset_path, load_dataset_config
    from curiosity_cli.maps.fetched import is_fetched
    from curiosity_cli.maps.map_data import load_map

    rows = []
    for name in dataset_names():
        config = load_dataset_config(dataset_path(name))
        if config.generate is not None:
            pixels = "generated"
        else:
            pixels = "embedded" if config.fetch is None else ("cached" if is_fetched(config.fetch) else "fetched on first use")
        if config.fetch is None or pixels == "cached":
            map_data = load_map(name)
            size, classes = map_data.image.shape[:2], len(map_data.legend)
        else:
            size, classes = config.size, None
        grid = map_grid(size, config.cell_width) if size is not None else None
        rows.append(DatasetRow(
            name, None if size is None else tuple(size), config.cell_width,
            None if grid is None else (grid.rows, grid.cols), classes, pixels, config.source, config.licence,
        ))
    return rows


class Preview(NamedTuple):
    """What :func:`show_datasets` read and wrote."""

    maps: list[MapData]
    notes: list[dict]  # per map, how a fetched map was made (crop, image); empty for an embedded one
    path: Path  # the preview written


def show_datasets(datasets: Sequence[str], *, out: Path | None = None) -> Preview:
    """``curiosity datasets show``: maps with their legends, and a preview of each image beside its labels.

    Parameters
    ----------
    datasets : sequence of str
        Registered names or paths to dataset YAMLs.
    out : Path, optional
        The preview PNG or PDF; default ``results/datasets/NAME.png``
        (``overview.png`` for several maps).

    Raises
    ------
    ParameterError
        No map, or ``out`` not a path.
    """
    from curiosity_cli.errors import ParameterError
    from curiosity_cli.maps.fetched import made_notes
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.plots.preview import write_preview

    from curiosity_cli.api.arguments import optional_path, strings

    datasets, out = strings(datasets, "datasets", "aerial-mosaic"), optional_path(out, "out")
    if not datasets:
        raise ParameterError(
            "datasets: got [], expected at least one map: a registered name or a path to a dataset YAML",
            parameter="datasets",
        )
    maps = [load_map(d) for d in datasets]
    notes = [made_notes(m.config.fetch) if m.config.fetch is not None else {} for m in maps]
    if out is None:
        out = PREVIEWS / f"{maps[0].config.name if len(maps) == 1 else 'overview'}.png"
    write_preview(maps, out)
    return Preview(maps, notes, out)


def build_vocabularies(
    out: Path = Path("data/vocab"), *, orb_words: int = 5000, texton_words: int = 1000, seed: int = 0,
    log: Callable[[str], None] = lambda line: None,
) -> list[tuple[Path, Vocabulary]]:
    """``curiosity vocab build``: texton words (k-means of MR8 responses), then ORB words (k-majority of
    descriptors), of scikit-image's photographs; each file written or kept and its vocabulary, in that order.

    A vocabulary already in ``out`` that was built by the same recipe (size, seed,
    photographs, versions: :func:`~curiosity_cli.words.vocab.built_vocabulary`) is kept, so
    a build stopped after the texton words goes on with the ORB words when run again.

    Parameters
    ----------
    out : Path
        The folder ``texton-N.npz`` and ``orb-N.npz`` go to.
    orb_words, texton_words : int
        The vocabularies' sizes (the paper's 5000 and 1000), 2 to
        :data:`~curiosity_cli.config.MAX_VOCABULARY`.
    log : callable
        Progress lines, and a line for each file written or kept.
    """
    from curiosity_cli.errors import ParameterError
    from curiosity_cli.files import display_path
    from curiosity_cli.words.vocab import (
        build_orb_vocabulary, build_texton_vocabulary, built_vocabulary, save_vocabulary, vocabulary_path,
    )

    from curiosity_cli.api.arguments import callback, folder_argument
    from curiosity_cli.checks import check_int

    out, seed, log = folder_argument(out, "out"), check_int("seed", seed, 0), callback(log, "log")
    plan = (
        ("texton_words", "texton", build_texton_vocabulary, texton_words),
        ("orb_words", "orb", build_orb_vocabulary, orb_words),
    )
    for name, _, _, size in plan:
        if isinstance(size, bool) or not isinstance(size, int) or not 2 <= size <= MAX_VOCABULARY:
            raise ParameterError(f"{name}: got {size!r}, expected 2 to {MAX_VOCABULARY}", parameter=name)
    written = []
    for _, kind, builder, size in plan:
        path, vocabulary = vocabulary_path(out, kind, size), built_vocabulary(out, kind, size, seed)
        if vocabulary is not None:
            log(f"kept {display_path(path)}, built by the same recipe (sha256 {vocabulary.sha256[:16]}…); "
                "delete it to build it again")
        else:
            vocabulary = builder(size, seed=seed, log=log)
            save_vocabulary(vocabulary, out)
            log(f"wrote {display_path(path)} (sha256 {vocabulary.sha256[:16]}…)")
        written.append((path, vocabulary))
    return written
