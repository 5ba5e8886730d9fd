#!/usr/bin/env bash
# Side-by-side TSDF benchmark: iscene against Open3D's ScalableTSDFVolume on the same frames and
# voxel sizes, in one run, with the speed ratio and held-out surface accuracy of both meshes.
#   scripts/bench-open3d.sh [SEQUENCE] [FRAMES] [RUNS]
# Defaults: ../shared/data/rgbd/7scenes-redkitchen, frames 0:300, every 10th frame held out, each
# side integrates 3 times into fresh maps and its fastest run counts (a shared machine's noise
# only ever slows a run down; single runs of either side vary by 10-20 % here).
# Installs open3d==0.19.0 (PyPI) into .venv-bench; Open3D 0.20's legacy volume integrates nothing
# on this data (../shared/ANCHORS.md). Open3D's wheel needs Debian's libusb-1.0-0.
set -euo pipefail
cd "$(dirname "$0")/.."
SEQ="${1:-../shared/data/rgbd/7scenes-redkitchen}"
FRAMES="${2:-0:300}"
RUNS="${3:-3}"
OUT=out/bench-open3d
if [ ! -d "$SEQ" ]; then
    echo "bench-open3d: $SEQ is missing (see ../shared/data/README.md)" >&2
    exit 2
fi
if ! ldconfig -p | grep -q libusb-1.0.so.0; then
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
    $SUDO apt-get install -y libusb-1.0-0 >/dev/null
fi
if [ ! -x .venv-bench/bin/python ]; then
    python3 -m venv .venv-bench
fi
.venv-bench/bin/python -c "import open3d" 2>/dev/null || .venv-bench/bin/pip install -q open3d==0.19.0
cargo build --release --locked --quiet
mkdir -p "$OUT"
for VOXEL in 0.02 0.01; do
    ./target/release/iscene bench tsdf "$SEQ" --frames "$FRAMES" --voxel "$VOXEL" --holdout 10 \
        --labels --runs "$RUNS" --mesh "$OUT/iscene_$VOXEL.ply" >"$OUT/iscene_$VOXEL.json"
    .venv-bench/bin/python scripts/bench_open3d.py "$SEQ" --frames "$FRAMES" --voxel "$VOXEL" \
        --holdout 10 --runs "$RUNS" --mesh "$OUT/open3d_$VOXEL.ply" --iscene-json "$OUT/iscene_$VOXEL.json" \
        --iscene-mesh "$OUT/iscene_$VOXEL.ply" >"$OUT/compare_$VOXEL.json"
done
echo "figures: $OUT/compare_*.json"
