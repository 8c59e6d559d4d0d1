#!/usr/bin/env bash
# The scan's speed with `metaplate monitor` attached (one client on /events) against without: RUNS mock-lab scans
# of each (7 x 5 points of the metamaterial plate, the quick protocol, Green's functions cached), alternating, and
# the median wall time of each. Usage: bash scripts/bench-monitor.sh [RUNS]  (default 5). Needs curl.
set -euo pipefail
runs="${1:-5}"
root="$(cd "$(dirname "$0")/.." && pwd)"
cargo build -q -p metaplate-cli --manifest-path "$root/Cargo.toml"
bin="$root/target/debug/metaplate"
work="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
cache="$work/cache"
scan() { "$bin" scan --scene metamaterial --uncalibrated --protocol quick --grid 7x5 --seed 3 --cache-dir "$cache" --out "$1" >/dev/null 2>&1 || [ $? -eq 3 ]; }
scan "$work/warm"   # computes and caches the Green's functions once
# Wall time of one scan, ms.
timed() { local t0 t1; t0=$(date +%s%N); scan "$1"; t1=$(date +%s%N); echo $(( (t1 - t0) / 1000000 )); }
without=(); with=()
for i in $(seq "$runs"); do
    without+=("$(timed "$work/plain-$i")")
    "$bin" monitor "$work/watched-$i" --bind 127.0.0.1:0 > "$work/monitor-$i.txt" &
    monitor=$!
    until grep -q 'http://' "$work/monitor-$i.txt" 2>/dev/null; do sleep 0.05; done
    url="$(grep -o 'http://[0-9.:]*/' "$work/monitor-$i.txt")"
    curl -sN "${url}events" > /dev/null &
    client=$!
    with+=("$(timed "$work/watched-$i")")
    kill "$client" "$monitor" 2>/dev/null || true
    wait "$client" "$monitor" 2>/dev/null || true
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
echo "without a monitor: median $(median "${without[@]}") ms (runs: ${without[*]})"
echo "with a monitor and an /events client: median $(median "${with[@]}") ms (runs: ${with[*]})"
