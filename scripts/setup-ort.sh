#!/usr/bin/env bash
# Fetches the ONNX Runtime shared library for the `onnx` segmentation backend from the PyPI wheel
# (the only registry that carries it; Debian has no package) into .ort/. Idempotent: does nothing
# when the library is already there. See ../shared/ORT.md.
set -euo pipefail
cd "$(dirname "$0")/.."

VERSION=1.31.1
LIB=".ort/libonnxruntime.so.$VERSION"
if [[ -f "$LIB" ]]; then
    echo "ONNX Runtime $VERSION already in $LIB"
    exit 0
fi

PYTHON=$(command -v python3 || command -v python)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The same library is in every CPython wheel; name one so pip picks a binary without building.
"$PYTHON" -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
    --platform manylinux_2_28_x86_64 --dest "$work" "onnxruntime==$VERSION"
wheel=$(ls "$work"/onnxruntime-"$VERSION"-*.whl)
"$PYTHON" - "$wheel" "$work" "$VERSION" <<'PY'
import sys, zipfile
wheel, dest, version = sys.argv[1:4]
name = f"capi/libonnxruntime.so.{version}"
member = [n for n in zipfile.ZipFile(wheel).namelist() if n.endswith(name)]
if len(member) != 1:
    sys.exit(f"{wheel}: expected one {name}, found {member}")
zipfile.ZipFile(wheel).extract(member[0], dest)
print(member[0])
PY
mkdir -p .ort
# Move into place last, so an interrupted run leaves no half-written library behind.
mv "$work/onnxruntime/capi/libonnxruntime.so.$VERSION" "$LIB.partial"
mv "$LIB.partial" "$LIB"
echo "ONNX Runtime $VERSION installed in $LIB"
