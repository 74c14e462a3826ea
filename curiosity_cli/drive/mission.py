"""A drive as a mission file Foxglove opens, ``mission.mcap``, and optionally a live Foxglove view of it.

Written with the Foxglove SDK (``foxglove-sdk``): it writes MCAP and serves Foxglove's
WebSocket protocol from the same channels, so a mission file and a live view show the
same messages. Every channel is protobuf with its schema embedded in the file, Foxglove's
own where one fits and this module's (:data:`CUSTOM_PROTO`, package ``curiosity``) where
none does, so the mcap project's protobuf decoder reads all of them. Each message's log
time is the frame's time in nanoseconds: a replay's bag time, or the host's clock for a
live camera. The channels, per frame:

- :data:`CAMERA` ``foxglove.CompressedImage``: the frame as JPEG in frame :data:`CAMERA_FRAME`,
  stamped with its image message's header stamp where it has one;
- :data:`SURPRISE` ``curiosity.Surprise``: the frame's surprise and its parts
  (:func:`~curiosity_cli.drive.frames_table.frame_summary`), for the Plot panel;
- :data:`PERPLEXITY` ``foxglove.RawImage`` (``32FC1``): the image cells' topic perplexity,
  one pixel a cell, for the Image panel's colour map;
- :data:`CELLS` ``foxglove.ImageAnnotations``: the target cell outlined over the frame;
- :data:`COMMAND` ``curiosity.Command``: the target cell and the velocity command;
- :data:`POSE` ``foxglove.PoseInFrame``: the frame's pose, where it has one;
- :data:`TRANSFORMS` ``foxglove.FrameTransforms``: what links the pose's frame, the robot and
  the camera for the 3D panel, with every frame so that a reader that seeks finds it. From a
  recording with ``/tf_static`` or ``/tf`` (:mod:`~curiosity_cli.drive.transforms`): its
  transforms at the frame's time, and the image messages' frame linked to
  :data:`CAMERA_FRAME` as the same place. Without: :data:`CAMERA_MOUNT` from
  :data:`ROBOT_FRAME` to the camera, a stated default (the camera at the robot's origin and
  axes). Either way the pose, as the transform from its frame (e.g. ``odom``) to
  :data:`ROBOT_FRAME`, where the frame has one and the recording does not place the robot itself.

The run's config and provenance are the file's metadata (``config``, ``provenance``), and
:func:`write_layout` writes a Foxglove layout for the file beside it. Every number comes
from the frame's record in ``log.jsonl``, so the file and the log agree value for value, but for
a pose's quaternion of another length than 1, which the file holds scaled to unit length (:func:`_rotation`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.drive.frames_table import frame_summary

#: A run folder's mission file, and the Foxglove layout written beside it.
MISSION_FILE = "mission.mcap"
LAYOUT_FILE = "mission.layout.json"
CAMERA, SURPRISE, PERPLEXITY, CELLS, COMMAND, POSE, TRANSFORMS = (
    "/camera/image", "/curiosity/surprise", "/curiosity/perplexity", "/curiosity/cells", "/curiosity/command", "/pose",
    "/tf",
)
#: The robot's frame (ROS's REP 105 name) and the camera's, which the transforms link to the pose's frame.
ROBOT_FRAME, CAMERA_FRAME = "base_link", "camera"
#: The camera's place on the robot, (x, y, z) metres and the quaternion (x, y, z, w): a stated default, the
#: robot's origin and axes, where a recording gives none.
CAMERA_MOUNT = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
#: JPEG quality of the frames in the file: near the camera's own, at a tenth of raw RGB's size.
JPEG_QUALITY = 90
#: The port a live view is served on when none is given (Foxglove's default).
DEFAULT_PORT = 8765

#: The custom channels' messages: (name, [(field, protobuf type)]), numbered in order. Their descriptions:
#: surprise, the mean topic perplexity of the frame's image cells; score_max, the decayed curiosity score that
#: steered; refined, the word samples of the frame's own refinement; surge in m/s, the rates in rad/s.
CUSTOM_PROTO = (
    ("Surprise", [("frame", "uint64"), ("surprise", "double"), ("perplexity_max", "double"), ("score_max", "double"),
                  ("refined", "int64"), ("words", "int64")]),
    ("Command", [("frame", "uint64"), ("target_row", "int32"), ("target_col", "int32"), ("surge", "double"),
                 ("yaw_rate", "double"), ("pitch_rate", "double")]),
)


def custom_messages() -> tuple[bytes, dict]:
    """The serialized ``FileDescriptorSet`` of :data:`CUSTOM_PROTO` (package ``curiosity``, proto3), which a
    channel's schema embeds, and each message's class by name."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    kinds = descriptor_pb2.FieldDescriptorProto
    file = descriptor_pb2.FileDescriptorProto(name="curiosity/mission.proto", package="curiosity", syntax="proto3")
    for name, fields in CUSTOM_PROTO:
        message = file.message_type.add(name=name)
        for number, (field, kind) in enumerate(fields, start=1):
            message.field.add(
                name=field, number=number, label=kinds.LABEL_OPTIONAL, type=getattr(kinds, f"TYPE_{kind.upper()}")
            )
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    classes = {
        name: message_factory.GetMessageClass(pool.FindMessageTypeByName(f"curiosity.{name}")) for name, _ in CUSTOM_PROTO
    }
    return descriptor_pb2.FileDescriptorSet(file=[file]).SerializeToString(), classes


class MissionFile:
    """A drive's ``mission.mcap``, and its live view on ``live_port`` when one is given.

    Parameters
    ----------
    path : Path
        The file, new.
    live_port : int, optional
        Serve the same channels over Foxglove's WebSocket protocol on localhost at this
        port (0: any free one, :attr:`port` says which) while the drive runs.
    metadata : dict of str to dict of str to str, optional
        MCAP metadata records, by name (a drive's: ``config`` and ``provenance``).
    recording : optional
        The camera, when it is a recording with coordinate frames: its ``transforms``
        (:class:`~curiosity_cli.drive.transforms.Transforms` or None) and ``image_frame_id``
        (str or None, known once a frame is read) link the frames.

    Raises
    ------
    CuriosityError
        The Foxglove SDK not installed (naming the extra that brings it), a file that
        cannot be made, a port that cannot be served on.
    """

    def __init__(
        self, path: Path, live_port: int | None = None, metadata: dict[str, dict[str, str]] | None = None,
        recording=None,
    ):
        from curiosity_cli.errors import CuriosityError
        from curiosity_cli.files import display_path

        try:
            import foxglove
            from foxglove.channels import (
                CompressedImageChannel,
                FrameTransformsChannel,
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
            for name, record in (metadata or {}).items():
                self._writer.write_metadata(name, record)
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
        descriptors, self._messages = custom_messages()

        def custom(topic: str, name: str):
            schema = foxglove.Schema(name=f"curiosity.{name}", encoding="protobuf", data=descriptors)
            return foxglove.Channel(topic, schema=schema, message_encoding="protobuf", context=c)

        self._surprise = custom(SURPRISE, "Surprise")
        self._perplexity = RawImageChannel(PERPLEXITY, context=c)
        self._cells = ImageAnnotationsChannel(CELLS, context=c)
        self._command = custom(COMMAND, "Command")
        self._pose = PoseInFrameChannel(POSE, context=c)
        self._transforms = FrameTransformsChannel(TRANSFORMS, context=c)
        self._recording = recording
        recorded = getattr(recording, "transforms", None)
        self._placed = set() if recorded is None else recorded.children()

    def frame(self, row: dict, image: np.ndarray) -> None:
        """Log one frame: its record in the drive's log and the (H, W, 3) uint8 RGB image it was made from."""
        import cv2
        from foxglove.messages import (
            Color,
            CompressedImage,
            FrameTransform,
            FrameTransforms,
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
        self._camera.log(
            CompressedImage(timestamp=stamp, frame_id=CAMERA_FRAME, data=jpeg.tobytes(), format="jpeg"), log_time=at
        )
        surprise = self._messages["Surprise"](frame=row["frame"], **frame_summary(row))
        self._surprise.log(surprise.SerializeToString(), log_time=at)
        perplexity = np.asarray(row["perplexity"], "<f4")
        rows, cols = perplexity.shape
        self._perplexity.log(
            RawImage(timestamp=stamp, frame_id=CAMERA_FRAME, width=cols, height=rows, encoding="32FC1", step=4 * cols,
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
        command = self._messages["Command"](frame=row["frame"], target_row=row_at, target_col=col_at, **row["command"])
        self._command.log(command.SerializeToString(), log_time=at)
        pose = row.get("pose")
        if pose is not None:
            position = Vector3(x=pose["x"], y=pose["y"], z=pose["z"])
            qx, qy, qz, qw = _rotation(pose)
            orientation = Quaternion(x=qx, y=qy, z=qz, w=qw)
            self._pose.log(
                PoseInFrame(timestamp=_timestamp(at), frame_id=pose["frame_id"], pose=Pose(position=position, orientation=orientation)),
                log_time=at,
            )
        links = [
            FrameTransform(
                timestamp=_timestamp(at), parent_frame_id=parent, child_frame_id=child,
                translation=Vector3(x=x, y=y, z=z), rotation=Quaternion(x=qx, y=qy, z=qz, w=qw),
            )
            for parent, child, (x, y, z), (qx, qy, qz, qw) in self._links(at, pose)
        ]
        self._transforms.log(FrameTransforms(transforms=links), log_time=at)
        # each frame a finished chunk on disk: a drive killed (SIGKILL, a power cut) leaves a file that the mcap
        # readers read up to its last frame, where the SDK's own chunks of about a megabyte lost every frame in it
        self._writer.flush()

    def _links(self, at: int, pose: dict | None) -> list[tuple]:
        """The frame's transforms as (parent, child, translation, rotation): the recording's, or the stated camera
        mount; and the pose, unless the recording places the robot itself."""
        recorded = getattr(self._recording, "transforms", None)
        if recorded is None:
            links = [(ROBOT_FRAME, CAMERA_FRAME, *CAMERA_MOUNT)]
        else:
            links = [(t.parent, t.child, t.translation, t.rotation) for t in recorded.at(at)]
            image_frame = getattr(self._recording, "image_frame_id", None)
            if image_frame and image_frame != CAMERA_FRAME:  # the frames this file shows are where the recording's were
                links.append((image_frame, CAMERA_FRAME, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
        # a pose in no frame, or in the robot's own, places nothing (its link would have no parent, or be a loop)
        if pose is not None and ROBOT_FRAME not in self._placed and pose["frame_id"] not in ("", ROBOT_FRAME):
            position = (pose["x"], pose["y"], pose["z"])
            links.insert(0, (pose["frame_id"], ROBOT_FRAME, position, _rotation(pose)))
        return links

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


def check_live_port(port: int | None) -> None:
    """Refuse a live view's ``port`` that cannot be served now (taken, or not ours to bind), before a drive loads its model.

    The port is bound and let go at once; ``0`` (any free port) and None (no live view) pass.

    Raises
    ------
    CuriosityError
        Naming the port and the system's reason (``parameter="foxglove"``).
    """
    import socket

    from curiosity_cli.errors import CuriosityError

    if not port:
        return
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        # as a server binds (SO_REUSEADDR): a port left in TIME_WAIT by an earlier run is free, a listening one is not
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(("127.0.0.1", port))
        except OSError as exc:
            raise CuriosityError(
                f"foxglove: cannot serve a live view on port {port} ({exc.strerror or exc})", parameter="foxglove"
            ) from None


def write_layout(folder: Path) -> Path:
    """Write :data:`LAYOUT_FILE` into ``folder``: a Foxglove layout for its mission file (import it with Foxglove's
    layout menu, "Import from file").

    The frame with its perplexity grid and the target cell over it; the surprise and its largest
    cell perplexity against time; the 3D scene of the transforms and the poses, following the robot.
    """
    import foxglove.layouts as fl

    from curiosity_cli.files import atomic_path

    image = fl.ImagePanel(title="frame and target cell", config=fl.ImageConfig(image_mode=fl.ImageModeConfig(
        image_topic=CAMERA, annotations={CELLS: fl.ImageAnnotationSettings(visible=True)},
    )))
    perplexity = fl.ImagePanel(title="topic perplexity per cell", config=fl.ImageConfig(image_mode=fl.ImageModeConfig(
        image_topic=PERPLEXITY, color_mode="colormap", color_map="turbo",
    )))
    plot = fl.PlotPanel(title="surprise", config=fl.PlotConfig(paths=[
        fl.PlotSeries(value=f"{SURPRISE}.surprise", label="surprise (mean cell perplexity)"),
        fl.PlotSeries(value=f"{SURPRISE}.perplexity_max", label="largest cell perplexity"),
    ]))
    scene = fl.ThreeDeePanel(title="trajectory", config=fl.ThreeDeeConfig(
        follow_tf=ROBOT_FRAME, topics={POSE: fl.BaseRendererPoseTopicSettings(visible=True)},
    ))
    layout = fl.Layout(content=fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(proportion=2, content=image), fl.SplitItem(content=perplexity),
        ])),
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(content=plot), fl.SplitItem(content=scene),
        ])),
    ]))
    path = Path(folder) / LAYOUT_FILE
    with atomic_path(path) as tmp:
        tmp.write_text(layout.to_json())
    return path


def _timestamp(time_ns: int):
    from foxglove.messages import Timestamp

    return Timestamp(sec=time_ns // 1_000_000_000, nsec=time_ns % 1_000_000_000)


#: How far from 1 a quaternion's length may be and still be taken as a unit one: rounding of a unit one's parts.
_UNIT_LENGTH_TOLERANCE = 1e-9


def _rotation(pose: dict) -> tuple[float, float, float, float]:
    """A pose's quaternion (x, y, z, w) scaled to unit length, as a rotation must be: a recorder's need not be one
    (the log keeps it as recorded), and one of another length, read as a rotation matrix, would scale as well as
    turn. One of unit length to within rounding is kept as it is, value for value. A quaternion of no length never
    gets here: such a pose is left out as senseless."""
    quaternion = np.array([pose["qx"], pose["qy"], pose["qz"], pose["qw"]], float)
    length = np.linalg.norm(quaternion)
    if abs(length - 1) > _UNIT_LENGTH_TOLERANCE:
        quaternion /= length
    return tuple(float(v) for v in quaternion)
