#!/usr/bin/env bash
# Installs everything the test suite needs on a fresh Debian machine
# (libLLVM for Mitsuba's llvm variant, Python packages), builds this
# package's abi3 wheel and smoke-tests it in fresh virtual environments
# without Rust, installs it, and runs the whole suite: pytest (two worker
# processes), and beside it, at low priority, Rust format / lint / unit
# tests / docs and the stub check. Prints when each stage starts; exits
# non-zero if any part failed. Arguments go to pytest (`-n 0` runs it in
# one process, as `--pdb` needs).
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

# Rust format, lint, unit tests and docs run in the background from here
# on, at the lowest CPU priority (`background`): beside the wheel's build,
# the install and pytest, which wait on each other, they take only the
# cycles those leave idle (the compiler's one-threaded phases, the
# downloads, pytest's one-threaded Python). They build in a target
# directory of their own (clippy and the docs), so that neither build
# waits on the other's lock, or in the wheel's (the unit tests: built with
# the release profile, they reuse most of the dependencies the wheel's
# build compiled, and mcsample's own code keeps its debug assertions and
# overflow checks, as `cargo test` has them). Their log is printed after
# pytest. (After the libraries above: the Rust tests check that Embree
# loads under CI.)
rust_checks() {
  rustup component add rustfmt clippy >/dev/null 2>&1 || true
  stage "cargo fmt, cargo clippy"
  cargo fmt --check
  CARGO_TARGET_DIR="$ROOT/target/checks" cargo clippy --all-targets --all-features --quiet \
    -- -D warnings
  stage "cargo test (after the wheel's build)"
  until [ -e "$LOGS/wheel-built" ]; do sleep 2; done
  cargo test --release --lib --quiet \
    --config 'profile.release.package.mcsample.debug-assertions=true' \
    --config 'profile.release.package.mcsample.overflow-checks=true'
  stage "cargo doc"
  CARGO_TARGET_DIR="$ROOT/target/checks" RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet
  stage "Rust checks done"
}
LOGS=$(mktemp -d)
# On an early exit, the background jobs (and their children) are stopped.
stop_jobs() {
  local p
  for p in $(jobs -p); do
    pkill -TERM -P "$p" 2>/dev/null || true
    kill "$p" 2>/dev/null || true
  done
}
trap 'stop_jobs; rm -rf "$LOGS"' EXIT
# Runs its arguments at the lowest CPU priority (nice 19).
background() { renice -n 19 -p "$BASHPID" >/dev/null; "$@"; }
stage "Rust checks (in the background)"
background rust_checks >"$LOGS/rust.log" 2>&1 &
RUST=$!

stage "pip, maturin"
python -m pip install --quiet --upgrade pip "maturin>=1.7,<2"

# What the suite needs from the package index (the package's dependencies
# and its test, mitsuba, plot and distributed extras, read from
# pyproject.toml) downloads while the wheel compiles.
python - >"$LOGS/requirements.txt" <<'PY'
try:
    import tomllib
except ModuleNotFoundError:     # Python < 3.11: the wheel's install below fetches them
    raise SystemExit(0)
project = tomllib.load(open("pyproject.toml", "rb"))["project"]
extras = project["optional-dependencies"]
for requirement in project["dependencies"] + [r for e in ("test", "mitsuba", "plot", "distributed")
                                              for r in extras[e]]:
    print(requirement)
PY
REQUIREMENTS=""
if [ -s "$LOGS/requirements.txt" ]; then
  python -m pip install --quiet -r "$LOGS/requirements.txt" >"$LOGS/requirements.log" 2>&1 &
  REQUIREMENTS=$!
fi

stage "wheel"
# The wheel users install: abi3 (one wheel for CPython 3.9+), stripped.
rm -rf target/wheels
maturin build --release --quiet
WHEEL=$(ls "$PWD"/target/wheels/mcsample_toolkit-*-cp39-abi3-*.whl)
touch "$LOGS/wheel-built"
ls -l "$WHEEL"

# Installed into fresh virtual environments with no Rust toolchain on PATH
# (the PATH entries holding cargo or rustc left out), by this Python and by
# 3.9 and 3.13 where pyenv has them: a smoke test, run outside the source
# tree. It waits mostly on the package index, so it runs in the background,
# beside what follows; its log is printed and its status checked at the end.
smoke_tests() {
  local no_rust_path="" dir py i=0
  IFS=: read -ra entries <<<"$PATH"
  for dir in "${entries[@]}"; do
    [ -x "$dir/cargo" ] || [ -x "$dir/rustc" ] || no_rust_path="${no_rust_path:+$no_rust_path:}$dir"
  done
  for py in python "$HOME"/.pyenv/versions/3.9.[0-9]*/bin/python \
      "$HOME"/.pyenv/versions/3.13.[0-9]*/bin/python; do
    command -v "$py" >/dev/null || { echo "smoke test: no $py here"; continue; }
    i=$((i + 1))
    "$py" -m venv "$LOGS/venv$i"
    (cd "$LOGS" && export PATH="$no_rust_path" &&
      "$LOGS/venv$i/bin/python" -m pip install --quiet "$WHEEL" &&
      "$LOGS/venv$i/bin/python" "$ROOT/scripts/smoke.py")
  done
}
stage "smoke tests (in the background)"
background smoke_tests >"$LOGS/smoke.log" 2>&1 &
SMOKE=$!

# The same wheel, with what the suite needs, into this Python, in place of
# any earlier install (pip keeps one of the same version otherwise; the
# distribution was called "mcsample" before: that name on the package
# index is another project's).
stage "test dependencies"
[ -z "$REQUIREMENTS" ] || wait "$REQUIREMENTS" || { cat "$LOGS/requirements.log"; exit 1; }
python -m pip uninstall --quiet -y mcsample mcsample-toolkit 2>/dev/null || true
python -m pip install --quiet "$WHEEL[test,mitsuba,plot,distributed]"

# The stub check, in the background as the Rust checks are.
stage "stub check (in the background)"
background python -m mypy.stubtest mcsample._core --allowlist scripts/stubtest-allowlist.txt \
  >"$LOGS/stubtest.log" 2>&1 &
STUBTEST=$!

failed=""
stage "pytest"
# Run pytest from outside the source tree so it imports the installed
# package, not python/mcsample without its compiled core. --nbmake also
# executes every notebook top to bottom and fails on any error. Two worker
# processes (pytest-xdist): half the suite's time is one-threaded Python
# (statistics, notebooks, setup), which the other worker's renders overlap.
# (--dist loadgroup: the tests of a Dask cluster share one worker.) The
# notebooks, the longest items (up to 1.5 minutes each), are collected
# first, so that the workers hand out the short tests last and finish
# together.
(cd tests && python -m pytest -q -p no:cacheprovider -n 2 --dist loadgroup --durations=20 \
  --nbmake ../notebooks . "$@") || failed="$failed pytest"

stage "stub check's results"
wait "$STUBTEST" || failed="$failed stubtest"
cat "$LOGS/stubtest.log"
stage "Rust checks' results"
wait "$RUST" || failed="$failed rust-checks"
cat "$LOGS/rust.log"
stage "smoke tests' results"
wait "$SMOKE" || failed="$failed smoke-tests"
cat "$LOGS/smoke.log"
if [ -n "$failed" ]; then
  echo "FAILED:$failed"
  exit 1
fi
stage "all passed"
