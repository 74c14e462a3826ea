"""A study's record (``reproduce --record``): seeds kept, taken instead of computed, the same bytes as computing
them again, and refused when made otherwise or edited."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from small_maps import tiny_yaml
from test_specifications import study_yaml
from test_sweep import sweep

from curiosity_cli import api
from curiosity_cli.errors import UsageError
from curiosity_cli.study.record import RECORD_FILE, RUNS, TABLES, RecordError, run_fingerprints, same_runs

#: One specification keeps the study small; the record's layout does not depend on how many.
ONE = {"default": {}}
#: The tables a computation writes again with other bytes: when, by which command and commit.
STAMPED = {"provenance.yaml"}


def _recorded(record: Path) -> list[str]:
    return sorted(str(p.relative_to(record)) for p in record.glob("seed-*/*") if p.is_dir())


@pytest.mark.slow
def test_a_study_keeps_its_seeds_takes_them_later_and_they_are_the_bytes_computing_them_again_gives(own_map, tmp_path):
    config = study_yaml(own_map, tmp_path, ONE)
    record = tmp_path / "studies" / "tiny"
    first = sweep(config, tmp_path / "first", "--record", str(record))
    assert first.exit_code == 0, first.output
    assert _recorded(record) == ["seed-1/default", "seed-2/default"]
    for folder in record.glob("seed-*/default"):
        assert sorted(p.name for p in folder.iterdir()) == sorted([*TABLES, RUNS, RECORD_FILE]), "labels not kept"
    kept = yaml.safe_load((record / "seed-1" / "default" / RECORD_FILE).read_text())
    assert kept["recipes"]["grid"] == {"weight_functions": ["random-walk", "stochastic-coverage", "topic-perplexity"], "restarts": 2}
    assert set(kept["recipes"]["maps"]["own"]) == {"run", "batch", "label"}

    # a later run adds seed 3: seeds 1 and 2 are taken, not explored again
    later = sweep(config, tmp_path / "later", "--record", str(record), "--sweep", "seed=1,2,3")
    assert later.exit_code == 0, later.output
    assert later.stderr.count("(taken from ") == 2
    folder = tmp_path / "later" / "tiny-sweep"
    assert sorted(p.name for p in folder.iterdir() if p.is_dir()) == ["specification-default_seed-3"]
    assert _recorded(record) == ["seed-1/default", "seed-2/default", "seed-3/default"]
    report = (folder / "SWEEP.md").read_text()
    assert f"Record `{record}`: 2 of 3 combinations taken from it" in report
    assert f"--record {record} --sweep seed=1,2,3\n" in report, "the command to run it again keeps the record"

    # every seed computed again from nothing, record or shared labels aside: the same bytes
    again = sweep(config, tmp_path / "again", "--sweep", "seed=1,2,3", "--no-reuse")
    assert again.exit_code == 0, again.output
    computed = tmp_path / "again" / "tiny-sweep"
    for seed in (1, 2, 3):
        for name in set(TABLES) - STAMPED:
            assert (computed / f"specification-default_seed-{seed}" / name).read_bytes() == (
                record / f"seed-{seed}" / "default" / name
            ).read_bytes(), (seed, name)
    for name in ("specifications.csv", "specifications-batch.csv"):
        assert (folder / name).read_bytes() == (computed / name).read_bytes(), f"{name}: the pooled curve"

    # the record pins the runs a new measure would need: those computed again are the recorded ones, run by run
    seed_1, again_1 = record / "seed-1" / "default", computed / "specification-default_seed-1"
    assert same_runs(seed_1, again_1) is None
    runs = run_fingerprints(again_1)
    assert list(runs.columns) == ["dataset", "weight_function", "restart", "cells", "phi_80"]
    assert len(runs) == 3 * 2 and runs["cells"].str.split().map(len).tolist() == [80] * 6
    assert same_runs(record / "seed-2" / "default", again_1).startswith("own/random-walk/0: its path is not the recorded one")


@pytest.mark.slow
def test_a_record_made_otherwise_or_edited_is_refused_naming_the_difference_before_anything_runs(own_map, tmp_path):
    config = study_yaml(own_map, tmp_path, ONE)
    record = tmp_path / "record"
    assert sweep(config, tmp_path / "first", "--record", str(record), "--sweep", "seed=1").exit_code == 0
    seed = record / "seed-1" / "default"

    other = sweep(config, tmp_path / "other", "--record", str(record), "--sweep", "seed=1", "--set", "label.sweeps=9")
    assert other.exit_code == 1
    assert other.output.strip().splitlines()[-1] == (
        f"Error: {seed}: recorded from another recipe than the study gives now "
        "(own's label recipe: label.sweeps was 2, now 9); remove it to compute it again, or give another --record folder"
    )
    assert not (tmp_path / "other").exists(), "refused before anything is written"

    mi, table = seed / "mi.csv", (seed / "mi.csv").read_text()
    mi.write_text(table.replace(",", ";", 1))  # the same size: found by its digest
    edited = sweep(config, tmp_path / "edited", "--record", str(record), "--sweep", "seed=1")
    assert edited.exit_code == 1 and f"Error: {mi}: not the table that was recorded (" in edited.output
    mi.write_text(table)

    kept = (seed / RECORD_FILE).read_text()
    written = yaml.safe_load(kept)
    # a record that lists no tables would let an edited one pass: refused, as any record not in its form
    for broken in ({**written, "tables": {}}, {**written, "tables": "oops"}, {**written, "recipes": "garbage"}, [1, 2]):
        (seed / RECORD_FILE).write_text(yaml.safe_dump(broken))
        refused = sweep(config, tmp_path / "broken", "--record", str(record), "--sweep", "seed=1")
        assert refused.exit_code == 1, refused.output
        assert refused.output.strip().splitlines()[-1].startswith(f"Error: {seed}/{RECORD_FILE}: expected a mapping of tables")
    (seed / RECORD_FILE).write_text(kept)

    # a folder recorded before runs.csv was kept is still taken: it has only no runs to check a recomputation against
    (seed / RUNS).unlink()
    (seed / RECORD_FILE).write_text(yaml.safe_dump({**written, "tables": {k: v for k, v in written["tables"].items() if k != RUNS}}))
    older = sweep(config, tmp_path / "older", "--record", str(record), "--sweep", "seed=1")
    assert older.exit_code == 0 and older.stderr.count("(taken from ") == 1, older.output
    with pytest.raises(RecordError, match="recorded before runs were kept"):
        same_runs(seed, tmp_path / "first" / "tiny-sweep" / "specification-default_seed-1")

    (seed / "headline.csv").unlink()
    missing = sweep(config, tmp_path / "missing", "--record", str(record), "--sweep", "seed=1")
    assert missing.exit_code == 1 and f"Error: {seed}: an incomplete record (no headline.csv)" in missing.output


def test_only_a_study_of_seeds_keeps_a_record(own_map, tmp_path):
    config = study_yaml(own_map, tmp_path, ONE)
    swept = sweep(config, tmp_path / "results", "--record", str(tmp_path / "record"), "--sweep", "model.topics=4,5")
    assert swept.exit_code == 1 and "declares sweeps model.topics" in swept.output
    (tmp_path / "file").write_text("")
    refused = sweep(config, tmp_path / "results", "--record", str(tmp_path / "file"))
    assert refused.exit_code == 1 and "expected a folder, found a file" in refused.output
    (tmp_path / "plain").mkdir()
    plain = tiny_yaml(own_map, tmp_path / "plain")
    with pytest.raises(UsageError, match="^record: keeps a study's seeds"):
        api.reproduce(plain, record=tmp_path / "record", results_dir=tmp_path / "r", cache_dir=tmp_path / "c")
    assert not (tmp_path / "r").exists() and not (tmp_path / "record").exists()


def test_a_record_folder_that_cannot_be_written_is_refused_before_anything_is_computed(own_map, tmp_path):
    """Issue 63: a read-only or looping --record folder failed only after the first combination was computed."""
    config = study_yaml(own_map, tmp_path, ONE)
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    refused = sweep(config, tmp_path / "results", "--record", str(loop), "--sweep", "seed=1")
    assert refused.exit_code == 1 and f"Error: --record {loop}: cannot be written (" in refused.output, refused.output
    assert not (tmp_path / "results" / "tiny-sweep" / "specification-default_seed-1").exists()


@pytest.mark.slow
def test_another_study_s_record_is_named_as_such_and_not_offered_for_removal(own_map, tmp_path):
    from small_maps import edit_yaml, write_own_map

    record = tmp_path / "record"
    assert sweep(study_yaml(own_map, tmp_path, ONE), tmp_path / "first", "--record", str(record), "--sweep", "seed=1").exit_code == 0
    (tmp_path / "second").mkdir()
    other_map = edit_yaml(write_own_map(tmp_path / "second"), name="elsewhere")
    other = study_yaml(other_map, tmp_path / "second", ONE)
    refused = sweep(other, tmp_path / "results", "--record", str(record), "--sweep", "seed=1")
    assert refused.exit_code == 1
    line = refused.output.strip().splitlines()[-1]
    assert line == (
        f"Error: {record / 'seed-1' / 'default'}: a record of the maps own, not this study's (elsewhere): another "
        "study's record, perhaps; give this study's own --record folder"
    )
    assert "remove it" not in line and (record / "seed-1" / "default" / "mi.csv").is_file()
