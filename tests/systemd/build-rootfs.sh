#!/usr/bin/env bash
# Prints the path of the cached ext4 image the systemd stage boots (copy it before booting: the
# stage changes it), building what the cache lacks:
#  1. rootfs-bookworm-KEY.tar: Debian 12 (mmdebstrap, minbase plus rootfs-packages.txt) from the
#     host's own Debian apt sources; KEY hashes rootfs-packages.txt and the mmdebstrap options
#     below, so a changed package list builds a new one. Minutes (downloads); about 210 MB.
#  2. rootfs-bookworm-KEY-BOOT.img: that tar in an ext4 file (mkfs.ext4 -d), plus the stage's
#     boot runner (guest/liftd-stage-boot, guest/liftd-stage.service; BOOT hashes them).
#     Seconds. Sparse: about 600 MB on disk.
#   build-rootfs.sh [CACHE_DIR]    (default $LIFTD_UML_CACHE or /var/cache/liftd-uml)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cache=${1:-${LIFTD_UML_CACHE:-/var/cache/liftd-uml}}
mmdebstrap_options=(--variant=minbase --format=tar
  --dpkgopt='path-exclude=/usr/share/locale/*' --dpkgopt='path-exclude=/usr/share/doc/*'
  --dpkgopt='path-include=/usr/share/doc/liftd/*' --aptopt='Acquire::Languages "none"'
  --customize-hook='rm -rf "$1"/var/cache/apt/* "$1"/var/lib/apt/lists/*')
key=$( (cat "$here/rootfs-packages.txt"; printf '%s\n' "${mmdebstrap_options[@]}") | sha256sum | cut -c1-16)
boot=$(cat "$here/guest/liftd-stage-boot" "$here/guest/liftd-stage.service" "$here/build-rootfs.sh" |
  sha256sum | cut -c1-8)
tar=$cache/rootfs-bookworm-$key.tar
img=$cache/rootfs-bookworm-$key-$boot.img
if [ -s "$img" ]; then
  echo "$img"
  exit 0
fi
mkdir -p "$cache"
if [ ! -s "$tar" ]; then
  packages=$(grep -v '^#' "$here/rootfs-packages.txt" | xargs | tr ' ' ',')
  # The host's Debian sources (deb822 or one-line), not third-party lists.
  sources=/etc/apt/sources.list.d/debian.sources
  [ -f "$sources" ] || sources=/etc/apt/sources.list
  start=$SECONDS
  echo "build-rootfs: building $tar (packages: $packages)" >&2
  rm -f "$cache"/rootfs-bookworm-*.tar "$cache"/rootfs-bookworm-*.img  # older keys' files
  mmdebstrap "${mmdebstrap_options[@]}" --include="$packages" bookworm "$tar.tmp" "$sources" >&2
  mv "$tar.tmp" "$tar"
  echo "build-rootfs: root file system built in $((SECONDS - start)) s, $(du -h "$tar" | cut -f1)" >&2
fi
start=$SECONDS
rm -f "$cache"/rootfs-bookworm-"$key"-*.img
dir=$(mktemp -d "$cache/root-XXXXXX")
trap 'rm -rf "$dir"' EXIT
tar -xpf "$tar" -C "$dir" --numeric-owner
install -m 0755 "$here/guest/liftd-stage-boot" "$dir/usr/local/sbin/liftd-stage-boot"
install -m 0644 "$here/guest/liftd-stage.service" "$dir/etc/systemd/system/liftd-stage.service"
ln -sf /etc/systemd/system/liftd-stage.service \
  "$dir/etc/systemd/system/multi-user.target.wants/liftd-stage.service"
# No consoles to log in on; a fixed machine id (no first-boot setup); a name.
for unit in getty@.service serial-getty@.service console-getty.service getty-static.service; do
  ln -sf /dev/null "$dir/etc/systemd/system/$unit"
done
echo 6c1f7d2a9b3e4f5a8d0c1b2a3e4f5d6c >"$dir/etc/machine-id"
echo liftd-stage >"$dir/etc/hostname"
echo "/dev/ubda / ext4 rw 0 1" >"$dir/etc/fstab"
# mke2fs says "Creating regular file" on stdout even with -q: stdout carries only the path.
mkfs.ext4 -q -F -L root -d "$dir" "$img.tmp" 1536M >&2
mv "$img.tmp" "$img"
echo "build-rootfs: image built in $((SECONDS - start)) s" >&2
echo "$img"
