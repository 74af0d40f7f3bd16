#!/usr/bin/env bash
# Builds the .deb from the build tree BUILD (cpack), then checks what a Debian 12 board would get:
# the files, the conffile, the dependencies, the maintainer scripts, man pages that open, and
# the unit as installed passing `systemd-analyze verify` against the packaged binary.
#   deb_test.sh BUILD VERSION
set -euo pipefail
build=$1
version=$2
for tool in cpack dpkg-deb; do
  command -v "$tool" >/dev/null || { echo "SKIPPED: $tool is not installed"; exit 0; }
done
work=$(mktemp -d /tmp/liftd-deb-test-XXXXXX)
trap 'rm -rf "$work"' EXIT
fail=0
bad() { echo "FAIL: $*"; fail=1; }

(cd "$build" && cpack -G DEB -B "$work/out" >"$work/cpack.log" 2>&1) ||
  { cat "$work/cpack.log"; bad "cpack failed"; exit 1; }
deb=$(ls "$work"/out/liftd_"$version"_*.deb 2>/dev/null | head -1)
[ -n "$deb" ] || { ls "$work/out"; bad "no liftd_${version}_*.deb"; exit 1; }
echo "built $(basename "$deb") ($(stat -c %s "$deb") bytes)"

dpkg-deb -I "$deb" >"$work/info"
dpkg-deb -c "$deb" | awk '{ print $6 }' | sed 's|^\./|/|' >"$work/files"
for want in "Package: liftd" "Version: $version" "Depends:.*systemd" "Depends:.*init-system-helpers" \
            "Depends:.*libsystemd0" "Depends:.*libspdlog"; do
  grep -q "^ *$want" "$work/info" || bad "control has no '$want'"
done
for f in /usr/bin/liftd /usr/bin/liftctl /usr/bin/dcp-drive-sim \
         /usr/lib/systemd/system/liftd.service /usr/lib/systemd/system/liftd.socket \
         /usr/lib/sysusers.d/liftd.conf /usr/lib/tmpfiles.d/liftd.conf \
         /usr/lib/systemd/catalog/liftd.catalog /etc/liftd/liftd.json \
         /usr/share/doc/liftd/examples/liftd.json /usr/share/doc/liftd/operations.md \
         /usr/share/man/man8/liftd.8.gz /usr/share/man/man1/liftctl.1.gz; do
  grep -qx "$f" "$work/files" || bad "package lacks $f"
done
# Nothing of the build itself: no tests, benchmarks or fuzzers.
if grep -E '_test$|bench|fuzz' "$work/files"; then bad "test or benchmark programs in the package"; fi

dpkg-deb -e "$deb" "$work/control"
[ "$(cat "$work/control/conffiles")" = "/etc/liftd/liftd.json" ] ||
  bad "conffiles is '$(cat "$work/control/conffiles")', want /etc/liftd/liftd.json"
for script in postinst prerm postrm; do
  [ -x "$work/control/$script" ] || bad "no executable $script"
  sh -n "$work/control/$script" || bad "$script does not parse"
done
grep -q "systemd-sysusers liftd.conf" "$work/control/postinst" || bad "postinst creates no user"

dpkg-deb -x "$deb" "$work/root"
for page in usr/share/man/man8/liftd.8.gz usr/share/man/man1/liftctl.1.gz; do
  gzip -dc "$work/root/$page" | grep -q '^\.SH DESCRIPTION' || bad "$page is not a man page"
done
gzip -dc "$work/root/usr/share/man/man8/liftd.8.gz" | grep -q -- '--check-config' ||
  bad "liftd.8 does not carry the --help text"
"$work/root/usr/bin/liftd" --version >/dev/null || bad "the packaged liftd does not run"

unit=$work/root/usr/lib/systemd/system/liftd.service
grep -q '^ExecStart=/usr/bin/liftd --config /etc/liftd/liftd.json$' "$unit" ||
  bad "ExecStart is '$(grep ^ExecStart= "$unit")'"
if command -v systemd-analyze >/dev/null; then
  # verify checks that ExecStart's program exists: point it at the extracted one.
  sed "s|^ExecStart=/usr/bin/liftd|ExecStart=$work/root/usr/bin/liftd|" "$unit" >"$work/liftd.service"
  cp "$work/root/usr/lib/systemd/system/liftd.socket" "$work/liftd.socket"
  out=$(cd "$work" && SYSTEMD_LOG_COLOR=0 systemd-analyze verify liftd.service liftd.socket 2>&1) ||
    bad "systemd-analyze verify failed: $out"
  [ -z "$out" ] || bad "systemd-analyze verify warns: $out"
else
  echo "SKIPPED: systemd-analyze verify (not installed)"
fi
[ "$fail" = 0 ] && echo "package ok: $(wc -l <"$work/files") paths"
exit "$fail"
