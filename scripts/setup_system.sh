#!/usr/bin/env bash
# Debian packages evpose needs: open3d loads libusb and libGL at import time,
# the browser tests drive Debian's chromium; python3-venv when the Makefile needs a venv (EVPOSE_NEED_VENV=yes:
# the interpreter refuses pip installs, PEP 668). Skips apt when all are present.
set -euo pipefail
need=()
for pkg in libusb-1.0-0 libgl1 libgomp1 chromium; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if [ "${EVPOSE_NEED_VENV:-no}" = yes ]; then
  dpkg -s python3-venv >/dev/null 2>&1 || need+=(python3-venv)
fi
if [ ${#need[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}"
fi
