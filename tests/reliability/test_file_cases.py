"""Issue 16, files, OS errors and corrupt inputs: each is one clean line, or redone with a note.

Every case breaks a copy of one small explored, labelled and evaluated experiment, then
runs ``curiosity`` on it in a subprocess. A case that cannot go on exits 1 with one
``Error:`` line naming the file; a case whose broken file can be made again (a cache, a
label file, a run) goes on, says so in one line on stderr and makes it again; a missing
or corrupt piece an evaluation leaves out is named in one line and in ``skipped.json``.
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from cli_cases import (
    EXPERIMENT,
    EXPLORE,
    LABEL,
    assert_clean_error,
    assert_written_only_inside,
    files_under,
    run_cli,
)

from curiosity_cli.config import load_config
from curiosity_cli.evaluate.report import write_report
from curiosity_cli.evaluate.stage import evaluate_experiment
from curiosity_cli.files import atomic_path, display_path, os_error_message

RUN = f"{EXPERIMENT}/runs/own/random-walk/restart-000"
LABEL_FILE = f"{EXPERIMENT}/labels/own/random-walk/restart-000.npz"
BATCH = f"{EXPERIMENT}/batch/own.npz"
#: Evaluating what has usable labels: without --partial, a run left out is an error
#: (test_a_run_left_out_is_an_error_unless_partial).
PARTIAL = ["evaluate", EXPERIMENT, "--partial"]


def _truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _replace_with_file(path: Path) -> None:
    shutil.rmtree(path)
    path.write_text("not a folder\n")


def _edit_run_json(work: Path, edit: Callable[[dict], object]) -> None:
    path = work / RUN / "run.json"
    path.write_text(json.dumps(edit(json.loads(path.read_text()))))


def _without(meta: dict, key: str) -> dict:
    return {k: v for k, v in meta.items() if k != key}


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _own_yaml(work: Path) -> Path:
    """The experiment's dataset YAML (``grid.yaml`` names it by its absolute path)."""
    return Path(yaml.safe_load((work / "grid.yaml").read_text())["datasets"][0])


def _dataset(work: Path, **paths: str) -> None:
    """``bad.yaml`` in ``work``: the experiment's map, with ``paths`` (``image``, ``labels``) in place of its files."""
    own = _own_yaml(work)
    dataset = yaml.safe_load(own.read_text())
    dataset.update(name="bad", **{key: str(own.parent / dataset[key]) for key in ("image", "labels", "legend")})
    dataset.update(paths)
    (work / "bad.yaml").write_text(yaml.safe_dump(dataset))


def _huge_png(work: Path) -> None:
    """A valid PNG whose header declares 60000 x 60000 RGB pixels."""
    header = struct.pack(">IIBBBBB", 60000, 60000, 8, 2, 0, 0, 0)
    (work / "huge.png").write_bytes(
        b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", header) + _png_chunk(b"IDAT", zlib.compress(b"\0" * 64))
        + _png_chunk(b"IEND", b"")
    )
    _dataset(work, image="huge.png")


def _loads_path_csv(work: Path) -> None:
    import pandas as pd

    steps = pd.read_csv(work / RUN / "path.csv")
    assert len(steps) == json.loads((work / RUN / "run.json").read_text())["path_length"]


def _truncated_png(work: Path) -> None:
    data = (_own_yaml(work).parent / "map.png").read_bytes()
    (work / "cut.png").write_bytes(data[: len(data) // 2])
    _dataset(work, labels="cut.png")


@dataclass(frozen=True)
class ErrorCase:
    """A broken input that stops the command: ``names`` are in its one ``Error:`` line."""

    id: str
    args: list[str]
    names: tuple[str, ...]
    breaks: Callable[[Path], None] = lambda work: None
    allowed: tuple[str, ...] = ("results",)


ERRORS = [
    # OS errors, reported by the path they concern
    ErrorCase("results-dir-is-a-file", [*EXPLORE, "--results-dir", "a-file"], ("a-file", "expected a folder")),
    ErrorCase("results-dir-under-a-file", [*EXPLORE, "--results-dir", "a-file/results"], ("a-file", "expected a folder")),
    ErrorCase("cache-dir-is-a-file", [*EXPLORE, "--cache-dir", "a-file"], ("a-file", "expected a folder")),
    ErrorCase(
        "runs-folder-is-a-file", [*EXPLORE, "--force"], (f"{EXPERIMENT}/runs", "expected a folder"),
        lambda work: _replace_with_file(work / EXPERIMENT / "runs"),
    ),
    ErrorCase(
        "labels-folder-is-a-file", [*LABEL, "--force"], (f"{EXPERIMENT}/labels", "expected a folder"),
        lambda work: _replace_with_file(work / EXPERIMENT / "labels"),
    ),
    ErrorCase(
        "density-out-under-a-file", ["extract", "bad.yaml", "--density", "a-file/density.png"], ("a-file", "expected a folder"),
        _dataset,
    ),
    ErrorCase(
        "preview-out-under-a-file", ["datasets", "show", "bad.yaml", "--out", "a-file/preview.png"],
        ("a-file", "expected a folder"), _dataset,
    ),
    ErrorCase(
        "figures-folder-is-a-file", ["plot", EXPERIMENT], (f"{EXPERIMENT}/figures", "expected a folder"),
        lambda work: (work / EXPERIMENT / "figures").write_text("not a folder\n"),
    ),
    ErrorCase("name-too-long", [*EXPLORE, "--results-dir", "x" * 300], ("x" * 300, "File name too long")),
    # corrupt pieces that cannot be made here
    ErrorCase(
        "run-json-is-a-list-at-label", LABEL, (f"{RUN}/run.json", "a JSON list", "explore redoes the run"),
        lambda work: _edit_run_json(work, lambda meta: [meta]),
    ),
    ErrorCase(
        # the other 7 runs are labelled; the unfinished one is named, and the command fails
        "deleted-run-json-at-label", [*LABEL, "--force"], ("1 of 8 runs could not be labelled", RUN, "no run.json"),
        # --force computes every item again and keeps it in the cache's shared items (issue 63), beside the experiment
        lambda work: (work / RUN / "run.json").unlink(), allowed=(EXPERIMENT, "results/cache/stores/shared"),
    ),
    ErrorCase(
        # plot reads the runs' paths: it checks them as label and evaluate do, though its tables are current
        "truncated-checkpoints-at-plot", ["plot", EXPERIMENT],
        (f"{RUN}/checkpoints.npz", "bytes, but", "were written", "`curiosity explore` redoes the run"),
        lambda work: _truncate(work / RUN / "checkpoints.npz"),
    ),
    ErrorCase(
        "missing-batch-at-evaluate", ["evaluate", EXPERIMENT], (BATCH, "not found", "curiosity label"),
        lambda work: (work / BATCH).unlink(),
    ),
    ErrorCase(
        "truncated-batch-at-evaluate", ["evaluate", EXPERIMENT], (BATCH, "corrupt", "curiosity label"),
        lambda work: _truncate(work / BATCH),
    ),
    # images
    ErrorCase("image-of-60000-x-60000-px", ["extract", "bad.yaml"], ("bad.yaml", "huge.png", "at most"), _huge_png),
    ErrorCase("truncated-png", ["extract", "bad.yaml"], ("bad.yaml", "labels", "cut.png", "truncated"), _truncated_png),
    ErrorCase(
        "image-is-a-folder", ["extract", "bad.yaml"], ("bad.yaml", "image", "results", "not a file"),
        lambda work: _dataset(work, image=str(work / "results")),
    ),
    ErrorCase(
        "labels-is-a-folder", ["extract", "bad.yaml"], ("bad.yaml", "labels", "results", "not a file"),
        lambda work: _dataset(work, labels=str(work / "results")),
    ),
]


@pytest.mark.slow
@pytest.mark.parametrize("case", ERRORS, ids=[case.id for case in ERRORS])
def test_a_broken_file_or_folder_is_one_error_line(work: Path, case: ErrorCase):
    case.breaks(work)
    before = files_under(work)
    outcome = run_cli(case.args, cwd=work)
    assert_clean_error(outcome, *case.names)
    after = files_under(work)
    assert_written_only_inside(before, after, *(work / name for name in case.allowed))
    assert not [p for p in after - before if ".tmp" in p.name], "a half-written file was left behind"


@pytest.mark.slow
@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only folder")
def test_a_read_only_results_folder_is_one_error_line(work: Path):
    (work / "locked").mkdir(mode=0o500)
    outcome = run_cli([*EXPLORE, "--results-dir", "locked"], cwd=work)
    assert_clean_error(outcome, "locked", "Permission denied")


@dataclass(frozen=True)
class RedoCase:
    """A broken piece the command makes again (or leaves out): ``says`` is in its one line on stderr."""

    id: str
    args: list[str]
    says: tuple[str, ...]
    breaks: Callable[[Path], None]
    checks: Callable[[Path], None] = lambda work: None
    outputs: tuple[str, ...] = ()


def _loads(path: Path) -> None:
    import numpy as np

    with np.load(path) as npz:
        assert npz.files


def _replace_meta(path: Path, meta) -> None:
    """Rewrite a label file with the same arrays and another ``meta``."""
    import numpy as np

    with np.load(path) as npz:
        arrays = {name: npz[name] for name in npz.files if name != "meta"}
    np.savez_compressed(path, **arrays, meta=json.dumps(meta))


def _skipped(work: Path, name: str) -> None:
    assert any(name in line for line in json.loads((work / EXPERIMENT / "skipped.json").read_text()))


REDOS = [
    RedoCase(
        "truncated-batch-at-label", LABEL, (BATCH, "corrupt", "computing it again"),
        lambda work: _truncate(work / BATCH), lambda work: _loads(work / BATCH),
    ),
    RedoCase(
        "truncated-label-file-at-label", LABEL, (LABEL_FILE, "corrupt", "labelling the run again"),
        lambda work: _truncate(work / LABEL_FILE), lambda work: _loads(work / LABEL_FILE), ("labelled 1 runs",),
    ),
    RedoCase(
        "zero-byte-label-file-at-evaluate", PARTIAL, ("skipped 1", LABEL_FILE, "corrupt", "label the experiment again"),
        lambda work: (work / LABEL_FILE).write_bytes(b""), lambda work: _skipped(work, LABEL_FILE),
    ),
    RedoCase(
        "truncated-label-file-at-evaluate", PARTIAL, ("skipped 1", LABEL_FILE, "corrupt"),
        lambda work: _truncate(work / LABEL_FILE), lambda work: _skipped(work, LABEL_FILE), ("(14 rows)",),
    ),
    RedoCase(
        "deleted-label-file-at-evaluate", PARTIAL, ("skipped 1", LABEL_FILE, "not found"),
        lambda work: (work / LABEL_FILE).unlink(), lambda work: _skipped(work, LABEL_FILE), ("(14 rows)",),
    ),
    RedoCase(
        "label-file-meta-without-keys-at-label", LABEL, (LABEL_FILE, "corrupt", "its meta lacks weight_function", "labelling the run again"),
        lambda work: _replace_meta(work / LABEL_FILE, {"dataset": "own"}), lambda work: _loads(work / LABEL_FILE),
        ("labelled 1 runs",),
    ),
    RedoCase(
        "label-file-meta-a-list-at-evaluate", PARTIAL, ("skipped 1", LABEL_FILE, "not a JSON object"),
        lambda work: _replace_meta(work / LABEL_FILE, [1, 2]), lambda work: _skipped(work, LABEL_FILE), ("(14 rows)",),
    ),
    RedoCase(
        # restart 0's file copied over restart 1's: it must not count restart 0 twice and restart 1 never
        "label-file-copied-over-another-at-evaluate", PARTIAL,
        ("skipped 1", LABEL_FILE.replace("000", "001"), "holds the labels of own / random-walk / restart 0"),
        lambda work: shutil.copy(work / LABEL_FILE, work / LABEL_FILE.replace("000", "001")),
        lambda work: _skipped(work, LABEL_FILE.replace("000", "001")), ("(14 rows)",),
    ),
    RedoCase(
        "many-deleted-label-files-at-evaluate", PARTIAL, ("skipped 5", "; and 2 more"),
        lambda work: [f.unlink() for f in sorted((work / EXPERIMENT / "labels").glob("*/*/restart-*.npz"))[:5]],
        lambda work: _skipped(work, LABEL_FILE), ("(6 rows)",),
    ),
    RedoCase(
        "run-json-is-a-list-at-explore", EXPLORE, (f"{RUN}/run.json", "a JSON list", "redoing the run"),
        lambda work: _edit_run_json(work, lambda meta: [meta]), outputs=("wrote 1 runs",),
    ),
    RedoCase(
        # path.csv cut to 4 of the run's steps: the run is not finished, and is made again
        "truncated-path-csv-at-explore", EXPLORE, (f"{RUN}/path.csv", "expected a header and", "redoing the run"),
        lambda work: (work / RUN / "path.csv").write_text(
            "".join((work / RUN / "path.csv").read_text().splitlines(keepends=True)[:5])
        ),
        lambda work: _loads_path_csv(work), outputs=("wrote 1 runs",),
    ),
    RedoCase(
        "run-json-without-seed-at-explore", EXPLORE, (f"{RUN}/run.json", "no key 'seed'", "redoing the run"),
        lambda work: _edit_run_json(work, lambda meta: _without(meta, "seed")), outputs=("wrote 1 runs",),
    ),
    RedoCase(
        "truncated-checkpoints-at-explore", EXPLORE, (f"{RUN}/checkpoints.npz", "corrupt", "redoing the run"),
        lambda work: _truncate(work / RUN / "checkpoints.npz"), outputs=("wrote 1 runs",),
    ),
]


@pytest.mark.slow
@pytest.mark.parametrize("case", REDOS, ids=[case.id for case in REDOS])
def test_a_broken_piece_is_redone_or_left_out_in_one_line(work: Path, case: RedoCase):
    case.breaks(work)
    before = files_under(work)
    outcome = run_cli(case.args, cwd=work)
    assert outcome.code == 0, outcome.output
    assert "Traceback" not in outcome.output and "Warning:" not in outcome.output, outcome.output
    lines = [line for line in outcome.stderr.splitlines() if all(said in line for said in case.says)]
    assert len(lines) == 1, outcome.stderr
    for said in case.outputs:
        assert said in outcome.stdout, outcome.stdout
    case.checks(work)
    assert_written_only_inside(before, files_under(work), work / "results")


@pytest.mark.slow
@pytest.mark.parametrize("case", [case for case in REDOS if case.args == PARTIAL], ids=lambda case: case.id)
def test_a_run_left_out_is_an_error_unless_partial(work: Path, case: RedoCase):
    case.breaks(work)
    tables = (work / EXPERIMENT / "mi.csv").read_text()
    named = [said for said in case.says if said.endswith(".npz")]  # the file at fault, where the case names one
    line = assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "have no usable labels", *named)
    assert "`curiosity label` makes them once their runs are explored, or evaluating with --partial leaves them out" in line
    assert (work / EXPERIMENT / "mi.csv").read_text() == tables  # the old set stays


@pytest.mark.slow
@pytest.mark.parametrize("args", [["extract", "DATASET"], EXPLORE], ids=["extract", "explore"])
def test_a_truncated_word_store_is_extracted_again(work: Path, args: list[str]):
    (store,) = (work / "results" / "cache" / "stores").glob("own-*.npz")
    _truncate(store)
    outcome = run_cli([_own_yaml(work) if arg == "DATASET" else arg for arg in args], cwd=work)
    assert outcome.code == 0, outcome.output
    assert "Traceback" not in outcome.output, outcome.output
    notes = [line for line in outcome.stderr.splitlines() if store.name in line]
    assert len(notes) == 1 and "corrupt" in notes[0] and "extracting the words again" in notes[0], outcome.stderr
    _loads(store)


@pytest.mark.slow
def test_the_report_says_how_many_runs_a_mean_is_over(work: Path):
    (work / LABEL_FILE).unlink()
    folder = work / EXPERIMENT
    evaluation = evaluate_experiment(folder, partial=True)
    config = load_config(folder / "config.yaml")
    report = write_report(folder, config, evaluation, [], [], {"total": 1.0}, {}).read_text()
    left_out = report.split("## Left out", 1)[1].split("##", 1)[0]
    assert "own / random-walk: means over 1 of 2 restarts" in left_out
    assert "restart-000.npz: not found" in left_out


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full, a device that is always full")
def test_a_full_disk_names_the_file_being_written(tmp_path: Path):
    target = tmp_path / "table.csv"
    with pytest.raises(OSError) as raised:
        with atomic_path(target), open("/dev/full", "w") as full:  # a write error says no file name
            full.write("x")
            full.flush()
    assert os_error_message(raised.value) == f"{display_path(target)}: No space left on device"
    assert not list(tmp_path.iterdir()), "a half-written file was left behind"
