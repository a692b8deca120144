#!/bin/sh
# Installs the Debian 12 packages the project needs, only those missing. One list for the
# Makefile, CI and the container image.
#   docker/install-deps.sh          build + run + test dependencies
#   docker/install-deps.sh --print  print the apt-get line for what is missing, install nothing
set -eu

PACKAGES="build-essential cmake pkg-config \
libvulkan-dev mesa-vulkan-drivers glslang-dev glslang-tools \
libglm-dev libtinyobjloader-dev libcpp-httplib-dev libssl-dev libbrotli-dev zlib1g-dev \
nlohmann-json3-dev libstb-dev libgtest-dev"

missing=""
for p in $PACKAGES; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing="$missing $p"
  fi
done

if [ -z "$missing" ]; then
  exit 0
fi
if [ "${1:-}" = "--print" ] || [ "$(id -u)" != "0" ]; then
  echo "Missing packages. Install them with:" >&2
  echo "  sudo apt-get install -y$missing" >&2
  [ "${1:-}" = "--print" ] && exit 0
  exit 1
fi
echo "Installing:$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# shellcheck disable=SC2086
apt-get install -y -qq --no-install-recommends $missing
