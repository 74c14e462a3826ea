"""Label files and batch references shared between experiments: taken, not computed, when what they
depend on is the same; the same bytes either way; an altered copy named and computed again; safe
when two experiments store one item at once."""

from __future__ import annotations

import dataclasses
import threading
from pathlib import Path

import numpy as np
import pytest
from small_maps import grid_config
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.explore.grid import run_grid
from curiosity_cli.label.shared_items import BATCH, LABELS, SHARED_FOLDER, SharedItems
from curiosity_cli.label.stage import label_experiment

runner = CliRunner()


def explored(own_map: Path, tmp_path: Path, name: str, **explore):
    """The small grid under ``name``, explored; the config and its folder."""
    config = dataclasses.replace(grid_config(own_map, **explore), name=name)
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    return config, tmp_path / name


def label_bytes(folder: Path) -> dict[str, bytes]:
    """Every label file, example map and batch reference of an experiment, by path in the folder."""
    files = [*folder.glob("labels/**/*.npz"), *folder.glob("batch/*.npz")]
    return {str(path.relative_to(folder)): path.read_bytes() for path in files}


@pytest.mark.slow
def test_a_second_experiment_takes_every_item_and_its_files_are_the_bytes_computing_gives(own_map, tmp_path):
    config, first = explored(own_map, tmp_path, "first")
    done = label_experiment(config, first, cache_dir=tmp_path / "cache", jobs=1)
    assert done["shared"] == {"labels": 0, "batches": 0} and done["labelled"] == 8
    shared = tmp_path / "cache" / SHARED_FOLDER
    assert len(list((shared / LABELS).glob("*.npz"))) == 8 and len(list((shared / BATCH).glob("*.npz"))) == 1

    # the same settings under another name: nothing computed, the same files
    config, second = explored(own_map, tmp_path, "second")
    done = label_experiment(config, second, cache_dir=tmp_path / "cache", jobs=1)
    assert done["shared"] == {"labels": 8, "batches": 1} and done["labelled"] == 8
    assert label_bytes(second) == label_bytes(first)

    # computed again without the shared items: the same bytes but the batch reference's seconds
    taken = label_bytes(second)
    result = runner.invoke(app, ["label", str(second), "--force", "--no-reuse", "--jobs", "1", "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 0, result.output
    assert "taken from other experiments' shared items: 0 label files, 0 batch references" in result.stdout
    computed = label_bytes(second)
    assert {k: v for k, v in computed.items() if not k.startswith("batch/")} == {
        k: v for k, v in taken.items() if not k.startswith("batch/")
    }
    with np.load(second / "batch" / "own.npz") as again, np.load(first / "batch" / "own.npz") as before:
        for name in ("labels", "word_labels", "log_likelihood"):
            assert np.array_equal(again[name], before[name])


@pytest.mark.slow
def test_a_comparator_whose_specification_changes_only_topic_perplexity_takes_its_labels(own_map, tmp_path):
    config, first = explored(own_map, tmp_path, "default")
    label_experiment(config, first, cache_dir=tmp_path / "cache", jobs=1)
    # counts-only P(k | path) changes topic perplexity's scores, and so its path; the other walkers read none of it
    config, second = explored(own_map, tmp_path, "counts", path_topics="counts")
    done = label_experiment(config, second, cache_dir=tmp_path / "cache", jobs=1)
    assert done["shared"] == {"labels": 6, "batches": 1}, "3 comparators x 2 restarts taken; topic perplexity computed"
    for walker in ("random-walk", "stochastic-coverage", "word-perplexity"):
        for path in sorted((second / "labels" / "own" / walker).glob("*.npz")):
            with np.load(path) as taken, np.load(first / path.relative_to(second)) as computed:
                assert all(np.array_equal(taken[k], computed[k]) for k in computed.files if k != "meta")
    # each file records its own experiment's recipe, not the one that first computed its labels; the report says it
    for command in (["evaluate", str(second), "--cache-dir", str(tmp_path / "cache")], ["plot", str(second)]):
        result = runner.invoke(app, command)
        assert result.exit_code == 0, result.output
    assert (
        "The last `label` that labelled anything took 6 of its 8 label files and 1 batch references from other "
        "experiments" in (second / "REPORT.md").read_text()
    )


@pytest.mark.slow
def test_an_altered_shared_item_is_named_and_computed_again(own_map, tmp_path, capsys):
    config, first = explored(own_map, tmp_path, "first")
    label_experiment(config, first, cache_dir=tmp_path / "cache", jobs=1)
    items = sorted((tmp_path / "cache" / SHARED_FOLDER / LABELS).glob("*.npz"))
    damaged = items[3]
    data = bytearray(damaged.read_bytes())
    data[len(data) // 2] ^= 0xFF
    damaged.write_bytes(bytes(data))
    capsys.readouterr()
    config, second = explored(own_map, tmp_path, "second")
    done = label_experiment(config, second, cache_dir=tmp_path / "cache", jobs=1)
    assert done["shared"]["labels"] == 7 and done["labelled"] == 8
    assert f"{damaged.name}: altered since it was stored (its digest is not its name's); computing it again" in capsys.readouterr().err
    assert label_bytes(second) == label_bytes(first)
    assert len(list(damaged.parent.glob("*.npz"))) == 8, "the altered copy was replaced by the one computed again"


@pytest.mark.slow
def test_a_whole_item_under_another_run_s_key_is_named_removed_and_computed_again(own_map, tmp_path, capsys):
    """A label file stored under another run's name, its digest its own, was taken for that run without a word
    (issue 63: one run's MI 0.746 -> 0.985 bits); each item holds the key it was made for."""
    config, first = explored(own_map, tmp_path, "first")
    label_experiment(config, first, cache_dir=tmp_path / "cache", jobs=1)
    items = sorted((tmp_path / "cache" / SHARED_FOLDER / LABELS).glob("*.npz"))
    source, victim = items[0], items[5]
    victim_key = victim.name.split(".")[0]
    swapped = victim.parent / f"{victim_key}.{source.name.split('.')[1]}.npz"
    victim.unlink()
    swapped.write_bytes(source.read_bytes())
    capsys.readouterr()
    config, second = explored(own_map, tmp_path, "second")
    done = label_experiment(config, second, cache_dir=tmp_path / "cache", jobs=1)
    assert done["shared"]["labels"] == 7 and done["labelled"] == 8
    assert f"{swapped.name}: made for another run's labels; computing it again" in capsys.readouterr().err
    assert label_bytes(second) == label_bytes(first)
    assert not swapped.exists() and len(list(victim.parent.glob(f"{victim_key}.*.npz"))) == 1


@pytest.mark.slow
def test_force_computes_every_item_again_and_stores_it(own_map, tmp_path):
    config, first = explored(own_map, tmp_path, "first")
    label_experiment(config, first, cache_dir=tmp_path / "cache", jobs=1)
    config, second = explored(own_map, tmp_path, "second")
    assert label_experiment(config, second, cache_dir=tmp_path / "cache", jobs=1)["shared"] == {"labels": 8, "batches": 1}
    taken = label_bytes(second)
    result = runner.invoke(app, ["label", str(second), "--force", "--jobs", "1", "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 0, result.output
    assert "taken from other experiments' shared items: 0 label files, 0 batch references" in result.stdout
    computed = label_bytes(second)
    assert {k: v for k, v in computed.items() if not k.startswith("batch/")} == {
        k: v for k, v in taken.items() if not k.startswith("batch/")
    }
    assert len(list((tmp_path / "cache" / SHARED_FOLDER / LABELS).glob("*.npz"))) == 8, "one item a run, as before"


def test_a_cache_whose_shared_items_cannot_be_written_is_refused_before_any_labelling(own_map, tmp_path):
    """Issue 63: a cache folder that is a file (or read-only) was reported after all the labelling."""
    config, first = explored(own_map, tmp_path, "first")
    (tmp_path / "cache" / SHARED_FOLDER).write_text("not a folder")
    result = runner.invoke(app, ["label", str(first), "--jobs", "1", "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 1
    assert f"Error: {tmp_path / 'cache' / SHARED_FOLDER}: cannot be written (" in result.output, result.output
    assert "--no-reuse to label without them" in result.output
    assert not list((first / "labels").glob("**/*.npz")), "refused before any labelling"
    done = runner.invoke(app, ["label", str(first), "--jobs", "1", "--no-reuse", "--cache-dir", str(tmp_path / "cache")])
    assert done.exit_code == 0, done.output


def test_items_of_a_cache_from_before_keys_are_computed_again_once_named_once(tmp_path, capsys):
    shared = SharedItems(tmp_path)
    arrays = {"lengths": np.arange(3, dtype=np.int32)}

    def old_format(tmp):  # as every item was stored before items held their key
        with open(tmp, "wb") as handle:
            np.savez_compressed(handle, **arrays)

    for key in ("a" * 32, "b" * 32):
        shared._keep(LABELS, key, old_format)
    capsys.readouterr()
    assert shared.labels("a" * 32) is None and shared.labels("b" * 32) is None
    assert capsys.readouterr().err.count("stored before shared items held the key they were made for") == 1
    assert not list((tmp_path / SHARED_FOLDER / LABELS).glob("*.npz"))
    shared.keep_labels("a" * 32, arrays, {})
    found = shared.labels("a" * 32)
    assert found is not None and set(found[0]) == {"lengths"}, "the key is not one of the label arrays"


def test_two_writers_of_one_item_leave_one_whole_file(tmp_path):
    shared = SharedItems(tmp_path)
    arrays = {"lengths": np.arange(3, dtype=np.int32), "batch": np.random.default_rng(0).integers(0, 9, (3, 8, 8))}
    examples = {12: np.ones((4, 4), np.int16)}
    errors = []

    def keep() -> None:
        try:
            for _ in range(20):
                shared.keep_labels("k" * 32, arrays, examples)
                found = shared.labels("k" * 32)
                assert found is not None and np.array_equal(found[0]["batch"], arrays["batch"])
        except Exception as exc:  # noqa: BLE001 - any failure of a writer fails the test below
            errors.append(exc)

    threads = [threading.Thread(target=keep) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors
    assert [p.name.startswith("k" * 32 + ".") for p in (tmp_path / SHARED_FOLDER / LABELS).iterdir()] == [True]


def test_a_batch_reference_that_fails_is_named_and_nothing_is_kept_of_it(own_map, tmp_path, monkeypatch):
    """A batch reference whose task raised stops its map's runs with a named line, not a KeyError."""
    import curiosity_cli.label.batch_references as batch_references
    import pytest

    from curiosity_cli.label.stage import LabelError

    def failing(task, config, store=None, *, threads=1):
        raise RuntimeError("out of memory")

    monkeypatch.setattr(batch_references, "batch_task", failing)
    config, folder = explored(own_map, tmp_path, "first")
    # one worker: the batch reference runs before the blocks, in this process's loky worker (which imports the patch)
    with pytest.raises(LabelError, match=r"the batch reference of own: RuntimeError: out of memory; its runs were not labelled"):
        label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1, backend="loky")
    assert not (tmp_path / "cache" / SHARED_FOLDER / BATCH).exists() or not list((tmp_path / "cache" / SHARED_FOLDER / BATCH).iterdir())
