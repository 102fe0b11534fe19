#!/usr/bin/env bash
# Checks that the packages that depend on crates/mp-workspace-hack resolve every dependency with
# the features of `cargo test --workspace`, so that their builds and the tests' share compiled
# crates:
# - every package's own tests (`cargo test -p NAME`, dev-dependencies included): the library
#   crates have the hack crate as a dev-dependency;
# - the packages built on their own (the set-up tool `xtask`, the Python extension `mp-py`, the
#   `mp` binary), without dev-dependencies: they have it as a normal dependency.
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
# The packages that depend on the hack crate: through any edge, and as a normal dependency.
dependents() {
  cargo tree --quiet --invert mp-workspace-hack --edges "$1" --depth 1 --prefix none \
    --format '{p}' | tail -n +2 | awk '{ print $1 }' | sort -u
}
status=0
# check PACKAGE EDGES WHAT: the package's resolution with those edges against the workspace's.
check() {
  features --package "$1" --edges "$2" > "$ws.p"
  # Packages in both graphs whose feature sets differ.
  diff=$(join -t'|' "$ws.p" "$ws" | awk -F'|' '$2 != $3 { print "  " $1 ": " $2 " (the workspace: " $3 ")" }')
  if [ -n "$diff" ]; then
    echo "features: $1 ($3) resolves these dependencies with other features than the workspace's tests;" >&2
    echo "add the workspace's features to crates/mp-workspace-hack/Cargo.toml:" >&2
    echo "$diff" >&2
    status=1
  fi
}
tested=$(dependents normal,dev)
alone=$(dependents normal)
for p in $tested; do check "$p" normal,build,dev "its tests"; done
for p in $alone; do check "$p" normal,build "built alone"; done
[ "$status" -eq 0 ] && echo "features:" $tested "resolve their dependencies as the workspace's tests do" \
  "(their own tests; built alone:" $alone")"
exit "$status"
