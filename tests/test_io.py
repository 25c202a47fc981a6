"""Image files: EXR round trips (RGB / RGBA, half / float), Radiance HDR,
PNG with exposure and sRGB, and clear errors for bad files and arrays."""

import os

import numpy as np
import pytest

import mcsample as mcs
from mcsample import io


@pytest.fixture
def image(rng):
    return (rng.random((9, 13, 3)) * 100).astype(np.float32)


@pytest.mark.parametrize("channels", [3, 4])
@pytest.mark.parametrize("half", [False, True])
def test_exr_round_trip(tmp_path, rng, channels, half):
    img = (rng.random((9, 13, channels)) * 50).astype(np.float32)
    path = tmp_path / "x.exr"
    io.write_exr(path, img, half=half)
    back = io.read_exr(str(path))
    assert back.shape == img.shape and back.dtype == np.float32
    tol = 1e-3 if half else 0
    assert np.allclose(back, img, rtol=tol, atol=0)
    assert np.array_equal(io.read_image(path), back)


def test_exr_read_by_mitsuba(tmp_path, image, mi):
    path = tmp_path / "x.exr"
    io.write_exr(path, image)
    theirs = np.array(mi.Bitmap(str(path)))
    assert theirs.shape[:2] == image.shape[:2]
    assert np.array_equal(theirs[..., :3], image)


def write_rgbe(path, img):
    """A minimal Radiance writer (flat scanlines), for the test only."""
    peak = img.max(axis=2)
    mant, exp = np.frexp(peak)
    scale = np.where(peak > 1e-32, mant * 256.0 / np.where(peak > 0, peak, 1), 0)
    rgbe = np.zeros(img.shape[:2] + (4,), np.uint8)
    rgbe[..., :3] = np.clip(img * scale[..., None], 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(peak > 1e-32, exp + 128, 0).astype(np.uint8)
    h, w = img.shape[:2]
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {h} +X {w}\n".encode())
        f.write(rgbe.tobytes())


def test_hdr_read(tmp_path, image):
    path = tmp_path / "x.hdr"
    write_rgbe(path, image)
    back = io.read_hdr(path)
    assert back.shape == image.shape and back.dtype == np.float32
    # RGBE keeps 8 bits of mantissa relative to the pixel's largest channel.
    err = np.abs(back - image) / image.max(axis=2, keepdims=True)
    assert err.max() < 2**-7


def test_hdr_written_by_mitsuba_reads_as_mitsuba_reads_it(tmp_path, image, mi):
    """Mitsuba writes the signature ``#?RGBE`` (the same format as
    ``#?RADIANCE``): the file reads, with Mitsuba's values to the bit, and
    as the same bytes under the other signature."""
    path = tmp_path / "m.hdr"
    mi.Bitmap(np.ascontiguousarray(image[..., :3])).write(str(path))
    assert path.read_bytes().startswith(b"#?RGBE\n")
    ours = io.read_hdr(path)
    theirs = np.array(mi.Bitmap(str(path)), dtype=np.float32)
    assert np.array_equal(ours, theirs[..., :3])
    renamed = tmp_path / "r.hdr"
    renamed.write_bytes(b"#?RADIANCE\n" + path.read_bytes()[len(b"#?RGBE\n"):])
    assert np.array_equal(io.read_hdr(renamed), ours)
    env = mcs.EnvMap.load(path)
    assert np.array_equal(env.image, ours)


def test_exr_is_written_compressed(tmp_path):
    """ZIP: a smooth float image shrinks well below its raw size (RLE, the
    old default, kept it at 99 %)."""
    y, x = np.mgrid[0:60, 0:160].astype(np.float32)
    img = np.stack([np.sin(x / 9) + 2, np.cos(y / 7) + 2, x * y / 9600], axis=-1)
    path = tmp_path / "z.exr"
    io.write_exr(path, img)
    assert path.stat().st_size < 0.8 * img.nbytes
    assert np.array_equal(io.read_exr(path), img)


@pytest.mark.parametrize("reader,name", [(io.read_exr, "t.exr"), (io.read_hdr, "t.hdr")])
def test_truncated_files_raise_oserror_with_path(tmp_path, image, reader, name):
    path = tmp_path / name
    if name.endswith(".exr"):
        io.write_exr(path, image)
    else:
        write_rgbe(path, image)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(OSError, match=name):
        reader(path)


def test_unreadable_and_wrong_files(tmp_path):
    with pytest.raises(OSError, match="missing.exr"):
        io.read_exr(tmp_path / "missing.exr")
    junk = tmp_path / "junk.exr"
    junk.write_bytes(b"not an image at all")
    with pytest.raises(OSError, match="junk.exr"):
        io.read_exr(junk)
    jpeg = tmp_path / "a.jpg"
    jpeg.write_bytes(b"\xff\xd8\xff\xe0 a JPEG")
    with pytest.raises(OSError, match="a.jpg: not an OpenEXR, Radiance HDR or PNG file"):
        io.read_image(jpeg)


@pytest.mark.parametrize("bad", [np.zeros((4, 4)), np.zeros((4, 4, 2)), np.zeros((0, 4, 3))])
def test_wrong_arrays_raise_value_error(tmp_path, bad):
    with pytest.raises(ValueError, match=r"image must have shape \(H, W, 3\)"):
        io.write_exr(tmp_path / "x.exr", bad)
    with pytest.raises(ValueError, match="image must have shape"):
        io.write_png(tmp_path / "x.png", bad)


def test_png_exposure_and_srgb(tmp_path):
    mpimg = pytest.importorskip("matplotlib.image")
    img = np.zeros((2, 3, 3), np.float32)
    img[0, 0] = 0.5
    img[0, 1] = 0.214041  # sRGB encodes it to ~0.5
    img[0, 2] = np.inf
    img[1, 0] = 0.25
    path = tmp_path / "x.png"
    io.write_png(path, img, exposure=0.0)
    back = np.round(mpimg.imread(path) * 255).astype(int)
    assert back.shape == (2, 3, 3)
    assert back[0, 1, 0] in (127, 128) and back[0, 2, 0] == 255 and back[1, 1, 0] == 0
    io.write_png(path, img, exposure=1.0, srgb=False)
    back = np.round(mpimg.imread(path) * 255).astype(int)
    assert back[0, 0, 0] == 255 and back[1, 0, 0] == 128
    img[1, 2, 1] = np.nan
    with pytest.raises(ValueError, match=r"image\[1, 2, 1\] = NaN"):
        io.write_png(path, img)
    assert os.path.getsize(path) > 0


def test_envmap_load_clamps_negative_texels_with_a_warning(tmp_path, image):
    """A file with a pixel of -1e-3 (left by compression or resampling)
    loads, as Mitsuba's envmap loads it, its negatives clamped to 0 with a
    warning; a NaN is still refused."""
    img = image.copy()
    img[2, 3, 1] = -1e-3
    img[4, 5, 0] = -2.5
    path = tmp_path / "neg.exr"
    io.write_exr(path, img)
    with pytest.warns(UserWarning, match=r"2 negative values \(the lowest -2.5\) clamped to 0"):
        env = mcs.EnvMap.load(path)
    assert np.array_equal(env.image, np.maximum(img, 0))
    img = np.maximum(img, 0)
    img[1, 1, 2] = np.nan
    io.write_exr(path, img)
    with pytest.raises(ValueError, match="NaN"):
        mcs.EnvMap.load(path)
