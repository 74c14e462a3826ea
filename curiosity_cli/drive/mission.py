"""A drive as a mission file Foxglove opens, ``mission.mcap``, and optionally a live Foxglove view of it.

Written with the Foxglove SDK (``foxglove-sdk``): it writes MCAP and serves Foxglove's
WebSocket protocol from the same channels, so a mission file and a live view show the
same messages, encoded with Foxglove's own schemas (protobuf, the schemas embedded in
the file) where one fits and as JSON with a JSON schema where none does. Each message's
log time is the frame's time in nanoseconds: a replay's bag time, or the host's clock
for a live camera. The channels, per frame:

- :data:`CAMERA` ``foxglove.CompressedImage``: the frame as JPEG, stamped with its
  image message's header stamp where it has one;
- :data:`SURPRISE` (JSON): the frame's surprise and its parts
  (:func:`~curiosity_cli.drive.frames_table.frame_summary`), for the Plot panel;
- :data:`PERPLEXITY` ``foxglove.RawImage`` (``32FC1``): the image cells' topic perplexity,
  one pixel a cell, for the Image panel's colour map;
- :data:`CELLS` ``foxglove.ImageAnnotations``: the target cell outlined over the frame;
- :data:`COMMAND` (JSON): the target cell and the velocity command;
- :data:`POSE` ``foxglove.PoseInFrame``: the frame's pose, where it has one.

Every number comes from the frame's record in ``log.jsonl``, so the file and the log
agree value for value.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.drive.frames_table import frame_summary

#: A run folder's mission file.
MISSION_FILE = "mission.mcap"
CAMERA, SURPRISE, PERPLEXITY, CELLS, COMMAND, POSE = (
    "/camera/image", "/curiosity/surprise", "/curiosity/perplexity", "/curiosity/cells", "/curiosity/command", "/pose",
)
#: JPEG quality of the frames in the file: near the camera's own, at a tenth of raw RGB's size.
JPEG_QUALITY = 90
#: The port a live view is served on when none is given (Foxglove's default).
DEFAULT_PORT = 8765

_SURPRISE_SCHEMA = {
    "type": "object",
    "title": "curiosity.Surprise",
    "properties": {
        "frame": {"type": "integer"},
        "surprise": {"type": "number", "description": "mean topic perplexity of the frame's image cells"},
        "perplexity_max": {"type": "number"},
        "score_max": {"type": "number", "description": "the decayed curiosity score that steered"},
        "refined": {"type": "integer", "description": "word samples of the frame's own refinement"},
        "words": {"type": "integer"},
    },
}
_COMMAND_SCHEMA = {
    "type": "object",
    "title": "curiosity.Command",
    "properties": {
        "frame": {"type": "integer"},
        "target_row": {"type": "integer"},
        "target_col": {"type": "integer"},
        "surge": {"type": "number", "description": "m/s"},
        "yaw_rate": {"type": "number", "description": "rad/s"},
        "pitch_rate": {"type": "number", "description": "rad/s"},
    },
}


class MissionFile:
    """A drive's ``mission.mcap``, and its live view on ``live_port`` when one is given.

    Parameters
    ----------
    path : Path
        The file, new.
    live_port : int, optional
        Serve the same channels over Foxglove's WebSocket protocol on localhost at this
        port (0: any free one, :attr:`port` says which) while the drive runs.

    Raises
    ------
    CuriosityError
        The Foxglove SDK not installed (naming the extra that brings it), a file that
        cannot be made, a port that cannot be served on.
    """

    def __init__(self, path: Path, live_port: int | None = None):
        from curiosity_cli.errors import CuriosityError
        from curiosity_cli.files import display_path

        try:
            import foxglove
            from foxglove.channels import (
                CompressedImageChannel,
                ImageAnnotationsChannel,
                PoseInFrameChannel,
                RawImageChannel,
            )
        except ImportError:
            raise CuriosityError("writing a mission file needs the Foxglove SDK, a dependency of curiosity: pip install 'foxglove-sdk>=0.30,<0.31'") from None
        self.path = Path(path)
        self._context = foxglove.Context()
        try:
            self._writer = foxglove.open_mcap(self.path, context=self._context)
        except Exception as exc:  # the SDK's own error for a path it cannot create
            raise CuriosityError(f"{display_path(self.path)}: cannot be written ({' '.join(str(exc).split())})") from None
        self._server = None
        self.port = None
        if live_port is not None:
            try:
                self._server = foxglove.start_server(
                    name="curiosity", host="127.0.0.1", port=live_port, context=self._context
                )
            except Exception as exc:  # the port is taken or not ours to bind
                self._writer.close()
                raise CuriosityError(
                    f"foxglove: cannot serve a live view on port {live_port} ({' '.join(str(exc).split())})",
                    parameter="foxglove",
                ) from None
            self.port = self._server.port
        c = self._context
        self._camera = CompressedImageChannel(CAMERA, context=c)
        self._surprise = foxglove.Channel(SURPRISE, schema=_SURPRISE_SCHEMA, context=c)
        self._perplexity = RawImageChannel(PERPLEXITY, context=c)
        self._cells = ImageAnnotationsChannel(CELLS, context=c)
        self._command = foxglove.Channel(COMMAND, schema=_COMMAND_SCHEMA, context=c)
        self._pose = PoseInFrameChannel(POSE, context=c)

    def frame(self, row: dict, image: np.ndarray) -> None:
        """Log one frame: its record in the drive's log and the (H, W, 3) uint8 RGB image it was made from."""
        import cv2
        from foxglove.messages import (
            Color,
            CompressedImage,
            ImageAnnotations,
            Point2,
            PointsAnnotation,
            PointsAnnotationType,
            Pose,
            PoseInFrame,
            Quaternion,
            RawImage,
            Vector3,
        )

        at = row["time_ns"]
        stamp = _timestamp(row.get("header_time_ns", at))
        ok, jpeg = cv2.imencode(".jpg", image[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        self._camera.log(CompressedImage(timestamp=stamp, frame_id="camera", data=jpeg.tobytes(), format="jpeg"), log_time=at)
        self._surprise.log({"frame": row["frame"], **frame_summary(row)}, log_time=at)
        perplexity = np.asarray(row["perplexity"], "<f4")
        rows, cols = perplexity.shape
        self._perplexity.log(
            RawImage(timestamp=stamp, frame_id="camera", width=cols, height=rows, encoding="32FC1", step=4 * cols,
                     data=perplexity.tobytes()),
            log_time=at,
        )
        height, width = image.shape[:2]
        row_at, col_at = row["target"]
        top, bottom = row_at * height / rows, (row_at + 1) * height / rows
        left, right = col_at * width / cols, (col_at + 1) * width / cols
        outline = PointsAnnotation(
            timestamp=stamp, type=PointsAnnotationType.LineLoop, thickness=3.0,
            points=[Point2(x=left, y=top), Point2(x=right, y=top), Point2(x=right, y=bottom), Point2(x=left, y=bottom)],
            outline_color=Color(r=1.0, g=0.85, b=0.0, a=1.0),
        )
        self._cells.log(ImageAnnotations(points=[outline]), log_time=at)
        command = row["command"]
        self._command.log(
            {"frame": row["frame"], "target_row": row_at, "target_col": col_at, **command}, log_time=at
        )
        pose = row.get("pose")
        if pose is not None:
            self._pose.log(
                PoseInFrame(
                    timestamp=_timestamp(at), frame_id=pose["frame_id"],
                    pose=Pose(position=Vector3(x=pose["x"], y=pose["y"], z=pose["z"]),
                              orientation=Quaternion(x=pose["qx"], y=pose["qy"], z=pose["qz"], w=pose["qw"])),
                ),
                log_time=at,
            )

    def close(self) -> None:
        """Finish the file (its summary and index) and stop the live view.

        Raises
        ------
        CuriosityError
            The file could not be finished (a full disk: the SDK's ``MCAP error``), naming it; what was written
            before stays, and replays to its last whole message.
        """
        from curiosity_cli.errors import CuriosityError
        from curiosity_cli.files import display_path

        if self._server is not None:
            self._server.stop()
            self._server = None
        if self._writer is not None:
            writer, self._writer = self._writer, None
            try:
                writer.close()
            except Exception as exc:  # the SDK's FoxgloveError, whatever the OS said beneath it
                raise CuriosityError(
                    f"{display_path(self.path)}: cannot be finished ({' '.join(str(exc).split())}; a full disk?); "
                    "what was written before stays, and replays to its last whole message"
                ) from None


def _timestamp(time_ns: int):
    from foxglove.messages import Timestamp

    return Timestamp(sec=time_ns // 1_000_000_000, nsec=time_ns % 1_000_000_000)
