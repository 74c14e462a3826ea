"""Exploration on a map's cell grid: weight functions, one walker's run, the experiment grid.

- :mod:`~curiosity_cli.explore.weights`: the paper's four weight functions (and where to add one);
- :mod:`~curiosity_cli.explore.walker`: one run, learning a topic model online along its path;
- :mod:`~curiosity_cli.explore.runs`: a run's folder on disk, written atomically, read back;
- :mod:`~curiosity_cli.explore.grid`: maps x weight functions x restarts, parallel and resumable.
"""
