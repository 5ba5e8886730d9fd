#!/usr/bin/env bash
# Installs what the tests need, then runs every test. This is the README's test command and
# exactly what CI runs (.ci/run). Needs only the Rust toolchain on a fresh machine; the tests that
# use real data read it from ../shared/data and say so when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== toolchain"
cargo --version
rustup component add clippy rustfmt >/dev/null 2>&1 || true

echo "== format and lints"
cargo fmt --all -- --check
cargo clippy --locked --all-targets -- -D warnings

echo "== ONNX Runtime for the onnx segmentation backend (from the PyPI wheel)"
./scripts/setup-ort.sh

echo "== validators (check_urdf, MuJoCo, PyBullet, Khronos glTF validator)"
./scripts/setup-validators.sh

echo "== tests"
cargo test --locked --lib --bins --tests --no-fail-fast

echo "== viewer (cargo feature viewer) off screen on Mesa's software Vulkan driver"
./scripts/setup-viewer.sh
# Lints of the viewer code: run `cargo clippy --features viewer --all-targets -- -D warnings`
# before committing; CI builds the feature once, for its tests, to stay in its time budget.
cargo test --locked --features viewer --test viewer

echo "== benchmarks build (run them with: cargo bench)"
cargo bench --locked --no-run
