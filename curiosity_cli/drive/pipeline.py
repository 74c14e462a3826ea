"""One camera frame to one velocity command: words, stream model, curiosity, controller."""

from __future__ import annotations

import time
from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.drive.controller import Command, steer
from curiosity_cli.drive.curiosity import CuriosityScores
from curiosity_cli.drive.frame_words import FrameWords
from curiosity_cli.drive.stream import StreamModel, newest_share
from curiosity_cli.drive.surprise import add_and_score


@dataclass(frozen=True)
class Decision:
    """What the pipeline made of one frame.

    Attributes
    ----------
    perplexity : (rows, cols) float64 ndarray
        The surprise of each image cell in this frame under ``drive.surprise``
        (:mod:`~curiosity_cli.drive.surprise`): a perplexity, or bits for ``bayesian``.
    scores : (rows, cols) float64 ndarray
        Decayed curiosity scores after this frame.
    target : (int, int)
        (row, col) of the highest score.
    command : Command
    words : int
        Words extracted from the frame.
    refined : int
        Word samples the frame itself got in its refinement, its share of the budget
        (:class:`~curiosity_cli.drive.stream.StreamModel`); 0 (a share that rounds to no
        samples): its perplexity reads the random topics its words were given.
    seconds : dict of str to float
        Time spent per stage: ``words``, ``model`` (add and refine, and the surprise), ``score``.
    surprises : dict of str to (rows, cols) float64 ndarray
        Each reading the pipeline was asked for (``drive.surprise``'s, and any ``readings`` beside it).
    """

    perplexity: np.ndarray
    scores: np.ndarray
    target: tuple[int, int]
    command: Command
    words: int
    refined: int
    seconds: dict
    surprises: dict


class CuriosityPipeline:
    """The driver's per-frame computation, with its state (model memory, scores).

    Parameters
    ----------
    config : ExperimentConfig
        Uses ``model``, ``words`` and ``drive``.
    seed : int
        Seeds the stream's topic models.
    readings : collection of str, optional
        Readings of the surprise to compute beside ``drive.surprise``'s, in :attr:`Decision.surprises`, to compare
        them on one run (they do not steer).
    """

    def __init__(self, config: ExperimentConfig, seed: int, readings: Collection[str] = ()):
        self.config = config
        self.readings = tuple(dict.fromkeys((config.drive.surprise, *readings)))
        drive, model = config.drive, config.model
        self.words = FrameWords(config.words, drive)
        self.grid = self.words.grid
        self.stream = StreamModel(
            model.topics,
            self.words.vocabulary_size,
            self.grid,
            memory=drive.memory_frames,
            spatial=model.spatial_neighbours,
            temporal=drive.temporal_neighbours,
            alpha=model.alpha,
            beta=model.beta,
            newest_share=newest_share(config),
            budget=drive.samples_per_frame,
            seed=seed,
            vocabulary_hashes=self.words.vocabulary_hashes,
        )
        self.curiosity = CuriosityScores(drive.gamma, self.grid)

    def process(self, frame: np.ndarray) -> Decision:
        """Decide on one frame.

        Parameters
        ----------
        frame : (H, W, 3) uint8 ndarray
            RGB, any size with at least one pixel per image cell.
        """
        start = time.perf_counter()
        cell_words = self.words(frame)
        extracted = time.perf_counter()
        surprises = {
            reading: values.reshape(self.grid)
            for reading, values in add_and_score(self.stream, cell_words, self.readings, self.config.model.alpha).items()
        }
        modelled = time.perf_counter()
        perplexity = surprises[self.config.drive.surprise]
        scores = self.curiosity.update(perplexity).copy()
        target = self.curiosity.target()
        command = steer(target, self.grid, self.config.drive)
        done = time.perf_counter()
        return Decision(
            perplexity=perplexity,
            scores=scores,
            target=target,
            command=command,
            words=sum(w.size for w in cell_words),
            refined=self.stream.refined,
            seconds={"words": extracted - start, "model": modelled - extracted, "score": done - modelled},
            surprises=surprises,
        )


def warm_up(config: ExperimentConfig) -> None:
    """Load (or compile) every numba kernel the pipeline uses, on a throwaway pipeline.

    Run before connecting to a robot: the first real frame then costs what every frame
    costs, and the robot is not kept waiting through a compilation.
    """
    rng = np.random.default_rng(0)
    width = config.drive.frame_width
    # square at the width frames are resized to: a pixel to each image cell whatever grid the config allows
    frame = rng.integers(0, 256, (width, width, 3), dtype=np.uint8)
    pipeline = CuriosityPipeline(config, seed=0)
    pipeline.process(frame)
    model = pipeline.stream.model
    model.remove_cells(model.observed_cells()[:1])  # what a bounded memory does from its M-th frame on
