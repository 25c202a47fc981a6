"""Image files as people have them, against the OpenEXR Python bindings as
the reference decoder: every compression, scanline and tiled, half and
float, one part and several, and the channel layouts Mitsuba's Bitmap
reads (Y, Y + A, lowercase r, g, b, layered channels, named parts) are read
by mcsample with the values OpenEXR reads; files mcsample writes read back
in OpenEXR (and Mitsuba) with the values written. PNG reads as linear
RGB, and loads as an environment map."""

from __future__ import annotations

import numpy as np
import pytest

import mcsample as mcs

OpenEXR = pytest.importorskip("OpenEXR")

H, W = 37, 53  # not multiples of the codecs' blocks (16 or 32 lines, 4x4)
LOSSLESS = ["NO", "RLE", "ZIPS", "ZIP", "PIZ"]
LOSSY = ["PXR24", "B44", "B44A", "DWAA", "DWAB"]


def image(seed: int = 0, channels: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    # Radiance-like values over six decades, and smooth areas (the lossy
    # codecs' blocks) next to noise.
    smooth = np.linspace(0.0, 1.0, W)[None, :, None] * np.linspace(0.5, 2.0, H)[:, None, None]
    noisy = 10.0 ** rng.uniform(-3, 3, size=(H, W, channels))
    return np.where(np.arange(W)[None, :, None] < W // 2, smooth + 0.1, noisy).astype(np.float32)


def write(path, channels: dict, compression: str = "ZIP", tiled: bool = False, parts=None):
    """Writes with OpenEXR (channel arrays made contiguous: the bindings
    read a strided view's memory as if it were not)."""
    channels = {k: np.ascontiguousarray(v) for k, v in channels.items()}
    parts = parts and [(n, {k: np.ascontiguousarray(v) for k, v in ch.items()}) for n, ch in parts]
    header = {"compression": getattr(OpenEXR, f"{compression}_COMPRESSION"),
              "type": OpenEXR.tiledimage if tiled else OpenEXR.scanlineimage}
    if tiled:
        tiles = OpenEXR.TileDescription()
        tiles.xSize, tiles.ySize, tiles.mode = 16, 8, OpenEXR.ONE_LEVEL
        header["tiles"] = tiles
    if parts is not None:
        f = OpenEXR.File([OpenEXR.Part({**header, "name": name}, ch, name=name)
                          for name, ch in parts])
    else:
        f = OpenEXR.File(header, channels)
    f.write(str(path))


def reference(path) -> dict:
    """What OpenEXR decodes, channel by channel (float32), per part."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return [{name: np.asarray(c.pixels, dtype=np.float32) for name, c in part.channels.items()}
                for part in f.parts]


@pytest.mark.parametrize("tiled", [False, True], ids=["scanline", "tiled"])
@pytest.mark.parametrize("dtype", [np.float16, np.float32], ids=["half", "float"])
@pytest.mark.parametrize("compression", LOSSLESS + LOSSY)
def test_every_compression_reads_as_openexr_decodes_it(tmp_path, compression, dtype, tiled):
    rgb = image(1).astype(dtype)
    path = tmp_path / "x.exr"
    write(path, {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]}, compression, tiled)
    [ref] = reference(path)
    expected = np.stack([ref["R"], ref["G"], ref["B"]], axis=-1)
    if compression in LOSSLESS:
        np.testing.assert_array_equal(expected, rgb.astype(np.float32))
    got = mcs.io.read_exr(path)
    assert got.dtype == np.float32 and got.shape == (H, W, 3)
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("compression", ["ZSTD", "HTJ2K32"])
def test_compressions_the_reader_lacks_give_a_clear_error(tmp_path, compression):
    path = tmp_path / "x.exr"
    rgb = image(2)
    write(path, {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]}, compression)
    with pytest.raises(OSError, match=r"x\.exr.*(compression|unsupported)"):
        mcs.io.read_exr(path)


def test_channel_layouts(tmp_path):
    rgb = image(3, 4)
    y, a = rgb[..., 0], rgb[..., 3]
    cases = {
        "rgba": ({"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2], "A": a}, rgb),
        "y": ({"Y": y}, np.stack([y, y, y], -1)),
        "ya": ({"Y": y, "A": a}, np.stack([y, y, y, a], -1)),
        "lower": ({"r": rgb[..., 0], "g": rgb[..., 1], "b": rgb[..., 2]}, rgb[..., :3]),
        "layered": ({f"diffuse.{c}": rgb[..., i] for i, c in enumerate("RGB")}, rgb[..., :3]),
        "deep.layer": ({f"view.left.{c}": rgb[..., i] for i, c in enumerate("RGBA")}, rgb),
    }
    for name, (channels, expected) in cases.items():
        path = tmp_path / f"{name}.exr"
        write(path, channels)
        np.testing.assert_array_equal(mcs.io.read_exr(path), expected, err_msg=name)
        np.testing.assert_array_equal(mcs.io.read_image(path), expected, err_msg=name)


def test_layer_choice(tmp_path):
    albedo, diffuse, beauty = image(4), image(5), image(6)
    path = tmp_path / "aovs.exr"
    channels = {f"{layer}.{c}": img[..., i] for layer, img in [("albedo", albedo),
                                                                ("diffuse", diffuse)]
                for i, c in enumerate("RGB")}
    write(path, channels)
    with pytest.raises(ValueError, match=r"'albedo', 'diffuse'.*layer="):
        mcs.io.read_exr(path)
    np.testing.assert_array_equal(mcs.io.read_exr(path, layer="albedo"), albedo)
    np.testing.assert_array_equal(mcs.io.read_exr(path, "diffuse"), diffuse)
    with pytest.raises(ValueError, match=r"layer = 'specular'.*'albedo', 'diffuse'"):
        mcs.io.read_exr(path, layer="specular")
    # With unnamed colour channels too, those are the default.
    write(path, {**channels, "R": beauty[..., 0], "G": beauty[..., 1], "B": beauty[..., 2]})
    np.testing.assert_array_equal(mcs.io.read_exr(path), beauty)
    np.testing.assert_array_equal(mcs.io.read_exr(path, layer="diffuse"), diffuse)
    env = mcs.EnvMap.load(path, layer="albedo", scale=2.0)
    np.testing.assert_array_equal(env.image, albedo)
    assert env.scale == 2.0


def test_parts_are_layers(tmp_path):
    """A multi-part file: each part's name is its channels' layer."""
    beauty, normal = image(7), image(8)
    path = tmp_path / "parts.exr"
    rgb = lambda img: {c: img[..., i] for i, c in enumerate("RGB")}  # noqa: E731
    write(path, {}, "PIZ", parts=[("beauty", rgb(beauty)), ("normal", rgb(normal))])
    assert len(reference(path)) == 2
    with pytest.raises(ValueError, match="several layers"):
        mcs.io.read_exr(path)
    np.testing.assert_array_equal(mcs.io.read_exr(path, layer="normal"), normal)
    np.testing.assert_array_equal(mcs.io.read_exr(path, layer="beauty"), beauty)


def test_a_file_without_colour_names_its_channels(tmp_path):
    path = tmp_path / "depth.exr"
    write(path, {"Z": image(9)[..., 0]})
    with pytest.raises(OSError, match=r"no R, G and B \(or Y\) channels.*Z"):
        mcs.io.read_exr(path)


@pytest.mark.parametrize("half", [False, True])
@pytest.mark.parametrize("channels", [3, 4])
def test_what_mcsample_writes_openexr_reads(tmp_path, half, channels):
    img = image(10, channels)
    path = tmp_path / "out.exr"
    mcs.io.write_exr(path, img, half=half)
    [ref] = reference(path)
    got = np.stack([ref[c] for c in "RGBA"[:channels]], -1)
    np.testing.assert_array_equal(got, img.astype(np.float16 if half else np.float32))
    with OpenEXR.File(str(path), header_only=True) as f:
        assert f.header()["compression"] == OpenEXR.ZIP_COMPRESSION


@pytest.mark.mitsuba
def test_what_mcsample_writes_mitsuba_reads(tmp_path):
    mi = pytest.importorskip("mitsuba")
    from mcsample.mitsuba import variant_set
    img = image(11)
    path = tmp_path / "out.exr"
    mcs.io.write_exr(path, img)
    with variant_set("scalar_rgb"):
        np.testing.assert_array_equal(np.asarray(mi.Bitmap(str(path))), img)


def test_png_reads_linear_and_loads_as_an_envmap(tmp_path):
    rng = np.random.default_rng(12)
    linear = rng.uniform(0, 1, size=(16, 32, 3)).astype(np.float32)
    path = tmp_path / "sky.png"
    mcs.io.write_png(path, linear)
    got = mcs.io.read_png(path)
    assert got.shape == (16, 32, 3) and got.dtype == np.float32
    # 8-bit sRGB: the round trip is good to half a step of the code values.
    encoded = np.where(linear <= 0.0031308, 12.92 * linear,
                       1.055 * np.power(linear, 1 / 2.4) - 0.055)
    decoded = np.round(encoded * 255) / 255
    expected = np.where(decoded <= 0.04045, decoded / 12.92, ((decoded + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-7)
    env = mcs.EnvMap.load(path)
    np.testing.assert_array_equal(env.image, got)
    np.testing.assert_array_equal(mcs.io.read_image(path), got)
    with pytest.raises(ValueError, match="layer"):
        mcs.io.read_image(path, layer="diffuse")
