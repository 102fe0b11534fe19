#!/usr/bin/env bash
# Checks that the packages built on their own, those that depend on crates/mp-workspace-hack (the
# set-up tool `xtask`, the Python extension `mp-py`, the `mp` binary), resolve every dependency
# with the features of `cargo test --workspace`, so that their builds and the tests' share
# compiled crates.
# Exits 1 and names each dependency whose features differ.
set -euo pipefail
cd "$(dirname "$0")/.."
# One collation for sort, join and the grouping below.
export LC_ALL=C
# "name version" → its feature sets (host and target builds may differ), one line per package.
features() {
  cargo tree --quiet "$@" --prefix none --format '{p}|{f}' |
    sed 's/ (\*)$//' |
    awk -F'|' '{ split($1, w, " "); print w[1] " " w[2] "|" $2 }' |
    sort -u |
    awk -F'|' '{ if ($1 == k) { v = v ";" $2 } else { if (k != "") print k "|" v; k = $1; v = $2 } }
               END { if (k != "") print k "|" v }'
}
ws=$(mktemp)
trap 'rm -f "$ws" "$ws.p"' EXIT
features --workspace --edges normal,build,dev > "$ws"
# The packages that depend on the hack crate.
packages=$(cargo tree --quiet --invert mp-workspace-hack --edges normal --depth 1 --prefix none \
  --format '{p}' | tail -n +2 | awk '{ print $1 }' | sort -u)
status=0
for p in $packages; do
  features --package "$p" --edges normal,build > "$ws.p"
  # Packages in both graphs whose feature sets differ.
  diff=$(join -t'|' "$ws.p" "$ws" | awk -F'|' '$2 != $3 { print "  " $1 ": " $2 " (the workspace: " $3 ")" }')
  if [ -n "$diff" ]; then
    echo "features: $p resolves these dependencies with other features than the workspace's tests;" >&2
    echo "add the workspace's features to crates/mp-workspace-hack/Cargo.toml:" >&2
    echo "$diff" >&2
    status=1
  fi
done
[ "$status" -eq 0 ] && echo "features:" $packages "resolve their dependencies as the workspace's tests do"
exit "$status"
