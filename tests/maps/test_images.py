"""Satellite-grade input: 8 or 16 bits, 1, 3 or 4 bands, loaded with their real contrast."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import tifffile
import yaml
from small_maps import edit_yaml

from curiosity_cli.config import CONFIG_DIR, load_words_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.errors import ConfigError, DatasetError
from curiosity_cli.words.extract import extract_words

# GeoTIFF keys as a real product carries them (pixel scale, tie point, key directory):
# tags OpenCV's decoder warns about.
GEO_TAGS = [
    (33550, "d", 3, (0.6, 0.6, 0.0), False),
    (33922, "d", 6, (0, 0, 0, 471420.6, 5249385.6, 0), False),
    (34735, "H", 8, (1, 1, 0, 1, 1024, 0, 1, 1), False),
]


def texture(shape, top, seed=0):
    """Smooth random texture with values 0..top in every band, both ends present."""
    import cv2

    rng = np.random.default_rng(seed)
    noise = cv2.GaussianBlur(rng.random(shape), (0, 0), 2).reshape(shape[0], shape[1], -1)
    low, high = noise.min(axis=(0, 1)), noise.max(axis=(0, 1))
    return np.rint((noise - low) / (high - low) * top).astype(np.uint16).reshape(shape)


def write_dataset(folder, name, image_file, **keys):
    text = {"name": name, "image": image_file, "cell_width": 16, "word_stride": 1, **keys}
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(text, sort_keys=False))
    return path


def test_16_bit_words_equal_the_same_image_scaled_to_8_bits_by_hand(tmp_path):
    eleven_bit = texture((96, 128, 3), 2047)
    tifffile.imwrite(tmp_path / "scene.tif", eleven_bit, photometric="rgb", extratags=GEO_TAGS)
    by_hand = np.round(eleven_bit.astype(np.float64) * 255 / 2047).astype(np.uint8)
    tifffile.imwrite(tmp_path / "by-hand.tif", by_hand, photometric="rgb")
    # percentiles 0 and 100 of an image spanning 0..2047 map 0 -> 0 and 2047 -> 255
    sixteen = load_map(write_dataset(tmp_path, "sixteen", "scene.tif", stretch=[0, 100]))
    eight = load_map(write_dataset(tmp_path, "eight", "by-hand.tif"))
    assert np.array_equal(sixteen.image, eight.image)
    words = load_words_config(CONFIG_DIR / "paper.yaml")
    a = extract_words(sixteen, words, cache_dir=tmp_path / "cache").store
    b = extract_words(eight, words, cache_dir=tmp_path / "cache").store
    assert a.words.size > 96 * 128 and np.array_equal(a.words, b.words) and np.array_equal(a.cols, b.cols)


def test_default_stretch_is_percentiles_2_and_98_per_band(tmp_path):
    scene = texture((64, 80, 3), 4000)
    scene[..., 2] //= 4  # a dimmer blue band gets its own range
    tifffile.imwrite(tmp_path / "scene.tif", scene, photometric="rgb")
    m = load_map(write_dataset(tmp_path, "scene", "scene.tif"))
    values = scene.astype(np.float64)
    low, high = np.percentile(values, 2, axis=(0, 1)), np.percentile(values, 98, axis=(0, 1))
    expected = np.clip(np.floor((values - low) / (high - low) * 255 + 0.5), 0, 255).astype(np.uint8)
    assert np.array_equal(m.image, expected)
    assert m.rendering.low == tuple(low) and m.rendering.percentiles == (2.0, 98.0)
    assert "stretched R" in m.rendering.describe() and "to 0..255" in m.rendering.describe()


def test_8_bit_image_is_used_as_is(own_map):
    assert load_map(own_map).rendering.low is None


def test_grey_16_bit_tiff_stays_grey(tmp_path):
    grey = texture((64, 80), 1500)
    tifffile.imwrite(tmp_path / "pan.tif", grey, photometric="minisblack")
    m = load_map(write_dataset(tmp_path, "pan", "pan.tif", stretch=[0, 100]))
    assert m.image.shape == (64, 80, 3)
    assert np.array_equal(m.image[..., 0], m.image[..., 1]) and np.array_equal(m.image[..., 1], m.image[..., 2])
    assert m.rendering.bands == (0,)
    # the real contrast: 0..1500 spans 0..255, not the high byte of 16 bits (0..5)
    assert m.image.min() == 0 and m.image.max() == 255


def test_four_band_tiff_needs_its_band_order(tmp_path):
    bgrn = texture((64, 80, 4), 2047)
    tifffile.imwrite(tmp_path / "bgrn.tif", bgrn, photometric="minisblack", planarconfig="contig", extratags=GEO_TAGS)
    path = write_dataset(tmp_path, "bgrn", "bgrn.tif")
    with pytest.raises(DatasetError, match=r"bgrn\.yaml: bands: the image has 4 bands and does not say which are red, green and blue; expected bands: \[r, g, b\]") as info:
        load_map(path)
    assert "\n" not in str(info.value)
    m = load_map(edit_yaml(path, bands=[2, 1, 0], stretch=[0, 100]))
    rgb = bgrn[..., [2, 1, 0]].astype(np.float64)
    low, high = rgb.min(axis=(0, 1)), rgb.max(axis=(0, 1))
    assert np.array_equal(m.image, np.floor((rgb - low) / (high - low) * 255 + 0.5).astype(np.uint8))


def test_a_tiff_of_several_same_size_images_is_refused(tmp_path):
    tifffile.imwrite(tmp_path / "stack.tif", texture((3, 32, 40), 900), photometric="minisblack")
    with pytest.raises(DatasetError, match=r"stack\.tif holds 3 images of 32 x 40 px; expected one image"):
        load_map(write_dataset(tmp_path, "stack", "stack.tif"))


def test_planar_four_band_tiff_reads_every_band(tmp_path):
    bgrn = texture((64, 80, 4), 2047)
    tifffile.imwrite(tmp_path / "planar.tif", np.moveaxis(bgrn, -1, 0), photometric="minisblack", planarconfig="separate")
    tifffile.imwrite(tmp_path / "contig.tif", bgrn, photometric="minisblack", planarconfig="contig")
    a = load_map(write_dataset(tmp_path, "planar", "planar.tif", bands=[3, 1, 0]))
    b = load_map(write_dataset(tmp_path, "contig", "contig.tif", bands=[3, 1, 0]))
    assert np.array_equal(a.image, b.image)


@pytest.mark.parametrize(
    "keys, message",
    [
        ({"bands": [0, 1]}, r"bands: got \[0, 1\], expected \[r, g, b\]"),
        ({"bands": [0, 1, 9]}, r"bands: got \[0, 1, 9\], expected 3 band indices \(or 1 for grey\) in 0\.\.2"),
        ({"stretch": [98, 2]}, r"stretch: got \[98\.0, 2\.0\], expected \[low, high\] percentiles"),
        ({"stretch": [0, 101]}, r"stretch\[1\]: got 101"),
    ],
)
def test_bad_band_or_stretch_keys_are_named(tmp_path, keys, message):
    tifffile.imwrite(tmp_path / "scene.tif", texture((32, 32, 3), 900), photometric="rgb")
    with pytest.raises((ConfigError, DatasetError), match=message):
        load_map(write_dataset(tmp_path, "scene", "scene.tif", **keys))


def test_a_dataset_yaml_needs_only_the_keys_it_uses(tmp_path):
    tifffile.imwrite(tmp_path / "scene.tif", texture((48, 64, 3), 255).astype(np.uint8), photometric="rgb")
    path = write_dataset(tmp_path, "bare", "scene.tif")
    m = load_map(path)
    assert (m.labels, m.legend, m.config.size, m.config.source, m.config.licence) == (None, (), None, "", "")
    assert m.config.stretch == (2.0, 98.0) and m.config.bands is None and m.config.stands_in_for is None
    path.write_text(yaml.safe_dump({"name": "bare", "cell_width": 16, "word_stride": 1}))
    with pytest.raises(ConfigError, match=r"bare\.yaml: image: missing key"):
        load_map(path)


@pytest.mark.slow
def test_geotiff_tags_give_no_warning_on_the_terminal(tmp_path):
    tifffile.imwrite(
        tmp_path / "scene.tif", texture((64, 64, 4), 2047), photometric="minisblack", planarconfig="contig", extratags=GEO_TAGS
    )
    path = write_dataset(tmp_path, "geo", "scene.tif", bands=[2, 1, 0])
    result = subprocess.run(
        [sys.executable, "-m", "curiosity_cli", "datasets", "show", str(path), "--out", str(tmp_path / "p.png")],
        capture_output=True, text=True, check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert "image: uint16, R = band 2, G = band 1, B = band 0; stretched R " in result.stdout


@pytest.mark.parametrize("offset, damage", [
    (lambda size: size // 2, r"is corrupt \(its IDAT chunk at byte \d+ fails its CRC check\)"),  # a byte of the pixels
    (lambda size: 10, r"is corrupt \(its chunks do not add up to the file, from byte 8\)"),  # the header's length
])
def test_a_png_with_a_flipped_byte_is_called_corrupt_in_one_line_without_libpngs_own(own_map, tmp_path, offset, damage):
    image = own_map.parent / "map.png"
    data = bytearray(image.read_bytes())
    data[offset(len(data))] ^= 0xFF
    image.write_bytes(bytes(data))
    with pytest.raises(DatasetError, match=rf"own\.yaml: image: .*map\.png {damage}; expected an intact PNG image$"):
        load_map(own_map)
    # libpng prints its own "libpng error: IDAT: CRC error" on stderr when it meets one: it must not meet it
    result = subprocess.run(
        [sys.executable, "-m", "curiosity_cli", "datasets", "show", str(own_map), "--out", str(tmp_path / "p.png")],
        capture_output=True, text=True, check=False,
    )
    assert result.returncode == 1 and len(result.stderr.splitlines()) == 1, result.stderr
    assert result.stderr.startswith("Error: ") and "is corrupt" in result.stderr
    assert not (tmp_path / "p.png").exists()
