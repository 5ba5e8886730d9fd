#!/usr/bin/env bash
# Installs the third-party validators the export tests drive (../shared/VALIDATORS.md):
# check_urdf (Debian liburdfdom-tools), MuJoCo and PyBullet (PyPI, in .venv-validators) and the
# Khronos glTF validator (npm, in .validators/). Idempotent; run by scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v check_urdf >/dev/null; then
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq --no-install-recommends liburdfdom-tools >/dev/null
fi

if [ ! -x .venv-validators/bin/python ] || ! .venv-validators/bin/python -c "import mujoco, pybullet, pyperplan" 2>/dev/null; then
    python3 -m venv .venv-validators
    # pyperplan checks the task planner's plan lengths on the exported PDDL.
    .venv-validators/bin/pip install -q mujoco==4.0.0 pybullet==3.2.7 pyperplan==2.1
fi

if [ ! -f .validators/node_modules/gltf-validator/package.json ]; then
    mkdir -p .validators
    npm install --silent --no-audit --no-fund --prefix .validators gltf-validator@2.0.0-dev.3.10 >/dev/null
fi
echo "validators: $(command -v check_urdf), mujoco $(.venv-validators/bin/python -c 'import mujoco; print(mujoco.__version__)'), gltf-validator $(node -p "require('./.validators/node_modules/gltf-validator/package.json').version")"
