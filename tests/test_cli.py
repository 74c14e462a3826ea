"""One CliRunner test (or more) per command: exit code and text."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from small_maps import edit_yaml
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.config import CONFIG_DIR, shipped_configs

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, list(args))


def test_help_in_a_subprocess_lists_every_command():
    console_script = str(Path(sys.executable).parent / "curiosity")
    for command in ([console_script, "--help"], [sys.executable, "-m", "curiosity_cli", "--help"]):
        result = subprocess.run(command, capture_output=True, text=True, check=False)
        assert result.returncode == 0, result.stderr
        for name in ("extract", "explore", "label", "evaluate", "plot", "reproduce", "drive", "datasets"):
            assert name in result.stdout


def test_help_imports_no_heavy_library():
    code = (
        "import sys\n"
        "from curiosity_cli.cli import app\n"
        "try:\n    app(['--help'])\nexcept SystemExit:\n    pass\n"
        "heavy = [m for m in ('numpy', 'numba', 'cv2', 'matplotlib', 'pandas', 'serial', 'dask', 'distributed') if m in sys.modules]\n"
        "print('HEAVY', heavy)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "HEAVY []" in result.stdout


def test_version():
    result = run("--version")
    assert result.exit_code == 0 and result.stdout.startswith("curiosity ")


def test_datasets_list_as_json_gives_the_rows_of_the_api():
    import json

    from curiosity_cli import api

    result = run("datasets", "list", "--json")
    assert result.exit_code == 0, result.output
    listed = json.loads(result.stdout)
    assert listed == [json.loads(json.dumps(row._asdict())) for row in api.list_datasets()]
    aerial = next(row for row in listed if row["name"] == "aerial-mosaic")
    assert aerial["size"] == [1024, 1024] and aerial["grid"] == [64, 64] and aerial["pixels"] == "embedded"


def test_datasets_list_shows_the_maps():
    result = run("datasets", "list")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].split()[:3] == ["name", "size", "(px)"]
    rows = {line.split()[0]: line for line in lines[2:]}
    assert sorted(rows) == [
        "aerial-mosaic", "geonrw-essen", "planted-disjoint", "planted-shared", "rare-patches", "reef-mosaic",
        "sentinel-coast", "zurich-zh17",
    ]
    assert "embedded" in rows["reef-mosaic"] and "generated" in rows["planted-shared"]
    assert "1024 x 1024" in rows["aerial-mosaic"] and "4096 (64 x 64)" in rows["aerial-mosaic"]
    assert "2500 x 2500" in rows["reef-mosaic"] and "6241 (79 x 79)" in rows["reef-mosaic"]
    assert "992 x 992" in rows["geonrw-essen"] and "3844 (62 x 62)" in rows["geonrw-essen"]


def test_datasets_show_prints_legend_and_writes_a_preview(tmp_path):
    out = tmp_path / "preview.png"
    result = run("datasets", "show", "aerial-mosaic", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "aerial-mosaic: 1024 x 1024 px, 16 px cells (64 x 64 = 4096)" in result.stdout
    assert "trail" in result.stdout
    preview = cv2.imread(str(out))
    assert preview is not None and preview.shape[1] > 1000
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left behind


def test_datasets_show_defaults_to_results_folder(tmp_path, monkeypatch, own_map):
    monkeypatch.chdir(tmp_path)
    result = run("datasets", "show", str(own_map))
    assert result.exit_code == 0, result.output
    assert (tmp_path / "results" / "datasets" / "own.png").is_file()
    assert "sand" in result.stdout and "50.00%" in result.stdout


def test_datasets_show_several_maps_in_one_figure(tmp_path, own_map):
    out = tmp_path / "both.pdf"
    result = run("datasets", "show", str(own_map), str(own_map), "--out", str(out))
    assert result.exit_code == 0, result.output
    assert out.read_bytes().startswith(b"%PDF")


def test_config_show_prints_the_resolved_config():
    result = run("config", "show", str(CONFIG_DIR / "quick.yaml"), "--set", "explore.restarts=3")
    assert result.exit_code == 0, result.output
    assert "name: quick" in result.stdout and "restarts: 3" in result.stdout and "base:" not in result.stdout


def _assert_one_line_error(result, *fragments: str) -> None:
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ")
    for fragment in fragments:
        assert fragment in lines[0]


def test_bad_override_is_one_line_error():
    result = run("config", "show", str(CONFIG_DIR / "quick.yaml"), "--set", "model.topics=1000")
    _assert_one_line_error(result, "--set: model.topics: got 1000 (int), expected an integer >= 2 and <= 127")


def test_unknown_key_in_config_file_is_one_line_error(tmp_path):
    path = tmp_path / "exp.yaml"
    text = (CONFIG_DIR / "quick.yaml").read_text().replace("restarts: 10", "restartz: 10")
    path.write_text(text.replace("base: paper.yaml", f"base: {CONFIG_DIR / 'paper.yaml'}"))
    _assert_one_line_error(run("config", "show", str(path)), "exp.yaml: explore.restartz: unknown key")


def test_missing_config_is_one_line_error():
    _assert_one_line_error(run("config", "show", "no/such.yaml"), "no/such.yaml: config file not found")


def test_a_folder_given_for_a_config_is_named_as_one(tmp_path):
    experiment = tmp_path / "quick"
    experiment.mkdir()
    _assert_one_line_error(run("explore", str(tmp_path)), f"{tmp_path}: a folder, not a config; expected a path to a YAML")
    (experiment / "config.yaml").write_text("name: quick\n")
    _assert_one_line_error(
        run("explore", str(experiment)), f"{experiment}: an experiment folder, not a config; its saved config is "
        f"{experiment / 'config.yaml'}",
    )


def test_a_map_listed_twice_is_refused_by_config_show_as_explore_would(own_map, tmp_path):
    twice = f"datasets=[aerial-mosaic, {own_map}, aerial-mosaic]"
    _assert_one_line_error(
        run("config", "show", "quick", "--set", twice),
        "--set: datasets[2]: got 'aerial-mosaic', a second map named 'aerial-mosaic' (datasets[0]); runs are filed by map name",
    )
    _assert_one_line_error(run("explore", "quick", "--set", twice, "--results-dir", str(tmp_path / "results")), "datasets[2]")
    assert not (tmp_path / "results").exists()


def test_a_vocabulary_that_is_not_there_is_refused_by_config_show_as_explore_would(tmp_path, monkeypatch):
    message = "orb-10.npz: vocabulary not found; `curiosity vocab build` builds the orb vocabulary of 10 words"
    _assert_one_line_error(run("config", "show", "quick", "--set", "words.orb_vocabulary=10"), message)
    # with nothing cached: refused before the quick map's source is fetched, not after a download
    cache = tmp_path / "cache"
    monkeypatch.setenv("CURIOSITY_CACHE", str(cache))
    _assert_one_line_error(
        run("explore", "quick", "--set", "words.orb_vocabulary=10", "--results-dir", str(tmp_path / "results"),
            "--cache-dir", str(cache / "stores")), message
    )
    assert not cache.exists() or not any(path.is_file() for path in cache.rglob("*"))


def test_unknown_dataset_is_one_line_error():
    _assert_one_line_error(run("datasets", "show", "atlantis"), "no dataset 'atlantis'")


def test_bad_preview_suffix_is_one_line_error(own_map, tmp_path):
    _assert_one_line_error(run("datasets", "show", str(own_map), "--out", str(tmp_path / "p.gif")), "Error: --out: got", "expected a .png or .pdf")


@pytest.mark.parametrize(
    "break_it, fragment",
    [
        (lambda d: (d / "map.png").write_text("garbage"), "image: cannot read"),
        (lambda d: (d / "map.png").write_bytes(b""), "is empty"),
        (lambda d: cv2.imwrite(str(d / "labels.png"), np.zeros((10, 10), np.uint8)), "expected the image's size"),
        (lambda d: cv2.imwrite(str(d / "labels.png"), np.full((96, 128), 9, np.uint8)), "class ids [9]"),
        (lambda d: edit_yaml(d / "own.yaml", cell_width=500), "cell_width: got 500"),
        (lambda d: edit_yaml(d / "own.yaml", cell_width="wide"), "cell_width: got 'wide' (str), expected an integer >= 1"),
        (lambda d: edit_yaml(d / "own.yaml", colour=True), "own.yaml: colour: unknown key"),
        (lambda d: edit_yaml(d / "own.yaml", image=...), "own.yaml: image: missing key"),
    ],
)
def test_bad_own_map_is_one_line_error(own_map, break_it, fragment):
    break_it(own_map.parent)
    _assert_one_line_error(run("datasets", "show", str(own_map)), fragment)


def test_extract_prints_counts_then_reuses_its_cache(own_map, tmp_path):
    cache = tmp_path / "cache"
    first = run("extract", str(own_map), "--cache-dir", str(cache))
    assert first.exit_code == 0, first.output
    assert "wrote " in first.stdout and "12,288  ids 5000..5999 (texton-1000)" in first.stdout
    assert "words per cell: min" in first.stdout and "seconds: orb" in first.stdout
    second = run("extract", str(own_map), "--cache-dir", str(cache))
    assert second.exit_code == 0 and "reused " in second.stdout and "seconds" not in second.stdout


def test_extract_writes_a_density_png(own_map, tmp_path):
    out = tmp_path / "density.png"
    result = run("extract", str(own_map), "--cache-dir", str(tmp_path / "c"), "--density", str(out))
    assert result.exit_code == 0, result.output
    assert cv2.imread(str(out)) is not None
    # a path that does not say PNG is a usage error, before anything is extracted or written
    text = tmp_path / "d.txt"
    result = run("extract", str(own_map), "--cache-dir", str(tmp_path / "c2"), "--density", str(text))
    box = " ".join(re.sub("[│╭╮╰╯─]", " ", result.stderr).split())  # click wraps its box to the terminal
    assert result.exit_code == 2 and "--density" in box and "expected a path ending in .png" in box
    assert not text.exists() and not (tmp_path / "c2").exists()


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--set", "model.topics=3"], "expected a words.* key"),
        (["--set", "words.texton_vocabulary=77"], "texton-77.npz: vocabulary not found"),
        # as the dataset YAML's word_stride is refused, named by the option that gave it
        (["--stride", "40"], "Error: --stride: got a stride of 40 px with cells of 16 px, expected a stride of at most the cell width"),
        (["--stride", "12", "--cell-width", "8"], "Error: --stride: got a stride of 12 px with cells of 8 px"),
        (["--cell-width", "1000"], "Error: --cell-width: got 1000, expected at most the image's smaller side (96 px)"),
    ],
)
def test_extract_bad_options_are_one_line_errors(own_map, tmp_path, args, fragment):
    cache = tmp_path / "cache"
    _assert_one_line_error(run("extract", str(own_map), "--cache-dir", str(cache), *args), fragment)
    assert not cache.exists()


def test_extract_names_a_cell_width_narrower_than_the_datasets_stride(own_map, tmp_path):
    edit_yaml(own_map, word_stride=16)
    result = run("extract", str(own_map), "--cache-dir", str(tmp_path / "cache"), "--cell-width", "8")
    _assert_one_line_error(result, "Error: --cell-width: got a stride of 16 px with cells of 8 px")


@pytest.mark.parametrize("option", ["--stride", "--cell-width"])
def test_extract_stride_or_cell_width_below_one_is_a_usage_error(own_map, tmp_path, option):
    result = run("extract", str(own_map), "--cache-dir", str(tmp_path / "cache"), option, "0")
    box = " ".join(re.sub("[│╭╮╰╯─]", " ", result.stderr).split())  # click wraps its box to the terminal
    assert result.exit_code == 2 and f"Invalid value for '{option}'" in box, result.output
    assert not (tmp_path / "cache").exists()


@pytest.mark.parametrize(
    "args, option",
    [
        (["explore", "quick", "--results-dir", ""], "--results-dir"),
        (["explore", "quick", "--cache-dir", ""], "--cache-dir"),
        (["extract", "aerial-mosaic", "--cache-dir", ""], "--cache-dir"),
        (["label", ""], "folder"),
        (["reproduce", "quick", "--results-dir", ""], "--results-dir"),
    ],
)
def test_an_empty_path_is_a_usage_error_not_the_current_folder(tmp_path, monkeypatch, args, option):
    # an unset shell variable: `--results-dir "$OUT"` would otherwise fill the working folder
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    box = " ".join(re.sub("[│╭╮╰╯─]", " ", result.stderr).split())
    assert result.exit_code == 2, result.output
    assert f"Invalid value for {option}: got '' (an empty path), expected a path" in box
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "args, option, given",
    [
        (["--weights", "random-walk,topic-perplexity,random-walk"], "--weights", "'random-walk' twice, expected each weight function once"),
        (["--map", "MAP", "--map", "MAP"], "--map", "twice, expected each map once"),
    ],
)
def test_explore_names_a_walker_or_map_given_twice_by_its_option(own_map, tmp_path, args, option, given):
    args = [str(own_map) if arg == "MAP" else arg for arg in args]
    result = run("explore", "quick", *args, "--results-dir", str(tmp_path / "results"))
    box = " ".join(re.sub("[│╭╮╰╯─]", " ", result.stderr).split())
    assert result.exit_code == 2, result.output
    assert f"Invalid value for {option}: got" in box and given in box and "--set" not in box
    assert not (tmp_path / "results").exists()


def test_datasets_show_notes_a_character_the_font_lacks_once_with_no_raw_warning(own_map, tmp_path, recwarn):
    legend = own_map.parent / "legend.yaml"
    legend.write_text(legend.read_text().replace("name: sand", "name: \"\\U0001F30A sand\""))
    result = run("datasets", "show", str(own_map), "--out", str(tmp_path / "p.png"))
    assert result.exit_code == 0, result.output
    assert "\U0001F30A sand" in result.stdout
    assert result.stderr.splitlines() == ["the figure's font has no \U0001F30A (U+1F30A): drawn as an empty box"]
    assert not [w for w in recwarn if "Glyph" in str(w.message)]


def test_extract_corrupt_image_is_one_line_error(own_map, tmp_path):
    (own_map.parent / "map.png").write_bytes(b"\x89PNG\r\n\x1a\n broken")
    _assert_one_line_error(run("extract", str(own_map), "--cache-dir", str(tmp_path / "c")), "image: ", "map.png is truncated")


def test_vocab_build_refuses_a_tiny_vocabulary_as_a_usage_error(tmp_path):
    result = run("vocab", "build", "--out", str(tmp_path), "--orb-words", "1")
    assert result.exit_code == 2 and "--orb-words" in result.output and "Traceback" not in result.output


def test_reproduce_quick_runs_quick_yaml_so_a_config_beside_it_is_a_usage_error():
    result = run("reproduce", str(CONFIG_DIR / "paper-grid.yaml"), "--quick")
    assert result.exit_code == 2
    assert "--quick" in result.output and "runs configs/quick.yaml" in result.output


@pytest.mark.parametrize("command", ["label", "reproduce"])
def test_converged_with_a_label_sweeps_override_is_one_clear_error(command, tmp_path):
    where = ["--results-dir", str(tmp_path)] if command == "reproduce" else [str(tmp_path)]
    result = run(command, "--converged", "--set", "label.sweeps=3", *where)
    assert result.exit_code == 1
    assert result.output.strip() == (
        "Error: --set 'label.sweeps=3': the converged schedule sets label.sweeps=256 and label.warm_sweeps=null; "
        "give either, not both"
    )


def test_config_init_writes_a_commented_copy_named_for_the_experiment(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run("config", "init", "my-exp", "--from", "paper-grid")
    assert result.exit_code == 0, result.output
    assert result.stdout.strip() == "wrote my-exp.yaml (a copy of the shipped paper-grid); run `curiosity reproduce my-exp.yaml`"
    text = (tmp_path / "my-exp.yaml").read_text()
    assert "# The paper's full experiment grid" in text and "\nname: my-exp " in text
    assert "name: my-exp\n" in run("config", "show", "my-exp.yaml").stdout  # its base: paper.yaml resolves from here
    again = run("config", "init", "my-exp")
    assert again.exit_code == 1 and again.stderr.strip() == "Error: my-exp.yaml: already exists; choose another name or edit that file"
    wrong = run("config", "init", "x", "--from", "paper")
    experiments = ", ".join(name for name in shipped_configs() if name != "paper")
    assert wrong.exit_code == 1 and f"--from: got 'paper', expected a shipped experiment config: {experiments}" in wrong.stderr
    assert {"paper-grid", "quick", "readings"} <= set(experiments.split(", "))
    assert run("config", "init", "../x").exit_code == 1 and not (tmp_path.parent / "x.yaml").exists()


def test_a_shipped_config_is_named_from_any_folder_and_a_path_still_means_a_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert "name: paper-grid\n" in run("config", "show", "paper-grid").stdout
    base = run("config", "show", "paper").stdout  # the base the others build on: its parameters, checked
    assert base.startswith("model:\n  topics: 64\n") and "name:" not in base
    (tmp_path / "quick").write_text("base: paper.yaml\nname: mine\nseed: 1\ndatasets: [aerial-mosaic]\n")
    assert "name: mine\n" in run("config", "show", "quick").stdout  # a file of that name is the file
    missing = run("config", "show", "qiuck")
    assert missing.exit_code == 1 and "qiuck: config file not found; expected a path to a YAML config or the name of a shipped one" in missing.stderr


def test_the_paths_table_follows_the_environment(tmp_path):
    code = "from curiosity_cli import paths; print(paths.DEFAULT_RESULTS, paths.DEFAULT_CACHE, paths.user_cache())"
    env = {**os.environ, "CURIOSITY_RESULTS": str(tmp_path / "r"), "CURIOSITY_CACHE": str(tmp_path / "c")}
    printed = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split()
    assert printed == [str(tmp_path / "r"), str(tmp_path / "c" / "stores"), str(tmp_path / "c")]
    env = {k: v for k, v in os.environ.items() if not k.startswith("CURIOSITY_")} | {"XDG_CACHE_HOME": str(tmp_path / "x")}
    printed = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split()
    assert printed == ["results", str(tmp_path / "x" / "curiosity" / "stores"), str(tmp_path / "x" / "curiosity")]


def saved_experiment(folder: Path) -> Path:
    """An experiment folder holding only its saved config (the quick job's): what `label` reads first."""
    import yaml

    from curiosity_cli.config import load_config
    from curiosity_cli.config_yaml import to_dict

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "config.yaml").write_text(yaml.safe_dump(to_dict(load_config("quick"))))
    return folder


def test_label_on_cuda_without_numba_cuda_is_one_error_line_naming_the_extra(tmp_path, monkeypatch):
    import curiosity_cli._numba

    def missing():
        raise ImportError("numba-cuda is not installed")

    monkeypatch.setattr(curiosity_cli._numba, "import_cuda", missing)
    result = run("label", str(saved_experiment(tmp_path / "exp")), "--set", "label.device=cuda")
    assert result.exit_code == 1
    assert result.stderr.strip().startswith("Error: label.device: cuda, but it needs numba-cuda, the extra curiosity-cli[cuda]")
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.output
    assert not (tmp_path / "exp" / "labels").exists()


def test_label_on_cuda_without_a_gpu_is_one_error_line_and_auto_falls_back_to_the_cpu_once(tmp_path, monkeypatch, capsys):
    pytest.importorskip("numba_cuda")
    from curiosity_cli.topics import _chain_kernels_cuda

    monkeypatch.setattr(_chain_kernels_cuda, "gpu_available", lambda: (False, "no driver here"))
    result = run("label", str(saved_experiment(tmp_path / "exp")), "--set", "label.device=cuda")
    assert result.exit_code == 1
    assert result.stderr.strip() == "Error: label.device: cuda, but no CUDA GPU was found (no driver here)"
    from curiosity_cli.topics.devices import resolve_device

    capsys.readouterr()
    assert resolve_device("auto") == "cpu"
    assert capsys.readouterr().err == "label.device is auto: labelling on the CPU, as no CUDA GPU was found (no driver here)\n"
