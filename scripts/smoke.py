"""A smoke test of an installed wheel, run by scripts/test.sh in a fresh
virtual environment without a Rust toolchain on PATH: the package imports
from the wheel, and its main parts work (a warp checked by chi-square, a
table, the packaged sky, a pickled Rng, a small render)."""

import pickle
import shutil
import sys

import numpy as np

import mcsample as mcs
from mcsample.demo import demo_scene

assert shutil.which("cargo") is None and shutil.which("rustc") is None, "Rust is on PATH"
assert "site-packages" in mcs.__file__, mcs.__file__
print(f"mcsample {mcs.__version__} on Python {sys.version.split()[0]}: {mcs._core.__file__}",
      flush=True)

u = mcs.uniform(200_000, 2, seed=1)
result = mcs.stats.chi2_test(mcs.warp.square_to_cosine_hemisphere,
                             mcs.warp.square_to_cosine_hemisphere_pdf,
                             mcs.stats.HemisphereDomain(), n=200_000, seed=1)
assert result.passed, result
table = mcs.Discrete1D([1.0, 2.0, 3.0])
assert np.isclose(table.pmf(2), 0.5)
sky = mcs.EnvMap.load(mcs.data.sky_path())
d = sky.sample(u[:1000])
assert np.all(np.isfinite(d.pdf))
rng = mcs.Rng(7)
rng.random(3)
copy = pickle.loads(pickle.dumps(rng))
assert np.array_equal(copy.random(4), rng.random(4))
scene = mcs.Scene.from_mitsuba(demo_scene(32, 12))
image = mcs.render(scene, 4, progress=False).image
assert image.shape == (12, 32, 3) and np.isfinite(image).all() and image.mean() > 0
print("smoke test passed")
