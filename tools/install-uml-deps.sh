#!/usr/bin/env bash
# Installs what the real-kernel stages need: user-mode Linux (a Linux kernel that runs as an
# ordinary process), kmod for its modules, and for the systemd stage mmdebstrap and e2fsprogs
# (the Debian 12 root file system and its ext4 image). Safe to run again: it only calls apt-get
# when something is missing.
set -euo pipefail

packages=(user-mode-linux kmod iproute2 mmdebstrap e2fsprogs python3)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-uml-deps: installing ${missing[*]}" >&2
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 update -qq
"${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}"
