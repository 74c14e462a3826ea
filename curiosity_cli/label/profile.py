"""Where the label stage's seconds go: ``label_profile.json`` of an experiment folder.

The stage's wall time, cut into consecutive segments of this process (they sum to it):
``setup`` (reading the runs, planning the blocks, taking shared items), ``batch references
before the blocks`` (when they do not run beside them), ``waiting for blocks`` (blocked
until a worker's next block arrives), ``handling results`` (writing batch references,
handing label files to the writer threads), ``writing`` (waiting for the writer threads
after the last block) and ``closing``. And per block, what its worker did: the ``runs``,
``chains`` (a checked run has two), the map's ``words``, ``chain_sweeps`` (the sweeps of
all its chains over every checkpoint) and so its ``work`` (word samples: chain sweeps x
words), when it ``began`` (seconds after the stage started, by the wall clock), and its seconds
``reading`` (its map's arrays, made once per worker),
``kernel`` (the label chains' sweeps, which ``chain_sweeps`` and ``work`` count), ``heldout``
(the sweeps of the chains over each map's observed words and the held-out words' scores,
:mod:`~curiosity_cli.label.heldout`) and ``tables`` (contingency tables and example maps,
and any wait for a batch reference computed beside). And per batch reference computed
beside the blocks, its ``seconds`` of sweeps and when it was ``written``.
``scripts/bench_label_profile.py`` reads it: how much of the stage the kernel's rate
times the work explains, and where the rest goes.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

from curiosity_cli.files import atomic_path

_END = object()


class LabelProfile:
    """The profile of one call of the label stage, marked as it goes (module docstring).

    Parameters
    ----------
    started : float
        ``time.perf_counter()`` when the stage started.
    """

    def __init__(self, started: float):
        self.started = self.last = started
        self.wall_clock = time.time() - (time.perf_counter() - started)  # time.time() when the stage started
        self.segments: dict[str, float] = {}
        self.blocks: list[dict] = []
        self.batches: dict[str, dict] = {}
        self.jobs: int | None = None

    def mark(self, segment: str) -> None:
        """The time since the last mark was spent on ``segment`` (added to what it had)."""
        now = time.perf_counter()
        self.segments[segment] = self.segments.get(segment, 0.0) + now - self.last
        self.last = now

    def waiting(self, results: Iterable) -> Iterator:
        """``results``, with the time blocked on each next one marked as waiting and the time between as handling."""
        iterator = iter(results)
        while True:
            self.mark("handling results")
            item = next(iterator, _END)
            self.mark("waiting for blocks")
            if item is _END:
                return
            yield item

    def block(self, chains: int, words: int, chain_sweeps: int, runs: int, dataset: str, seconds: dict) -> None:
        """A block's work and its worker's seconds (``began``: its ``time.time()``; ``reading``, ``kernel``, ``heldout``,
        ``tables``)."""
        seconds = {**seconds, "began": seconds["began"] - self.wall_clock}
        self.blocks.append({
            "dataset": dataset, "runs": runs, "chains": chains, "words": words, "chain_sweeps": chain_sweeps,
            "work": chain_sweeps * words, **{k: round(v, 4) for k, v in seconds.items()},
        })

    def batch(self, dataset: str, seconds: float) -> None:
        """A batch reference computed beside the blocks, written now after ``seconds`` of sweeps."""
        self.batches[dataset] = {"seconds": round(seconds, 4), "written": round(time.perf_counter() - self.started, 4)}

    def write(self, path: Path) -> None:
        """Write the profile as JSON, atomically: ``wall`` (the segments' sum), ``jobs``, ``segments``, ``blocks``, ``batches``."""
        record = {
            "wall": round(self.last - self.started, 4), "jobs": self.jobs,
            "segments": {k: round(v, 4) for k, v in self.segments.items()}, "blocks": self.blocks,
            "batches": self.batches,
        }
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(record, indent=1) + "\n")
