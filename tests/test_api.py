"""The Python API, function by function, beside the command line's tests: every command has its function, with
the command's arguments and defaults, and each function does from Python what its command does."""

from __future__ import annotations

import enum
import inspect
from pathlib import Path

import numpy as np
import pytest
import typer.main
import yaml
from small_maps import tiny_yaml

from curiosity_cli import api
from curiosity_cli.cli import app
from curiosity_cli.config import ExperimentConfig
from curiosity_cli.errors import ConfigError, CuriosityError, ParameterError, UsageError
from curiosity_cli.experiment.stage_seconds import STAGES, read_stage_seconds

#: Each command's function, and the options the command line keeps to itself (each
#: parsed into an argument, or choosing which function to call).
COMMANDS = {
    "extract": (api.extract, set()),
    "explore": (api.explore, set()),
    "label": (api.label, set()),
    "evaluate": (api.evaluate, set()),
    "plot": (api.plot, {"animate", "out", "cache_dir"}),
    "reproduce": (api.reproduce, {"quick"}),
    "drive": (api.drive, {"timeline"}),
    "simrobot": (api.simrobot, set()),
    "datasets list": (api.list_datasets, {"as_json"}),  # how the rows are printed
    "datasets show": (api.show_datasets, set()),
    "vocab build": (api.build_vocabularies, set()),
    "config show": (api.show_config, set()),
    "config init": (api.init_config, set()),
}
#: Arguments a command leaves unset for an option it keeps to decide (``reproduce`` without ``--quick``).
DECIDED = {("reproduce", "config"): "quick"}
#: The functions of the options a command keeps: ``plot --animate``, ``drive --timeline``.
OPTION_FUNCTIONS = {("plot", "animate"): api.animate, ("drive", "timeline"): api.redraw_timeline}


def leaf_commands(command, prefix: str = ""):
    for name, sub in getattr(command, "commands", {}).items():
        yield from leaf_commands(sub, f"{prefix} {name}".strip())
    if not getattr(command, "commands", None):
        yield prefix, command


def _value(default):
    return default.value if isinstance(default, enum.Enum) else default


def test_every_command_has_a_function_with_its_arguments_and_defaults():
    commands = dict(leaf_commands(typer.main.get_command(app)))
    assert set(commands) == set(COMMANDS)
    for name, command in commands.items():
        function, kept = COMMANDS[name]
        signature = inspect.signature(function)
        for param in command.params:
            if param.name in kept or param.name == "help":
                continue
            assert param.name in signature.parameters, f"{name}: {param.name}"
            default = signature.parameters[param.name].default
            if param.required:
                assert default is inspect.Parameter.empty, f"{name}: {param.name}"
                continue
            given = DECIDED.get((name, param.name), _value(param.default))
            if isinstance(default, (str, Path)) and isinstance(given, (str, Path)):
                default, given = str(default), str(given)
            # a repeatable option's empty default is an empty sequence either way
            if param.multiple and not given:
                given, default = (), tuple(default)
            assert default == given, f"{name} {param.name}: the API's {default!r}, the command's {given!r}"
    for (command, option), function in OPTION_FUNCTIONS.items():
        assert option in COMMANDS[command][1] and function.__doc__.startswith(f"``curiosity {command} --{option}``")
    assert all(function.__doc__.startswith(f"``curiosity {name}``") for name, (function, _) in COMMANDS.items())


# --------------------------------------------------------------------------- configs


def test_load_refuses_a_config_that_declares_a_sweep_unless_its_swept_keys_are_fixed():
    with pytest.raises(ConfigError, match=r"^config: .*readings.yaml declares a sweep over explore.coverage, seed") as many:
        api.load("readings")
    assert many.value.parameter == "config"
    config = api.load("readings", ["explore.coverage=clamp", "seed=2"])
    assert (config.name, config.explore.coverage, config.seed) == ("readings", "clamp", 2)
    with pytest.raises(ConfigError, match=r"^overrides: got \['seed=1'\], but the config is already resolved"):
        api.load(config, ["seed=1"])
    assert api.load(config) is config


def test_show_and_init_config(tmp_path):
    shown = yaml.safe_load(api.show_config("quick", ["explore.restarts=3"]))
    assert (shown["name"], shown["explore"]["restarts"]) == ("quick", 3)
    path = api.init_config("mine", "readings", tmp_path)
    assert path == tmp_path / "mine.yaml" and "name: mine" in path.read_text()
    with pytest.raises(ConfigError, match="already exists"):
        api.init_config("mine", "readings", tmp_path)


# --------------------------------------------------------------------------- maps and words


def test_list_and_show_datasets(own_map, tmp_path):
    rows = {row.name: row for row in api.list_datasets()}
    aerial = rows["aerial-mosaic"]
    assert aerial.pixels == "embedded" and aerial.size is not None and aerial.classes > 1
    assert aerial.grid == (aerial.size[0] // aerial.cell_width, aerial.size[1] // aerial.cell_width)
    preview = api.show_datasets([str(own_map)], out=tmp_path / "own.png")
    assert preview.path.is_file() and [m.config.name for m in preview.maps] == ["own"] and preview.notes == [{}]


def test_extract_makes_then_reuses_a_store_and_refuses_a_density_that_is_no_png(own_map, tmp_path):
    made = api.extract(str(own_map), cache_dir=tmp_path, density=tmp_path / "density.png")
    assert not made.reused and (tmp_path / "density.png").is_file() and len(made.store.words) > 0
    again = api.extract(str(own_map), cache_dir=tmp_path)
    assert again.reused and again.path == made.path
    np.testing.assert_array_equal(api.word_store(str(own_map), cache_dir=tmp_path).words, made.store.words)
    with pytest.raises(UsageError, match=r"^density: got .*density.jpg, expected a path ending in .png") as bad:
        api.extract(str(own_map), cache_dir=tmp_path, density=tmp_path / "density.jpg")
    assert bad.value.detail({"density": "--density"}).startswith("got ")


def test_build_vocabularies_refuses_a_size_out_of_range_before_any_work(tmp_path):
    with pytest.raises(ParameterError, match=r"^orb_words: got 1, expected 2 to 30000$"):
        api.build_vocabularies(tmp_path, orb_words=1)
    assert not any(tmp_path.iterdir())


# --------------------------------------------------------------------------- the experiment


@pytest.mark.slow
def test_explore_label_evaluate_plot_and_animate_from_python(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    results = tmp_path / "results"
    prepared = []
    summary = api.explore(
        config, weights=["topic-perplexity"], restarts=1, steps=40, results_dir=results, cache_dir=tmp_path / "cache",
        jobs=1, on_prepared=lambda *args: prepared.append(args),
    )
    assert prepared == [("tiny", 1, 0)] and summary.ran == 1 and summary.folder == results / "tiny"
    run = api.open_experiment(summary.folder).run("own", "topic-perplexity", 0)
    assert len(run.path) == 40 and run.meta["checkpoints"] == [40]  # --steps: 80 dropped, 40 the last
    labelled = api.label(summary.folder, cache_dir=tmp_path / "cache", jobs=1)
    assert labelled["labelled"] == 1
    evaluation = api.evaluate(summary.folder)
    assert set(evaluation.mi["weight_function"]) == {"topic-perplexity"}
    written = api.plot(summary.folder)
    assert written and all(path.is_file() for path in written)
    # the stages one at a time give the report reproduce gives, timed by what each stage did
    assert written.report == summary.folder / "REPORT.md" and "## Verdict" in written.report.read_text()
    times = read_stage_seconds(summary.folder)
    assert list(times) == list(STAGES) and all(seconds > 0 for seconds in times.values())
    table = written.report.read_text().split("## Time")[1]
    assert f"| label | {times['label']:.0f} |" in table and f"| total | {sum(times.values()):.0f} |" in table
    assert api.label(summary.folder, cache_dir=tmp_path / "cache", jobs=1)["labelled"] == 0
    assert read_stage_seconds(summary.folder)["label"] == times["label"]  # a call with nothing to do adds nothing
    api.explore(config, weights=["topic-perplexity"], restarts=2, steps=40, results_dir=results,
                cache_dir=tmp_path / "cache", jobs=1)
    assert read_stage_seconds(summary.folder)["extract and explore"] > times["extract and explore"]  # resumed: added
    animation = api.animate(summary.folder, "own", "topic-perplexity", 0, cache_dir=tmp_path / "cache")
    assert animation.is_file() and animation.suffix == ".gif"


def test_explore_refuses_arguments_that_do_not_fit_as_usage_errors(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    with pytest.raises(UsageError, match=r"^weights: got 'topic', expected one of random-walk, ") as bad:
        api.explore(config, weights=["topic"], results_dir=tmp_path)
    assert bad.value.parameter == "weights"
    with pytest.raises(UsageError, match=r"^maps: no dataset 'nowhere'"):
        api.explore(config, maps=["nowhere"], results_dir=tmp_path)
    with pytest.raises(UsageError, match=r"^scheduler: needs `backend` dask$") as bad:
        api.explore(config, scheduler="tcp://127.0.0.1:1", results_dir=tmp_path)
    assert bad.value.detail({"backend": "--backend"}) == "needs --backend dask"
    with pytest.raises(UsageError, match=r"^scheduler: "):
        api.label(tmp_path, scheduler="tcp://127.0.0.1:1")
    assert not (tmp_path / "tiny").exists()


@pytest.mark.slow
def test_reproduce_runs_a_declared_sweep_as_the_command_does(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    text = yaml.safe_load(config.read_text())
    text["explore"].update(weight_functions=["random-walk", "topic-perplexity"], restarts=2)
    text["sweep"] = {"seed": [0, 1]}
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    status = []
    report = api.reproduce(config, results_dir=tmp_path / "results", cache_dir=tmp_path / "cache", jobs=1,
                           on_status=status.append)
    folder = tmp_path / "results" / "tiny-sweep"
    assert report == folder / "SWEEP.md" and report.is_file()
    assert status == [f"2 combinations, in {folder}"]
    assert sorted(p.name for p in folder.iterdir() if p.is_dir()) == ["seed-0", "seed-1"]
    with pytest.raises(UsageError, match=r"^sweeps: .*KEY=V1,V2"):
        api.reproduce(config, sweeps=["seed"], results_dir=tmp_path / "results")


def test_reproduce_defaults_to_quick_as_explore_and_the_command_do():
    assert inspect.signature(api.reproduce).parameters["config"].default == "quick"
    assert inspect.signature(api.explore).parameters["config"].default == "quick"
    with pytest.raises(UsageError, match=r"^sweeps: a resolved config is one experiment"):
        api.reproduce(api.load("quick"), sweeps=["seed=0,1"])


# --------------------------------------------------------------------------- the robot


@pytest.mark.parametrize("arguments, parameter, detail", [
    (dict(dry_run=True, serial="/dev/null"), "dry_run", "--dry-run sends nothing; leave out --serial"),
    (dict(dry_run=True, camera="sim"), "sim_map", "--camera sim and --sim-map go together"),
    (dict(dry_run=True, start=(1.0, 1.0)), "start", "only a dry run simulates the robot here; give the start to `curiosity simrobot`"),
    (dict(dry_run=True, heading_deg=float("nan")), "heading_deg", "got nan, expected a finite number"),
    (dict(), "serial", "give the robot's port with --serial (or drive.port in the config), or --dry-run"),
])
def test_drive_refuses_arguments_that_do_not_go_together(arguments, parameter, detail, tmp_path):
    with pytest.raises(UsageError) as bad:
        api.drive(out=tmp_path / "run", **arguments)
    options = {"dry_run": "--dry-run", "serial": "--serial", "camera": "--camera", "sim_map": "--sim-map"}
    assert bad.value.parameter == parameter and bad.value.detail(options) == detail
    assert not (tmp_path / "run").exists()


def test_drive_a_dry_run_on_the_simulated_camera_and_refuse_a_start_off_the_map(own_map, tmp_path):
    with pytest.raises(UsageError, match=r"^start: got 500,1, expected a point inside the map \(96 x 128 px\)$"):
        api.drive(dry_run=True, camera="sim", sim_map=str(own_map), start=(500.0, 1.0), out=tmp_path / "off")
    frames = []
    outcome, folder = api.drive(
        dry_run=True, camera="sim", sim_map=str(own_map), overrides=["drive.sim_frame_interval=0.1"], max_frames=3,
        out=tmp_path / "run", on_frame=lambda number, decision: frames.append(number),
    )
    assert outcome.frames == 3 and len(frames) == 3 and folder == tmp_path / "run" and (folder / "log.jsonl").is_file()
    saved = yaml.safe_load((folder / "config.yaml").read_text())
    assert list(saved) == ["seed", "model", "words", "drive"] and saved["drive"]["sim_frame_interval"] == 0.1
    # a camera's run: no timeline to draw, its trajectory (the simulated robot's poses) alone
    assert api.redraw_timeline(folder) == [folder / "trajectory.png"]


def test_simrobot_refuses_a_start_off_the_map_and_a_heading_that_is_no_number(own_map):
    with pytest.raises(UsageError, match=r"^start: got -1,1, expected a point inside the map"):
        api.simrobot(str(own_map), start=(-1.0, 1.0))
    with pytest.raises(UsageError, match=r"^heading_deg: got inf, expected a finite number$"):
        api.simrobot(str(own_map), heading_deg=float("inf"))


def test_a_resolved_config_is_taken_as_it_is():
    config = api.load("quick")
    assert isinstance(config, ExperimentConfig) and api.load(config) is config


# --------------------------------------------------------------------------- misuse from Python


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory):
    """A tiny experiment on an embedded map, explored, labelled and evaluated through the API."""
    folder = tmp_path_factory.mktemp("evaluated")
    small = ["datasets=[aerial-mosaic]", "explore.restarts=2", "explore.path_length=20", "explore.checkpoints=[10, 20]",
             "explore.weight_functions=[random-walk, topic-perplexity]", "label.sweeps=2", "label.batch_sweeps=3",
             "name=misuse"]
    experiment = api.explore("quick", overrides=small, results_dir=folder, cache_dir=folder / "cache", jobs=1).folder
    api.label(experiment, cache_dir=folder / "cache", jobs=1)
    api.evaluate(experiment)
    return api.open_experiment(experiment)


@pytest.mark.slow
@pytest.mark.parametrize("call, parameter", [
    (lambda r: r.table("nope"), "name"),
    (lambda r: r.table("../provenance"), "name"),
    (lambda r: r.run("aerial-mosaic", "topic-perplexity", "0"), "restart"),
    (lambda r: r.run("aerial-mosaic", "topic-perplexity", 0.5), "restart"),
    (lambda r: r.run("aerial-mosaic", "topic-perplexity", -1), "restart"),
    (lambda r: r.run("aerial-mosaic", "topic-perplexity", True), "restart"),
    (lambda r: r.run("aerial-mosaic", "topic-perplexity", 0).phi("20"), "length"),
])
def test_misused_results_name_the_argument(evaluated, call, parameter):
    with pytest.raises(ParameterError, match=rf"^{parameter}: got "):
        call(evaluated)
    assert evaluated.table("summary")["dataset"].unique().tolist() == ["aerial-mosaic"]
    assert evaluated.run("aerial-mosaic", "topic-perplexity", 1).phi(20).sum() > 0


@pytest.mark.slow
@pytest.mark.parametrize("run, message", [
    (("aerial-mosaic", "topic-perplexity", 7), r"^restart: got 7, expected a restart of .*config\.yaml: 0 to 1$"),
    (("nomap", "topic-perplexity", 0), r"^dataset: got 'nomap', expected a map of .*config\.yaml: aerial-mosaic$"),
    (("aerial-mosaic", "lawnmower", 0), r"^weight_function: got 'lawnmower', expected a walker of .*: random-walk, topic-perplexity$"),
])
def test_a_run_outside_the_grid_is_named_not_called_unfinished(evaluated, run, message):
    # explore would never make it: "not finished; explore redoes the run" would send the user in circles
    with pytest.raises(ParameterError, match=message):
        evaluated.run(*run)


@pytest.mark.parametrize("call, parameter", [
    (lambda: api.load(123), "config"),
    (lambda: api.load(None), "config"),
    (lambda: api.load("quick", overrides=[3]), "overrides"),
    (lambda: api.load("quick", overrides="explore.restarts=3"), "overrides"),
    (lambda: api.explore(42), "config"),
    (lambda: api.explore("quick", jobs="2"), "jobs"),
    (lambda: api.explore("quick", restarts=True), "restarts"),
    (lambda: api.explore("quick", weights="topic-perplexity"), "weights"),
    (lambda: api.explore("quick", maps="aerial-mosaic"), "maps"),
    (lambda: api.label(None), "folder"),
    (lambda: api.label("results/quick", jobs=0), "jobs"),
    (lambda: api.evaluate(5), "folder"),
    (lambda: api.plot(5), "folder"),
    (lambda: api.animate("results/quick", "aerial-mosaic", "topic-perplexity", "0"), "restart"),
    (lambda: api.reproduce(7), "config"),
    (lambda: api.reproduce("quick", sweeps="seed=0,1"), "sweeps"),
    (lambda: api.extract(3), "dataset"),
    (lambda: api.extract("aerial-mosaic", stride=0), "stride"),
    (lambda: api.show_datasets("aerial-mosaic"), "datasets"),
    (lambda: api.show_datasets([]), "datasets"),  # not matplotlib's ValueError of a figure with no rows
    # an empty path (an unset variable) is refused, not taken as the current folder
    (lambda: api.explore("quick", results_dir=""), "results_dir"),
    (lambda: api.extract("aerial-mosaic", cache_dir=""), "cache_dir"),
    (lambda: api.show_datasets(["aerial-mosaic"], out=""), "out"),
    (lambda: api.build_vocabularies(texton_words=2.5), "texton_words"),
    (lambda: api.show_config(1), "config"),
    (lambda: api.init_config(None), "name"),
    (lambda: api.open_experiment(3), "folder"),
    (lambda: api.drive(dry_run=True, max_frames=0), "max_frames"),
    (lambda: api.simrobot(None), "map_name"),
    # a flag is True or False: "no" is not taken as true (issue 44)
    (lambda: api.evaluate("results/quick", partial="no"), "partial"),
    (lambda: api.label("results/quick", converged="yes"), "converged"),
    (lambda: api.label("results/quick", reuse=0), "reuse"),
    (lambda: api.label("results/quick", force="false"), "force"),
    (lambda: api.explore("quick", force=1), "force"),
    (lambda: api.extract("aerial-mosaic", force="no"), "force"),
    (lambda: api.reproduce("quick", converged="no"), "converged"),
    (lambda: api.reproduce("quick", reuse=None), "reuse"),
    (lambda: api.drive(dry_run="yes"), "dry_run"),
    (lambda: api.drive(dry_run=True, strict="no"), "strict"),
    (lambda: api.word_store("aerial-mosaic", config=42), "config"),
    (lambda: api.redraw_timeline("results/drive/x", clock="utc"), "clock"),
    (lambda: api.drive(dry_run=True, clock="x"), "clock"),
    (lambda: api.drive(dry_run=True, camera="sim", sim_map="aerial-mosaic", start="5,5"), "start"),
    (lambda: api.drive(dry_run=True, camera="sim", sim_map="aerial-mosaic", start=(5, "x")), "start"),
    (lambda: api.drive(dry_run=True, heading_deg="north"), "heading_deg"),
    (lambda: api.simrobot("aerial-mosaic", noise=5), "noise"),
])
def test_misused_functions_name_the_argument(call, parameter):
    with pytest.raises(ParameterError, match=rf"^{parameter}: got "):
        call()


def test_explore_names_a_registered_map_by_its_name_and_a_dataset_yaml_by_its_path(own_map, monkeypatch):
    """Issue 44: `explore --map reef-mosaic` saved this checkout's absolute path, which a copied folder cannot follow."""
    import curiosity_cli.explore.grid as grid

    monkeypatch.setattr(grid, "run_grid", lambda config, **_: config.datasets)
    assert api.explore("quick", maps=["reef-mosaic"]) == ("reef-mosaic",)
    assert api.explore("quick", maps=[str(own_map)]) == (str(own_map.resolve()),)


class _Wrong:
    """A value of no type any argument takes."""

    def __repr__(self) -> str:
        return "<wrong>"


#: What each required argument of the API is given while another one is wrong: a folder with nothing in it, a
#: shipped map or config; never enough for work to start, which a wrong argument must stop first.
_REQUIRED = {
    "folder": Path("no-such-experiment"), "dataset": "zurich-zh17", "weight_function": "random-walk", "restart": 0,
    "name": "x", "map_name": "aerial-mosaic", "text": "aerial-mosaic/random-walk/0", "parameter": "run",
    "datasets": ["zurich-zh17"], "source": Path("no-such-experiment"), "config": "quick",
}
_ARGUMENTS = [
    (name, parameter)
    for name in sorted(dir(api)) if not name.startswith("_") and inspect.isfunction(getattr(api, name))
    for parameter in inspect.signature(getattr(api, name)).parameters
]


@pytest.mark.parametrize("name, parameter", _ARGUMENTS)
def test_every_api_argument_of_a_wrong_type_is_refused_by_its_name(name, parameter, tmp_path, monkeypatch):
    """Issue 63: a callback that cannot be called, png_every=3.5, overrides=b"x" failed as raw TypeErrors deep in
    the work, or were taken."""
    monkeypatch.chdir(tmp_path)
    function = getattr(api, name)
    arguments = {
        other.name: _REQUIRED[other.name] for other in inspect.signature(function).parameters.values()
        if other.default is inspect.Parameter.empty and other.name != parameter
    }
    with pytest.raises(ParameterError) as info:
        function(**arguments, **{parameter: _Wrong()})
    # run_named's text is named by the option it stands for, its parameter
    named = "run" if (name, parameter) == ("run_named", "text") else parameter
    assert str(info.value).startswith(f"{named}: got <wrong>"), str(info.value)
    assert not any(tmp_path.iterdir()), "refused before anything was written"


def test_a_file_where_a_folder_goes_is_refused_by_its_name(tmp_path):
    """Issue 64's hostile round: api.explore(results_dir=FILE) and api.init_config(folder=FILE) raised raw OS errors."""
    afile = tmp_path / "afile"
    afile.write_text("")
    with pytest.raises(ParameterError, match=r"^results_dir: got .*afile, which is a file; expected a folder"):
        api.explore("quick", results_dir=afile)
    with pytest.raises(ParameterError, match=r"^folder: got .*afile, which is a file; expected a folder"):
        api.init_config("x", folder=afile)
    with pytest.raises(ParameterError, match=r"^folder: got .*afile, which is a file"):
        api.label(afile)
