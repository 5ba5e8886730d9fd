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

echo "== format and lints"
cargo fmt --all -- --check
cargo clippy --locked --all-targets -- -D warnings
disk

echo "== ONNX Runtime for the onnx segmentation backend (from the PyPI wheel)"
./scripts/setup-ort.sh

disk
echo "== validators (check_urdf, MuJoCo, PyBullet, Khronos glTF validator)"
./scripts/setup-validators.sh

disk
echo "== Sweet Home 3D furniture catalogues (Debian packages, unpacked into .sh3d)"
./scripts/setup-sh3d.sh

disk
echo "== Slurm and MUNGE from Debian (the batch test starts a one-node cluster: scripts/slurm-local.sh)"
./scripts/setup-slurm.sh

disk
echo "== viewer runtime: Mesa's software Vulkan driver and Xvfb"
./scripts/setup-viewer.sh

disk
echo "== tests (with the viewer feature: one build serves every test)"
# The viewer feature only adds code (src/viewer, the view command); the default build's code is
# the same and clippy above checks it as it is. Building the tests once, with the feature,
# keeps a clean CI run within its time budget: a second build of the Bevy stack would not.
# Lints of the viewer code: `cargo clippy --features viewer --all-targets -- -D warnings`.
# The command line (src/bin/iscene) has no tests: Cargo.toml turns its test harness off (`test = false`), which saves
# one more link of the whole Bevy stack. The integration tests build and run the binary.
cargo test --locked --features viewer --lib --tests --no-run
disk
cargo test --locked --features viewer --lib --tests --no-fail-fast
disk
# The benchmarks are type-checked by clippy --all-targets above; building them is another full
# build (release profile) that CI has neither the time nor the disk for. Run them with cargo bench.
