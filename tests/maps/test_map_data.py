from __future__ import annotations

import cv2
import numpy as np
import pytest
import yaml
from small_maps import edit_yaml

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.maps.map_data import dataset_names, load_legend, load_map
from curiosity_cli.errors import ConfigError, DatasetError

# Size and cells from each map's purpose: the paper's Table 1 and section 5.1 settings.
EMBEDDED = {
    "aerial-mosaic": ((1024, 1024), 16, 1, 4096),
    "sentinel-coast": ((1024, 1024), 16, 1, 4096),
    "reef-mosaic": ((2500, 2500), 32, 2, 6241),
    "rare-patches": ((512, 512), 16, 1, 1024),
    # a real 1 m photo: the centred 992 x 992 (a multiple of 16) of a 1000 x 1000 GeoNRW tile
    "geonrw-essen": ((992, 992), 16, 1, 3844),
}


@pytest.mark.parametrize("name", sorted(EMBEDDED))
def test_embedded_map_matches_its_metadata(name):
    m = load_map(name)
    size, cell_width, stride, cells = EMBEDDED[name]
    assert m.image.shape == (*size, 3) and m.image.dtype == np.uint8
    assert m.labels.shape == size
    assert tuple(m.config.size) == size
    assert (m.config.cell_width, m.config.word_stride) == (cell_width, stride)
    rows, cols = m.grid.shape
    assert rows * cols == cells


@pytest.mark.parametrize("name", sorted(EMBEDDED))
def test_embedded_label_ids_match_the_legend_exactly(name):
    m = load_map(name)
    assert sorted(np.unique(m.labels).tolist()) == [c.id for c in m.legend]
    assert [c.id for c in m.legend] == list(range(len(m.legend)))
    assert len({c.colour for c in m.legend}) == len(m.legend)


def test_aerial_mosaic_has_a_rare_class():
    m = load_map("aerial-mosaic")
    fractions = np.bincount(m.labels.ravel()) / m.labels.size
    assert 0 < fractions.min() < 0.02


def test_grid_counts_partial_border_cells():
    assert SquareGrid.covering((2500, 2500), 32).shape == (79, 79)
    assert SquareGrid.covering((1024, 1024), 16).shape == (64, 64)
    assert SquareGrid.covering((96, 129), 16).shape == (6, 9)


def test_own_map_loads(own_map):
    m = load_map(own_map)
    assert m.image.shape == (96, 128, 3)
    assert m.grid.shape == (6, 8)
    assert [c.name for c in m.legend] == ["sand", "rock"]
    assert m.legend[1].colour == (0x60, 0x60, 0x60)


def test_own_map_image_is_rgb(own_map):
    bgr = cv2.imread(str(own_map.parent / "map.png"))
    assert np.array_equal(load_map(own_map).image, bgr[:, :, ::-1])


def test_own_map_without_labels(own_map):
    edit_yaml(own_map, labels=None, legend=None)
    m = load_map(own_map)
    assert m.labels is None and m.legend == ()


@pytest.mark.parametrize("suffix", [".jpg", ".tif"])
def test_own_map_in_jpeg_or_tiff(own_map, suffix):
    image = cv2.imread(str(own_map.parent / "map.png"))
    cv2.imwrite(str(own_map.parent / f"map{suffix}"), image)
    edit_yaml(own_map, image=f"map{suffix}")
    assert load_map(own_map).image.shape == (96, 128, 3)


def test_unreadable_image(own_map):
    (own_map.parent / "map.png").write_text("not an image")
    with pytest.raises(DatasetError, match=r"own\.yaml: image: cannot read .*map\.png; expected a PNG, JPEG or TIFF image$"):
        load_map(own_map)


def test_empty_image(own_map):
    (own_map.parent / "map.png").write_bytes(b"")
    with pytest.raises(DatasetError, match=r"own\.yaml: image: .*map\.png is empty"):
        load_map(own_map)


def test_label_image_of_another_size(own_map):
    cv2.imwrite(str(own_map.parent / "labels.png"), np.zeros((96, 100), np.uint8))
    with pytest.raises(DatasetError, match=r"labels: .*labels\.png is \[96, 100\] \[rows, cols\]; expected the image's size \[96, 128\]"):
        load_map(own_map)


def test_label_ids_missing_from_the_legend(own_map):
    labels = np.zeros((96, 128), np.uint8)
    labels[0, :3] = [1, 5, 7]
    cv2.imwrite(str(own_map.parent / "labels.png"), labels)
    with pytest.raises(DatasetError, match=r"labels: class ids \[5, 7\] in .*labels\.png are missing from the legend"):
        load_map(own_map)


def test_colour_label_image_is_refused(own_map):
    cv2.imwrite(str(own_map.parent / "labels.png"), np.zeros((96, 128, 3), np.uint8))
    with pytest.raises(DatasetError, match=r"expected a single-channel 8- or 16-bit image of class ids"):
        load_map(own_map)


def test_cell_wider_than_the_image(own_map):
    edit_yaml(own_map, cell_width=200)
    with pytest.raises(DatasetError, match=r"own\.yaml: cell_width: got 200, expected at most the image's smaller side \(96 px\)"):
        load_map(own_map)


def test_declared_size_must_match(own_map):
    edit_yaml(own_map, size=[100, 128])
    with pytest.raises(DatasetError, match=r"size: declared \[100, 128\] \[rows, cols\], but .*map\.png is \[96, 128\]"):
        load_map(own_map)


def test_unknown_dataset_name():
    with pytest.raises(ConfigError, match="no dataset 'nowhere': expected one of aerial-mosaic, geonrw-essen, planted-disjoint, planted-shared, rare-patches, reef-mosaic, sentinel-coast, zurich-zh17"):
        load_map("nowhere")


@pytest.mark.parametrize(
    "entry, message",
    [
        ({"id": "a", "name": "x", "colour": "#000000"}, r"classes\[0\]\.id: got 'a', expected an integer"),
        ({"id": 0, "name": "", "colour": "#000000"}, r"classes\[0\]\.name: got '', expected a non-empty string"),
        ({"id": 0, "name": "x", "colour": "red"}, r"classes\[0\]\.colour: got 'red', expected \"#rrggbb\""),
        ({"id": 0, "name": "x", "colour": "#000000", "color": 1}, r"classes\[0\]\.color: unknown key"),
    ],
)
def test_a_bad_legend_entry_is_named(tmp_path, entry, message):
    path = tmp_path / "legend.yaml"
    path.write_text(yaml.safe_dump({"classes": [entry]}))
    with pytest.raises(DatasetError, match=message):
        load_legend(path)


def test_duplicate_legend_ids(tmp_path):
    path = tmp_path / "legend.yaml"
    entries = [{"id": 0, "name": "a", "colour": "#000000"}, {"id": 0, "name": "b", "colour": "#ffffff"}]
    path.write_text(yaml.safe_dump({"classes": entries}))
    with pytest.raises(DatasetError, match="classes: id 0 appears more than once"):
        load_legend(path)


def test_geonrw_essen_is_forest_crossed_by_roads_with_geonrw_classes():
    m = load_map("geonrw-essen")
    names = [c.name for c in m.legend]
    assert names == ["forest", "water", "agricultural", "residential", "grassland", "roads", "buildings"]
    shares = np.bincount(m.labels.ravel(), minlength=len(names)) / m.labels.size
    # mostly forest, roads a rare linear class, and every class present (shares as in data/README.md)
    assert round(shares[0], 3) == 0.590 and round(shares[5], 3) == 0.056 and shares.min() > 0.005
    assert m.config.stands_in_for == "Montreal1"


def test_registry_lists_the_embedded_maps_the_fetched_one_and_the_generated_ones():
    assert dataset_names() == sorted([*EMBEDDED, "zurich-zh17", "planted-disjoint", "planted-shared"])
