"""Issue 16, configs, YAML and names: each bad input is one clean line through the real CLI.

Every case runs ``curiosity`` in a subprocess from a working folder three levels below the
test's temporary folder, so a name that climbs out with ``..`` would still be seen
writing outside ``results/``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from cli_cases import assert_clean_error, assert_written_only_inside, files_under, run_cli

from curiosity_cli.config import CONFIG_DIR

#: The longest ``Error:`` line a case may print: no value is shown in full.
LONGEST_LINE = 400


def _bomb(levels: int = 9) -> str:
    """A "billion laughs" YAML mapping: 9 levels of 9 aliases, 9**9 strings once expanded."""
    lines = ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for level in range(1, levels):
        lines.append(f"a{level}: &a{level} [{', '.join([f'*a{level - 1}'] * 9)}]")
    return "\n".join(lines) + "\n"


def _flow_bomb(levels: int = 9) -> str:
    """The same bomb on one line, as a ``--set`` value."""
    items = ["&a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    items += [f"&a{level} [{', '.join([f'*a{level - 1}'] * 9)}]" for level in range(1, levels)]
    return f"[{', '.join(items)}]"


def _experiment(work: Path, name: str = "E", dataset: str = "aerial-mosaic") -> Path:
    path = work / "e.yaml"
    path.write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\nname: {name}\nseed: 1\ndatasets: [{dataset}]\n")
    return path


def _own_map(work: Path, **changes) -> Path:
    """A 64 x 64 px map with a legend beside it; ``changes`` replace keys of its YAML."""
    image = np.random.default_rng(0).integers(0, 256, size=(64, 64, 3), dtype=np.uint8)
    cv2.imwrite(str(work / "map.png"), image)
    cv2.imwrite(str(work / "labels.png"), np.zeros((64, 64), dtype=np.uint8))
    (work / "legend.yaml").write_text(yaml.safe_dump({"classes": [{"id": 0, "name": "sand", "colour": "#e0c080"}]}))
    config = {"name": "own", "image": "map.png", "labels": "labels.png", "legend": "legend.yaml", "cell_width": 16,
              "word_stride": 1, **changes}
    path = work / "own.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def _saved_config(work: Path, text: str) -> None:
    _experiment(work)
    folder = work / "results" / "E"
    folder.mkdir(parents=True)
    (folder / "config.yaml").write_text(text)


# Each case: how to lay out the working folder, the command, its exit code, and what the
# one Error line must name.
CASES = {
    # 1. bombs and oversized documents, in every YAML the tool reads
    "bomb in an experiment config": (
        lambda w: (w / "bomb.yaml").write_text(_bomb()), ["config", "show", "bomb.yaml"], 1,
        ["bomb.yaml", "more than 100000 values"]),
    "bomb in a base config": (
        lambda w: ((w / "bomb.yaml").write_text(_bomb()), (w / "e.yaml").write_text("base: bomb.yaml\n")),
        ["config", "show", "e.yaml"], 1, ["bomb.yaml", "more than 100000 values"]),
    "bomb in a dataset YAML": (
        lambda w: (w / "own.yaml").write_text(_bomb()), ["datasets", "show", "own.yaml"], 1,
        ["own.yaml", "more than 100000 values"]),
    "bomb in a legend YAML": (
        lambda w: (_own_map(w), (w / "legend.yaml").write_text(_bomb())), ["datasets", "show", "own.yaml"], 1,
        ["legend.yaml", "more than 100000 values"]),
    "bomb in a saved config": (
        lambda w: _saved_config(w, _bomb()), ["label", "results/E"], 1,
        ["results/E/config.yaml", "more than 100000 values"]),
    "bomb in a --set value": (
        _experiment, ["config", "show", "e.yaml", "--set", f"model={_flow_bomb()}"], 1,
        ["--set 'model'", "more than 100000 values"]),
    "alias to itself": (
        lambda w: (w / "e.yaml").write_text("model: &m {topics: [*m]}\n"), ["config", "show", "e.yaml"], 1,
        ["e.yaml", "an alias refers to a list or mapping that contains it"]),
    "deep nesting": (
        lambda w: (w / "e.yaml").write_text("model: " + "[" * 5000 + "]" * 5000 + "\n"), ["config", "show", "e.yaml"],
        1, ["e.yaml", "nested more than 50 levels"]),
    "a config over 1 MiB": (
        lambda w: (w / "e.yaml").write_text("# padding\n" * 200_000), ["config", "show", "e.yaml"], 1,
        ["e.yaml", "larger than 1 MiB"]),
    # 3. messages as a person writes them
    "a seed out of range": (
        _experiment, ["config", "show", "e.yaml", "--set", "seed=5000000000"], 1,
        ["--set: seed", "got 5000000000 (int), expected an integer >= 0 and <= 4294967295"]),
    "an empty list of checkpoints": (
        _experiment, ["config", "show", "e.yaml", "--set", "explore.checkpoints=[]"], 1,
        ["--set: explore.checkpoints", "expected a non-empty list of integers"]),
    "a huge value": (
        _experiment, ["config", "show", "e.yaml", "--set", f"model.topics={'x' * 100_000}"], 1,
        ["--set: model.topics", "'xxxxx", "... (str)"]),
    "a huge unknown key": (
        lambda w: (w / "e.yaml").write_text(f"? {'k' * 100_000}\n: 1\n"), ["config", "show", "e.yaml"], 1,
        ["e.yaml: kkkk", "...: unknown key"]),
    # 4. names become paths
    "a dataset name climbing out": (
        lambda w: (_own_map(w, name="../../../escaped"), _experiment(w, dataset="own.yaml")), ["explore", "e.yaml"], 1,
        ["own.yaml: name", "'../../../escaped'", "letters, digits, '-', '_' or '.'"]),
    "a dataset name with a folder": (
        lambda w: _own_map(w, name="sub/dir"), ["datasets", "show", "own.yaml"], 1,
        ["own.yaml: name", "'sub/dir'", "starting with a letter or digit"]),
    "an empty dataset name": (
        lambda w: _own_map(w, name=""), ["datasets", "show", "own.yaml"], 1, ["own.yaml: name", "got '' (str)"]),
    "an experiment name of 300 characters": (
        _experiment, ["explore", "e.yaml", "--set", f"name={'n' * 300}"], 1, ["--set: name", "1 to 120 letters"]),
    # 5. a saved config.yaml that does not validate
    "an empty saved config, label": (
        lambda w: _saved_config(w, ""), ["label", "results/E"], 1, ["results/E/config.yaml: empty; expected a YAML config"]),
    "an empty saved config, explore": (
        lambda w: _saved_config(w, ""), ["explore", "e.yaml"], 1, ["results/E/config.yaml: empty; expected a YAML config"]),
    "an invalid saved config, label": (
        lambda w: _saved_config(w, "name: [E\n"), ["label", "results/E"], 1,
        ["results/E/config.yaml: not valid YAML"]),
    "an invalid saved config, explore": (
        lambda w: _saved_config(w, "name: [E\n"), ["explore", "e.yaml"], 1,
        ["results/E/config.yaml: not valid YAML"]),
    "a list as saved config, label": (
        lambda w: _saved_config(w, "- E\n"), ["label", "results/E"], 1,
        ["results/E/config.yaml: expected a mapping of keys at the top level, got list"]),
    "a list as saved config, explore": (
        lambda w: _saved_config(w, "- E\n"), ["explore", "e.yaml"], 1,
        ["results/E/config.yaml: expected a mapping of keys at the top level, got list"]),
    "a list as saved config, plot": (
        lambda w: _saved_config(w, "- E\n"), ["plot", "results/E"], 1, ["results/E/"]),
    # 6. issue 25: a key given twice, a symlink loop where a file belongs, a stride wider than a cell
    "a key given twice in an experiment config": (
        lambda w: (w / "e.yaml").write_text(f"base: {CONFIG_DIR / 'paper.yaml'}\nname: E\nseed: 1\nseed: 2\n"),
        ["config", "show", "e.yaml"], 1, ["e.yaml", "key 'seed' is given twice (lines 3 and 4)"]),
    "a key given twice in a dataset YAML": (
        lambda w: _own_map(w).write_text((w / "own.yaml").read_text() + "cell_width: 8\n"),
        ["datasets", "show", "own.yaml"], 1, ["own.yaml", "key 'cell_width' is given twice"]),
    "a symlink loop as the config": (
        lambda w: (w / "e.yaml").symlink_to(w / "e.yaml"), ["config", "show", "e.yaml"], 1,
        ["e.yaml: Too many levels of symbolic links"]),
    "a symlink loop as a base": (
        lambda w: ((w / "loop.yaml").symlink_to(w / "loop.yaml"), (w / "e.yaml").write_text("base: loop.yaml\n")),
        ["config", "show", "e.yaml"], 1, ["e.yaml: base: file not found", "loop.yaml"]),
    "a symlink loop as a map's image": (
        lambda w: (_own_map(w), (w / "map.png").unlink(), (w / "map.png").symlink_to(w / "map.png")),
        ["datasets", "show", "own.yaml"], 1, ["map.png: Too many levels of symbolic links"]),
    "a word stride wider than a cell": (
        lambda w: _own_map(w, word_stride=256), ["datasets", "show", "own.yaml"], 1,
        ["own.yaml: word_stride: got a stride of 256 px with cells of 16 px, expected a stride of at most the cell width"]),
    # 7. out-of-range numbers on the command line are usage errors
    "a huge texton vocabulary": (
        lambda w: None, ["vocab", "build", "--out", "results/vocab", "--texton-words", "100000000"], 2,
        ["--texton-words", "less than or equal to", "30000"]),
    "a negative ORB vocabulary": (
        lambda w: None, ["vocab", "build", "--out", "results/vocab", "--orb-words", "-5"], 2,
        ["--orb-words", "greater than or equal to 2"]),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_a_bad_config_yaml_or_name_is_one_clean_line(tmp_path, case):
    prepare, args, code, names = CASES[case]
    work = tmp_path / "a" / "b" / "c" / "work"
    work.mkdir(parents=True)
    prepare(work)
    before = files_under(tmp_path)
    outcome = run_cli(args, cwd=work, env={"CURIOSITY_CACHE": str(work / "results" / "cache")}, timeout=120)
    line = assert_clean_error(outcome, *names, code=code)
    assert len(line) < LONGEST_LINE, line
    assert_written_only_inside(before, files_under(tmp_path), work / "results")


@pytest.mark.parametrize("text, value", [("1e-3", "0.001"), ("1E2", "100.0"), (".5", "0.5"), ("5.", "5.0")])
def test_the_float_forms_people_type_are_accepted(tmp_path, text, value):
    outcome = run_cli(["config", "show", _experiment(tmp_path).name, "--set", f"model.alpha={text}"], cwd=tmp_path)
    assert outcome.code == 0, outcome.output
    assert f"  alpha: {value}\n" in outcome.stdout


def test_the_grid_refuses_a_folder_outside_the_results_as_a_second_line_of_defence(tmp_path):
    from curiosity_cli.config import load_config
    from curiosity_cli.errors import ConfigError
    from curiosity_cli.explore.grid import run_grid

    # a name that slipped past the loader's check, as code (not a YAML file) could pass it
    config = dataclasses.replace(load_config(CONFIG_DIR / "quick.yaml"), name="../escaped")
    before = files_under(tmp_path)
    with pytest.raises(ConfigError, match=r"^name: .*escaped is not inside .*results; expected a name without '/' or '\.\.'$"):
        run_grid(config, results_dir=tmp_path / "results", cache_dir=tmp_path / "results" / "cache")
    assert files_under(tmp_path) == before
