"""Drawing a generated map: section 3's generative model on a grid, with its truth (the generating topics).

Every cell takes one topic, its class: the background topics cover the grid's Voronoi
regions (:func:`voronoi_regions`), then the rare topics' square patches are laid over
them (:func:`layout`). A topic is ``φ_k ~ Dirichlet(beta)`` over its support
(:func:`draw_topics`); each cell's words are drawn from its class's ``φ``,
independently (θ of a cell is its class: the limit of the model's neighbourhood prior
inside a region of one topic). Words sit one every ``word_stride`` px, in drawn order
along the cell's rows, so their places are as random as the draws.

Numpy only; one seed feeds three streams (layout, topics, words), so maps that differ only
in ``overlap`` or ``beta`` have the same regions and patches.
"""

from __future__ import annotations

import colorsys
from dataclasses import dataclass

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.maps.generative_spec import GenerativeSpec

# the streams spawned from the spec's seed
_LAYOUT, _TOPICS, _WORDS = range(3)


@dataclass(frozen=True)
class GeneratedMap:
    """A drawn map and its truth.

    Attributes
    ----------
    classes : (rows * cols,) int64 ndarray
        The topic of each cell, row-major: background ``0 .. B - 1``, rare ``B .. B + R - 1``.
    phi : (B + R, V) float64 ndarray
        Each topic's word distribution, zero outside its support.
    words : (N,) int64 ndarray
        Word ids, cell by cell in cell order, ``(cell_width / word_stride)^2`` per cell.
    pixel_rows, pixel_cols : (N,) int64 ndarrays
        Each word's pixel.
    labels : (H, W) uint8 ndarray
        The class of every pixel: its cell's.
    legend : tuple of (str, (int, int, int), str)
        Per class id: its name, RGB colour and description.
    """

    classes: np.ndarray
    phi: np.ndarray
    words: np.ndarray
    pixel_rows: np.ndarray
    pixel_cols: np.ndarray
    labels: np.ndarray
    legend: tuple[tuple[str, tuple[int, int, int], str], ...]

    @property
    def image(self) -> np.ndarray:
        """(H, W, 3) uint8: the truth in its legend's colours, what figures draw paths and labels over."""
        colours = np.array([colour for _, colour, _ in self.legend], np.uint8)
        return colours[self.labels]


def _stream(generate: GenerativeSpec, stage: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(generate.seed).spawn(3)[stage])


def voronoi_regions(rows: int, cols: int, n_regions: int, rng: np.random.Generator) -> np.ndarray:
    """Cut a ``rows x cols`` grid into the Voronoi cells of ``n_regions`` random seed cells.

    Every cell joins the region of its nearest seed (Euclidean distance between cell
    centres; ties go to the lower region id). Each region is contiguous (a Voronoi cell
    is convex, and it contains its own seed), and none is empty.

    Returns
    -------
    (rows * cols,) int32 ndarray
        Region id of each cell, row-major.
    """
    grid = SquareGrid(rows, cols)
    seeds = rng.choice(grid.n_cells, size=n_regions, replace=False)
    return np.argmin(grid.squared_distances(np.arange(grid.n_cells), seeds), axis=1).astype(np.int32)


def layout(generate: GenerativeSpec) -> tuple[np.ndarray, np.ndarray | None]:
    """The background's regions (:func:`voronoi_regions`), then the rare topics' patches, from the layout's stream.

    Patch corners are tried in a random order of all of them and a patch is kept when
    its nearest edges lie at least ``patch_gap`` cells from every patch kept before,
    until each rare topic has its patches; patch ``i`` belongs to rare topic ``i % R``.

    Returns
    -------
    regions : (rows * cols,) int32 ndarray
        The background topic of each cell, row-major.
    corners : (R * patches_per_topic, 2) int64 ndarray or None
        (row, col) of each patch's top-left cell; None when the patches do not fit.
    """
    g = generate
    rng = _stream(g, _LAYOUT)
    regions = voronoi_regions(g.rows, g.cols, g.background_topics, rng)
    wanted, side = g.rare_topics * g.patches_per_topic, g.patch_cells
    if side > min(g.rows, g.cols):
        return regions, None
    rows, cols = np.divmod(rng.permutation((g.rows - side + 1) * (g.cols - side + 1)), g.cols - side + 1)
    kept = np.empty((0, 2), np.int64)
    for row, col in zip(rows, cols):
        # cells between the nearest edges of two square patches of one side, along rows or columns
        if np.all(np.maximum(np.abs(kept[:, 0] - row), np.abs(kept[:, 1] - col)) - side >= g.patch_gap):
            kept = np.vstack([kept, [[row, col]]])
            if len(kept) == wanted:
                return regions, kept
    return regions, None


def cell_classes(generate: GenerativeSpec) -> np.ndarray:
    """(rows * cols,) int64: each cell's topic, the background's regions with the rare topics' patches over them.

    Raises
    ------
    ValueError
        The patches do not fit (:func:`~curiosity_cli.maps.generative_spec.generation_problem` says so first).
    """
    g = generate
    regions, corners = layout(g)
    if corners is None:
        raise ValueError("the patches do not fit the grid")
    classes = regions.astype(np.int64).reshape(g.rows, g.cols)
    for index, (row, col) in enumerate(corners):
        classes[row : row + g.patch_cells, col : col + g.patch_cells] = g.background_topics + index % g.rare_topics
    return classes.ravel()


def background_left_out(generate: GenerativeSpec) -> int | None:
    """A background topic the patches cover entirely (the lowest), or None."""
    present = np.bincount(cell_classes(generate), minlength=generate.background_topics)[: generate.background_topics]
    empty = np.flatnonzero(present == 0)
    return int(empty[0]) if empty.size else None


def generation_problem(generate: GenerativeSpec, cell_width: int, word_stride: int) -> tuple[str, str] | None:
    """The key at fault and what is wrong with it, or None when the map can be drawn.

    The layout is drawn to check it (a few array operations on the grid's cells).
    """
    g = generate
    if cell_width % word_stride:
        return "word_stride", (
            f"got {word_stride} with cells of {cell_width} px, expected a divisor of the cell width: a generated map "
            "draws (cell_width / word_stride)^2 words per cell, one every word_stride px"
        )
    if g.words_needed > g.vocabulary:
        return "generate.vocabulary", (
            f"got {g.vocabulary}, expected at least {g.words_needed}: {g.background_topics} background topics x "
            f"{g.support} words and {g.rare_topics} rare topics x {g.own_words} words of their own "
            f"({g.shared_words} shared with the background at overlap {g.overlap:g})"
        )
    if g.background_topics > g.rows * g.cols:
        return "generate.background_topics", f"got {g.background_topics}, expected at most the grid's {g.rows * g.cols} cells"
    if layout(g)[1] is None:
        return "generate.patches_per_topic", (
            f"{g.rare_topics} rare topics x {g.patches_per_topic} patches of {g.patch_cells} x {g.patch_cells} cells, "
            f"{g.patch_gap} cells apart, do not fit in {g.rows} x {g.cols} cells; expected fewer or smaller patches, "
            "or a smaller patch_gap"
        )
    left_out = background_left_out(g)
    if left_out is not None:
        return "generate.background_topics", (
            f"background topic {left_out + 1} of {g.background_topics} has no cell outside the patches; expected fewer "
            "background topics, or fewer or smaller patches"
        )
    return None


def draw_topics(generate: GenerativeSpec) -> tuple[list[np.ndarray], np.ndarray]:
    """Each topic's support and ``φ``, background topics first, from the topics' stream.

    Background topic ``b`` has the words ``b S .. (b + 1) S - 1`` (S = ``support``); rare
    topic ``r`` has ``shared_words`` of the background's ``B S`` words, drawn without
    replacement, and ``own_words`` of its own after them. Each ``φ_k`` is
    ``Dirichlet(beta)`` over its support and 0 elsewhere.

    Returns
    -------
    supports : list of (support,) int64 ndarrays
        Sorted word ids, one per topic.
    phi : (B + R, V) float64 ndarray
    """
    g = generate
    rng = _stream(g, _TOPICS)
    supports = [np.arange(b * g.support, (b + 1) * g.support) for b in range(g.background_topics)]
    pool = g.background_topics * g.support
    for r in range(g.rare_topics):
        shared = rng.choice(pool, size=g.shared_words, replace=False)
        own = np.arange(pool + r * g.own_words, pool + (r + 1) * g.own_words)
        supports.append(np.sort(np.concatenate([shared, own])))
    phi = np.zeros((len(supports), g.vocabulary))
    for k, support in enumerate(supports):
        phi[k, support] = rng.dirichlet(np.full(support.size, g.beta))
    return supports, phi


def _legend(generate: GenerativeSpec) -> tuple[tuple[str, tuple[int, int, int], str], ...]:
    """Background topics in greens of rising value, rare topics in saturated hues around the wheel."""
    g = generate

    def rgb(h: float, s: float, v: float) -> tuple[int, int, int]:
        return tuple(int(round(255 * x)) for x in colorsys.hsv_to_rgb(h, s, v))

    background = [
        (f"background-{b + 1}", rgb(0.3, 0.55, 0.3 + 0.5 * b / max(g.background_topics - 1, 1)),
         f"background topic {b + 1}: a Voronoi region, {g.support} words")
        for b in range(g.background_topics)
    ]
    rare = [
        (f"rare-{r + 1}", rgb(r / g.rare_topics, 0.85, 0.95),
         f"rare topic {r + 1}: {g.patches_per_topic} patches of {g.patch_cells} x {g.patch_cells} cells, "
         f"{g.shared_words} of its {g.support} words shared with the background")
        for r in range(g.rare_topics)
    ]
    return tuple(background + rare)


def generate_map(generate: GenerativeSpec, cell_width: int, word_stride: int) -> GeneratedMap:
    """Draw a generated map (module docstring).

    Parameters
    ----------
    generate : GenerativeSpec
        Checked by :func:`~curiosity_cli.maps.generative_spec.generation_problem`.
    cell_width : int
        Cell side in pixels.
    word_stride : int
        Pixels between words, a divisor of ``cell_width``.

    Returns
    -------
    GeneratedMap
        The same for the same arguments.
    """
    g = generate
    classes = cell_classes(g)
    _, phi = draw_topics(g)
    per_side = cell_width // word_stride
    per_cell = per_side * per_side
    n_cells = g.rows * g.cols
    words = np.empty(n_cells * per_cell, np.int64)
    rng = _stream(g, _WORDS)
    for k in range(phi.shape[0]):
        cells = np.flatnonzero(classes == k)
        at = (cells[:, None] * per_cell + np.arange(per_cell)).ravel()
        words[at] = rng.choice(g.vocabulary, size=at.size, p=phi[k])
    slot = np.tile(np.arange(per_cell), n_cells)
    cell = np.repeat(np.arange(n_cells), per_cell)
    pixel_rows = (cell // g.cols) * cell_width + (slot // per_side) * word_stride
    pixel_cols = (cell % g.cols) * cell_width + (slot % per_side) * word_stride
    labels = np.repeat(np.repeat(classes.reshape(g.rows, g.cols), cell_width, axis=0), cell_width, axis=1)
    return GeneratedMap(
        classes=classes, phi=phi, words=words, pixel_rows=pixel_rows, pixel_cols=pixel_cols,
        labels=labels.astype(np.uint8), legend=_legend(g),
    )
