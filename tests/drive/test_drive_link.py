"""The host's link through real pseudo-terminals: handshake, ACKs, resends, bad lines, ESTOP."""

from __future__ import annotations

import time

import pytest
from pty_robot import PATIENCE, PtyRobot, polite

from curiosity_cli.drive import protocol
from curiosity_cli.drive.link import LinkError, LinkTiming, RobotLink
from curiosity_cli.drive.protocol import Ack, Estop, Hello, Nak, Ping, State, Stop, Vel

# Generous answer time where the test is not about timing: a loaded machine must not
# turn a slow thread switch into a lost link.
RELAXED = LinkTiming(hello_timeout=PATIENCE, ack_timeout=0.5, resends=3, keepalive=0.15)
STRICT = LinkTiming(hello_timeout=2.0, ack_timeout=0.1, resends=3, keepalive=0.15)


@pytest.fixture
def robots():
    started = []

    def start(respond=polite):
        robot = PtyRobot(respond)
        started.append(robot)
        return robot

    yield start
    for robot in started:
        robot.close()


def events():
    logged = []
    return logged, lambda event, **fields: logged.append((event, fields))


def test_handshake_then_commands_flow_with_acks(robots):
    robot = robots()
    link = RobotLink.open(robot.port, 115200, RELAXED)
    assert link.robot_name == "pty-robot"
    seqs = []
    for i in range(5):
        seqs.append(link.command(0.1 * i, -0.2, 0.05))
        assert robot.wait_for(lambda: link.ack_latency(seqs[-1]) is not None)
    assert link.close() is True
    frames = robot.frames()
    assert frames[0] == Hello(0, 1)
    vels = [f for f in frames if isinstance(f, Vel)]
    assert [v.seq for v in vels] == seqs and vels[3] == Vel(seqs[3], 0.3, -0.2, 0.05)
    assert isinstance(frames[-1], Stop) and link.stats.acked == link.stats.sent
    assert all(link.ack_latency(s) > 0 for s in seqs)


def test_an_idle_host_keeps_the_robot_fed_with_pings(robots):
    robot = robots()
    link = RobotLink.open(robot.port, 115200, RELAXED)
    assert robot.wait_for(lambda: len(robot.frames(Ping)) >= 3)
    link.close()


def test_a_frame_without_ack_is_resent_three_times_then_the_link_is_lost_and_stop_sent(robots):
    robot = robots(lambda f: [] if isinstance(f, Vel) else polite(f))
    logged, log = events()
    link = RobotLink.open(robot.port, 115200, STRICT, log=log)
    seq = link.command(0.3, 0.0, 0.0)
    assert robot.wait_for(lambda: link.error is not None)
    assert link.error == "no ACK for VEL 1 after 4 transmissions 100 ms apart: link lost"
    assert [f.seq for f in robot.frames(Vel)] == [seq] * 4
    assert robot.wait_for(lambda: robot.frames(Stop))
    assert [e for e, _ in logged].count("resend") == 3 and logged[-1][0] == "link-lost"
    assert link.command(0.3, 0.0, 0.0) is None  # a lost link commands nothing more
    link.close()


def test_a_lost_ack_is_made_good_by_a_resend(robots):
    seen = set()

    def forgetful(frame):
        if isinstance(frame, Vel) and frame.seq not in seen:
            seen.add(frame.seq)
            return []  # the first ACK of every VEL is lost
        return polite(frame)

    robot = robots(forgetful)
    link = RobotLink.open(robot.port, 115200, STRICT)
    for _ in range(3):
        seq = link.command(0.2, 0.1, 0.0)
        assert robot.wait_for(lambda: link.ack_latency(seq) is not None)
    assert link.error is None and link.stats.resent >= 3
    assert link.close() is True


@pytest.mark.slow
def test_a_robot_that_never_answers_hello_is_refused_and_stopped(robots):
    robot = robots(lambda frame: [])
    start = time.monotonic()
    with pytest.raises(LinkError, match="the robot did not answer HELLO within 2 s"):
        RobotLink.open(robot.port, 115200, STRICT)
    assert time.monotonic() - start >= 2.0
    assert [f.seq for f in robot.frames(Hello)] == [0] * 4  # sent, then resent 3 times
    assert robot.wait_for(lambda: robot.frames(Stop))


def test_a_hello_reply_lost_after_its_ack_is_made_good_by_a_resend(robots):
    replies = []

    def reply_lost_once(frame):
        if isinstance(frame, Hello):
            replies.append(frame.seq)
            return [Ack(frame.seq)] if len(replies) == 1 else polite(frame)
        return polite(frame)

    robot = robots(reply_lost_once)
    logged, log = events()
    link = RobotLink.open(robot.port, 115200, STRICT, log=log)
    assert link.robot_name == "pty-robot" and replies == [0, 0]  # the same HELLO, resent once
    assert (link.stats.sent, link.stats.resent, link.stats.acked) == (1, 1, 1)  # one frame, ACKed (twice)
    assert [f for e, f in logged if e == "resend"] == [{"seq": 0, "frame": "HELLO"}]
    seq = link.command(0.1, 0.0, 0.0)
    assert seq == 1 and robot.wait_for(lambda: link.ack_latency(seq) is not None)
    assert link.close() is True


def test_a_robot_of_another_protocol_version_is_refused(robots):
    robot = robots(lambda f: [Ack(f.seq), Hello(f.seq, 2, "future")] if isinstance(f, Hello) else polite(f))
    with pytest.raises(LinkError, match="the robot speaks protocol version 2; this host speaks version 1"):
        RobotLink.open(robot.port, 115200, RELAXED)


def test_a_port_that_does_not_exist_is_a_one_line_error(tmp_path):
    with pytest.raises(LinkError, match=f"serial port {tmp_path}/ttyNONE: cannot open it"):
        RobotLink.open(str(tmp_path / "ttyNONE"), 115200, RELAXED)


def test_corrupt_lines_are_counted_and_never_acted_on(robots):
    robot = robots()
    logged, log = events()
    link = RobotLink.open(robot.port, 115200, RELAXED, log=log)
    good = protocol.encode(State(1, 1.0, 2.0, 3.0, 0.5, 0.0))
    decoy_state = protocol.encode(State(2, 1.1, 9999.0, 9999.0, 0.5, 0.0))
    decoy_estop = protocol.encode(Estop(3, "DECOY"))
    robot.send(
        good,
        decoy_state[:-3] + b"00\n",  # wrong checksum
        decoy_estop.replace(b"DECOY", b"DECOX"),  # payload changed, checksum kept
        b"\x00\xff garbage \x13\n",
        decoy_estop[:9] + b"\n",  # truncated
        b"$ACK,999999*00\n",
    )
    assert robot.wait_for(lambda: link.stats.refused_lines == 5)
    assert link.state() == State(1, 1.0, 2.0, 3.0, 0.5, 0.0)
    assert link.estop is None and link.error is None
    reasons = [fields["reason"] for event, fields in logged if event == "refused"]
    assert reasons == ["BAD_CHECKSUM", "BAD_CHECKSUM", "NO_DOLLAR", "NO_CHECKSUM", "BAD_CHECKSUM"]
    link.close()


def test_a_nak_is_logged_and_the_frame_not_resent(robots):
    robot = robots(lambda f: [Nak(f.seq, "TOO_FAST")] if isinstance(f, Vel) else polite(f))
    logged, log = events()
    link = RobotLink.open(robot.port, 115200, STRICT, log=log)
    link.command(5.0, 0.0, 0.0)
    assert robot.wait_for(lambda: link.stats.naks == 1)
    assert ("nak", {"seq": 1, "reason": "TOO_FAST", "frame": "VEL"}) in logged
    assert len(robot.frames(Vel)) == 1 and link.error is None
    link.close()


def test_on_estop_the_host_stops_commanding(robots):
    robot = robots()
    link = RobotLink.open(robot.port, 115200, RELAXED)
    seq = link.command(0.3, 0.0, 0.0)
    # Once the VEL is answered nothing is left to resend, so a frame the robot reads
    # after the ESTOP can only be one the host sent knowing of it.
    assert robot.wait_for(lambda: link.ack_latency(seq) is not None)
    robot.send(Estop(7, "LEAK"))
    assert robot.wait_for(lambda: link.estop is not None)
    assert link.estop == Estop(7, "LEAK")
    assert link.command(0.3, 0.0, 0.0) is None
    time.sleep(0.2)  # a keepalive already on the wire when the ESTOP arrived lands now
    before = len(robot.frames())
    time.sleep(0.5)  # several keepalive periods: no PING or VEL may follow an ESTOP
    assert not any(isinstance(f, (Ping, Vel)) for f in robot.frames()[before:])
    assert link.close() is True and isinstance(robot.frames()[-1], Stop)


def test_a_robot_that_disconnects_ends_the_link_with_an_error(robots):
    robot = robots()
    link = RobotLink.open(robot.port, 115200, RELAXED)
    robot.close()  # both ends of the pty closed: the host's port is gone
    assert robot.wait_for(lambda: link.error is not None)
    assert link.error.startswith("the robot disconnected")
    assert link.close() is False
