from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
import yaml

from curiosity_cli.config import (
    CONFIG_DIR,
    COVERAGE_READINGS,
    SHIPPED_VOCABULARIES,
    ExperimentConfig,
    load_config,
    shipped_configs,
)
from curiosity_cli.config_yaml import saved_yaml, to_yaml
from curiosity_cli.errors import ConfigError
from curiosity_cli.maps.datasets import dataset_names, load_dataset_config

EXPERIMENTS = sorted(p for p in CONFIG_DIR.glob("*.yaml") if p.name != "paper.yaml")


@pytest.mark.parametrize("path", EXPERIMENTS, ids=lambda p: p.name)
def test_every_experiment_config_loads_on_top_of_paper_yaml(path):
    config = load_config(path)
    assert isinstance(config, ExperimentConfig)
    assert yaml.safe_load(path.read_text())["base"] == "paper.yaml"


def test_paper_yaml_holds_the_papers_parameters():
    config = load_config(CONFIG_DIR / "paper-grid.yaml")
    assert (config.model.topics, config.model.alpha, config.model.beta, config.model.eta) == (64, 0.1, 0.1, 0.5)
    assert config.model.spatial_neighbours == 4 and config.drive.temporal_neighbours == 2
    assert (config.words.orb_vocabulary, config.words.texton_vocabulary) == (5000, 1000)
    assert config.explore.restarts == 20 and config.explore.path_length == 320
    assert config.explore.checkpoints == (10, 20, 40, 80, 160, 320)
    assert config.explore.weight_functions[:4] == (
        "random-walk",
        "stochastic-coverage",
        "word-perplexity",
        "topic-perplexity",
    )
    assert config.explore.weight_functions[4:] == ("lawnmower", "scattered-cells", "compact-block")
    assert config.explore.coverage == "literal", "eq. 8 as written: a visited neighbour has weight 0"
    assert config.drive.gamma == 0.7
    assert config.drive.newest_share is None, "null: model.eta, eq. 6's eta read as the newest frame's share"
    assert config.datasets == ("zurich-zh17", "aerial-mosaic", "sentinel-coast", "reef-mosaic")


def test_quick_config_is_the_real_map_with_ten_restarts():
    config = load_config(CONFIG_DIR / "quick.yaml")
    assert config.datasets == ("zurich-zh17",) and config.explore.restarts == 10
    # with n pairs the smallest two-sided Wilcoxon p is 2 / 2**n: 10 pairs can show p < 0.05
    assert 2 / 2**config.explore.restarts < 0.05 and config.explore.path_length >= 80


@pytest.mark.parametrize("name", dataset_names())
def test_every_dataset_config_loads(name):
    config = load_dataset_config(CONFIG_DIR / "datasets" / f"{name}.yaml")
    assert config.name == name
    if config.generate is not None:  # drawn, no files
        assert config.image is None and config.labels is None
    elif config.fetch is None:
        assert config.image.is_file() and config.labels.is_file() and config.legend.is_file()
    else:  # made on first use, in the user's cache
        assert config.image.name == "image.png" and config.labels.name == "labels.png"
    # every map stands in for one of the paper's, but the controls (the positive control, the generated maps)
    controls = ("rare-patches", "planted-disjoint", "planted-shared")
    assert config.stands_in_for in ("Montreal1", "Montreal2", "SouthBellairs") or name in controls


def test_the_embedded_fetched_and_generated_datasets_are_registered():
    assert dataset_names() == [
        "aerial-mosaic", "geonrw-essen", "planted-disjoint", "planted-shared", "rare-patches", "reef-mosaic",
        "sentinel-coast", "zurich-zh17",
    ]
    configs = {n: load_dataset_config(CONFIG_DIR / "datasets" / f"{n}.yaml") for n in dataset_names()}
    assert [n for n, c in configs.items() if c.fetch] == ["zurich-zh17"]
    assert [n for n, c in configs.items() if c.generate] == ["planted-disjoint", "planted-shared"]


def test_overrides_apply_on_top_and_parse_yaml_values():
    config = load_config(
        CONFIG_DIR / "quick.yaml",
        ["explore.restarts=3", "model.alpha=0.5", "explore.step_seconds=0.2", "datasets=[reef-mosaic]"],
    )
    assert config.explore.restarts == 3
    assert config.model.alpha == 0.5
    assert config.explore.step_seconds == 0.2
    assert config.datasets == ("reef-mosaic",)


def test_resolved_config_reloads_to_the_same_config(tmp_path):
    config = load_config(CONFIG_DIR / "quick.yaml", ["explore.restarts=2"])
    saved = tmp_path / "resolved.yaml"
    saved.write_text(to_yaml(config))
    assert load_config(saved) == config


def test_a_saved_config_names_the_shipped_vocabularies_not_this_machines_path(tmp_path, monkeypatch):
    config = load_config(CONFIG_DIR / "quick.yaml")
    assert config.words.vocabulary_dir == SHIPPED_VOCABULARIES["shipped"] and config.words.vocabulary_dir.is_dir()
    saved = yaml.safe_load(to_yaml(config))
    assert saved["words"]["vocabulary_dir"] == "shipped"
    # another folder of vocabularies is saved as its path
    (tmp_path / "vocab").mkdir()
    own = load_config(CONFIG_DIR / "quick.yaml", [f"words.vocabulary_dir={tmp_path / 'vocab'}"])
    assert yaml.safe_load(to_yaml(own))["words"]["vocabulary_dir"] == str(tmp_path / "vocab")
    # the saved config loads from anywhere: copied to another folder and read from another cwd
    copy = tmp_path / "elsewhere" / "config.yaml"
    copy.parent.mkdir()
    copy.write_text(to_yaml(config))
    monkeypatch.chdir(tmp_path)
    assert load_config(copy) == config


def test_a_saved_config_still_loads_after_a_key_is_added_to_the_project(tmp_path):
    config = load_config(CONFIG_DIR / "quick.yaml", ["explore.restarts=2"])
    saved = tmp_path / "results" / "quick" / "config.yaml"
    saved.parent.mkdir(parents=True)
    saved.write_text(saved_yaml(config))
    assert load_config(saved) == config
    # a folder saved before explore.coverage existed (min_d2 null: eq. 8 as written) reads as literal
    data = yaml.safe_load(saved.read_text())
    del data["explore"]["coverage"]
    data["explore"]["min_d2"] = None
    saved.write_text(yaml.safe_dump(data, sort_keys=False))
    paper = yaml.safe_load((CONFIG_DIR / "paper.yaml").read_text())
    assert paper["explore"]["coverage"] == "literal"
    assert load_config(saved).explore.coverage == "literal"
    # one saved with the old clamp (min_d2 alone) is refused, never read as literal
    data["explore"]["min_d2"] = 0.25
    saved.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(ConfigError, match=r"config.yaml: explore.min_d2: got 0.25 without explore.coverage.*clamp"):
        load_config(saved)
    data["explore"]["coverage"] = "clamp"
    saved.write_text(yaml.safe_dump(data, sort_keys=False))
    assert load_config(saved).explore.min_d2 == 0.25
    # a base beside the config still comes first: a key missing from both is refused
    del data["explore"]["coverage"]
    saved.write_text(yaml.safe_dump(data, sort_keys=False))
    (saved.parent / "paper.yaml").write_text("seed: 7\n")
    with pytest.raises(ConfigError, match="missing key"):
        load_config(saved)


def test_an_int_is_accepted_where_a_number_is_expected():
    config = load_config(CONFIG_DIR / "quick.yaml", ["model.alpha=1"])
    assert config.model.alpha == 1.0 and isinstance(config.model.alpha, float)


def _experiment(tmp_path: Path, text: str) -> Path:
    """An experiment config of ``text`` and, for the keys it leaves out, a name, a seed and a map."""
    try:
        given = yaml.safe_load(text)
    except yaml.YAMLError:
        given = None
    given = given if isinstance(given, dict) else {}
    defaults = {"name": "t", "seed": "1", "datasets": "[aerial-mosaic]"}
    head = "".join(f"{key}: {value}\n" for key, value in defaults.items() if key not in given)
    path = tmp_path / "exp.yaml"
    path.write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\n{head}{text}")
    return path


@pytest.mark.parametrize(
    "text, message",
    [
        ("explore:\n  restart: 3\n", "exp.yaml: explore.restart: unknown key; expected one of weight_functions"),
        ("explore:\n  restarts: twenty\n", "exp.yaml: explore.restarts: got 'twenty' (str), expected an integer >= 1"),
        ("explore:\n  restarts: 0\n", "exp.yaml: explore.restarts: got 0 (int), expected an integer >= 1"),
        ("explore:\n  restarts: 2.5\n", "exp.yaml: explore.restarts: got 2.5 (float), expected an integer >= 1"),
        ("model:\n  eta: 1.5\n", "exp.yaml: model.eta: got 1.5 (float), expected a number >= 0 and <= 1"),
        ("model:\n  alpha: 0\n", "exp.yaml: model.alpha: got 0 (int), expected a number > 0"),
        ("model:\n  alpha: .nan\n", "exp.yaml: model.alpha: got nan (float), expected a finite number > 0"),
        ("model:\n  spatial_neighbours: 8\n", "exp.yaml: model.spatial_neighbours: got 8 (int), expected one of 0, 4"),
        ("words:\n  colour_words: 1\n", "exp.yaml: words.colour_words: got 1 (int), expected true or false"),
        ("drive:\n  gamma: 1.0\n", "exp.yaml: drive.gamma: got 1.0 (float), expected a number >= 0 and < 1"),
        ("drive:\n  newest_share: 1.5\n", "exp.yaml: drive.newest_share: got 1.5 (float), expected a number >= 0 and <= 1"),
        ("drive:\n  newest_share: -0.1\n", "exp.yaml: drive.newest_share: got -0.1 (float), expected a number >= 0 and <= 1"),
        ("drive:\n  newest_share: half\n", "exp.yaml: drive.newest_share: got 'half' (str), expected a finite number >= 0"),
        ("explore:\n  weight_functions: [random-walk, curious]\n", "exp.yaml: explore.weight_functions[1]: got 'curious'"),
        ("explore:\n  weight_functions: [random-walk, random-walk]\n", "expected each weight function once"),
        ("explore:\n  weight_functions: []\n", "exp.yaml: explore.weight_functions: got [] (list), expected a non-empty list"),
        ("explore:\n  checkpoints: [20, 10]\n", "exp.yaml: explore.checkpoints: got [20, 10], expected increasing"),
        ("explore:\n  checkpoints: [10, 640]\n", "no longer than explore.path_length (320)"),
        ("model: 3\n", "exp.yaml: model: got 3 (int), expected a mapping of keys"),
        ("seed: -1\n", "exp.yaml: seed: got -1 (int), expected an integer >= 0"),
        ("name: 'a b'\n", "exp.yaml: name: got 'a b' (str), expected 1 to 120 letters, digits, '-', '_' or '.'"),
        ("name: ../escaped\n", "exp.yaml: name: got '../escaped' (str), expected 1 to 120 letters"),
        (f"name: {'n' * 300}\n", "exp.yaml: name: got 'nnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnn... (str), expected 1 to 120"),
        ("explore:\n  checkpoints: []\n", "explore.checkpoints: got [] (list), expected a non-empty list of integers"),
        ("seed: 4294967296\n", "exp.yaml: seed: got 4294967296 (int), expected an integer >= 0 and <= 4294967295"),
        ("datasets: [no-such-map]\n", "exp.yaml: datasets[0]: no dataset 'no-such-map': expected one of aerial-mosaic"),
    ],
)
def test_a_bad_experiment_config_names_file_key_value_and_expectation(tmp_path, text, message):
    with pytest.raises(ConfigError) as info:
        load_config(_experiment(tmp_path, text))
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_a_missing_key_is_named(tmp_path):
    path = tmp_path / "exp.yaml"
    path.write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\nname: t\ndatasets: [aerial-mosaic]\n")
    with pytest.raises(ConfigError, match=r"exp\.yaml: seed: missing key; an experiment config names its name, seed, "
                       r"datasets \(its base holds only parameters\), e\.g\. seed: 0$"):
        load_config(path)
    path.write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\nname: t\nseed: 0\ndatasets: [aerial-mosaic]\nexplore: {{}}\n")
    load_config(path)  # the parameters come from the base
    path.write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\nname: t\nseed: 0\ndatasets: [aerial-mosaic]\nmodel: {{topicz: 3}}\n")
    with pytest.raises(ConfigError, match=r"exp\.yaml: model\.topicz: unknown key"):
        load_config(path)  # a key of neither is refused as before


def test_an_error_in_a_base_file_names_the_base_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "base.yaml").write_text((CONFIG_DIR / "paper.yaml").read_text().replace("topics: 64", "topics: 500"))
    path = tmp_path / "exp.yaml"
    path.write_text("base: base.yaml\nname: t\nseed: 0\ndatasets: [aerial-mosaic]\n")
    with pytest.raises(ConfigError, match=r"^base\.yaml: model\.topics: got 500 \(int\), expected an integer >= 2 and <= 127$"):
        load_config(path)


@pytest.mark.parametrize(
    "text, message",
    [
        ("base: missing.yaml\n", "exp.yaml: base: file not found: missing.yaml"),
        ("base: exp.yaml\n", "exp.yaml: base: the chain of base configs loops back here"),
        ("name: [unclosed\n", "exp.yaml: not valid YAML (line 2)"),
        ("- a list\n", "exp.yaml: expected a mapping of keys at the top level, got list"),
    ],
)
def test_a_broken_config_file_is_refused_in_one_line(tmp_path, monkeypatch, text, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "exp.yaml").write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(tmp_path / "exp.yaml")
    assert message in str(info.value) and "\n" not in str(info.value)


def test_a_missing_config_file_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    shipped = ", ".join(shipped_configs())
    assert {"paper", "paper-grid", "quick", "readings"} <= set(shipped_configs())
    message = f"nope.yaml: config file not found; expected a path to a YAML config or the name of a shipped one ({shipped})"
    with pytest.raises(ConfigError, match="^" + re.escape(message) + "$"):
        load_config("nope.yaml")


def test_a_bad_override_names_the_argument(tmp_path):
    with pytest.raises(ConfigError, match=r"^overrides: explore\.restarts: got -2 \(int\), expected an integer >= 1 and <= 10000$") as bad:
        load_config(CONFIG_DIR / "quick.yaml", ["explore.restarts=-2"])
    assert bad.value.parameter == "overrides"
    with pytest.raises(ConfigError, match=r"^overrides 'restarts': expected KEY=VALUE") as malformed:
        load_config(CONFIG_DIR / "quick.yaml", ["restarts"])
    assert malformed.value.parameter == "overrides"
    with pytest.raises(ConfigError, match=r"^overrides 'seed': ") as not_yaml:
        load_config(CONFIG_DIR / "quick.yaml", ["seed=[1"])
    assert not_yaml.value.parameter == "overrides"
    with pytest.raises(ConfigError, match=r"exp\.yaml: explore\.restarts: got -2") as in_a_file:
        load_config(_experiment(tmp_path, "explore:\n  restarts: -2\n"))
    assert in_a_file.value.parameter is None


def test_a_dataset_yaml_missing_its_image_is_refused(own_map):
    from small_maps import edit_yaml

    edit_yaml(own_map, image="gone.png")
    with pytest.raises(ConfigError, match=r"own\.yaml: image: file not found: .*gone\.png$"):
        load_dataset_config(own_map)


def test_a_dataset_with_labels_needs_a_legend(own_map):
    from small_maps import edit_yaml

    edit_yaml(own_map, legend=None)
    with pytest.raises(ConfigError, match=r"own\.yaml: legend: missing; a dataset with labels needs a legend"):
        load_dataset_config(own_map)


def test_a_dataset_path_entry_is_stored_absolute(own_map, tmp_path):
    path = tmp_path / "exp.yaml"
    path.write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\nname: t\nseed: 0\ndatasets: [own.yaml, aerial-mosaic]\n")
    config = load_config(path)
    assert config.datasets == (str(own_map), "aerial-mosaic")
    assert dataclasses.replace(config) == config


# --- ORB keys of words (issue 13) ------------------------------------------------------


def test_orb_words_default_to_every_keypoint_at_opencvs_threshold():
    from curiosity_cli.config import load_words_config

    words = load_words_config(CONFIG_DIR / "paper.yaml")
    assert (words.orb_per_tile, words.orb_fast_threshold, words.orb_fill_threshold) == (None, 20, None)
    capped = load_words_config(
        CONFIG_DIR / "paper.yaml", ["words.orb_per_tile=2", "words.orb_fill_threshold=1", "words.orb_fast_threshold=30"]
    )
    assert (capped.orb_per_tile, capped.orb_fast_threshold, capped.orb_fill_threshold) == (2, 30, 1)


@pytest.mark.parametrize(
    "text, message",
    [
        ("words:\n  orb_per_tile: 0\n", "exp.yaml: words.orb_per_tile: got 0 (int), expected an integer >= 1"),
        ("words:\n  orb_fast_threshold: 0\n", "exp.yaml: words.orb_fast_threshold: got 0 (int), expected an integer >= 1 and <= 255"),
        ("words:\n  orb_fast_threshold: 256\n", "exp.yaml: words.orb_fast_threshold: got 256 (int), expected an integer >= 1"),
        ("words:\n  orb_fast_threshold: null\n", "exp.yaml: words.orb_fast_threshold: got None (NoneType), expected an integer"),
        ("words:\n  orb_per_tile: 2\n  orb_fill_threshold: 0\n", "exp.yaml: words.orb_fill_threshold: got 0 (int), expected an integer >= 1"),
        (
            "words:\n  orb_fill_threshold: 1\n",
            "exp.yaml: words.orb_fill_threshold: got 1, expected null when words.orb_per_tile is null",
        ),
        (
            "words:\n  orb_per_tile: 2\n  orb_fill_threshold: 21\n",
            "exp.yaml: words.orb_fill_threshold: got 21, expected an integer between 1 and words.orb_fast_threshold (20)",
        ),
    ],
)
def test_bad_orb_keys_are_refused_naming_the_key(tmp_path, text, message):
    from curiosity_cli.config import load_words_config

    path = _experiment(tmp_path, text)
    for load in (load_config, load_words_config):
        with pytest.raises(ConfigError) as info:
            load(path)
        assert message in str(info.value) and "\n" not in str(info.value)


def test_orb_words_default_to_keypoints_and_the_grid_is_a_named_value():
    from curiosity_cli.config import load_words_config

    words = load_words_config(CONFIG_DIR / "paper.yaml")
    assert (words.orb_detector, words.orb_grid_step) == ("keypoints", 1)
    grid = load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_detector=grid", "words.orb_grid_step=4"])
    assert (grid.orb_detector, grid.orb_grid_step) == ("grid", 4)


@pytest.mark.parametrize(
    "text, message",
    [
        ("words:\n  orb_detector: dense\n", "exp.yaml: words.orb_detector: got 'dense' (str), expected one of keypoints, grid"),
        ("words:\n  orb_grid_step: 0\n", "exp.yaml: words.orb_grid_step: got 0 (int), expected an integer >= 1"),
        ("words:\n  orb_grid_step: null\n", "exp.yaml: words.orb_grid_step: got None (NoneType), expected an integer"),
        (
            "words:\n  orb_detector: grid\n  orb_per_tile: 2\n",
            "exp.yaml: words.orb_per_tile: got 2, expected null when words.orb_detector is grid",
        ),
        (
            "words:\n  orb_detector: grid\n  orb_max_features: 50\n",
            "exp.yaml: words.orb_max_features: got 50, expected null when words.orb_detector is grid",
        ),
        (
            "words:\n  orb_detector: grid\n  orb_fill_threshold: 1\n",
            "exp.yaml: words.orb_fill_threshold: got 1, expected null when words.orb_per_tile is null",
        ),
    ],
)
def test_bad_grid_orb_keys_are_refused_naming_the_key(tmp_path, text, message):
    from curiosity_cli.config import load_words_config

    path = _experiment(tmp_path, text)
    for load in (load_config, load_words_config):
        with pytest.raises(ConfigError) as info:
            load(path)
        assert message in str(info.value) and "\n" not in str(info.value)


def test_a_grid_with_a_tile_cap_is_refused_on_the_command_line():
    from curiosity_cli.config import load_words_config

    with pytest.raises(ConfigError, match=r"^overrides: words\.orb_per_tile: got 2, expected null when words\.orb_detector is grid"):
        load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_detector=grid", "words.orb_per_tile=2"])


def test_a_top_up_without_a_tile_cap_is_refused_on_the_command_line():
    from curiosity_cli.config import load_words_config

    with pytest.raises(ConfigError, match=r"^overrides: words\.orb_fill_threshold: got 1, expected null when words\.orb_per_tile is null"):
        load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_fill_threshold=1"])


@pytest.mark.parametrize("text, value", [("1e-3", 1e-3), ("1E1", 10.0), ("2.5e0", 2.5), (".5", 0.5), ("5.", 5.0)])
def test_the_float_forms_people_type_are_numbers(text, value):
    config = load_config(CONFIG_DIR / "quick.yaml", [f"drive.surge_cruise={text}"])
    assert config.drive.surge_cruise == value
    # read as the number it is, then held to its bounds
    with pytest.raises(ConfigError, match=r"^overrides: drive\.surge_cruise: got -0\.5 \(float\), expected a number >= 0"):
        load_config(CONFIG_DIR / "quick.yaml", ["drive.surge_cruise=-.5"])


def test_the_newest_frames_share_is_a_share_of_the_budget_or_null():
    assert load_config(CONFIG_DIR / "quick.yaml", ["drive.newest_share=0.25"]).drive.newest_share == 0.25
    assert load_config(CONFIG_DIR / "quick.yaml", ["drive.newest_share=1"]).drive.newest_share == 1.0
    assert load_config(CONFIG_DIR / "quick.yaml", ["drive.newest_share=null"]).drive.newest_share is None
    with pytest.raises(ConfigError, match=r"^overrides: drive\.newest_share: got 2 \(int\), expected a number >= 0 and <= 1$"):
        load_config(CONFIG_DIR / "quick.yaml", ["drive.newest_share=2"])


def test_a_string_that_reads_as_a_float_is_saved_quoted(tmp_path):
    config = load_config(CONFIG_DIR / "quick.yaml", ["name='1e5'"])
    saved = tmp_path / "resolved.yaml"
    saved.write_text(to_yaml(config))
    assert load_config(saved) == config and config.name == "1e5"


def test_the_converged_schedule_sets_its_two_label_keys_and_refuses_a_clash():
    from curiosity_cli.config import with_converged_labels

    config = load_config(CONFIG_DIR / "quick.yaml", with_converged_labels(["seed=3"]))
    assert (config.label.sweeps, config.label.warm_sweeps, config.seed) == (256, None, 3)
    with pytest.raises(ConfigError, match=r"'label.warm_sweeps=4': the converged schedule sets label.sweeps=256 and "
                                          r"label.warm_sweeps=null; give either, not both"):
        with_converged_labels(["label.warm_sweeps=4"])


@pytest.mark.parametrize(
    "text, message",
    [
        ("explore:\n  coverage: clamped\n", "exp.yaml: explore.coverage: got 'clamped'"),
        ("explore:\n  coverage: clamp\n  min_d2: null\n", "exp.yaml: explore.min_d2: got null, expected a number > 0"),
        (
            "explore:\n  min_d2: 0.5\n",
            "exp.yaml: explore.min_d2: got 0.5 without explore.coverage; the reading of eq. 8 is now named there "
            f"(one of {', '.join(COVERAGE_READINGS)}): add explore.coverage: clamp",
        ),
    ],
)
def test_bad_readings_of_eq_8_are_refused_naming_the_key(tmp_path, text, message):
    with pytest.raises(ConfigError) as info:
        load_config(_experiment(tmp_path, text))
    assert message in str(info.value) and "\n" not in str(info.value)


def test_each_reading_is_one_value_and_the_floor_counts_only_where_the_reading_reads_it():
    for reading in COVERAGE_READINGS.values():
        config = load_config(CONFIG_DIR / "quick.yaml", [f"explore.coverage={reading.name}"])
        assert config.explore.coverage == reading.name and config.explore.min_d2 == 0.25
        assert ("min_d2" in config.explore.run_settings()) == reading.reads_min_d2
    clamp = load_config(CONFIG_DIR / "quick.yaml", ["explore.coverage=clamp", "explore.min_d2=0.5"])
    assert clamp.explore.run_settings()["min_d2"] == 0.5
    # a floor on the command line without a reading is the old syntax: refused, naming the option
    with pytest.raises(ConfigError, match=r"^overrides: explore.min_d2: got 0.5 without explore.coverage"):
        load_config(CONFIG_DIR / "quick.yaml", ["explore.min_d2=0.5"])


@pytest.mark.parametrize("key, value, bound", [
    ("explore.candidate_sweeps", 10**12, 1000),
    ("explore.samples_per_step", 2**63, 100000000),
    ("explore.restarts", 10**6, 10000),
    ("explore.path_length", 10**9, 100000),
    ("label.sweeps", 10**20, 100000),
    ("label.warm_sweeps", 10**6, 100000),
    ("label.batch_sweeps", 10**20, 100000),
    ("drive.samples_per_frame", 10**23, 100000000),
])
def test_every_count_has_a_bound_that_the_command_line_names(key, value, bound):
    """A count beyond its bound is refused before anything runs (issue 44: runs that never ended, numba overflows)."""
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    result = CliRunner().invoke(app, ["config", "show", "quick", "--set", f"{key}={value}"])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert f"--set: {key}: got {value} (int), expected an integer >= " in result.stderr
    assert f"and <= {bound}" in result.stderr


@pytest.mark.parametrize(
    "override, message",
    [  # issue 63's hostile cases: each hung, overflowed or ended in a traceback deep inside a run
        ("explore.step_seconds=1e308", "explore.step_seconds: got 1e+308 (float), expected a number > 0 and <= 3600"),
        ("model.alpha=1e308", "model.alpha: got 1e+308 (float), expected a number > 0 and <= 1000"),
        ("words.orb_tile=1e23", "words.orb_tile: got 1e+23 (float), expected an integer >= 1 and <= 16384"),
        ("drive.hello_timeout=1e308", "drive.hello_timeout: got 1e+308 (float), expected a number > 0 and <= 3600"),
        ("drive.sim_frame_interval=1e308", "drive.sim_frame_interval: got 1e+308 (float), expected a number >= 0 and <= 3600"),
        ("drive.baud=99999999999", "drive.baud: got 99999999999 (int), expected an integer >= 1 and <= 12000000"),
        ("drive.ack_timeout=1e308", "drive.ack_timeout: got 1e+308 (float), expected a number > 0 and <= 3600"),
        # the wire protocol wants a host frame every 200 ms; the robot never backs up
        ("drive.keepalive=0.5", "drive.keepalive: got 0.5 (float), expected a number > 0 and <= 0.2"),
        ("drive.surge_min=-1", "drive.surge_min: got -1 (int), expected a number >= 0 and <= 10"),
    ],
)
def test_every_number_has_an_upper_bound_named_in_its_error(override, message):
    with pytest.raises(ConfigError) as info:
        load_config(CONFIG_DIR / "quick.yaml", [override])
    assert str(info.value) == f"overrides: {message}"


def test_a_key_given_twice_is_refused_not_the_last_taken():
    with pytest.raises(ConfigError, match=r"^overrides: seed is given twice \(seed=1, seed=2\); give each key once$"):
        load_config(CONFIG_DIR / "quick.yaml", ["seed=1", "seed=2"])
    with pytest.raises(ConfigError, match=r"^overrides: drive.gamma is given twice \(drive=\{gamma: 0.5\}, drive.gamma=0.6\)"):
        load_config(CONFIG_DIR / "quick.yaml", ["drive={gamma: 0.5}", "drive.gamma=0.6"])


def test_an_empty_config_and_one_that_is_no_regular_file_are_named_as_such(tmp_path):
    """Issue 64: an empty config said "model: got None"; a config linked to /dev/zero said "not found"."""
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    with pytest.raises(ConfigError, match=r"empty.yaml: empty; expected a YAML config, e.g. base: paper.yaml"):
        load_config(empty)
    device = tmp_path / "zero.yaml"
    device.symlink_to("/dev/zero")
    with pytest.raises(ConfigError, match=r": not a regular file \(a folder, a device or a pipe\); expected a YAML config file$"):
        load_config(device)
