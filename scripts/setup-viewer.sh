#!/usr/bin/env bash
# Installs what the viewer (cargo feature `viewer`) needs to render without a GPU: the Vulkan
# loader and Mesa's software Vulkan driver (lavapipe), from Debian's packages; Xvfb and the X
# libraries winit loads, for a window on a machine without a display. Idempotent; run by
# scripts/test.sh.
set -euo pipefail

packages=(libvulkan1 mesa-vulkan-drivers xvfb xauth libx11-xcb1 libxcursor1 libxi6 libxrandr2 libxkbcommon-x11-0)
missing=()
for p in "${packages[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
icd=$(ls /usr/share/vulkan/icd.d/lvp_icd.*.json 2>/dev/null | head -1)
echo "viewer: Vulkan software driver ${icd:-MISSING}"
