"""Issue 16: the config loaders on arbitrary input raise only the project's own errors.

Any YAML document, any mapping of the keys a config has to any values, and any ``--set``
text either loads or is refused with a :class:`CuriosityError` (one line for the CLI);
nothing else may escape.
"""

from __future__ import annotations

import dataclasses
import typing
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from curiosity_cli.config import CONFIG_DIR, ExperimentConfig, load_config
from curiosity_cli.maps.datasets import DatasetConfig, load_dataset_config
from curiosity_cli.errors import CuriosityError

FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

#: Scalars a YAML document holds, and strings that look like paths, names or numbers.
SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=20),
    st.sampled_from(["", ".", "..", "/", "~", "~nobody-here/x", "a\x00b", "../../x", "aerial-mosaic", "1e5", "-.5"]),
)
VALUES = st.recursive(
    SCALARS, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=12,
)


def _keys(cls) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def _section_keys() -> list[str]:
    """Every dotted key of an experiment config: ``seed``, ``model.alpha``, …"""
    keys = []
    for name, tp in typing.get_type_hints(ExperimentConfig).items():
        keys += [f"{name}.{k}" for k in _keys(tp)] if dataclasses.is_dataclass(tp) else [name]
    return keys


def _refused_or_loaded(load, *args) -> None:
    try:
        load(*args)
    except CuriosityError as exc:
        assert "\n" not in str(exc)


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.slow
@FUZZ
@given(text=st.text(max_size=200))
def test_any_text_as_a_config_or_a_dataset_yaml(tmp_path, text):
    _refused_or_loaded(load_config, _write(tmp_path, "e.yaml", text))
    _refused_or_loaded(load_dataset_config, _write(tmp_path, "d.yaml", text))


@pytest.mark.slow
@FUZZ
@given(document=VALUES)
def test_any_yaml_document_as_a_config_or_a_dataset_yaml(tmp_path, document):
    text = yaml.safe_dump(document)
    _refused_or_loaded(load_config, _write(tmp_path, "e.yaml", text))
    _refused_or_loaded(load_dataset_config, _write(tmp_path, "d.yaml", text))


@pytest.mark.slow
@FUZZ
@given(changes=st.dictionaries(st.sampled_from(_section_keys()), VALUES, max_size=4))
@example(changes={"words.vocabulary_dir": "~nobody-here/x"})
@example(changes={"words.vocabulary_dir": "a\x00b"})
def test_any_values_for_an_experiment_configs_keys(tmp_path, changes):
    document = {"base": str(CONFIG_DIR / "paper.yaml"), "name": "f", "seed": 0, "datasets": ["aerial-mosaic"]}
    for key, value in changes.items():
        section, _, leaf = key.partition(".")
        if leaf:
            document.setdefault(section, {})[leaf] = value
        else:
            document[section] = value
    _refused_or_loaded(load_config, _write(tmp_path, "e.yaml", yaml.safe_dump(document)))


@pytest.mark.slow
@FUZZ
@given(key=st.sampled_from(_section_keys()) | st.text(max_size=12), text=st.text(max_size=40))
def test_any_set_override(key, text):
    _refused_or_loaded(load_config, CONFIG_DIR / "quick.yaml", [f"{key}={text}"])


@pytest.mark.slow
@FUZZ
@given(document=st.dictionaries(st.sampled_from(_keys(DatasetConfig)), VALUES, max_size=6))
@example(document={"name": "f", "cell_width": 16, "word_stride": 1, "image": "~nobody-here/x"})
@example(document={"name": "f", "cell_width": 16, "word_stride": 1, "image": "a\x00b"})
def test_any_values_for_a_dataset_yamls_keys(tmp_path, document):
    _refused_or_loaded(load_dataset_config, _write(tmp_path, "d.yaml", yaml.safe_dump(document)))
