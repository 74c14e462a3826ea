"""Live from a ROS 2 robot without ROS: its camera as a drive's camera, its ``cmd_vel`` as the drive's robot.

ROS 2's wire is DDS; Cyclone DDS's Python binding (``cyclonedds``, the ``ros2`` extra) speaks it
with the message types of :mod:`~curiosity_cli.drive.ros2_types`. A ROS topic ``/a/b`` is the
DDS topic ``rt/a/b``. What the network is comes from the environment as for any Cyclone DDS
program (``CYCLONEDDS_URI``: interfaces, peers, multicast), and the ROS domain from
``domain_id``, else ``ROS_DOMAIN_ID``, else 0.

:class:`Ros2Camera` reads ``sensor_msgs/msg/CompressedImage`` from a topic whose name ends in
``/compressed`` (image_transport's name for it) and ``sensor_msgs/msg/Image`` from any other,
with ROS's sensor-data QoS (best effort, keep last), decoded as a bag's frames are
(:func:`~curiosity_cli.drive.bags.decode`); with ``odom_topic``, each frame gets the pose of the
odometry nearest its header stamp (:class:`~curiosity_cli.drive.odometry.RecentPoses`).

:class:`Ros2Robot` publishes each command as ``geometry_msgs/msg/Twist`` (or ``TwistStamped``)
with ROS's default QoS (reliable, keep last 10), again every ``keepalive`` seconds while no new
one comes (a base's ``cmd_vel`` timeout stops it otherwise) for up to :data:`STALE_AFTER` s, then
a zero twist, and each frame's surprise and
target on :data:`SURPRISE_TOPIC` and :data:`TARGET_TOPIC`; closing it sends STOP, a zero twist.
"""

from __future__ import annotations

import os
import re
import threading
import time

from curiosity_cli.drive.bags import COMPRESSED, IMAGE, BadMessage, decode
from curiosity_cli.drive.camera import CameraError, Frame
from curiosity_cli.drive.frames_table import frame_summary
from curiosity_cli.drive.link import LinkError
from curiosity_cli.drive.odometry import MAX_POSE_GAP_NS, ODOMETRY, RecentPoses
from curiosity_cli.errors import CuriosityError, ParameterError

#: What a drive's ``camera`` begins with to name a ROS 2 image topic: ``ros2:/camera/image/compressed``.
PREFIX = "ros2:"
#: The largest ROS domain id (ROS 2's rule: the ports of higher ones fall outside the range DDS computes).
MAX_DOMAIN_ID = 232
#: Seconds a camera may go without a frame, the first one included (discovery takes part of it), before the drive
#: stops with an error.
FRAME_TIMEOUT = 5.0
#: Seconds after its last command from the drive that the robot's newest twist is still published again: a drive
#: whose camera stalls has nothing new to say, and the robot is halted (a zero twist) rather than driven blind.
STALE_AFTER = 1.0
#: Seconds the robot's ``cmd_vel`` may go without a subscriber before a drive starts, and before its STOP is sent.
MATCH_TIMEOUT = 5.0
#: STOP is a zero twist sent this many times, :data:`STOP_INTERVAL` s apart: one lost on a best-effort reader's
#: network is not the only one.
STOP_REPEATS = 3
STOP_INTERVAL = 0.05
#: Seconds the STOP waits for every reliable subscriber's acknowledgement.
STOP_ACK_TIMEOUT = 1.0
#: Where each frame goes: ``std_msgs/msg/Float32``, its surprise (the frames table's, the mean over its image cells);
#: ``geometry_msgs/msg/PointStamped``, its target cell (x its column, y its row, in :data:`TARGET_FRAME`).
SURPRISE_TOPIC = "/curiosity/surprise"
TARGET_TOPIC = "/curiosity/target"
#: The target's frame id: image cells, not metres; no transform leads there.
TARGET_FRAME = "curiosity_image_cells"
#: A stamped twist's frame id: the robot's body (REP 105).
BODY_FRAME = "base_link"
#: Sensor-data QoS keeps this many frames; a drive decides on the newest and drops the rest, which are stale.
CAMERA_DEPTH = 5
#: Odometry comes faster than frames: this many are kept between two frames.
ODOMETRY_DEPTH = 100
#: How long one wait for a frame lasts: SIGINT's handler runs between two.
_WAIT_SLICE = 0.1
#: The longest topic name taken: DDS's topic names ("rt" and the ROS name) are bounded at 256 bytes.
MAX_TOPIC_LENGTH = 253
#: A ROS name: tokens of letters, digits and underscores, not starting with a digit, joined by single slashes.
_ROS_NAME = re.compile(r"/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")


def is_ros2(camera: str) -> bool:
    """Whether a drive's ``camera`` names a ROS 2 image topic (``ros2:/TOPIC``)."""
    return camera.startswith(PREFIX)


def ros_topic(name: str, parameter: str, prefix: str = "") -> str:
    """``name`` as an absolute ROS topic name (``camera/image`` is ``/camera/image``: a drive's node is at the root);
    ``prefix`` is what came before it in the argument (:data:`PREFIX` for a camera).

    Raises
    ------
    ParameterError
        A name ROS does not allow, naming ``parameter``.
    """
    if len(name) > MAX_TOPIC_LENGTH or not _ROS_NAME.fullmatch(name):
        shown = prefix + (name if len(name) <= 80 else f"{name[:60]}... ({len(name)} characters)")
        raise ParameterError(
            f"{parameter}: got {shown!r}, expected a ROS topic name such as /cmd_vel or /camera/image/compressed "
            f"(letters, digits and underscores between single slashes, no token starting with a digit, at most "
            f"{MAX_TOPIC_LENGTH} characters)", parameter=parameter,
        )
    return name if name.startswith("/") else f"/{name}"


def ros_domain_id(value: int | None) -> int:
    """The ROS domain: ``value``, else the environment's ``ROS_DOMAIN_ID``, else 0.

    Raises
    ------
    ParameterError
        A domain outside 0..:data:`MAX_DOMAIN_ID`, naming ``ros_domain_id`` or ``ROS_DOMAIN_ID``.
    """
    expected = f"expected a whole number 0..{MAX_DOMAIN_ID}"
    if value is None:
        text = os.environ.get("ROS_DOMAIN_ID", "").strip()
        if not text:
            return 0
        if not (text.isascii() and text.isdigit()) or int(text) > MAX_DOMAIN_ID:  # '²' and '٣' are digits to isdigit
            raise ParameterError(
                f"ros_domain_id: not given, and ROS_DOMAIN_ID is {text!r} in the environment; {expected}",
                parameter="ros_domain_id",
            )
        return int(text)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_DOMAIN_ID:
        raise ParameterError(f"ros_domain_id: got {value!r}, {expected}", parameter="ros_domain_id")
    return value


def require_dds(parameter: str, value: str) -> None:
    """Refuse a ROS 2 ``camera`` or ``cmd_vel`` (``parameter``, given ``value``) before any work when Cyclone DDS is
    not installed.

    Raises
    ------
    CuriosityError
        Naming the parameter, its value and the extra to install.
    """
    try:
        import cyclonedds.core  # noqa: F401 - the binding's C library loads here
        import cyclonedds.domain  # noqa: F401
    except ImportError:
        raise CuriosityError(
            f"{parameter} {value}: ROS 2 is spoken through Cyclone DDS's Python binding: pip install "
            "'curiosity-cli[ros2]'", parameter=parameter,
        ) from None


def _participant(domain: int, parameter: str, value: str):
    """A participant of ROS domain ``domain``, and our message types (:mod:`~curiosity_cli.drive.ros2_types`).

    Raises
    ------
    CuriosityError
        ``cyclonedds`` is not installed (:func:`require_dds`); Cyclone DDS cannot join the domain (a
        ``CYCLONEDDS_URI`` it refuses), with its reason.
    """
    require_dds(parameter, value)
    from cyclonedds.core import DDSException
    from cyclonedds.domain import DomainParticipant

    from curiosity_cli.drive import ros2_types

    try:
        return DomainParticipant(domain), ros2_types
    except DDSException as exc:
        raise CuriosityError(
            f"{parameter} {value}: Cyclone DDS cannot join ROS domain {domain} ({_one_line(exc)}); is CYCLONEDDS_URI "
            "right?", parameter=parameter,
        ) from None


def _stamp(types, time_ns: int):
    return types.Time(sec=time_ns // 1_000_000_000, nanosec=time_ns % 1_000_000_000)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


class Ros2Camera:
    """Frames of a ROS 2 image topic, the newest at each read, each with the pose of an odometry topic if given.

    Parameters
    ----------
    topic : str
        The image topic: ``sensor_msgs/msg/CompressedImage`` if its name ends in ``/compressed``,
        else ``sensor_msgs/msg/Image``.
    odom_topic : str, optional
        A ``nav_msgs/msg/Odometry`` topic; each frame gets the pose nearest its header stamp.
    domain_id : int, optional
        The ROS domain (:func:`ros_domain_id`).
    stopped : callable, optional
        Whether the drive was asked to stop (a signal): a wait for a frame ends then.

    Attributes
    ----------
    topic, odom_topic : str
        The absolute topic names (``odom_topic`` None without one).
    domain_id : int
    pose_note : str
        Where frames' poses come from, or why they have none.
    odometry_counts : dict or None
        With ``odom_topic``: the odometry messages ``kept``, and left out as ``damaged`` (not decoded, or a value
        not finite) or ``senseless`` (outside physical sense), as
        :func:`~curiosity_cli.drive.odometry.pose_problem` says; None without.

    Raises
    ------
    CameraError
        No frame within :data:`FRAME_TIMEOUT` s, naming the topic, its type and the domain.
    ParameterError
        A topic name ROS does not allow; a domain outside 0..232.
    CuriosityError
        ``cyclonedds`` is not installed, or cannot join the domain.
    """

    def __init__(
        self, topic: str, odom_topic: str | None = None, domain_id: int | None = None, stopped=lambda: False,
    ):
        self.topic = ros_topic(topic, "camera", PREFIX)
        self._stopped = stopped
        self.odom_topic = None if odom_topic is None else ros_topic(odom_topic, "odom_topic")
        self.domain_id = ros_domain_id(domain_id)
        self._participant, types = _participant(self.domain_id, "camera", f"{PREFIX}{self.topic}")
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
        from cyclonedds.qos import Policy, Qos
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        compressed = self.topic.endswith("/compressed")
        self._type, self._msgtype = (types.CompressedImage, COMPRESSED) if compressed else (types.Image, IMAGE)
        participant = self._participant

        def sensor_data(name: str, kind, depth: int):
            """A reader with ROS's sensor-data QoS: it matches a best-effort publisher and a reliable one alike."""
            qos = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(depth), Policy.Durability.Volatile)
            return DataReader(participant, Topic(participant, f"rt{name}", kind), qos=qos)

        self._images = sensor_data(self.topic, self._type, CAMERA_DEPTH)
        self._waitset = WaitSet(participant)
        self._waitset.attach(ReadCondition(self._images, SampleState.Any | ViewState.Any | InstanceState.Any))
        self._odometry_type = types.Odometry
        self._poses = self._odometry = None
        self.pose_note = "frames have no pose: no odom_topic"
        if self.odom_topic is not None:
            self._odometry = sensor_data(self.odom_topic, types.Odometry, ODOMETRY_DEPTH)
            self._poses = RecentPoses()
            self.pose_note = (
                f"poses from {self.odom_topic} ({ODOMETRY}): each frame given the one stamped nearest its own stamp "
                f"within {MAX_POSE_GAP_NS / 1e9:g} s (none beyond)"
            )
        self._received = 0
        self._pending: list = []
        self._usable_at = time.monotonic()  # the last usable frame's time (from the start: none yet)
        if not self._wait() and not stopped():  # stopped: the drive's loop ends at once, by the signal
            self.close()
            raise CameraError(
                f"camera {PREFIX}{self.topic}: no frame within {FRAME_TIMEOUT:g} s on ROS domain {self.domain_id}; "
                f"expected {self._msgtype} there ({COMPRESSED} on a topic whose name ends in /compressed, else "
                f"{IMAGE}): is the camera publishing, on this domain and network (ROS_DOMAIN_ID, CYCLONEDDS_URI)?",
                parameter="camera",
            )

    def _wait(self) -> bool:
        """Wait up to :data:`FRAME_TIMEOUT` s for a frame, in slices (a signal's handler runs between two); whether
        one came."""
        from cyclonedds.util import duration

        deadline = time.monotonic() + FRAME_TIMEOUT
        while not self._pending:
            self._pending = self._take()
            left = deadline - time.monotonic()
            if self._pending or left <= 0 or self._stopped():
                break
            self._waitset.wait(duration(seconds=min(_WAIT_SLICE, left)))
        return bool(self._pending)

    def _take(self) -> list:
        """The frames received since the last take, oldest first (a leaving camera's notices are not frames).

        Raises
        ------
        BadMessage
            Bytes that are no message of the topic's type.
        """
        try:
            samples = self._images.take(CAMERA_DEPTH)
        except Exception as exc:  # cyclonedds' own errors for bytes it cannot deserialize: that frame, not the camera
            self._received += 1
            reason = f"not a {self._msgtype} ({_one_line(exc)})"
            raise BadMessage(f"{PREFIX}{self.topic}: {reason}", reason=reason) from None
        frames = [sample for sample in samples if isinstance(sample, self._type)]
        self._received += len(frames)
        return frames

    def read(self) -> Frame:
        """The newest frame (older ones waiting are dropped: a decision is on what the camera sees now), with its
        header stamp and pose.

        Raises
        ------
        BadMessage
            A frame that holds no usable image (:func:`~curiosity_cli.drive.bags.decode`), with its index among the
            frames received; the next call reads the next frame.
        CameraError
            No frame for :data:`FRAME_TIMEOUT` s (the camera stopped, or the network lost it); an encoding the
            camera does not decode.
        """
        self._pending += self._take()
        if not self._pending and not self._wait():
            raise CameraError(
                f"camera {PREFIX}{self.topic}: no frame for {FRAME_TIMEOUT:g} s on ROS domain {self.domain_id} "
                "(the camera stopped publishing, or the network lost it)", parameter="camera",
            )
        message, self._pending = self._pending[-1], []
        captured = time.monotonic()
        index = self._received - 1
        try:
            image = decode(message, self._msgtype, f"{PREFIX}{self.topic}, message {index}")
        except BadMessage as bad:
            bad.index = index
            # a camera sending only damaged frames is as good as none: a drive skips them, so it would never end
            if captured - self._usable_at > FRAME_TIMEOUT:
                raise CameraError(
                    f"camera {PREFIX}{self.topic}: no usable frame for {FRAME_TIMEOUT:g} s on ROS domain "
                    f"{self.domain_id}, only damaged ones (the last: {bad.reason})", parameter="camera",
                ) from None
            raise
        self._usable_at = captured
        stamp = message.header.stamp
        header_ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        return Frame(image, captured, None, header_ns, self._pose(header_ns))

    @property
    def odometry_counts(self) -> dict | None:
        poses = self._poses
        return None if poses is None else {"kept": poses.kept, "damaged": poses.damaged, "senseless": poses.senseless}

    def _pose(self, header_ns: int):
        if self._odometry is None:
            return None
        for message in self._odometry.take(ODOMETRY_DEPTH):
            if isinstance(message, self._odometry_type):  # not a leaving publisher's notice
                self._poses.add(message)
        return self._poses.nearest(header_ns)

    def close(self) -> None:
        """Leave the domain: the participant and its readers go with it."""
        # cyclonedds deletes an entity with its last reference; the participant takes its readers with it
        self._waitset = self._images = self._odometry = self._participant = None


class Ros2Robot:
    """A ROS 2 robot steered through its velocity topic: what :func:`~curiosity_cli.drive.driver.run` asks of a robot.

    Velocities are the wire protocol's (PROTOCOL.md: NED body frame, yaw positive to the right, pitch positive
    nose up), published in ROS's body frame (REP 103: x forward, y left, z up): ``linear.x`` is the surge,
    ``angular.z`` minus the yaw rate, ``angular.y`` minus the pitch rate.

    Parameters
    ----------
    cmd_vel_topic : str
        The robot's velocity topic, usually ``/cmd_vel``.
    stamped : bool
        Publish ``geometry_msgs/msg/TwistStamped`` (stamped with this host's clock, frame :data:`BODY_FRAME`)
        instead of ``geometry_msgs/msg/Twist``.
    domain_id : int, optional
        The ROS domain (:func:`ros_domain_id`).
    keepalive : float
        Seconds after which the newest command is published again while no new one comes, > 0; for
        :data:`STALE_AFTER` s after the drive's last command, then a zero twist, once.
    stopped : callable, optional
        Whether the drive was asked to stop (a signal): the wait for a subscriber ends then.
    surprise_topic, target_topic : str
        Where each frame's surprise and target go (:meth:`publish_frame`).
    log : callable, optional
        ``log(event, **fields)``: the ``stop`` it sent.

    Attributes
    ----------
    topic : str
        The absolute velocity topic.
    message_type : str
        What is published on it.
    subscribers : int
        Its subscribers when the robot was opened.

    Raises
    ------
    LinkError
        No subscriber of ``cmd_vel_topic`` within :data:`MATCH_TIMEOUT` s, naming it and the domain.
    ParameterError
        A topic name ROS does not allow; a domain outside 0..232.
    CuriosityError
        ``cyclonedds`` is not installed, or cannot join the domain.
    """

    # what the driver reads from a link: a ROS robot has no ESTOP here, and DDS counts its own traffic
    estop = None
    stats = None

    def __init__(
        self, cmd_vel_topic: str, stamped: bool = False, domain_id: int | None = None, *, keepalive: float = 0.15,
        surprise_topic: str = SURPRISE_TOPIC, target_topic: str = TARGET_TOPIC, log=lambda event, **fields: None,
        stopped=lambda: False,
    ):
        self.topic = ros_topic(cmd_vel_topic, "cmd_vel")
        surprise_topic = ros_topic(surprise_topic, "surprise_topic")
        target_topic = ros_topic(target_topic, "target_topic")
        self.domain_id = ros_domain_id(domain_id)
        participant, types = _participant(self.domain_id, "cmd_vel", self.topic)
        from cyclonedds.pub import DataWriter
        from cyclonedds.qos import Policy, Qos
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        self._participant, self._types, self._stamped = participant, types, stamped
        twist = types.TwistStamped if stamped else types.Twist
        self.message_type = f"geometry_msgs/msg/{twist.__name__}"
        # ROS's default QoS: a best-effort writer would match no reliable subscriber, a base's usual one
        default = Qos(
            Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)), Policy.History.KeepLast(10),
            Policy.Durability.Volatile,
        )

        def writer(name: str, kind):
            return DataWriter(participant, Topic(participant, f"rt{name}", kind), qos=default)

        self._writer = writer(self.topic, twist)
        self._surprise = writer(surprise_topic, types.Float32)
        self._target = writer(target_topic, types.PointStamped)
        self._frame_topics = f"{surprise_topic} and {target_topic}"
        self._keepalive = keepalive
        self._log = log
        self._lock = threading.Lock()
        self._command: tuple[float, float, float] | None = None
        self._last_sent = time.monotonic()
        self._seq = -1
        self._error: str | None = None
        self._closing = threading.Event()
        self._stop_acked: bool | None = None
        self._stopped = stopped
        self._commanded_at = time.monotonic()
        self.subscribers = self._matched(MATCH_TIMEOUT)
        if not self.subscribers and not stopped():  # stopped: the drive's loop ends at once, by the signal
            self._participant = self._writer = self._surprise = self._target = None
            raise LinkError(
                f"cmd_vel: no subscriber of {self.topic} ({self.message_type}) within {MATCH_TIMEOUT:g} s on ROS "
                f"domain {self.domain_id} (is the robot's driver running, on this domain and network: ROS_DOMAIN_ID, "
                "CYCLONEDDS_URI?)", parameter="cmd_vel",
            )
        self._thread = threading.Thread(target=self._keep_alive, name="ros2-cmd-vel", daemon=True)
        self._thread.start()

    def _matched(self, timeout: float) -> int:
        """The subscribers of the velocity topic, once there is one or ``timeout`` s have passed."""
        deadline = time.monotonic() + timeout
        while True:
            count = self._writer.get_publication_matched_status().current_count
            if count or time.monotonic() >= deadline or self._stopped():
                return count
            time.sleep(0.02)

    # ------------------------------------------------------------------ the driver's side

    @property
    def error(self) -> str | None:
        """Why the robot cannot be steered any more (its subscriber left, a publication failed), or None."""
        with self._lock:
            return self._error

    def state(self) -> None:
        """None: a ROS robot's pose comes from its odometry (the camera's ``odom_topic``), not a STATE."""

    def ack_latency(self, seq) -> None:
        """None: a twist has no answer."""

    def command(self, surge: float, yaw_rate: float, pitch_rate: float) -> int | None:
        """Publish a velocity command; its number (from 0), or None once the robot is no longer steered."""
        with self._lock:
            if self._closing.is_set() or self._error is not None:
                return None
            if not self._writer.get_publication_matched_status().current_count:
                self._error = (
                    f"{self.topic} has no subscriber any more (the robot's driver left, or the network lost it)"
                )
                return None
            self._command = (surge, yaw_rate, pitch_rate)
            self._commanded_at = time.monotonic()
            self._publish(self._command)
            self._seq += 1
            return self._seq

    def publish_frame(self, row: dict) -> None:
        """Publish a frame's surprise and target cell, from its log record (the driver's ``frame`` row, read as
        :func:`~curiosity_cli.drive.frames_table.frame_summary` reads it); the target is stamped with the frame's
        header stamp, else its time."""
        types = self._types
        stamp = row.get("header_time_ns") or row["time_ns"]
        target_row, target_col = row["target"]
        with self._lock:
            if self._error is not None or self._closing.is_set():
                return
            try:
                self._surprise.write(types.Float32(data=frame_summary(row)["surprise"]))
                self._target.write(types.PointStamped(
                    header=types.Header(stamp=_stamp(types, stamp), frame_id=TARGET_FRAME),
                    point=types.Point(x=float(target_col), y=float(target_row)),
                ))
            except Exception as exc:  # noqa: BLE001 - cyclonedds' DDSException and its own; the drive stops on it
                self._error = f"publishing on {self._frame_topics} failed ({_one_line(exc)})"

    def close(self) -> bool:
        """Send STOP: a zero twist, :data:`STOP_REPEATS` times, once the topic has a subscriber (waiting up to
        :data:`MATCH_TIMEOUT` s for one); then leave the domain. Safe to call more than once.

        Returns
        -------
        bool
            True when every reliable subscriber acknowledged the STOP within :data:`STOP_ACK_TIMEOUT` s.
        """
        if self._stop_acked is not None:
            return self._stop_acked
        from cyclonedds.util import duration

        self._closing.set()
        self._thread.join()
        subscribers = self._matched(MATCH_TIMEOUT)
        sent = 0
        with self._lock:
            for repeat in range(STOP_REPEATS):
                if repeat:
                    time.sleep(STOP_INTERVAL)
                if self._publish((0.0, 0.0, 0.0)):
                    sent += 1
        self._stop_acked = bool(subscribers and sent and self._writer.wait_for_acks(duration(seconds=STOP_ACK_TIMEOUT)))
        self._log("stop", topic=self.topic, sent=sent, subscribers=subscribers, acknowledged=self._stop_acked)
        self._participant = self._writer = self._surprise = self._target = None
        return self._stop_acked

    # ------------------------------------------------------------------ publishing (lock held)

    def _publish(self, velocities: tuple[float, float, float]) -> bool:
        """Publish one twist; whether it went out (a failure is the robot's :attr:`error`)."""
        types = self._types
        surge, yaw_rate, pitch_rate = velocities
        # REP 103's body frame is x forward, y left, z up: a yaw to the right and a nose up are negative turns there
        # (0.0 - v, not -v: a STOP's zeros go out as +0.0, not -0.0)
        twist = types.Twist(
            linear=types.Vector3(x=float(surge)), angular=types.Vector3(y=0.0 - pitch_rate, z=0.0 - yaw_rate)
        )
        if self._stamped:
            twist = types.TwistStamped(
                header=types.Header(stamp=_stamp(types, time.time_ns()), frame_id=BODY_FRAME), twist=twist
            )
        try:
            self._writer.write(twist)
        except Exception as exc:  # noqa: BLE001 - cyclonedds' DDSException and its own
            self._error = self._error or f"publishing on {self.topic} failed ({_one_line(exc)})"
            return False
        self._last_sent = time.monotonic()
        return True

    def _keep_alive(self) -> None:
        """Publish the newest command again whenever ``keepalive`` s passed without one, until closing."""
        wait = self._keepalive
        while not self._closing.wait(wait):
            with self._lock:
                since = time.monotonic() - self._last_sent
                if since >= self._keepalive:
                    if self._command is not None and self._error is None:
                        if time.monotonic() - self._commanded_at <= STALE_AFTER:
                            self._publish(self._command)
                        elif any(self._command):  # the drive has gone quiet (its camera stalled): halt, once
                            self._command = (0.0, 0.0, 0.0)
                            self._publish(self._command)
                    since = 0.0
            wait = self._keepalive - since
