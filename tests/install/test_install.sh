#!/usr/bin/env bash
# Issue 22 item 9: `cmake --install` into a temporary prefix, then the installed programs run
# from there: `mocapd --check-config` on every installed example rig and on a rig using the
# installed body files, a UTF-8 name through the installed `mocapd --print-config`, and the
# installed systemd unit starts the installed mocapd.
#   test_install.sh CMAKE BUILD_DIR
set -euo pipefail
cmake_bin="$1"
build="$2"
prefix="$(mktemp -d -t mocap-install.XXXXXX)"
trap 'rm -rf "$prefix"' EXIT
fail() { echo "test_install: FAIL: $*" >&2; exit 1; }

"$cmake_bin" --install "$build" --prefix "$prefix" >"$prefix.log" 2>&1 || { cat "$prefix.log" >&2; rm -f "$prefix.log"; fail "cmake --install"; }
rm -f "$prefix.log"

for p in mocapd mocapctl mocap; do
  [[ -x "$prefix/bin/$p" ]] || fail "missing $prefix/bin/$p"
done
if [[ -x "$build/bin/mocap-viewer" ]]; then
  [[ -x "$prefix/bin/mocap-viewer" ]] || fail "mocap-viewer was built but not installed"
fi
for f in share/mocap/witmotion.toml share/mocap/demo.toml share/mocap/body/default.toml \
  share/mocap/body/joint_limits.toml lib/udev/rules.d/70-mocap.rules lib/systemd/user/mocapd.service \
  share/mocap/blender/mocap_live.zip; do
  [[ -f "$prefix/$f" ]] || fail "missing $prefix/$f"
done

# Run from elsewhere: nothing may depend on the checkout or the build directory.
cd /
n=0
for rig in "$prefix"/share/mocap/*.toml; do
  "$prefix/bin/mocapd" --check-config "$rig" || fail "mocapd --check-config $rig"
  n=$((n + 1))
done
[[ $n -ge 6 ]] || fail "only $n example rigs installed"

cat >"$prefix/rig.toml" <<TOML
# Rig de José — capteur du bassin
[[sensor]]
name = "José"
driver = "witmotion"
port = "/dev/ttyUSB0"
segment = "pelvis" # bassin
[body]
model = "$prefix/share/mocap/body/default.toml"
joint_limits = "$prefix/share/mocap/body/joint_limits.toml"
TOML
"$prefix/bin/mocapd" --check-config "$prefix/rig.toml" || fail "check-config with installed body files"
"$prefix/bin/mocapd" --print-config --config "$prefix/rig.toml" | grep -q "name = .José." \
  || fail "UTF-8 sensor name lost by --print-config"
printf 'name = "Jos\xC3"\n' >"$prefix/bad.toml"
if out="$("$prefix/bin/mocapd" --check-config "$prefix/bad.toml" 2>&1)"; then fail "invalid UTF-8 accepted"; fi
grep -q "bad.toml:1:12: invalid UTF-8" <<<"$out" || fail "invalid UTF-8 error without its position: $out"

unit="$prefix/lib/systemd/user/mocapd.service"
grep -qx "ExecStart=$prefix/bin/mocapd --config %h/.config/mocap/rig.toml" "$unit" \
  || fail "ExecStart does not run the installed mocapd: $(grep ExecStart= "$unit")"
grep -qx "ExecStartPre=$prefix/bin/mocapd --check-config %h/.config/mocap/rig.toml" "$unit" \
  || fail "ExecStartPre: $(grep ExecStartPre= "$unit")"
grep -qx "ExecStop=$prefix/bin/mocapctl quit" "$unit" || fail "ExecStop: $(grep ExecStop= "$unit")"
exec_bin="$(sed -n 's/^ExecStart=\([^ ]*\).*/\1/p' "$unit")"
[[ -x "$exec_bin" ]] || fail "ExecStart binary $exec_bin is not executable"
echo "test_install: OK ($n example rigs checked by the installed mocapd in $prefix)"
