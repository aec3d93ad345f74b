#!/usr/bin/env bash
# Debian packages evpose needs: open3d loads libusb and libGL at import time,
# the browser tests drive Debian's chromium. Skips apt when all are present.
set -euo pipefail
need=()
for pkg in libusb-1.0-0 libgl1 libgomp1 chromium; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if [ ${#need[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}"
fi
