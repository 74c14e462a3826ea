"""`write_figures` on synthetic experiment folders: real PNG and PDF files, and missing inputs skipped."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest
import yaml
from synthetic_experiment import make_experiment, seal

from curiosity_cli.errors import ConfigError, CuriosityError
from curiosity_cli.experiment.experiment import StaleTablesError
from curiosity_cli.plots.experiment_inputs import PlotError
from curiosity_cli.plots.figures import mi_figure, weight_style, write_figures

LENGTHS = (10, 20, 40, 80)


@pytest.fixture
def bare_map(own_map: Path) -> Path:
    """The own map again under another name, without human labels."""
    data = yaml.safe_load(own_map.read_text())
    data.update(name="bare", labels=None, legend=None)
    path = own_map.parent / "bare.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.fixture
def experiment(tmp_path, own_map, bare_map) -> Path:
    return make_experiment(tmp_path / "results", [str(own_map), str(bare_map)], restarts=3, lengths=LENGTHS, n_topics=12, sweeps=30)


def names(paths) -> list[str]:
    return [p.name for p in paths]


@pytest.mark.slow
def test_every_figure_is_written_as_png_and_pdf(experiment):
    import matplotlib

    rc = dict(matplotlib.rcParams)
    write_figures(experiment)
    written = write_figures(experiment)  # a second time replaces the files
    assert dict(matplotlib.rcParams) == rc  # styles are set in a context, not globally
    stems = [
        "mi-vs-length-human", "mi-vs-length-batch", "mi-vs-distinct",
        "path-own", "labelings-own", "path-bare", "labelings-bare", "batch-convergence",
    ]
    assert names(written) == [f"{stem}{suffix}" for stem in stems for suffix in (".png", ".pdf")]
    # the synthetic folder has evaluate's mi.csv and summary.csv only: the report, which reads them all, is named as left out
    assert len(written.skipped) == 1 and written.skipped[0].startswith("REPORT.md: ") and "skipped.json" in written.skipped[0]
    assert written.report is None and not (experiment / "REPORT.md").exists()
    for path in written:
        assert path.parent == experiment / "figures"
        if path.suffix == ".png":
            image = cv2.imread(str(path))
            assert image is not None and image.shape[1] >= 600 and image.std() > 10  # drawn, not blank
        else:
            assert path.read_bytes().startswith(b"%PDF")
    assert sorted(p.name for p in (experiment / "figures").iterdir()) == sorted(names(written))  # no temp files


@pytest.mark.slow
def test_a_map_without_human_labels_gets_no_human_panel(tmp_path, bare_map):
    experiment = make_experiment(tmp_path, [str(bare_map)], restarts=2, lengths=(10, 20, 40), n_topics=8, sweeps=5)
    written = write_figures(experiment)
    assert "mi-vs-length-human.png" not in names(written)
    assert "mi-vs-length-batch.png" in names(written) and "labelings-bare.png" in names(written)
    assert written.skipped[0] == "mi-vs-length-human: summary.csv has no MI against human labels (no map has them)"
    assert len(written.skipped) == 2 and written.skipped[1].startswith("REPORT.md: ")


@pytest.mark.slow
def test_missing_labelings_skip_their_figures_only(experiment):
    shutil.rmtree(experiment / "batch")
    shutil.rmtree(experiment / "labels" / "bare")
    with pytest.raises(StaleTablesError, match=r"mi.csv: made from other files than the experiment holds now \(\S*batch/bare.npz is gone\)"):
        write_figures(experiment)
    seal(experiment)  # as an evaluate after the files went would
    written = write_figures(experiment)
    assert names(written) == [
        f"{stem}{suffix}"
        for stem in ("mi-vs-length-human", "mi-vs-length-batch", "mi-vs-distinct", "path-own", "labelings-own")
        for suffix in (".png", ".pdf")
    ]
    skipped = "\n".join(written.skipped)
    assert "batch/own.npz: not found (label the experiment first)" in skipped
    assert "path-bare: no example path labelling under labels/bare/examples/" in skipped
    assert "labelings-bare: neither a batch nor a path labelling to draw" in skipped
    assert "batch-convergence: no batch log-likelihood trace" in skipped

    (experiment / "config.yaml").unlink()
    with pytest.raises(ConfigError, match=r"config.yaml: not found; explore makes the experiment"):
        write_figures(experiment)


@pytest.mark.slow
def test_corrupt_or_misshapen_inputs_are_named_and_skipped(experiment):
    (experiment / "batch" / "own.npz").write_bytes(b"not a zip file")
    example = next((experiment / "labels" / "bare" / "examples").glob("topic-perplexity-restart-000-*.npz"))
    np.savez(example, labels=np.zeros((5, 5), np.int16))
    (experiment / "runs" / "own" / "topic-perplexity" / "restart-000" / "path.csv").unlink()
    summary = pd.read_csv(experiment / "summary.csv")
    summary["mean"] = summary["mean"].astype(object)
    summary.loc[0, "mean"] = "oops"  # a stray text cell: that point is left out
    summary.to_csv(experiment / "summary.csv", index=False)
    with pytest.raises(StaleTablesError, match=r"summary.csv: not the table evaluate wrote with the others"):
        write_figures(experiment)
    seal(experiment)  # as if the tables and files were written so
    written = write_figures(experiment)
    skipped = written.skipped
    assert sum("batch/own.npz: corrupt" in note for note in skipped) == 1
    assert any(f"{example.name}: labels are int16 of shape (5, 5)" in note for note in skipped)
    assert any("restart-000/path.csv: not found; no path figure" in note for note in skipped)
    assert "path-own.png" not in names(written)
    assert {"mi-vs-length-human.png", "labelings-own.png", "labelings-bare.png", "batch-convergence.png"} <= set(names(written))


@pytest.mark.slow
def test_other_weight_functions_get_grey_styles(tmp_path, own_map):
    experiment = make_experiment(
        tmp_path, [str(own_map)], restarts=2, lengths=(10, 20), weights=("random-walk", "levy-flight", "greedy"), n_topics=6
    )
    written = write_figures(experiment)
    assert "mi-vs-length-human.png" in names(written)
    others = ["greedy", "levy-flight"]
    styles = {weight_style(name, others) for name in ["random-walk", *others]}
    assert len(styles) == 3 and weight_style("greedy", others)[0].startswith("0.")
    # no topic-perplexity run: figs. 2 and 3 fall back to another weight function's example
    assert "path-own.png" in names(written)


@pytest.mark.slow
def test_the_lawnmower_has_its_own_marker_and_ceilings_are_dashed_lines_after_the_walkers(tmp_path, own_map):
    weights = ("random-walk", "topic-perplexity", "lawnmower", "scattered-cells", "compact-block")
    experiment = make_experiment(tmp_path, [str(own_map)], restarts=2, lengths=(10, 20), weights=weights, n_topics=6)
    summary = pd.read_csv(experiment / "summary.csv")
    figure = mi_figure(summary, "human", ["own"])
    (ax,) = [a for a in figure.axes if a.get_visible()]
    lines = ax.get_lines()
    assert len(lines) == 5
    walkers, ceilings = lines[:3], lines[3:]
    assert [line.get_marker() for line in walkers] == ["s", "^", "x"]  # legend order: topic perplexity first
    assert all(line.get_marker() in ("None", "", None) and line.get_linestyle() != "-" for line in ceilings)
    assert len(ax.collections) == 3, "a CI band for each walker, none for the ceilings"
    legend = [text.get_text() for text in figure.legends[0].get_texts()]
    assert legend == ["topic perplexity", "random walk", "lawnmower", "ceiling: scattered cells", "ceiling: compact block"]
    assert "mi-vs-length-human.png" in names(write_figures(experiment))


@pytest.mark.slow
def test_missing_folder_or_mi_table_is_a_plot_error(tmp_path, experiment):
    with pytest.raises(PlotError, match=r"no such experiment folder; explore makes it"):
        write_figures(tmp_path / "nowhere")
    (experiment / "summary.csv").unlink()
    with pytest.raises(StaleTablesError, match=r"summary.csv: not the table evaluate wrote with the others \(missing\)"):
        write_figures(experiment)
    seal(experiment)
    written = write_figures(experiment)
    assert not any(p.name.startswith("mi-vs-length") for p in written)
    assert any("summary.csv: not found; evaluate makes it" in note for note in written.skipped)

    mi = pd.read_csv(experiment / "mi.csv")
    mi.drop(columns="mi_batch").to_csv(experiment / "mi.csv", index=False)
    with pytest.raises(PlotError, match=r"mi.csv: no column 'mi_batch'"):
        write_figures(experiment)
    (experiment / "mi.csv").unlink()
    with pytest.raises(CuriosityError, match=r"mi.csv: not found; evaluate makes it"):
        write_figures(experiment)


def test_maps_are_shrunk_before_drawing_labels_by_picking_and_images_by_averaging():
    from curiosity_cli.plots.preview import MAX_SIDE, shrink_image, shrink_labels

    labels = np.arange(2000 * 1700).reshape(2000, 1700) % 7
    small = shrink_labels(labels)
    assert max(small.shape) <= MAX_SIDE and small.shape == labels[::3, ::3].shape
    np.testing.assert_array_equal(small, labels[::3, ::3])  # a label is never blended with its neighbours
    image = np.zeros((2000, 1700, 3), np.uint8)
    image[:, ::2] = 255  # stripes a pixel wide average to grey, not to black or white
    shrunk = shrink_image(image)
    assert shrunk.shape == (*small.shape, 3) and 60 < shrunk.min() <= shrunk.max() < 195
    assert abs(float(shrunk.mean()) - 127.5) < 3
    same = np.ones((MAX_SIDE, 10, 3), np.uint8)
    assert shrink_image(same) is same and shrink_labels(same[:, :, 0]).shape == (MAX_SIDE, 10)


def _summary(lengths, high):
    """A summary.csv of one map and one walker, MI 1 bit at each length, the interval up to ``high``."""
    return pd.DataFrame({
        "dataset": "own", "weight_function": "topic-perplexity", "path_length": lengths, "against": "human",
        "n": 2, "mean": 1.0, "std": 1.0, "ci_low": -0.5, "ci_high": high,
    })


def test_a_ci_band_is_cut_at_the_largest_mi_there_can_be_and_one_length_gets_an_error_bar():
    figure = mi_figure(_summary([10, 20], 3.7), "human", ["own"], {"own": math.log2(7)})
    (ax,) = [a for a in figure.axes if a.get_visible()]
    (band,) = ax.collections
    ys = band.get_paths()[0].vertices[:, 1]
    assert ys.max() == pytest.approx(math.log2(7)) and ys.min() == 0  # neither above log2(classes) nor below 0
    assert "cut at the largest MI there can be, log2 of the classes" in figure._suptitle.get_text().replace("\n", " ")
    uncut = mi_figure(_summary([10, 20], 1.5), "human", ["own"], {"own": math.log2(7)})
    assert "cut at" not in uncut._suptitle.get_text()
    single = mi_figure(_summary([80], 1.5), "human", ["own"])
    (ax,) = [a for a in single.axes if a.get_visible()]
    (bar,) = ax.containers  # an error bar, not a band with nothing to stretch between
    segment = bar.lines[2][0].get_segments()[0]
    assert segment[:, 1].tolist() == [0.0, 1.5]


def test_the_convergence_subtitle_says_rising_or_too_few_instead_of_within_nothing():
    from curiosity_cli.plots.figures import convergence_figure

    titles = {
        name: convergence_figure({"own": trace}).axes[1].get_title()
        for name, trace in {
            "few": np.array([-9.0, -8.5]), "rising": -8.0 + np.linspace(0, 1, 40) ** 0.5,
            "flat": np.r_[np.linspace(-9, -8, 36), [-8.0, -8.001, -8.0005, -8.0002]],
        }.items()
    }
    assert titles["few"].endswith("2 sweeps: too few to tell whether it converged")
    assert "still rising: +" in titles["rising"] and "over the last 4 sweeps" in titles["rising"]
    assert titles["flat"].endswith("last 4 sweeps within 0.001 nats")
