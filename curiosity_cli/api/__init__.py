"""curiosity from Python: every command as a function a notebook can call, and an experiment's results as pandas frames.

This is the one front end: each ``curiosity`` command parses its options, calls the
function of the same name here with the same defaults, and reports what it returns, so a
notebook and a terminal make the same files, byte for byte::

    from curiosity_cli import api as cur

    folder = cur.explore("quick", restarts=4).folder
    cur.label(folder)
    cur.evaluate(folder)
    results = cur.open_experiment(folder)
    results.headline                     # pandas.DataFrame
    results.run("zurich-zh17", "topic-perplexity", 0).path

A config is a shipped config's name (``quick``, ``paper-grid``), a path to a YAML file or
an :class:`~curiosity_cli.config.ExperimentConfig`; folders default to the paths table of
:mod:`curiosity_cli.paths`. Errors are :class:`~curiosity_cli.errors.CuriosityError`\\ s,
whose messages name the argument at fault; arguments that do not go together raise a
:class:`~curiosity_cli.errors.UsageError`.

=====================  ==============================================
command                function
=====================  ==============================================
``extract``            :func:`extract` (and :func:`word_store`)
``explore``            :func:`explore`
``label``              :func:`label`
``evaluate``           :func:`evaluate`
``plot``               :func:`plot`; ``--animate``: :func:`animate`
``reproduce``          :func:`reproduce` (``--measure``: one of :func:`measures`)
``drive``              :func:`drive`; ``--timeline``: :func:`redraw_timeline`
``simrobot``           :func:`simrobot`
``datasets list``      :func:`list_datasets`
``datasets show``      :func:`show_datasets`
``vocab build``        :func:`build_vocabularies`
``config show``        :func:`show_config`
``config init``        :func:`init_config`
=====================  ==============================================

:func:`load` gives a config, :func:`open_experiment` an experiment's results, :func:`open_mission` a drive's
frames. Long functions take progress callbacks (``on_stage(description, units)``, ``on_done()``);
:class:`Progress` shows them (``with cur.Progress() as p: cur.label(folder, on_stage=p.stage,
on_done=p.advance)``), and in a notebook a function given none shows its own.
"""

from __future__ import annotations

from curiosity_cli.api.configs import init_config, show_config
from curiosity_cli.api.maps import DatasetRow, Preview, build_vocabularies, list_datasets, show_datasets
from curiosity_cli.api.pipeline import (
    Config, animate, evaluate, explore, extract, label, load, measures, plot, reproduce, run_named, word_store,
)
from curiosity_cli.api.results import Results, open_experiment, verdict
from curiosity_cli.api.robot import RobotStart, drive, open_mission, redraw_timeline, simrobot
from curiosity_cli.progress import Progress

__all__ = [
    "Config", "DatasetRow", "Preview", "Progress", "Results", "RobotStart", "animate", "build_vocabularies", "drive", "evaluate",
    "explore", "extract", "init_config", "label", "list_datasets", "load", "measures", "open_experiment", "open_mission", "plot",
    "redraw_timeline",
    "reproduce", "run_named", "show_config", "show_datasets", "simrobot", "verdict", "word_store",
]
