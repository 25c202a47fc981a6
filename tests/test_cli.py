"""``python -m mcsample render | compare | demo`` as a user runs them."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

import mcsample as mcs


def _run(*args, cwd):
    out = subprocess.run([sys.executable, "-m", "mcsample", *args], cwd=cwd,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_render_a_json_scene_then_compare(tmp_path):
    mcs.io.write_exr(tmp_path / "sky.exr", mcs.EnvMap().image)
    scene = {"type": "scene",
             "sensor": {"type": "perspective", "fov": 40,
                        "to_world": {"look_at": {"origin": [0, 1, 4], "target": [0, 0.5, 0],
                                                 "up": [0, 1, 0]}},
                        "film": {"type": "hdrfilm", "width": 32, "height": 24}},
             "sky": {"type": "envmap", "filename": "sky.exr"},
             "ball": {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5}}
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    _run("render", "scene.json", "-o", "a.exr", "--spp", "16", cwd=tmp_path)
    _run("render", "scene.json", "-o", "b.exr", "--spp", "64", "--seed", "1", cwd=tmp_path)
    a = mcs.io.read_exr(tmp_path / "a.exr")
    assert a.shape == (24, 32, 3) and np.all(np.isfinite(a)) and a.mean() > 0.1
    assert (tmp_path / "a.png").exists()
    report = _run("compare", "a.exr", "b.exr", cwd=tmp_path)
    assert "relMSE" in report and (tmp_path / "a_error.png").exists()


def test_demo_writes_its_images(tmp_path):
    out = _run("demo", "-o", "out", "-n", "20000", "--spp", "4", cwd=tmp_path)
    for name in ("strategies.png", "render_mis.exr", "render_bsdf.png", "samplers.png"):
        assert (tmp_path / "out" / name).exists(), out
    assert "relMSE" in out


def test_demo_refuses_what_it_cannot_do(tmp_path):
    """Every option value the command line accepts works; the others are
    refused before anything runs (spp 1 leaves no variance for the z-test
    against Mitsuba)."""
    for args in (["demo", "--spp", "1"], ["demo", "-n", "10"], ["demo", "--seed", "-1"],
                 ["render", "x.json", "--max-depth", "-2"], ["bench", "--only", "nope"]):
        out = subprocess.run([sys.executable, "-m", "mcsample", *args], cwd=tmp_path,
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 2 and "error:" in out.stderr, (args, out.stderr)


def test_the_command_line_lists_every_bench_suite():
    from mcsample import __main__, bench

    assert tuple(bench.SUITES) == __main__.SUITE_NAMES
