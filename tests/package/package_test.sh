#!/usr/bin/env bash
# The service as the shop floor installs it, checked in scratch folders (never on this machine's
# own system): `cmake --install` into a DESTDIR, then the CPack .deb installed, removed and
# purged with dpkg into a scratch root (--root, maintainer scripts run chrootless with
# DPKG_ROOT), each step checked.
#   tests/package/package_test.sh BUILD_DIR SCRATCH_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
scratch=$2
fail() {
  echo "package test: $*" >&2
  exit 1
}
rm -rf "$scratch"
mkdir -p "$scratch"
scratch=$(cd "$scratch" && pwd)

echo "== cmake --install into a DESTDIR"
DESTDIR="$scratch/destdir" cmake --install "$build" >"$scratch/install.log"
prefix=$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$build/CMakeCache.txt")
[[ $prefix == /usr ]] && sysconf=/etc || sysconf=$prefix/etc
d="$scratch/destdir"
for f in "$prefix/bin/millwatch" "$prefix/bin/millwatchd" \
  "$prefix/lib/systemd/system/millwatchd.service" "$prefix/lib/sysusers.d/millwatch.conf" \
  "$prefix/share/millwatch/config/millwatchd.json" "$prefix/share/millwatch/config/presets/cpti_masrani2023.json" \
  "$prefix/share/millwatch/lcmtypes/force_block_t.lcm" "$prefix/share/doc/millwatch/README.md" \
  "$sysconf/millwatch/millwatchd.json"; do
  [[ -e $d$f ]] || fail "cmake --install did not install $f"
done
if [[ -e $build/millwatch_types.jar ]]; then
  [[ -e $d$prefix/share/java/millwatch_types.jar ]] || fail "the lcm-spy jar is not installed"
fi
unit="$d$prefix/lib/systemd/system/millwatchd.service"
grep -qx "ExecStart=$prefix/bin/millwatchd -c $sysconf/millwatch/millwatchd.json --summary %S/millwatch/last-summary.json" "$unit" ||
  fail "the unit does not start the installed daemon with $sysconf/millwatch/millwatchd.json: $(grep ExecStart= "$unit")"
"$d$prefix/bin/millwatch" --help >/dev/null || fail "the installed millwatch does not run"
"$d$prefix/bin/millwatchd" --check -c "$d$sysconf/millwatch/millwatchd.json" >/dev/null ||
  fail "the installed configuration does not pass millwatchd --check"
# A second install keeps an edited configuration.
echo '{"edited": true}' >"$d$sysconf/millwatch/millwatchd.json"
DESTDIR="$d" cmake --install "$build" >/dev/null
grep -q edited "$d$sysconf/millwatch/millwatchd.json" || fail "a reinstall overwrote the configuration"

echo "== cpack -G DEB"
(cd "$build" && cpack -G DEB -B "$scratch/cpack" >"$scratch/cpack.log" 2>&1) || {
  cat "$scratch/cpack.log" >&2
  fail "cpack failed"
}
deb=$(ls "$scratch"/cpack/millwatch_*.deb)
dpkg-deb -c "$deb" >"$scratch/contents.txt"
for f in ./usr/bin/millwatch ./usr/bin/millwatchd ./etc/millwatch/millwatchd.json \
  ./usr/lib/systemd/system/millwatchd.service ./usr/lib/sysusers.d/millwatch.conf \
  ./usr/share/millwatch/lcmtypes/force_block_t.lcm; do
  grep -q " $f\$" "$scratch/contents.txt" || fail "the package lacks $f"
done
depends=$(dpkg-deb -f "$deb" Depends)
for lib in libmatio11 liblcm1 libsystemd0 libfftw3-double3; do
  [[ $depends == *"$lib"* ]] || fail "Depends lacks $lib: $depends"
done
[[ $(dpkg-deb -I "$deb" conffiles) == /etc/millwatch/millwatchd.json ]] || fail "conffiles"

echo "== dpkg -i, -r, -P into a scratch root"
root="$scratch/root"
mkdir -p "$root/var/lib/dpkg/info" "$root/var/lib/dpkg/updates" "$root/etc" "$root/var/log"
touch "$root/var/lib/dpkg/status" "$root/var/lib/dpkg/available"
cp /etc/passwd /etc/group "$root/etc/"
dpkg_root() {
  dpkg --root="$root" --force-script-chrootless --force-depends --log="$scratch/dpkg.log" "$@"
}
dpkg_root -i "$deb" >"$scratch/dpkg-i.log" 2>&1 || {
  cat "$scratch/dpkg-i.log" >&2
  fail "dpkg -i failed"
}
dpkg --root="$root" -s millwatch | grep -qx "Status: install ok installed" || fail "not installed"
[[ -x $root/usr/bin/millwatchd ]] || fail "no /usr/bin/millwatchd"
grep -q '^millwatch:' "$root/etc/passwd" || fail "postinst did not create the user millwatch"
grep -qx "ExecStart=/usr/bin/millwatchd -c /etc/millwatch/millwatchd.json --summary %S/millwatch/last-summary.json" \
  "$root/usr/lib/systemd/system/millwatchd.service" || fail "the packaged unit's paths"
"$root/usr/bin/millwatchd" --check -c "$root/etc/millwatch/millwatchd.json" >/dev/null ||
  fail "the packaged configuration does not pass --check"

dpkg_root -r millwatch >"$scratch/dpkg-r.log" 2>&1 || fail "dpkg -r failed: $(cat "$scratch/dpkg-r.log")"
[[ ! -e $root/usr/bin/millwatchd ]] || fail "dpkg -r left /usr/bin/millwatchd"
[[ ! -e $root/usr/lib/systemd/system/millwatchd.service ]] || fail "dpkg -r left the unit"
[[ -e $root/etc/millwatch/millwatchd.json ]] || fail "dpkg -r removed the configuration (a conffile)"
dpkg --root="$root" -s millwatch | grep -qx "Status: deinstall ok config-files" || fail "status after -r"

dpkg_root -P millwatch >"$scratch/dpkg-p.log" 2>&1 || fail "dpkg -P failed: $(cat "$scratch/dpkg-p.log")"
[[ ! -e $root/etc/millwatch ]] || fail "dpkg -P left /etc/millwatch"
left=$(cd "$root" && find . -type f ! -path './var/lib/dpkg/*' ! -path './etc/passwd*' \
  ! -path './etc/group*' ! -path './etc/shadow*' ! -path './etc/gshadow*' ! -path './etc/.pwd.lock' | sort)
[[ -z $left ]] || fail "files left after purge: $left"
if dpkg --root="$root" -s millwatch >/dev/null 2>&1; then
  fail "dpkg still knows millwatch after purge"
fi
echo "package test passed: $(basename "$deb")"
