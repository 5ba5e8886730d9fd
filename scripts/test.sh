#!/usr/bin/env bash
# Installs what the tests need, then runs every test. This is the README's test command and
# exactly what CI runs (.ci/run). Needs only the Rust toolchain on a fresh machine; the tests that
# use real data read it from ../shared/data and say so when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

# Incremental state is for editing sessions; a clean run only pays its disk for it.
export CARGO_INCREMENTAL=0

disk() { echo "-- disk: target $(du -sh target 2>/dev/null | cut -f1), free $(df -h . | awk 'NR==2 {print $4}')"; }

echo "== toolchain"
cargo --version
rustup component add clippy rustfmt >/dev/null 2>&1 || true

echo "== format and lints"
cargo fmt --all -- --check
cargo clippy --locked --all-targets -- -D warnings
disk

echo "== ONNX Runtime for the onnx segmentation backend (from the PyPI wheel)"
./scripts/setup-ort.sh

echo "== validators (check_urdf, MuJoCo, PyBullet, Khronos glTF validator)"
./scripts/setup-validators.sh

echo "== tests"
cargo test --locked --lib --bins --tests --no-fail-fast
disk

echo "== viewer (cargo feature viewer) off screen on Mesa's software Vulkan driver"
./scripts/setup-viewer.sh
# Lints of the viewer code: run `cargo clippy --features viewer --all-targets -- -D warnings`
# before committing; CI builds the feature once, for its tests, to stay in its time budget.
cargo test --locked --features viewer --lib --test viewer
disk
# The benchmarks are type-checked by clippy --all-targets above; building them is a third full
# build (release profile) that CI has neither the time nor the disk for. Run them with cargo bench.
