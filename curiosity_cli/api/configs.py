"""The config commands as functions: ``config show`` and ``config init``."""

from __future__ import annotations

import typing
from pathlib import Path


def show_config(config: str | Path, overrides: typing.Iterable[str] = ()) -> str:
    """``curiosity config show``: a config validated and resolved (base files and ``overrides`` applied), as
    YAML, every key, as a run saves it; a base that names no experiment (``paper``), its parameter sections.
    As :func:`curiosity_cli.config.show_config`; and the vocabularies it names are there (a ``CuriosityError``
    naming the file that is not)."""
    from curiosity_cli.api.arguments import name_or_path, overrides_argument
    from curiosity_cli.config import load_words_config
    from curiosity_cli.config import show_config as shown
    from curiosity_cli.words.kinds import WordRecipe

    config, overrides = name_or_path(config, "config"), overrides_argument(overrides)
    text = shown(config, overrides)
    # the vocabularies it names must be there, as explore needs them (the config layer cannot know their files)
    WordRecipe(load_words_config(config, [o for o in overrides if o.split("=", 1)[0].startswith("words.")]))
    return text + _study(config, overrides)


def _study(config: str | Path, overrides: typing.Iterable[str]) -> str:
    """For a config that declares a sweep or specifications: every experiment it makes checked
    (as ``reproduce`` would, before it runs), and what they are, as YAML comments after the config."""
    from curiosity_cli.config import HYPOTHESES_KEY, SPECIFICATIONS_KEY, SWEEP_KEY
    from curiosity_cli.study.hypotheses import declared_hypotheses
    from curiosity_cli.study.specifications import declared_specifications, study_size
    from curiosity_cli.study.sweep import declared_sweeps, parse_sweeps, plan_sweep
    from curiosity_cli.study.types import count

    sweeps, specifications = declared_sweeps(config), declared_specifications(config)
    if not sweeps and not specifications:
        declared_hypotheses(config, (), ())  # refuses hypotheses without the specifications they name
        return ""
    sweep = plan_sweep(config, parse_sweeps(sweeps, list(overrides)), list(overrides), specifications, declared=[
        text.partition("=")[0] for text in sweeps
    ])
    size = f" ({study_size(sweep)})" if specifications else ""
    lines = [
        f"`curiosity reproduce` runs {count(len(sweep.combinations), 'experiment')}{size}: the config above with "
        "the overrides of each, as checked here",
        *(f"  {SWEEP_KEY}: {axis.key} = {', '.join(axis.values)}" for axis in sweep.axes),
        *(f"  {SPECIFICATIONS_KEY}: {s.name}: {', '.join(s.overrides) or '(none: the config as it is)'}" for s in specifications),
        *(
            f"  {HYPOTHESES_KEY}: {h.name} ({'primary' if h.primary else 'secondary'}): {h.claim} ({h.specification}, "
            f"{h.measure} at {h.path_length}, seeds {', '.join(map(str, h.seeds))})" for h in sweep.hypotheses
        ),
    ]
    return "".join(f"# {line}\n" for line in lines)


def init_config(name: str, source: str = "quick", folder: Path = Path(".")) -> Path:
    """``curiosity config init``: an editable, commented copy of the shipped config ``source`` written to
    ``folder/NAME.yaml``; returns its path. As :func:`curiosity_cli.config.init_config`."""
    from curiosity_cli.api.arguments import folder_argument, name_or_path
    from curiosity_cli.config import init_config as initialised

    return initialised(name_or_path(name, "name"), name_or_path(source, "source"), folder_argument(folder))
