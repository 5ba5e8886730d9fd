#!/usr/bin/env bash
# Fetches the Sweet Home 3D furniture catalogues from Debian (../shared/data/README.md): the
# packages sweethome3d-furniture (820 models in five *.sh3f catalogues) and sweethome3d (its
# default catalogue of 100 models, inside sweethome3d.jar), unpacked into .sh3d/ without
# installing them (no Java needed: `iscene cad import sh3d` reads the zip files itself).
# Idempotent; run by scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

target=.sh3d/usr/share/sweethome3d
if [ ! -f "$target/sweethome3d.jar" ] || ! ls "$target"/furniture/*.sh3f >/dev/null 2>&1; then
    rm -rf .sh3d && mkdir -p .sh3d/debs
    fetch() { (cd .sh3d/debs && apt-get download sweethome3d-furniture sweethome3d >/dev/null 2>&1); }
    if ! fetch; then
        SUDO=""
        if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
        $SUDO apt-get update -qq
        fetch
    fi
    for deb in .sh3d/debs/*.deb; do dpkg-deb -x "$deb" .sh3d; done
    rm -rf .sh3d/debs
fi
echo "sweet home 3d: $(ls "$target"/furniture/*.sh3f | wc -l) plugin catalogues and $target/sweethome3d.jar"
