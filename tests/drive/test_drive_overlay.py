"""The paper's overlay: blue discs with opacity by score, the target in red; video and PNG files."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from curiosity_cli.drive.overlay import MAX_OPACITY, VideoSink, draw_overlay, write_png
from curiosity_cli.errors import CuriosityError


def test_discs_are_blue_with_opacity_by_score_and_the_target_red():
    frame = np.full((60, 80, 3), 100, np.uint8)
    scores = np.array([[1.0, 2.0, 4.0, 0.0], [4.0, 3.0, 2.0, 1.0]])
    out = draw_overlay(frame, scores, (1, 0))

    def centre(row, col):
        return out[int((row + 0.5) * 30), int((col + 0.5) * 20)].astype(int)

    red = MAX_OPACITY * np.array([255, 30, 30]) + (1 - MAX_OPACITY) * 100
    assert np.abs(centre(1, 0) - red).max() <= 1  # the target, at full opacity
    full = MAX_OPACITY * np.array([40, 90, 255]) + (1 - MAX_OPACITY) * 100
    assert np.abs(centre(0, 2) - full).max() <= 1  # the highest score: the most opaque blue
    blues = [centre(0, c)[2] for c in (3, 0, 1, 2)]  # scores 0, 1, 2, 4
    assert blues == sorted(blues) and blues[0] == 100  # a zero score leaves the frame as it was
    assert out[0, 0].tolist() == [100, 100, 100]  # between discs: untouched
    assert frame.max() == 100  # the input is not drawn on


def test_a_video_takes_its_name_when_closed_and_pngs_are_written_whole(tmp_path):
    sink = VideoSink(tmp_path / "out" / "run.avi", 5.0)
    for i in range(3):
        sink.write(np.full((48, 64, 3), 60 * i, np.uint8))
    sink.write(np.zeros((96, 128, 3), np.uint8))  # another size: resized to the first
    assert not (tmp_path / "out" / "run.avi").exists()
    sink.close()
    capture = cv2.VideoCapture(str(tmp_path / "out" / "run.avi"))
    sizes = []
    while True:
        ok, image = capture.read()
        if not ok:
            break
        sizes.append(image.shape)
    assert sizes == [(48, 64, 3)] * 4 and sorted(p.name for p in (tmp_path / "out").iterdir()) == ["run.avi"]

    image = np.zeros((10, 12, 3), np.uint8)
    image[:, :, 0] = 255
    write_png(image, tmp_path / "a.png")
    assert cv2.imread(str(tmp_path / "a.png"))[0, 0].tolist() == [0, 0, 255]  # RGB red, read back as BGR
    with pytest.raises(CuriosityError, match="expected a .mp4, .avi or .mkv file name"):
        VideoSink(tmp_path / "run.gif", 5.0)
