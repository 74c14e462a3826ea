"""Issue 25: one fault anywhere in a finished experiment is refused by name, or makes no difference.

Take a small explored, labelled and evaluated experiment (built once, as ``conftest.py``'s
``experiment``, and restored from an untouched copy before each example, its map too, so
an edit of the map does not leak into the next example), apply ONE fault to one file or
input, and run the stages that follow, as a user would. The faults are drawn by hypothesis
for each family of files in turn (``EXAMPLES_PER_FAMILY`` each, so that every family is
broken in every run), and the faults met before are run as they were:

* the faulted piece: a run's ``run.json``, ``path.csv`` or ``checkpoints.npz``; a label
  file; an example label map; the batch reference; a table (``mi.csv``, ``summary.csv``,
  ``headline.csv``); ``config.yaml``; ``runs.csv``; the map's image, its labels PNG, its
  dataset YAML;
* the fault: truncated to a fraction, cut to its header and a few rows, deleted,
  swapped with a sibling of the same kind, overwritten by a sibling, a byte flipped, a
  config or dataset value edited to another valid one, pixels of the image or labels
  changed;
* the stages: ``label`` (with the fast settings of ``cli_cases``), ``evaluate``,
  ``plot``, from the drawn first one on (a run, config or map fault naturally starts at
  ``label``, a label file or batch fault at ``evaluate``, a table fault at ``plot``).

The contract, checked at each stage:

* a stage that does not exit 0 exits 1 with exactly one ``Error:`` line naming the
  faulted file (its name or path, or the run it belongs to) or the edited input (the
  config key, ``config.yaml``, the map's name or dataset YAML), and no traceback or raw
  warning; the sequence stops there;
* if every stage exits 0, the experiment's tables (``mi.csv``, ``summary.csv``,
  ``headline.csv``, ``tests.csv``, ``effects.csv``, ``classes.csv``,
  ``classes_summary.csv``) are byte for byte a clean rerun's, whichever stages ran (after
  a table fault, a ``plot`` that exits 0 must have found nothing wrong); and if ``plot``
  ran and left nothing out (no ``skipped:`` note), each PNG figure it drew is the clean
  rerun's too.

The clean rerun of a fault in a derived file (runs, labels, batch, tables, ``runs.csv``,
a deleted ``config.yaml``) is the unbroken experiment: results are seed-deterministic, so
a stage that goes on must redo what broke to the same bytes. The clean rerun of an edited
input (``config.yaml``, the map's image, labels or dataset YAML) is ``explore``,
``label`` and the same stages from scratch in a fresh folder on the edited inputs, made
only when every stage exited 0; if that clean rerun itself refuses, exiting 0 was wrong.
Never exit 0 with other numbers.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from cli_cases import EXPERIMENT, EXPLORE, LABEL, Outcome, run_cli
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st
from small_maps import PAPER_WALKERS, grid_yaml, write_own_map

MAP = "own"
MAP_FILES = ("map.png", "labels.png", "legend.yaml", "own.yaml")
CONFIG = f"{EXPERIMENT}/config.yaml"
STAGES = {"label": LABEL, "evaluate": ["evaluate", EXPERIMENT], "plot": ["plot", EXPERIMENT]}
ORDER = tuple(STAGES)
TABLES = ("mi", "summary", "headline", "tests", "effects", "classes", "classes_summary")

RUNS = [f"{EXPERIMENT}/runs/{MAP}/{w}/restart-{r:03d}" for w in PAPER_WALKERS for r in (0, 1)]
LABEL_FILES = [f"{EXPERIMENT}/labels/{MAP}/{w}/restart-{r:03d}.npz" for w in PAPER_WALKERS for r in (0, 1)]
EXAMPLES = [f"{EXPERIMENT}/labels/{MAP}/examples/{w}-restart-000-12.npz" for w in PAPER_WALKERS]

#: Edits of one value to another valid one: the experiment's config.yaml, the map's dataset YAML.
CONFIG_EDITS = (
    ("seed", 5), ("seed", 1), ("name", "other"), ("model.topics", 6), ("model.alpha", 0.2),
    ("explore.path_length", 14), ("explore.restarts", 1), ("explore.restarts", 3),
    ("explore.samples_per_step", 4000), ("explore.coverage", "clamp"),
    ("explore.weight_functions", list(PAPER_WALKERS[:3])),
    ("label.sweeps", 3), ("label.batch_sweeps", 3), ("label.warm_sweeps", 8), ("label.check_restarts", 2),
)
DATASET_EDITS = (
    ("cell_width", 8), ("cell_width", 32), ("word_stride", 2), ("name", "other"), ("description", "edited"),
    ("size", [128, 96]), ("labels", "map.png"), ("image", "labels.png"),
)

FILE_FAULTS = ("truncate", "delete", "flip")
SIBLING_FAULTS = ("swap", "copy")


@dataclass(frozen=True)
class Family:
    """Files of one kind: the faults that apply to them and the stage a user would run next (first)."""

    name: str
    files: tuple[str, ...]
    actions: tuple[str, ...]
    starts: tuple[str, ...]
    edits: tuple = ()
    pixel_values: int = 0  # pixels: values are 0 .. pixel_values - 1


def _starts(first: str) -> tuple[str, ...]:
    return (first, *(s for s in ORDER if s != first))


FAMILIES = (
    Family("run-json", tuple(f"{run}/run.json" for run in RUNS), (*FILE_FAULTS, *SIBLING_FAULTS), _starts("label")),
    Family(
        "path-csv", tuple(f"{run}/path.csv" for run in RUNS), (*FILE_FAULTS, "cut-rows", *SIBLING_FAULTS),
        _starts("label"),
    ),
    Family(
        "checkpoints", tuple(f"{run}/checkpoints.npz" for run in RUNS), (*FILE_FAULTS, *SIBLING_FAULTS),
        _starts("label"),
    ),
    Family("label-files", tuple(LABEL_FILES), (*FILE_FAULTS, *SIBLING_FAULTS), _starts("evaluate")),
    Family("example-maps", tuple(EXAMPLES), (*FILE_FAULTS, *SIBLING_FAULTS), _starts("evaluate")),
    Family("batch", (f"{EXPERIMENT}/batch/{MAP}.npz",), FILE_FAULTS, _starts("evaluate")),
    Family(
        "tables", tuple(f"{EXPERIMENT}/{t}.csv" for t in ("mi", "summary", "headline")), (*FILE_FAULTS, "cut-rows"),
        _starts("plot"),
    ),
    Family("config", (CONFIG,), ("edit", *FILE_FAULTS), _starts("label"), CONFIG_EDITS),
    Family("runs-csv", (f"{EXPERIMENT}/runs.csv",), (*FILE_FAULTS, "cut-rows"), _starts("label")),
    Family("map-image", ("map.png",), ("pixels", *FILE_FAULTS), _starts("label"), pixel_values=256),
    # pixel values 0-2: 2 is no class of the legend
    Family("map-labels", ("labels.png",), ("pixels", *FILE_FAULTS), _starts("label"), pixel_values=3),
    Family("dataset-yaml", ("own.yaml",), ("edit", *FILE_FAULTS), _starts("label"), DATASET_EDITS),
)


@dataclass(frozen=True)
class Fault:
    """One fault: ``target`` (relative to the experiment's root) broken by ``action``, then the stages from ``start``.

    ``at`` is the percentage of the file kept (truncate) or the position of the flipped byte
    (flip); ``rows`` the data rows kept (cut-rows); ``mask`` the flipped bits; ``partner`` the
    sibling swapped with or copied from; ``key`` and ``value`` the edit; ``box`` (row, col,
    height, width) and ``value`` the pixels set.
    """

    target: str
    action: str
    start: str
    partner: str | None = None
    at: int = 0
    rows: int = 0
    mask: int = 0
    key: str | None = None
    value: object = None
    box: tuple[int, int, int, int] = (0, 0, 0, 0)

    @property
    def stages(self) -> tuple[str, ...]:
        return ORDER[ORDER.index(self.start):]

    @property
    def edits_an_input(self) -> bool:
        """An edited input's clean rerun is made from scratch; a derived file's is the unbroken experiment."""
        return self.target in MAP_FILES or (self.target == CONFIG and self.action != "delete")


@st.composite
def faults(draw, family: Family) -> Fault:
    index = draw(st.integers(0, len(family.files) - 1))
    action = draw(st.sampled_from(family.actions))
    fault = dict(target=family.files[index], action=action, start=draw(st.sampled_from(family.starts)))
    if action in SIBLING_FAULTS:
        fault["partner"] = family.files[(index + draw(st.integers(1, len(family.files) - 1))) % len(family.files)]
    elif action == "truncate":
        fault["at"] = draw(st.integers(0, 99))
    elif action == "flip":
        fault.update(at=draw(st.integers(0, 99)), mask=draw(st.integers(1, 255)))
    elif action == "cut-rows":
        fault["rows"] = draw(st.integers(0, 15))
    elif action == "edit":
        fault["key"], fault["value"] = draw(st.sampled_from(family.edits))
    elif action == "pixels":
        fault.update(
            box=tuple(draw(st.integers(low, high)) for low, high in ((0, 95), (0, 127), (1, 48), (1, 64))),
            value=draw(st.integers(0, family.pixel_values - 1)),
        )
    return Fault(**fault)


# ---- the experiment, copied


def _dataset_entry(config: Path) -> str:
    (entry,) = yaml.safe_load(config.read_text())["datasets"]
    return entry


@dataclass(frozen=True)
class Finished:
    """The experiment's folder ``root`` (map, ``grid.yaml``, ``results``) and an untouched copy of it, ``pristine``.

    The saved config names the map by its absolute path, and the experiment records what
    its config and maps were: a copy elsewhere, its config rewritten to name the copy's map,
    would be an edited experiment. So each example breaks ``root`` itself, restored first.
    """

    root: Path
    pristine: Path

    def restored(self) -> Path:
        shutil.rmtree(self.root)
        shutil.copytree(self.pristine, self.root, symlinks=True)
        return self.root


class Made:
    """An experiment's tables and figures by name, as bytes (figures None: not compared)."""

    def __init__(self, tables: dict[str, bytes], figures: dict[str, bytes] | None):
        self.tables, self.figures = tables, figures

    def __repr__(self) -> str:  # hypothesis shows the fixtures of a failing example
        return f"Made(tables={sorted(self.tables or ())}, figures={sorted(self.figures or ())})"


def made(folder: Path, figures: bool) -> Made:
    tables = {t: (folder / f"{t}.csv").read_bytes() for t in TABLES if (folder / f"{t}.csv").is_file()}
    drawn = {p.name: p.read_bytes() for p in sorted((folder / "figures").glob("*.png"))} if figures else None
    return Made(tables, drawn)


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Finished:
    """As conftest's ``experiment``: the own map, ``grid.yaml`` and ``results/grid`` explored, labelled, evaluated."""
    root = tmp_path_factory.mktemp("faults") / "experiment"
    root.mkdir()
    grid_yaml(write_own_map(root), root)
    for args in (EXPLORE, LABEL, STAGES["evaluate"]):
        outcome = run_cli(args, cwd=root)
        assert outcome.code == 0, outcome.output
    assert Path(_dataset_entry(root / CONFIG)) == root / "own.yaml", "the experiment's config names another map"
    shutil.copytree(root, root.parent / "pristine", symlinks=True)
    return Finished(root, root.parent / "pristine")


@pytest.fixture(scope="module")
def clean(finished: Finished) -> Made:
    """The unbroken experiment's tables and figures: the clean rerun of a fault in a derived file."""
    root = finished.restored()
    for stage in ORDER:
        outcome = run_cli(STAGES[stage], cwd=root)
        assert outcome.code == 0, outcome.output
        assert "again" not in outcome.stderr, f"a clean rerun redid something:\n{outcome.stderr}"
    reference = made(root / EXPERIMENT, figures=True)
    for table in TABLES:
        original = (finished.pristine / EXPERIMENT / f"{table}.csv").read_bytes()
        assert reference.tables[table] == original, f"rerunning the stages changed {table}.csv"
    assert len(reference.figures) >= 4, sorted(reference.figures)
    return reference


# ---- faults


def _set_key(data: dict, dotted: str, value) -> None:
    *sections, key = dotted.split(".")
    for section in sections:
        data = data[section]
    assert key in data, f"no key {dotted}"
    data[key] = value


def apply_fault(fault: Fault, root: Path) -> None:
    path = root / fault.target
    assert path.is_file(), f"the experiment has no {fault.target} to break"
    data = path.read_bytes()
    if fault.action == "truncate":
        path.write_bytes(data[: len(data) * fault.at // 100])
    elif fault.action == "cut-rows":
        lines = data.splitlines(keepends=True)
        path.write_bytes(b"".join(lines[: 1 + min(fault.rows, max(len(lines) - 2, 0))]))
    elif fault.action == "delete":
        path.unlink()
    elif fault.action == "flip":
        if data:
            flipped = bytearray(data)
            flipped[len(data) * fault.at // 100] ^= fault.mask
            path.write_bytes(bytes(flipped))
    elif fault.action == "swap":
        other = root / fault.partner
        path.write_bytes(other.read_bytes())
        other.write_bytes(data)
    elif fault.action == "copy":
        path.write_bytes((root / fault.partner).read_bytes())
    elif fault.action == "edit":
        config = yaml.safe_load(data)
        _set_key(config, fault.key, fault.value)
        path.write_text(yaml.safe_dump(config, sort_keys=False))
    elif fault.action == "pixels":
        import cv2

        image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        row, col, height, width = fault.box
        image[row : row + height, col : col + width] = fault.value
        assert cv2.imwrite(str(path), image)
    else:
        raise AssertionError(f"no fault {fault.action!r}")


def names_of(fault: Fault) -> list[str]:
    """What an ``Error:`` line may name for ``fault``: regular expressions."""
    names = []
    for target in filter(None, (fault.target, fault.partner)):
        if target in MAP_FILES:
            names += [re.escape(target), re.escape("own.yaml"), rf"\b{MAP}\b"]
            continue
        inside = target.removeprefix(f"{EXPERIMENT}/")
        names.append(re.escape(inside))  # the path inside the experiment folder, or the whole of it
        if inside.count("/") == 0 or inside.startswith("batch/"):
            names.append(re.escape(Path(inside).name))  # a name no other file of the experiment has
        if inside.startswith("runs/"):
            run = Path(inside).parent
            walker, restart = run.parts[-2], int(run.name.removeprefix("restart-"))
            names += [re.escape(str(run)), re.escape(f"{MAP} / {walker} / restart {restart}")]
    if fault.key:
        leaf = fault.key.rsplit(".", 1)[-1]
        names += [re.escape(fault.key), rf"(?<![\w.]){re.escape(leaf)}\b"]
    if fault.target == "own.yaml" and fault.key == "name":
        names.append(rf"\b{re.escape(fault.value)}\b")  # the map by its new name
    return names


# ---- stages and the clean rerun


def run_stages(root: Path, stages: tuple[str, ...]) -> list[tuple[str, Outcome]]:
    """The stages in order, up to the first that does not exit 0."""
    done = []
    for stage in stages:
        outcome = run_cli(STAGES[stage], cwd=root)
        done.append((stage, outcome))
        if outcome.code != 0:
            break
    return done


def _shown(done: list[tuple[str, Outcome]]) -> str:
    return "\n".join(
        f"--- {stage}: exit {outcome.code}\n{outcome.stdout.strip()[-1500:]}\n{outcome.stderr.strip()[-3000:]}"
        for stage, outcome in done
    )


def rerun_from_scratch(root: Path, config: bytes | None, stages: tuple[str, ...]) -> Made | str:
    """``explore``, ``label`` and ``stages`` in a fresh folder on ``root``'s inputs; what went wrong if one fails."""
    with tempfile.TemporaryDirectory(prefix="clean-rerun-") as fresh:
        fresh = Path(fresh)
        for name in MAP_FILES:
            if (root / name).is_file():
                shutil.copy(root / name, fresh / name)
        if config is None:
            return "the experiment's config.yaml is gone"
        (fresh / "grid.yaml").write_bytes(config.replace(bytes(root / "own.yaml"), bytes(fresh / "own.yaml")))
        # the label settings are the config's own; evaluate makes the tables plot draws
        commands = [["explore", "grid.yaml", "--jobs", "2"], ["label", EXPERIMENT, "--jobs", "2"]]
        commands += [STAGES["evaluate"]] * ("evaluate" not in stages) + [STAGES[stage] for stage in stages]
        for args in commands:
            outcome = run_cli(args, cwd=fresh)
            if args[0] == "explore" and outcome.code == 0:
                # a config of another name explores into results/<name>: the user's folder stays results/grid
                (explored,) = [d for d in (fresh / "results").iterdir() if d.is_dir() and d.name != "cache"]
                explored.rename(fresh / EXPERIMENT)
            if outcome.code != 0:
                return f"`curiosity {' '.join(map(str, args))}` exits {outcome.code}:\n{outcome.output.strip()[-2000:]}"
        return made(fresh / EXPERIMENT, figures="plot" in stages)


def _differences(got: Made, want: Made) -> list[str]:
    lines = []
    for name in TABLES:
        mine, theirs = got.tables.get(name), want.tables.get(name)
        if mine != theirs:
            if mine is None or theirs is None:
                lines.append(f"{name}.csv: {'missing' if mine is None else 'there'}, the clean rerun's is not")
                continue
            mine, theirs = (t.decode(errors="replace").splitlines() for t in (mine, theirs))
            first = next(
                (f"line {i}: {a!r} != {b!r}" for i, (a, b) in enumerate(zip(mine, theirs)) if a != b),
                f"{len(mine)} lines != {len(theirs)} lines",
            )
            lines.append(f"{name}.csv differs from the clean rerun's: {first}")
    if got.figures is not None:
        for name, data in got.figures.items():
            if name not in want.figures:
                lines.append(f"figures/{name}: the clean rerun draws no such figure")
            elif data != want.figures[name]:
                lines.append(f"figures/{name} differs from the clean rerun's")
    return lines


def check_fault(fault: Fault, root: Path, clean: Made) -> None:
    """Break ``root`` (the restored experiment) with ``fault``, run the stages, hold them to the contract."""
    apply_fault(fault, root)
    config = (root / CONFIG).read_bytes() if (root / CONFIG).is_file() else None  # as faulted, before any stage
    done = run_stages(root, fault.stages)
    for stage, outcome in done:
        where = f"{fault}\nat `curiosity {stage}`:\n{_shown(done)}"
        assert "Traceback" not in outcome.output, f"a traceback: {where}"
        assert "Warning:" not in outcome.output, f"a raw warning: {where}"
        if outcome.code != 0:
            assert outcome.code == 1, f"exit {outcome.code}, expected 1 (an error) or 0: {where}"
            errors = [line for line in outcome.stderr.splitlines() if "Error" in line]
            assert len(errors) == 1, f"{len(errors)} Error lines, expected one: {where}"
            names = names_of(fault)
            assert any(re.search(name, errors[0]) for name in names), (
                f"the Error line names none of {names}: {where}"
            )
            return
    # a figure plot leaves out, or draws in part, says so on a `skipped:` line; then only the tables are held
    noted = any("skipped:" in outcome.stderr for stage, outcome in done if stage == "plot")
    got = made(root / EXPERIMENT, figures="plot" in fault.stages and not noted)
    want = rerun_from_scratch(root, config, fault.stages) if fault.edits_an_input else clean
    assert not isinstance(want, str), f"every stage exited 0, but a clean rerun refuses ({want}): {fault}\n{_shown(done)}"
    differences = "\n".join(_differences(got, want))
    assert not differences, f"every stage exited 0 with other numbers: {fault}\n{differences}\n{_shown(done)}"


# ---- the property


def _run(walker: str, restart: int = 0) -> str:
    return f"{EXPERIMENT}/runs/{MAP}/{walker}/restart-{restart:03d}"


def _labels(walker: str, restart: int = 0) -> str:
    return f"{EXPERIMENT}/labels/{MAP}/{walker}/restart-{restart:03d}.npz"


#: Faults drawn per family: hypothesis's first is the family's simplest (its first file, its first fault at
#: 0 %, from its first stage), the rest random. Raise it for a deeper search, e.g. before a release:
#: ``CURIOSITY_FAULT_EXAMPLES=8 pytest tests/reliability/test_fault_property.py``.
EXAMPLES_PER_FAMILY = int(os.environ.get("CURIOSITY_FAULT_EXAMPLES", "2"))

#: Faults met before: the known cases of issue 25, then those this test found.
KNOWN_FAULTS = {
    "label-file-copied-over-another-at-evaluate":
        Fault(_labels("random-walk"), "copy", "evaluate", partner=_labels("stochastic-coverage")),
    "path-csv-cut-to-4-rows-at-label": Fault(f"{_run('random-walk')}/path.csv", "cut-rows", "label", rows=4),
    "human-labels-edited-after-labelling-at-evaluate":
        Fault("labels.png", "pixels", "evaluate", box=(0, 0, 48, 64), value=1),
    "seed-edited-at-plot": Fault(CONFIG, "edit", "plot", key="seed", value=5),
    "grid-widened-by-hand-at-label": Fault(CONFIG, "edit", "label", key="explore.restarts", value=3),
    "grid-narrowed-by-hand-at-label":
        Fault(CONFIG, "edit", "label", key="explore.weight_functions", value=list(PAPER_WALKERS[:3])),
    "config-cut-short-at-label": Fault(CONFIG, "truncate", "label", at=50),
    "map-renamed-at-label": Fault("own.yaml", "edit", "label", key="name", value="other"),
}


def check_drawn(family: Family, clean: Made, finished: Finished) -> None:
    """``EXAMPLES_PER_FAMILY`` faults of ``family`` drawn by hypothesis, each held to the contract."""

    # a seed of the family's own (fixed: the same faults each run), so that the families' draws differ
    @seed(FAMILIES.index(family))
    @settings(
        max_examples=EXAMPLES_PER_FAMILY, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow],
    )
    @given(fault=faults(family))
    def check(fault: Fault):
        check_fault(fault, finished.restored(), clean)

    check()


@pytest.mark.slow
def test_one_fault_is_refused_by_name_or_makes_no_difference(finished: Finished, clean: Made, subtests):
    # One test, its cases subtests: the experiment and its clean rerun are made once, where separate tests
    # could be sent to both of xdist's workers and each would make them.
    with subtests.test("the faults are what they say"):
        check_the_faults_are_what_they_say(finished)
    for name, fault in KNOWN_FAULTS.items():
        with subtests.test(met_before=name):
            check_fault(fault, finished.restored(), clean)
    for family in FAMILIES:  # drawn per family, so that every kind of file is broken in every run of the suite
        with subtests.test(family=family.name):
            check_drawn(family, clean, finished)


def check_the_faults_are_what_they_say(finished: Finished) -> None:
    """Each kind of fault changes its file as described, and a restore undoes it."""
    root, experiment = finished.restored(), finished.pristine
    label, other = _labels("random-walk"), _labels("word-perplexity", 1)
    apply_fault(Fault(label, "swap", "evaluate", partner=other), root)
    assert (root / label).read_bytes() == (experiment / other).read_bytes()
    assert (root / other).read_bytes() == (experiment / label).read_bytes()
    path_csv = f"{_run('topic-perplexity', 1)}/path.csv"
    apply_fault(Fault(path_csv, "cut-rows", "label", rows=4), root)
    assert len((root / path_csv).read_text().splitlines()) == 5
    apply_fault(Fault(CONFIG, "edit", "label", key="label.sweeps", value=3), root)
    assert yaml.safe_load((root / CONFIG).read_text())["label"]["sweeps"] == 3
    apply_fault(Fault(f"{EXPERIMENT}/mi.csv", "flip", "plot", at=50, mask=1), root)
    flipped, original = ((r / EXPERIMENT / "mi.csv").read_bytes() for r in (root, experiment))
    assert sum(a != b for a, b in zip(flipped, original)) == 1
    apply_fault(Fault("labels.png", "pixels", "evaluate", box=(0, 0, 48, 64), value=1), root)
    import cv2

    edited, original = (cv2.imread(str(r / "labels.png"), cv2.IMREAD_UNCHANGED) for r in (root, experiment))
    assert (edited[:48, :64] == 1).all() and (original[:48, :64] == 0).all()
    assert not Fault(CONFIG, "delete", "label").edits_an_input and Fault(CONFIG, "flip", "label").edits_an_input
    root = finished.restored()
    for path in experiment.rglob("*"):
        if path.is_file():
            assert (root / path.relative_to(experiment)).read_bytes() == path.read_bytes(), path
