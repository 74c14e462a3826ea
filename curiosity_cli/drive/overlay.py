"""The paper's view of curiosity (section 5.2), drawn on a frame, and where frames go.

Every image cell gets a blue disc whose opacity grows with its score, ``opacity =
MAX_OPACITY * score / max(score)``; the target cell's disc is red. A line of text on top
gives the frame number and the command.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.drive.controller import Command
from curiosity_cli.files import atomic_path, display_path, unwritable
from curiosity_cli.errors import CuriosityError, UsageError

MAX_OPACITY = 0.6
_BLUE = (40, 90, 255)  # RGB
_RED = (255, 30, 30)


def draw_overlay(frame: np.ndarray, scores: np.ndarray, target: tuple[int, int], caption: str = "") -> np.ndarray:
    """The frame with the curiosity discs (module docstring) and a caption.

    Parameters
    ----------
    frame : (H, W, 3) uint8 ndarray
        RGB, any size; the grid of ``scores`` is stretched over it
        (:meth:`~curiosity_cli.maps.cell_grid.SquareGrid.centres`).
    scores : (rows, cols) float ndarray
        Curiosity scores, >= 0.
    target : (int, int)
        (row, col) of the cell drawn in red.
    caption : str
        Drawn at the top left; empty for none.

    Returns
    -------
    (H, W, 3) uint8 ndarray
        A new image.
    """
    import cv2

    height, width = frame.shape[:2]
    rows, cols = scores.shape
    grid = SquareGrid(rows, cols)
    top = float(scores.max())
    opacity = np.zeros((height, width), np.float32)
    paint = np.zeros_like(frame)
    radius = max(1, int(0.35 * min(height / rows, width / cols)))
    centre_rows, centre_cols = grid.centres(np.arange(grid.n_cells).reshape(rows, cols), (height, width))
    for row in range(rows):
        for col in range(cols):
            centre = (int(centre_cols[row, col]), int(centre_rows[row, col]))  # OpenCV's (x, y)
            alpha = MAX_OPACITY * (scores[row, col] / top if top > 0 else 0.0)
            is_target = (row, col) == tuple(target)
            cv2.circle(opacity, centre, radius, MAX_OPACITY if is_target else alpha, -1, cv2.LINE_AA)
            cv2.circle(paint, centre, radius, _RED if is_target else _BLUE, -1, cv2.LINE_AA)
    weight = opacity[:, :, None]
    out = (frame * (1 - weight) + paint * weight).round().astype(np.uint8)
    if caption:
        scale = max(0.35, width / 1000)
        (text_width, text_height), baseline = cv2.getTextSize(caption, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
        band = text_height + baseline + 8
        out[:band, : text_width + 12] //= 3  # a dark band keeps the caption legible on any image
        cv2.putText(out, caption, (6, text_height + 4), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def caption_for(frame_number: int, command: Command | None) -> str:
    if command is None:
        return f"frame {frame_number}"
    return f"frame {frame_number}  surge {command.surge:+.2f}  yaw {command.yaw_rate:+.2f}  pitch {command.pitch_rate:+.2f}"


def write_png(image: np.ndarray, path: Path) -> None:
    """An RGB image as a PNG, atomically."""
    import cv2

    ok, data = cv2.imencode(".png", np.ascontiguousarray(image[:, :, ::-1]))
    if not ok:  # pragma: no cover - encoding a uint8 image to PNG does not fail
        raise CuriosityError(f"{display_path(path)}: PNG encoding failed")
    with atomic_path(path) as tmp:
        tmp.write_bytes(data.tobytes())


#: The annotated video's container (its file name's suffix) and the codec written in it.
VIDEO_CODECS = {".mp4": "mp4v", ".avi": "MJPG", ".mkv": "mp4v"}


def check_video_out(path: Path) -> None:
    """Refuse a video file name whose suffix is no container of :data:`VIDEO_CODECS`, or whose folder
    cannot take files (made if missing).

    OpenCV opens a writer in a read-only folder without a word and writes nothing, so the
    folder is asked first: the run would otherwise end on its missing temporary file.

    Raises
    ------
    UsageError
        Naming ``video_out``: no video file name.
    CuriosityError
        Naming ``video_out``: its folder cannot take files, and why.
    """
    if Path(path).suffix.lower() not in VIDEO_CODECS:
        raise UsageError(
            f"video_out: got {display_path(Path(path))}, expected a .mp4, .avi or .mkv file name", parameter="video_out"
        )
    reason = unwritable(Path(path).parent)
    if reason is not None:
        raise CuriosityError(f"video_out {display_path(Path(path))}: {reason}", parameter="video_out")


class VideoSink:
    """An annotated video, written to a temporary file that takes its name on :meth:`close`.

    Frames of another size than the first are resized to it. The container and codec
    follow the extension: ``.mp4`` (MPEG-4 part 2), ``.avi`` (Motion JPEG), ``.mkv``.
    A run that ends with an error still closes the sink, so the video shows what led
    to it; only a killed process leaves the temporary file behind.

    Parameters
    ----------
    path : Path
        A ``.mp4``, ``.avi`` or ``.mkv`` file (:func:`check_video_out`; a drive checks it before
        it writes anything).
    fps : float
        Frame rate written into the file.
    """

    def __init__(self, path: Path, fps: float):
        self.path = Path(path)
        check_video_out(self.path)
        self._tmp = self.path.with_name(f".{self.path.stem}.tmp{self.path.suffix}")
        self._fps = fps
        self._writer = None
        self._size = None
        self.frames = 0

    def write(self, image: np.ndarray) -> None:
        """Append an RGB frame."""
        import cv2

        if self._writer is None:
            self._size = (image.shape[1], image.shape[0])  # OpenCV's (width, height)
            fourcc = cv2.VideoWriter_fourcc(*VIDEO_CODECS[self.path.suffix.lower()])
            self._writer = cv2.VideoWriter(str(self._tmp), fourcc, self._fps, self._size)
            if not self._writer.isOpened():
                raise CuriosityError(
                    f"video_out {display_path(self.path)}: OpenCV cannot write this video", parameter="video_out"
                )
        if (image.shape[1], image.shape[0]) != self._size:
            image = cv2.resize(image, self._size, interpolation=cv2.INTER_AREA)
        self._writer.write(np.ascontiguousarray(image[:, :, ::-1]))
        self.frames += 1

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None
            os.replace(self._tmp, self.path)
