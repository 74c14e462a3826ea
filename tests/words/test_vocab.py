from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.config import CONFIG_DIR, load_words_config
from curiosity_cli.words.vocab import (
    SOURCE_IMAGES,
    build_texton_vocabulary,
    load_vocabulary,
    save_vocabulary,
)

WORDS = load_words_config(CONFIG_DIR / "paper.yaml")
MAP_SOURCES = {"grass", "gravel", "brick", "immunohistochemistry"}  # SKIMAGE_PHOTOS in scripts/embedded_maps/sources.py


def test_shipped_vocabularies_load_with_their_recipes():
    orb = load_vocabulary(WORDS.vocabulary_dir, "orb", 5000)
    texton = load_vocabulary(WORDS.vocabulary_dir, "texton", 1000)
    assert orb.centres.shape == (5000, 32) and orb.centres.dtype == np.uint8
    assert texton.centres.shape == (1000, 8) and texton.centres.dtype == np.float32
    for vocabulary in (orb, texton):
        assert vocabulary.recipe["size"] == len(vocabulary.centres)
        assert vocabulary.recipe["source_images"] == [f"skimage.data.{n}" for n in SOURCE_IMAGES]
    # no two ORB words alike, no two textons alike: every word is usable
    assert len(np.unique(orb.centres, axis=0)) == 5000 and len(np.unique(texton.centres, axis=0)) == 1000


def test_vocabulary_sources_are_unrelated_to_the_maps():
    assert not MAP_SOURCES & set(SOURCE_IMAGES)


def test_vocabulary_round_trips(tmp_path):
    texton = load_vocabulary(WORDS.vocabulary_dir, "texton", 1000)
    path = save_vocabulary(texton, tmp_path)
    assert path.name == "texton-1000.npz"
    again = load_vocabulary(tmp_path, "texton", 1000)
    assert again.sha256 == texton.sha256 and again.recipe == texton.recipe


@pytest.mark.slow
def test_texton_vocabulary_build_is_seeded(monkeypatch):
    import curiosity_cli.words.vocab as vocab

    monkeypatch.setattr(vocab, "SOURCE_IMAGES", ("camera", "coins"))
    monkeypatch.setattr(vocab, "TEXTON_SAMPLES_PER_IMAGE", 2000)
    a = build_texton_vocabulary(20, seed=5)
    b = build_texton_vocabulary(20, seed=5)
    assert a.sha256 == b.sha256 and a.centres.shape == (20, 8)
    assert build_texton_vocabulary(20, seed=6).sha256 != a.sha256


@pytest.mark.slow
def test_a_vocabulary_built_by_the_same_recipe_is_kept_so_a_stopped_build_goes_on(monkeypatch, tmp_path):
    import curiosity_cli.words.vocab as vocab
    from curiosity_cli import api

    monkeypatch.setattr(vocab, "SOURCE_IMAGES", ("camera", "coins"))
    monkeypatch.setattr(vocab, "TEXTON_SAMPLES_PER_IMAGE", 2000)
    save_vocabulary(build_texton_vocabulary(2, seed=0), tmp_path)  # a build stopped after its texton words
    texton = tmp_path / "texton-2.npz"
    stamp = texton.stat().st_mtime_ns
    lines = []
    written = api.build_vocabularies(tmp_path, orb_words=2, texton_words=2, log=lines.append)
    assert [path.name for path, _ in written] == ["texton-2.npz", "orb-2.npz"]
    assert lines[0].startswith("kept ") and "texton-2.npz, built by the same recipe" in lines[0]
    assert texton.stat().st_mtime_ns == stamp and not [line for line in lines if "texton:" in line]
    assert [line for line in lines if "orb: clustering" in line]

    def clustered(seed: int) -> list[str]:
        lines.clear()
        api.build_vocabularies(tmp_path, orb_words=2, texton_words=2, seed=seed, log=lines.append)
        return [line.split(":")[0].strip() for line in lines if ": clustering" in line]

    orb = tmp_path / "orb-2.npz"
    orb.write_bytes(orb.read_bytes()[: orb.stat().st_size // 2])
    assert clustered(0) == ["orb"]  # a file cut short is no vocabulary: built again
    assert clustered(1) == ["texton", "orb"]  # another seed is another recipe
    assert load_vocabulary(tmp_path, "texton", 2).recipe["seed"] == 1


@pytest.mark.slow
def test_shipped_vocabularies_are_rebuilt_bit_for_bit_from_their_recipe(tmp_path):
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    result = CliRunner().invoke(app, ["vocab", "build", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    for kind, size in (("orb", 5000), ("texton", 1000)):
        rebuilt = load_vocabulary(tmp_path, kind, size)
        assert rebuilt.sha256 == load_vocabulary(WORDS.vocabulary_dir, kind, size).sha256
