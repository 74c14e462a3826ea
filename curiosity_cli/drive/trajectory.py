"""Where a mission went, coloured by what it found surprising: ``trajectory.png``.

Drawn from the frames table (:mod:`~curiosity_cli.drive.frames_table`): each frame with a
pose is a point at its x, y in its pose's frame of reference, coloured by its surprise
(the mean topic perplexity of its image cells), joined in time order, from a start
marker to an end marker. A mission whose frames have no pose gets no figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: The figure's file in a run folder.
TRAJECTORY_FILE = "trajectory.png"


def write_trajectory(folder: Path, table) -> Path | None:
    """Write ``folder/trajectory.png`` from a frames table; its path, or None when no frame has a pose.

    Parameters
    ----------
    folder : Path
        The run folder.
    table : DataFrame
        :func:`~curiosity_cli.drive.frames_table.frames_table` of its log.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from curiosity_cli.files import atomic_path

    posed = table[table["x"].notna() & table["y"].notna()]
    if posed.empty:
        return None
    x, y = posed["x"].to_numpy(np.float64), posed["y"].to_numpy(np.float64)
    surprise = posed["surprise"].to_numpy(np.float64)
    frames = sorted(set(posed["pose_frame"].dropna()))
    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(x, y, color="0.75", linewidth=0.8, zorder=1)
    points = ax.scatter(x, y, c=surprise, cmap="viridis", s=12, zorder=2)
    ax.scatter(x[:1], y[:1], marker="o", s=80, facecolors="none", edgecolors="black", zorder=3, label="start")
    ax.scatter(x[-1:], y[-1:], marker="s", s=80, facecolors="none", edgecolors="black", zorder=3, label="end")
    fig.colorbar(points, ax=ax, label="surprise (mean topic perplexity of the frame's cells)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x (m, frame {', '.join(frames) or 'unknown'})")
    ax.set_ylabel("y (m)")
    missing = len(table) - len(posed)
    ax.set_title(
        f"{len(posed)} frames with a pose" + (f", {missing} without (not drawn)" if missing else ""), fontsize=10
    )
    ax.legend(loc="best", fontsize=8)
    path = Path(folder) / TRAJECTORY_FILE
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=150, format="png")
    return path
