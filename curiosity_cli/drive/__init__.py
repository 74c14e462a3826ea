"""Drive a robot with live curiosity (paper section 5.2).

- :mod:`~curiosity_cli.drive.protocol`: the wire protocol (``PROTOCOL.md`` beside it):
  frames, checksum, a strict parser.
- :mod:`~curiosity_cli.drive.link`: the host side over a serial port: handshake, ACKs,
  resends, keepalive, STOP.
- :mod:`~curiosity_cli.drive.frame_words`, :mod:`~curiosity_cli.drive.stream`,
  :mod:`~curiosity_cli.drive.curiosity`, :mod:`~curiosity_cli.drive.controller`,
  :mod:`~curiosity_cli.drive.pipeline`: frame → words → topic model of the stream →
  decayed cell perplexity → target cell → velocity command.
- :mod:`~curiosity_cli.drive.camera`: OpenCV captures, the simulated camera, and an
  in-process simulated robot for dry runs.
- :mod:`~curiosity_cli.drive.sim`, :mod:`~curiosity_cli.drive.simrobot`: the simulated
  robot's motion and view, and its protocol server on a pseudo-terminal.
- :mod:`~curiosity_cli.drive.overlay`, :mod:`~curiosity_cli.drive.driver`: the paper's
  overlay, video and PNG output, and the loop that ties it together.
- :mod:`~curiosity_cli.drive.bags`, :mod:`~curiosity_cli.drive.foxglove_mcap`,
  :mod:`~curiosity_cli.drive.mcap_scan`, :mod:`~curiosity_cli.drive.odometry`: recorded
  missions as a camera, with each frame's pose.
- :mod:`~curiosity_cli.drive.mission`, :mod:`~curiosity_cli.drive.frames_table`,
  :mod:`~curiosity_cli.drive.trajectory`, :mod:`~curiosity_cli.drive.timeline`: what a drive
  leaves for Foxglove, pandas and a reader.
- :mod:`~curiosity_cli.drive.session`: what ``curiosity drive`` and ``curiosity simrobot``
  open, run and close (camera, robot, run folder and log; the pseudo-terminal).

Heavy libraries (OpenCV, pyserial, numba) are imported inside functions.
"""
