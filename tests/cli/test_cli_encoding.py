"""Photos saved for a screen (the sRGB curve) in files that state no colour space are read as
linear, as raw camera data and benchmarks mostly are; the data then say which reading is right
(solve/reading_check.h): a warning that names --encoding srgb when the photos are clearly more
likely decoded, nothing but a log line when the linear reading is the more likely one. The
photos are a matte sphere shaded here in numpy and written as bare 8-bit PNG (no gAMA, sRGB or
iCCP chunk), as a renderer or an editor may write them."""
import json
import struct
import zlib

import numpy as np
import pytest

from cli import IPHONG, binary_available, run

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")


def write_png(path, rgb8):
    """An 8-bit RGB PNG with no colour-space chunk."""
    h, w, _ = rgb8.shape
    raw = b"".join(b"\x00" + rgb8[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def capture(folder, display_encoded, size=64, count=12):
    c = (np.arange(size) + 0.5) / size * 2 - 1
    x, y = np.meshgrid(c, -c)
    mask = x * x + y * y < 0.8
    n = np.stack([x, y, np.sqrt(np.clip(1 - x * x - y * y, 0, None))], -1)
    golden = np.pi * (3 - np.sqrt(5))
    z = 1 - 0.6 * (np.arange(count) + 0.5) / count
    lights = np.stack([np.sqrt(1 - z * z) * np.cos(golden * np.arange(count)),
                       np.sqrt(1 - z * z) * np.sin(golden * np.arange(count)), z], -1)
    folder.mkdir()
    names = []
    for j, l in enumerate(lights):
        value = 0.8 * np.clip(n @ l, 0, None)[..., None] * np.array([1.0, 0.8, 0.6]) * mask[..., None]
        if display_encoded:
            value = np.where(value <= 0.0031308, 12.92 * value, 1.055 * value ** (1 / 2.4) - 0.055)
        names.append(f"{j + 1:03d}.png")
        write_png(folder / names[-1], np.round(value * 255).astype(np.uint8))
    write_png(folder / "mask.png", np.repeat((mask * 255).astype(np.uint8)[..., None], 3, -1))
    (folder / "filenames.txt").write_text("\n".join(names) + "\n")
    np.savetxt(folder / "light_directions.txt", lights)
    return folder


def test_display_encoded_photos_read_as_linear_are_named(tmp_path):
    folder = capture(tmp_path / "srgb", True)
    code, _, err = run("normals", folder, "-o", tmp_path / "out")
    assert code == 0, err
    assert "a Lambertian fit finds them more likely decoded as sRGB (display-encoded)" in err, err
    assert "pass --encoding srgb" in err
    check = json.loads((tmp_path / "out" / "metrics.json").read_text())["encoding_check"]
    assert check["srgb_better"] and check["loglik_gain_srgb"] > 10 * check["loglik_gain_error"], check
    # In bands of rows the check reads the plan sample, here every pixel: the same figures.
    code, _, err = run("normals", folder, "-o", tmp_path / "bands", "--band-rows", "16")
    assert code == 0 and "more likely decoded as sRGB" in err, err
    banded = json.loads((tmp_path / "bands" / "metrics.json").read_text())["encoding_check"]
    assert banded["loglik_gain_srgb"] == check["loglik_gain_srgb"], (banded, check)
    # Told the encoding: no check, no warning.
    code, _, err = run("normals", folder, "-o", tmp_path / "told", "--encoding", "srgb")
    assert code == 0 and "display-encoded" not in err, err
    assert "encoding_check" not in json.loads((tmp_path / "told" / "metrics.json").read_text())


def test_linear_photos_keep_their_reading_quietly(tmp_path):
    folder = capture(tmp_path / "linear", False)
    code, out, err = run("normals", folder, "-o", tmp_path / "out")
    assert code == 0, err
    assert "display-encoded" not in err, err
    assert "Encoding: linear kept" in out, out
    check = json.loads((tmp_path / "out" / "metrics.json").read_text())["encoding_check"]
    assert not check["srgb_better"] and check["loglik_gain_srgb"] < -10 * check["loglik_gain_error"], check
