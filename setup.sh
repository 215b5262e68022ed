#!/bin/sh
# What `lbm-server run` needs beyond the Rust toolchain on a fresh Debian or Ubuntu machine: the
# Vulkan loader and Mesa's Vulkan drivers (lavapipe runs the GPU kernels where there is no GPU; a
# GPU's own driver, where there is one, is preferred). Nothing to do where both are installed.
set -eu
if dpkg -s mesa-vulkan-drivers libvulkan1 >/dev/null 2>&1; then
    exit 0
fi
as_root=""
if [ "$(id -u)" != 0 ]; then
    as_root=sudo
fi
$as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
$as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    mesa-vulkan-drivers libvulkan1 >/dev/null
