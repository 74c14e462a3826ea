"""Watch one run: its path growing over the map, beside the path labelling Z_p at each checkpoint.

:func:`animate_run` writes one frame per step: the map with the path so far (blue at the
start to red at the end, as fig. 2), and beside it Z_p as labelled at the newest
checkpoint reached (blank before the first), with the step counter. Z_p is computed again
for the run with the label stage's own chains and seeds, so each panel is the labelling
``label`` made of that checkpoint. A GIF is written through Pillow (which matplotlib
needs anyway); an ``.mp4`` needs matplotlib's FFmpeg writer.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import atomic_path, display_path

#: Frames per second of an animation: a 320-step run lasts 32 s.
FPS = 10


class AnimationError(CuriosityError):
    """A run that cannot be animated, or an animation that cannot be written."""


def checkpoint_labels(experiment, run, store, shape: tuple[int, int]) -> dict[int, np.ndarray]:
    """Z_p at each of a run's checkpoints, (H, W) topic ids by path length, as ``label`` computes it."""
    from curiosity_cli.label.sampling import label_paths, pixel_labels
    from curiosity_cli.label.sampling import path_seed

    config = experiment.config
    lengths = run.meta["checkpoints"]
    labelled = label_paths(
        store, config.model, [[run.phi(n) for n in lengths]], [path_seed(run.meta["seed"])],
        sweeps=config.label.sweeps, warm_sweeps=config.label.warm_sweeps,
    )
    return {lengths[j]: pixel_labels(store, labels[:, 0], shape) for j, _, labels in labelled}


def animate_run(
    experiment_dir: Path, dataset: str, weight_function: str, restart: int, *, out: Path | None = None,
    cache_dir: Path | None = None,
) -> Path:
    """Write the animation of one run and return its path (default ``figures/animation-<map>-<walker>-<NNN>.gif``).

    Raises
    ------
    AnimationError
        A map, walker or restart not in the experiment's grid, an output that is neither
        ``.gif`` nor ``.mp4``, or an ``.mp4`` without an FFmpeg writer.
    RunError
        The run is missing, incomplete or altered, naming the file.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import animation
    from matplotlib.figure import Figure

    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.explore.runs import read_run
    from curiosity_cli.paths import DEFAULT_CACHE
    from curiosity_cli.plots.palette import match_topics, paint_topics
    from curiosity_cli.plots.preview import shrink_image, shrink_labels
    from curiosity_cli.words.extract import extract_words

    experiment = Experiment.open(experiment_dir)
    layout = experiment.folder
    if dataset not in experiment.maps:
        raise AnimationError(
            f"animate: map {dataset!r} is not in {display_path(layout.config)}: {', '.join(experiment.maps)}",
            parameter="animate",
        )
    grid = experiment.config.explore
    if weight_function not in grid.weight_functions:
        raise AnimationError(
            f"animate: walker {weight_function!r} is not in {display_path(layout.config)}: {', '.join(grid.weight_functions)}",
            parameter="animate",
        )
    if not 0 <= restart < grid.restarts:
        raise AnimationError(
            f"animate: restart {restart} is not in the grid of {display_path(layout.config)} (restarts 0 to {grid.restarts - 1})",
            parameter="animate",
        )
    out = Path(out) if out is not None else layout.figures / f"animation-{dataset}-{weight_function}-{restart:03d}.gif"
    if out.suffix not in (".gif", ".mp4"):
        raise AnimationError(f"out: got {display_path(out)}, expected a .gif or .mp4 file", parameter="out")
    if out.suffix == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise AnimationError(f"out: {display_path(out)} needs FFmpeg, which matplotlib cannot find; write a .gif", parameter="out")
    run = read_run(layout.run(dataset, weight_function, restart))
    map_data = load_map(experiment.maps[dataset].entry)
    store = extract_words(map_data, experiment.config.words, cache_dir=cache_dir or DEFAULT_CACHE).store
    shape = map_data.image.shape[:2]
    z_p = {n: shrink_labels(labels) for n, labels in checkpoint_labels(experiment, run, store, shape).items()}
    last = z_p[max(z_p)]
    # each checkpoint's topics take the colours of the last one's they share the most pixels with
    painted = {n: paint_topics(labels, match_topics(labels, last)[0]) for n, labels in z_p.items()}
    image = shrink_image(map_data.image)
    scale = image.shape[0] / shape[0]
    grid = map_data.grid
    rows, cols = (np.asarray(v, np.float64) for v in grid.row_col(run.path))
    centres_y, centres_x = (rows + 0.5) * grid.cell_width * scale, (cols + 0.5) * grid.cell_width * scale

    fig = Figure(figsize=(9, 4.6), layout="constrained")
    left, right = fig.subplots(1, 2)
    left.imshow(image)
    right.imshow(np.full_like(image, 255))
    for ax in (left, right):
        ax.set_xticks([])
        ax.set_yticks([])
    labels_image = right.images[0]
    trail = left.scatter([], [], s=10, c=[], cmap="coolwarm", vmin=0, vmax=len(run.path) - 1)
    left.set_title(f"{dataset}: {weight_function}, restart {restart}", fontsize=10)
    counter = fig.suptitle("", fontsize=11)
    lengths = sorted(z_p)

    def draw(step: int):
        trail.set_offsets(np.column_stack([centres_x[: step + 1], centres_y[: step + 1]]))
        trail.set_array(np.arange(step + 1))
        reached = [n for n in lengths if n <= step + 1]
        if reached:
            labels_image.set_data(painted[reached[-1]])
            right.set_title(f"$Z_p$ at the checkpoint of {reached[-1]} steps", fontsize=10)
        else:
            right.set_title("$Z_p$: no checkpoint yet", fontsize=10)
        counter.set_text(f"step {step + 1} of {len(run.path)}")
        return trail, labels_image, counter

    movie = animation.FuncAnimation(fig, draw, frames=len(run.path), blit=False)
    writer = animation.PillowWriter(fps=FPS) if out.suffix == ".gif" else animation.FFMpegWriter(fps=FPS)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        movie.save(tmp, writer=writer, dpi=90)
    return out
