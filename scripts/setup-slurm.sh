#!/usr/bin/env bash
# Installs Slurm and MUNGE from Debian (slurmctld, slurmd, slurm-client, munge) for the test that
# runs a batch as a job array on a one-node cluster (scripts/slurm-local.sh starts it). Idempotent;
# run by scripts/test.sh. Needs root or sudo, as apt-get does.
set -euo pipefail

if command -v slurmctld >/dev/null && command -v slurmd >/dev/null && command -v sbatch >/dev/null \
    && command -v munged >/dev/null; then
    echo "slurm: $(dpkg-query -W -f='${Version}' slurm-client), $(munged --version 2>&1 | head -1)"
    exit 0
fi
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
packages=(slurmctld slurmd slurm-client munge)
if ! $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${packages[@]}" >/dev/null; then
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${packages[@]}" >/dev/null
fi
echo "slurm: $(dpkg-query -W -f='${Version}' slurm-client), $(munged --version 2>&1 | head -1)"
