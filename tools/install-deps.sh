#!/usr/bin/env bash
# Installs the Debian 12 packages liftd needs to build, test and run its demo.
# Safe to run again: it only calls apt-get when something is missing.
#   tools/install-deps.sh              build, test and demo
#   tools/install-deps.sh --uml-can    what the real-SocketCAN stage needs besides (user-mode
#                                      Linux, its module loader, ip, candump/cangen)
#   tools/install-deps.sh --uml-systemd  what the systemd stage needs besides (user-mode Linux,
#                                      its management console, kmod, mmdebstrap and e2fsprogs for
#                                      the Debian 12 root file system and its ext4 image)
#   tools/install-deps.sh --vm         what the real-UART stage needs besides (tools/vm: QEMU,
#                                      busybox-static and cpio for its initramfs, kmod for depmod
#                                      and modprobe of the fetched kernel's modules)
#   tools/install-deps.sh --with-uml   the build and the three stages at once (tools/test.sh: one
#                                      apt-get run)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libasio-dev libspdlog-dev nlohmann-json3-dev libsystemd-dev libsqlite3-dev systemd
  googletest libgtest-dev libgmock-dev libbenchmark-dev
  clang-16 libclang-rt-16-dev clang-format
  python3 python3-jsonschema
)
uml_can=(user-mode-linux kmod iproute2 can-utils)
uml_systemd=(user-mode-linux uml-utilities kmod iproute2 mmdebstrap e2fsprogs python3)
vm=(qemu-system-x86 busybox-static cpio kmod python3)
case "${1:-}" in
  --uml-can) packages=("${uml_can[@]}") ;;
  --uml-systemd) packages=("${uml_systemd[@]}") ;;
  --vm) packages=("${vm[@]}") ;;
  --with-uml) packages+=("${uml_can[@]}" "${uml_systemd[@]}" "${vm[@]}") ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 update -qq
"${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends \
  "${missing[@]}"
