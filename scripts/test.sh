#!/usr/bin/env bash
# Installs everything the test suite needs on a fresh Debian machine
# (libLLVM for Mitsuba's llvm variant, Python packages), builds this
# package's abi3 wheel and smoke-tests it in fresh virtual environments
# without Rust, installs it, and runs the whole suite: Rust format / lint /
# unit tests / docs, stub check, then pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

# Each stage's start, seconds into the run, for the log.
stage() { echo "== ${SECONDS} s: $*"; }

# A libLLVM >= 16 lets Mitsuba 3 run its llvm_ad_rgb variant (Dr.Jit finds
# it by itself); without one the suite falls back to scalar_rgb. Embree 3
# traces mcsample's meshes when it loads (the suite checks both tracers,
# and under CI that Embree loads).
# (Installed where the distribution has it: Debian 12 does.)
if ! { dpkg -s libllvm19 && dpkg -s libembree3-3; } >/dev/null 2>&1 \
    && command -v apt-get >/dev/null; then
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  EMBREE=""
  apt-cache show libembree3-3 >/dev/null 2>&1 && EMBREE=libembree3-3
  $SUDO apt-get install -y -qq libllvm19 $EMBREE >/dev/null
fi

stage "pip, maturin"
python -m pip install --quiet --upgrade pip "maturin>=1.7,<2"

stage "wheel"
# The wheel users install: abi3 (one wheel for CPython 3.9+), stripped.
rm -rf target/wheels
maturin build --release --quiet
WHEEL=$(ls "$PWD"/target/wheels/mcsample_toolkit-*-cp39-abi3-*.whl)
ls -l "$WHEEL"

# Installed into fresh virtual environments with no Rust toolchain on PATH
# (the PATH entries holding cargo or rustc left out), by this Python and by
# 3.9 and 3.13 where pyenv has them: a smoke test, run outside the source
# tree.
stage "smoke tests"
NO_RUST_PATH=""
IFS=: read -ra entries <<<"$PATH"
for dir in "${entries[@]}"; do
  [ -x "$dir/cargo" ] || [ -x "$dir/rustc" ] || NO_RUST_PATH="${NO_RUST_PATH:+$NO_RUST_PATH:}$dir"
done
SMOKE=$(mktemp -d)
trap 'rm -rf "$SMOKE"' EXIT
i=0
for py in python "$HOME"/.pyenv/versions/3.9.[0-9]*/bin/python \
    "$HOME"/.pyenv/versions/3.13.[0-9]*/bin/python; do
  command -v "$py" >/dev/null || { echo "smoke test: no $py here"; continue; }
  i=$((i + 1))
  "$py" -m venv "$SMOKE/venv$i"
  (cd "$SMOKE" && export PATH="$NO_RUST_PATH" &&
    "$SMOKE/venv$i/bin/python" -m pip install --quiet "$WHEEL" &&
    "$SMOKE/venv$i/bin/python" "$ROOT/scripts/smoke.py")
done

# The same wheel, with what the suite needs, into this Python, in place of
# any earlier install (pip keeps one of the same version otherwise; the
# distribution was called "mcsample" before: that name on the package
# index is another project's).
stage "test dependencies"
python -m pip uninstall --quiet -y mcsample mcsample-toolkit 2>/dev/null || true
python -m pip install --quiet "$WHEEL[test,mitsuba,plot,distributed]"

stage "Rust checks"
rustup component add rustfmt clippy >/dev/null 2>&1 || true
cargo fmt --check
cargo clippy --all-targets --all-features --quiet -- -D warnings
stage "cargo test"
cargo test --quiet
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet
python -m mypy.stubtest mcsample._core --allowlist scripts/stubtest-allowlist.txt

stage "pytest"
# Run pytest from outside the source tree so it imports the installed
# package, not python/mcsample without its compiled core. --nbmake also
# executes every notebook top to bottom and fails on any error.
cd tests && python -m pytest -q -p no:cacheprovider --durations=20 --nbmake . ../notebooks "$@"
