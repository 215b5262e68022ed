#!/bin/sh
# Idempotent install of the DEM reference codes (Debian bookworm packages).
# Fast no-op when liggghts and yade (+ python3-yade) are already present.
set -e
need=""
command -v liggghts >/dev/null 2>&1 || need="$need liggghts"
command -v yade >/dev/null 2>&1 || need="$need yade"
dpkg -s python3-yade >/dev/null 2>&1 || need="$need python3-yade"
# python3-matplotlib / python3-numpy: the system python (numpy 1.x) is used for the charts
/usr/bin/python3 -c "import matplotlib, numpy" >/dev/null 2>&1 || need="$need python3-matplotlib python3-numpy"
if [ -z "$need" ]; then
  echo "install.sh: liggghts, yade, python3-yade already installed"
  exit 0
fi
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends $need
