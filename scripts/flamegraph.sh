#!/usr/bin/env bash
# A flame graph (SVG) of one iscene command: perf samples the release binary with DWARF call
# stacks, inferno folds and draws them. Installs Debian's linux-perf and inferno (crates.io)
# when they are missing.
#
#   scripts/flamegraph.sh OUT.svg "TITLE" iscene reconstruct ../shared/data/rgbd/7scenes-redkitchen --frames 0:300 --segmentation none --out /tmp/r
#
# The figures of docs/profile/ were made this way (docs/live.md#profile). HZ (default 250)
# sets the sampling rate: lower it for runs of more than a minute.
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 OUT.svg TITLE iscene ARGS..." >&2
    exit 2
fi
out=$1
title=$2
shift 2
[ "$1" = iscene ] && shift
cd "$(dirname "$0")/.."
command -v perf >/dev/null || apt-get install -y linux-perf >/dev/null
command -v inferno-flamegraph >/dev/null || cargo install inferno --locked --version 0.12.8
cargo build --release --locked
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
perf record -F "${HZ:-250}" --call-graph dwarf,16384 -o "$work/perf.data" ./target/release/iscene "$@"
perf script -i "$work/perf.data" 2>/dev/null | inferno-collapse-perf > "$work/folded"
inferno-flamegraph --title "$title" --subtitle "$(nproc) cores, perf record -F ${HZ:-250} --call-graph dwarf, $(date -u +%F)" \
    --minwidth 2 < "$work/folded" > "$out"
echo "wrote $out"
