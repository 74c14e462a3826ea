"""A long replay: the stream model learns for the whole mission and never starts again."""

from __future__ import annotations

import numpy as np
import pytest
from test_bags import frame_records, replay, write_bag

from curiosity_cli.maps.map_data import load_map

FRAMES = 400


def near_identical_frames(n: int) -> list[np.ndarray]:
    """(120, 160, 3) RGB views of one place of the aerial mosaic, each with its own sensor noise."""
    view = load_map("aerial-mosaic").image[200:320, 300:460].astype(np.int16)
    rng = np.random.default_rng(0)
    return [np.clip(view + rng.integers(-3, 4, view.shape), 0, 255).astype(np.uint8) for _ in range(n)]


@pytest.mark.slow
def test_400_near_identical_frames_show_no_jump_in_perplexity(tmp_path):
    # the whole mission in memory (the default); a memory bound forgets one frame at a time
    # (tests/drive/test_drive_stream.py), which gave the same smooth curve here (largest change 4.9 %)
    bag = write_bag(tmp_path / "hover", "mcap", {"/camera/image_raw": "rgb8"}, near_identical_frames(FRAMES))
    result = replay(bag, tmp_path / "run")
    assert result.exit_code == 0, result.output
    records = frame_records(tmp_path / "run")
    assert [r["frame"] for r in records] == list(range(FRAMES))
    mean = np.array([np.mean(r["perplexity"]) for r in records])
    # the view does not change, so once the model has seen it a few times neither does its surprise:
    # a model that started again (as every 150 frames before) doubled it from one frame to the next
    # (from 2.0 to 54.8 at frame 150, where the model used to start again)
    change = np.abs(np.diff(mean[10:])) / mean[10:-1]
    at = 10 + int(change.argmax())
    assert change.max() < 0.2, f"frame {at + 1}: {mean[at]:.1f} -> {mean[at + 1]:.1f}"
    assert mean[10:].max() < 2 * mean[10:].min()
