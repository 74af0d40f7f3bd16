#!/usr/bin/env bash
# Prints the kernel and the initramfs the VM stage boots (two lines: the vmlinuz, the initramfs,
# then a third: the folder holding the kernel's lib/modules, for modprobe -d in the guest),
# building what the cache lacks:
#  1. Debian 12's kernel (the package linux-image-amd64 depends on, e.g. linux-image-6.1.0-57-amd64),
#     fetched with apt-get download and unpacked with dpkg-deb -x: never installed on the host
#     (the host keeps its own kernel). depmod writes its modules.dep (the package's postinst would
#     have). About 70 MB to fetch, 400 MB unpacked.
#  2. A small initramfs: busybox (busybox-static), the modules that mount the host's own files
#     over 9p (virtio_pci, 9pnet_virtio, 9p and what modules.dep says they need, in load order),
#     and an init that mounts the host root and the run's output share and hands over to the
#     run's own init.sh there (tools/vm/boot.sh writes it).
#   tools/vm/kernel.sh [CACHE_DIR]   (default $LIFTD_VM_CACHE, else /var/cache/liftd-vm as root,
#                                     else build/vm/cache in the checkout)
# Nothing else of the machine changes; a new kernel version in Debian's lists gets a new folder
# and the older ones are removed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
default_cache=$here/../../build/vm/cache
[ "$(id -u)" = 0 ] && default_cache=/var/cache/liftd-vm
cache=${1:-${LIFTD_VM_CACHE:-$default_cache}}
mkdir -p "$cache"
cache=$(cd "$cache" && pwd)

# Which kernel: the one Debian's metapackage points at now (apt's lists; read once at least).
image_package() {
  apt-cache depends linux-image-amd64 2>/dev/null | sed -n 's/^ *Depends: \(linux-image-[0-9].*-amd64\)$/\1/p' | head -1
}
package=$(image_package)
if [ -z "$package" ]; then
  apt-get -o DPkg::Lock::Timeout=600 update -qq >&2
  package=$(image_package)
fi
[ -n "$package" ] || { echo "vm kernel: apt knows no linux-image-amd64" >&2; exit 1; }
version=${package#linux-image-}
dir=$cache/$version
if [ ! -s "$dir/vmlinuz" ] || [ ! -s "$dir/lib/modules/$version/modules.dep" ]; then
  start=$SECONDS
  echo "vm kernel: fetching $package (apt-get download, not installed)" >&2
  rm -rf "$cache"/[0-9]*-amd64 "$cache"/download
  mkdir -p "$cache/download"
  # apt downloads as its sandbox user where that user may write (else it warns and goes on).
  chown _apt "$cache/download" 2>/dev/null || true
  (cd "$cache/download" && apt-get download "$package" >&2)
  mkdir -p "$dir.tmp"
  dpkg-deb -x "$cache"/download/"$package"_*.deb "$dir.tmp"
  cp "$dir.tmp/boot/vmlinuz-$version" "$dir.tmp/vmlinuz"
  depmod -b "$dir.tmp" "$version"
  rm -rf "$cache/download" "$dir.tmp/boot"
  mv "$dir.tmp" "$dir"
  echo "vm kernel: $version unpacked in $((SECONDS - start)) s" >&2
fi
moddir=$dir/lib/modules/$version

# The initramfs; its key hashes this script (its init below) and busybox's version.
# /bin/busybox of busybox-static: it runs without the host's libraries, which the initramfs lacks.
busybox=/bin/busybox
[ -x "$busybox" ] || { echo "vm kernel: no $busybox (Debian package busybox-static)" >&2; exit 1; }
key=$( (cat "$0"; "$busybox" --help 2>&1 | sed -n 1p) | sha256sum | cut -c1-12)
initrd=$dir/initramfs-$key.cpio.gz
if [ ! -s "$initrd" ]; then
  rm -f "$dir"/initramfs-*.cpio.gz
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  mkdir -p "$work"/{bin,dev,proc,sys,newroot,out,keep,lib/modules}
  cp "$busybox" "$work/bin/busybox"
  # Each wanted module after what modules.dep says it needs (that list's last entry first).
  order=()
  add() {
    local line deps i m
    line=$(grep -E "^[^:]*/$1\.ko(\.[a-z]+)?:" "$moddir/modules.dep" | head -1)
    [ -n "$line" ] || { echo "vm kernel: no module $1 in $version" >&2; exit 1; }
    read -ra deps <<<"${line#*:}"
    for ((i = ${#deps[@]} - 1; i >= 0; i--)); do
      m=${deps[i]}
      [[ " ${order[*]} " == *" $m "* ]] || order+=("$m")
    done
    m=${line%%:*}
    [[ " ${order[*]} " == *" $m "* ]] || order+=("$m")
  }
  for m in virtio_pci 9pnet_virtio 9p; do add "$m"; done
  for m in "${order[@]}"; do
    cp "$moddir/$m" "$work/lib/modules/"
    basename "$m" >>"$work/lib/modules/order"
  done
  cat >"$work/init" <<'INIT'
#!/bin/busybox sh
# The initramfs's PID 1: the host's "/" read-only over 9p at /newroot, the run's output share
# (writable) at /out, then the run's own init (tools/vm/boot.sh wrote it there).
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
for m in $(cat /lib/modules/order); do
  insmod /lib/modules/$m || echo "initramfs: insmod $m failed"
done
opts=trans=virtio,version=9p2000.L,msize=512000
mount -t 9p -o $opts,ro,cache=loose host /newroot || echo "initramfs: cannot mount the host's root"
mount -t 9p -o $opts out /out || echo "initramfs: cannot mount the output share"
if [ -f /out/init.sh ]; then
  exec sh /out/init.sh
fi
echo "initramfs: no /out/init.sh"
poweroff -f
INIT
  chmod +x "$work/init"
  (cd "$work" && find . | cpio -o -H newc --quiet | gzip -1) >"$initrd.tmp"
  mv "$initrd.tmp" "$initrd"
  echo "vm kernel: initramfs $(basename "$initrd") with ${#order[@]} modules" >&2
fi
echo "$dir/vmlinuz"
echo "$initrd"
echo "$dir"
