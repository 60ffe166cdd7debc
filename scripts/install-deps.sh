#!/usr/bin/env sh
# Installs the Debian 12 packages inimtrace needs (run as root, or with sudo available).
#   libembree-dev libclang-dev   Embree backend: bindgen over wrapper.h, libembree3 (+ TBB)
#   glmark2-data                 the Stanford bunny mesh for scenes/bunny.toml
#   pkg-config libfontconfig1-dev libfreetype-dev fontconfig fonts-dejavu-core
#                                plotters' text rendering (figure labels, plots)
#   build-essential              C toolchain for crates that build C
#   slurm-wlm munge              `inimtrace sweep --slurm` and its tests: scripts/slurm-local.sh runs
#                                a single-node Slurm cluster on this machine
set -eu
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends \
    build-essential pkg-config libembree-dev libclang-dev glmark2-data \
    libfontconfig1-dev libfreetype-dev fontconfig fonts-dejavu-core slurm-wlm munge
