#!/usr/bin/env bash
# Installs what the tests need, then runs every test. This is the README's test command and
# exactly what CI runs (.ci/run). Needs only the Rust toolchain on a fresh machine; the tests that
# use real data read it from ../shared/data and say so when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

# Incremental state is for editing sessions; a clean run only pays its disk for it.
export CARGO_INCREMENTAL=0

# Each step says how long the run has taken so far and what the disk holds: a CI run that
# fails for time or for space shows where both went.
disk() { echo "-- ${SECONDS} s so far; disk: target $(du -sh target 2>/dev/null | cut -f1), free $(df -h . | awk 'NR==2 {print $4}')"; }
disk

echo "== toolchain"
cargo --version
rustup component add clippy rustfmt >/dev/null 2>&1 || true

echo "== format"
cargo fmt --all -- --check

# The set-up scripts download and install (network and disk, little CPU) while the build below
# uses both cores; the tests wait for them. They run one after the other: apt holds one lock.
setup_log=$(mktemp)
(
    set -e
    echo "== ONNX Runtime for the onnx segmentation backend (from the PyPI wheel)"
    ./scripts/setup-ort.sh
    echo "== validators (check_urdf, MuJoCo, PyBullet, Khronos glTF validator)"
    ./scripts/setup-validators.sh
    echo "== Sweet Home 3D furniture catalogues (Debian packages, unpacked into .sh3d)"
    ./scripts/setup-sh3d.sh
    echo "== Slurm and MUNGE from Debian (the batch test starts a one-node cluster: scripts/slurm-local.sh)"
    ./scripts/setup-slurm.sh
    echo "== viewer runtime: Mesa's software Vulkan driver and Xvfb"
    ./scripts/setup-viewer.sh
    echo "-- set-up done at ${SECONDS} s"
) >"$setup_log" 2>&1 &
setup_pid=$!

echo "== one build for the lints and the tests: clippy's lints (-D warnings) on every target"
# clippy-driver is rustc with clippy's lints: run as the workspace's compiler (what `cargo
# clippy` does, but with code generation), it lints the very build the tests use, so the
# dependencies are compiled once instead of once more in check mode for `cargo clippy`. The
# targets: the library with the viewer feature, its unit tests, the command line, the
# integration tests and the benchmarks (built, not run). Locally: `cargo clippy --all-targets
# --features viewer -- -D warnings`, and without the feature.
# The viewer feature only adds code (src/viewer, the view command): building the tests once,
# with it, keeps a clean CI run within its time budget; a second build of the Bevy stack would not.
# The command line (src/bin/iscene) has no tests: Cargo.toml turns its test harness off
# (`test = false`), which saves one more link of the whole Bevy stack. The integration tests
# build and run the binary.
# The test run below keeps the same compiler: cargo would otherwise build the crate again.
export RUSTC_WORKSPACE_WRAPPER="$(rustc --print sysroot)/bin/clippy-driver"
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
cargo test --locked --features viewer --lib --tests --benches --no-run
disk

if ! wait "$setup_pid"; then
    cat "$setup_log"
    echo "set-up failed (its output is above)" >&2
    exit 1
fi
cat "$setup_log"
rm -f "$setup_log"
disk

echo "== tests"
# One test thread more than cores: some tests wait on what they started (MuJoCo and PyBullet in
# Python, a Slurm job's scheduling, a process they kill) and leave a core idle meanwhile. The 95
# integration tests on 2 cores (2026-12-02, the same binary, one run each): 659 s on 2 threads (174 %
# CPU), 546 s on 3 (185 %), 573 s on 4.
export RUST_TEST_THREADS="${RUST_TEST_THREADS:-$(($(nproc) + 1))}"
cargo test --locked --features viewer --lib --tests --no-fail-fast
disk
# The benchmarks are built above in the test profile; their figures come from `cargo bench`
# (release profile), which is another full build that CI has neither the time nor the disk for.
