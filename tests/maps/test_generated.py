"""Generated maps: drawn the same for the same seed, words that agree with their truth, the YAML's one-line errors,
their stores, and the pipeline end to end on one."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
import yaml
from small_maps import TINY_GENERATE, edit_yaml, write_generated_map
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.config import CONFIG_DIR, load_words_config
from curiosity_cli.errors import ConfigError, ParameterError
from curiosity_cli.maps.cell_classes import classes_present, map_class_pixels
from curiosity_cli.label.sampling import pixel_words
from curiosity_cli.maps.datasets import load_dataset_config
from curiosity_cli.maps.generated import draw_topics, generate_map
from curiosity_cli.maps.generative_spec import GenerativeSpec
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.words.extract import extract_words, store_name

runner = CliRunner()

TINY = GenerativeSpec(**TINY_GENERATE)


def test_the_same_seed_draws_the_same_map_and_another_seed_another():
    first, again = generate_map(TINY, 8, 2), generate_map(TINY, 8, 2)
    for field in ("classes", "phi", "words", "pixel_rows", "pixel_cols", "labels"):
        assert np.array_equal(getattr(first, field), getattr(again, field)), field
    other = generate_map(dataclasses.replace(TINY, seed=2), 8, 2)
    assert not np.array_equal(first.words, other.words)


def test_maps_that_differ_in_overlap_share_their_layout():
    shared = generate_map(dataclasses.replace(TINY, overlap=0.8), 8, 2)
    assert np.array_equal(shared.classes, generate_map(TINY, 8, 2).classes)


def test_the_truth_is_background_regions_with_rare_patches_over_them():
    spec = dataclasses.replace(TINY, rows=12, cols=12, patch_cells=2)
    drawn = generate_map(spec, 8, 2)
    counts = np.bincount(drawn.classes, minlength=4)
    # each rare topic: its patches of 2 x 2 cells, no more; the background the rest
    assert counts[2:].tolist() == [2 * 4, 2 * 4] and counts[:2].sum() == 144 - 16 and (counts[:2] > 0).all()
    # every pixel takes its cell's class
    assert np.array_equal(drawn.labels[::8, ::8].ravel(), drawn.classes) and drawn.labels.shape == (96, 96)
    assert [name for name, _, _ in drawn.legend] == ["background-1", "background-2", "rare-1", "rare-2"]
    assert len({colour for _, colour, _ in drawn.legend}) == 4


@pytest.mark.parametrize("overlap", [0.0, 0.5, 1.0])
def test_every_word_of_a_cell_is_in_its_topic_s_support(overlap):
    spec = dataclasses.replace(TINY, overlap=overlap)
    supports, phi = draw_topics(spec)
    drawn = generate_map(spec, 8, 2)
    cells = np.repeat(np.arange(spec.rows * spec.cols), 16)
    in_support = np.zeros((len(supports), spec.vocabulary), bool)
    for k, support in enumerate(supports):
        in_support[k, support] = True
    assert in_support[drawn.classes[cells], drawn.words].all()
    assert np.allclose(phi.sum(axis=1), 1) and (phi[~in_support] == 0).all()
    background_words = np.concatenate(supports[: spec.background_topics])
    for support in supports[spec.background_topics :]:
        assert np.isin(support, background_words).sum() == round(overlap * spec.support)


def test_words_sit_on_the_stride_s_lattice_of_their_own_cell():
    drawn = generate_map(TINY, 8, 2)
    cells = np.repeat(np.arange(TINY.rows * TINY.cols), 16)
    assert np.array_equal((drawn.pixel_rows // 8) * TINY.cols + drawn.pixel_cols // 8, cells)
    assert (drawn.pixel_rows % 2 == 0).all() and (drawn.pixel_cols % 2 == 0).all()


def test_a_generated_map_loads_with_its_truth_as_labels(tmp_path):
    m = load_map(write_generated_map(tmp_path))
    assert m.image.shape == (64, 80, 3) and m.labels.shape == (64, 80) and m.grid.shape == (8, 10)
    assert [c.id for c in m.legend] == [0, 1, 2, 3] and m.n_classes == 4
    # a patch cell is wholly its rare class: found by the 10 % rule the moment a path steps on it
    present = classes_present(map_class_pixels(m), 10)
    assert present.sum(axis=1).tolist() == [1] * 80 and present[:, 2:].sum() == 4


def test_its_store_is_drawn_cached_and_named_by_its_spec_alone(tmp_path):
    m = load_map(write_generated_map(tmp_path))
    words = load_words_config(CONFIG_DIR / "paper.yaml")
    made = extract_words(m, words, cache_dir=tmp_path / "cache")
    store = made.store
    assert not made.reused and [t.kind for t in store.types] == ["generated"] and store.vocabulary_size == 60
    drawn = generate_map(m.config.generate, 8, 2)
    for cell in range(80):
        assert sorted(store.cell_words(cell).tolist()) == sorted(drawn.words[16 * cell : 16 * cell + 16].tolist())
    assert extract_words(m, words, cache_dir=tmp_path / "cache").reused
    assert made.path.name == store_name(m, words)[0]
    # the words settings make none of its words: the store's name does not change with them
    orb = dataclasses.replace(words, orb_per_tile=3)
    assert store_name(m, orb) == store_name(m, words)
    other = load_map(edit_yaml(tmp_path / "tiny-generated.yaml", generate={**TINY_GENERATE, "overlap": 0.5}))
    assert store_name(other, words)[0] != store_name(m, words)[0]
    # every pixel takes the label of a word of its own cell
    at = pixel_words(store, (64, 80))
    pixel_rows, pixel_cols = np.indices((64, 80))
    assert np.array_equal(
        store.grid.cells_of_pixels(store.rows[at], store.cols[at]), store.grid.cells_of_pixels(pixel_rows, pixel_cols)
    )
    with pytest.raises(ParameterError, match="^stride: got 4, but tiny-generated is a generated map"):
        extract_words(m, words, stride=4, cache_dir=tmp_path / "cache")


def test_the_shipped_generated_maps_differ_only_in_overlap():
    disjoint, shared = load_dataset_config(CONFIG_DIR / "datasets" / "planted-disjoint.yaml"), load_dataset_config(
        CONFIG_DIR / "datasets" / "planted-shared.yaml")
    assert dataclasses.replace(shared.generate, overlap=0.0) == disjoint.generate
    assert disjoint.generate.rare_topics >= 8 and (disjoint.generate.overlap, shared.generate.overlap) == (0.0, 0.8)
    assert disjoint.image is None and disjoint.cell_width == 16


def _refusal(tmp_path, **changes) -> str:
    path = write_generated_map(tmp_path)
    data = yaml.safe_load(path.read_text())
    for key, value in changes.items():
        if key.startswith("generate."):
            data["generate"][key.split(".", 1)[1]] = value
        else:
            data[key] = value
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as caught:
        load_dataset_config(path)
    message = str(caught.value)
    assert "\n" not in message and "tiny-generated.yaml: " in message
    return message.split("tiny-generated.yaml: ", 1)[1]


@pytest.mark.parametrize(("changes", "expected"), [
    ({"generate.rows": 1}, "generate.rows: got 1 (int), expected an integer >= 2"),
    ({"generate.overlap": 1.5}, "generate.overlap: got 1.5 (float), expected a number >= 0 and <= 1"),
    ({"generate.beta": 0}, "generate.beta: got 0 (int), expected a number > 0"),
    ({"generate.rare_topics": "many"}, "generate.rare_topics: got 'many' (str), expected an integer >= 1 and <= 64"),
    ({"generate.colour": "red"}, "generate.colour: unknown key; expected one of seed, rows, cols"),
    ({"generate": [1, 2]}, "generate: got [1, 2] (list), expected a mapping of keys"),
    ({"size": [64, 80]}, "size: a generated map draws its words and truth; leave size out"),
    ({"image": "not-there.png"}, "image: a generated map draws its words and truth; leave image out"),
    ({"word_stride": 3}, "word_stride: got 3 with cells of 8 px, expected a divisor of the cell width"),
    ({"generate.vocabulary": 30}, "generate.vocabulary: got 30, expected at least 40: 2 background topics x 10 words "
     "and 2 rare topics x 10 words of their own (0 shared with the background at overlap 0)"),
    ({"generate.patches_per_topic": 20}, "generate.patches_per_topic: 2 rare topics x 20 patches of 1 x 1 cells, "
     "1 cells apart, do not fit in 8 x 10 cells"),
    ({"generate.background_topics": 10, "generate.rows": 2, "generate.cols": 4, "generate.vocabulary": 1000},
     "generate.background_topics: got 10, expected at most the grid's 8 cells"),
    # every cell its own region: the patches cover two background topics' only cells
    ({"generate.background_topics": 16, "generate.rows": 2, "generate.cols": 8, "generate.patches_per_topic": 1,
      "generate.vocabulary": 1000}, "generate.background_topics: background topic "),
])
def test_a_bad_generate_value_is_one_line_naming_file_key_and_expectation(tmp_path, changes, expected):
    assert _refusal(tmp_path, **changes).startswith(expected)


@pytest.mark.slow
def test_explore_label_and_evaluate_run_on_a_generated_map(tmp_path):
    own = write_generated_map(tmp_path)
    config = {
        "base": str(CONFIG_DIR / "paper.yaml"), "name": "generated", "seed": 0, "datasets": [str(own)],
        "model": {"topics": 8},
        "explore": {"weight_functions": ["random-walk", "topic-perplexity"], "restarts": 2, "path_length": 12,
                    "checkpoints": [5, 12], "samples_per_step": 2000},
        "label": {"sweeps": 2, "warm_sweeps": 1, "batch_sweeps": 4},
    }
    (tmp_path / "generated.yaml").write_text(yaml.safe_dump(config))
    common = ["--jobs", "1", "--cache-dir", str(tmp_path / "cache")]
    folder = tmp_path / "results" / "generated"
    result = runner.invoke(app, ["explore", str(tmp_path / "generated.yaml"), *common, "--results-dir", str(tmp_path / "results")])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["label", str(folder), *common])
    assert result.exit_code == 0, result.output
    assert "labelled 4 runs" in result.stdout
    result = runner.invoke(app, ["evaluate", str(folder)])
    assert result.exit_code == 0, result.output
    mi = pd.read_csv(folder / "mi.csv")
    assert len(mi) == 2 * 2 * 2 and (mi["classes"] == 4).all() and mi["mi_human"].ge(0).all()
