#!/usr/bin/env bash
# Installs everything the test suite needs on a fresh Debian machine
# (libLLVM for Mitsuba's llvm variant, Python packages, this package) and
# runs the whole suite: Rust format / lint / unit tests / docs, then pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

# A libLLVM >= 16 lets Mitsuba 3 run its llvm_ad_rgb variant (Dr.Jit finds
# it by itself); without one the suite falls back to scalar_rgb.
if ! dpkg -s libllvm19 >/dev/null 2>&1 && command -v apt-get >/dev/null; then
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq libllvm19 >/dev/null
fi

python -m pip install --quiet --upgrade pip
python -m pip install --quiet ".[test,mitsuba,plot,distributed]"

rustup component add rustfmt clippy >/dev/null 2>&1 || true
cargo fmt --check
cargo clippy --all-targets --all-features --quiet -- -D warnings
cargo test --quiet
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet
python -m mypy.stubtest mcsample._core --allowlist scripts/stubtest-allowlist.txt

# Run pytest from outside the source tree so it imports the installed
# package, not python/mcsample without its compiled core. --nbmake also
# executes every notebook top to bottom and fails on any error.
cd tests && python -m pytest -q -p no:cacheprovider --nbmake . ../notebooks "$@"
