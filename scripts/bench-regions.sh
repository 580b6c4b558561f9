#!/usr/bin/env bash
# How the command line's time and peak memory grow with the number of regions: random Voronoi
# layers (scripts/make-test-layers.py) of 1,000 to 100,000 regions (with BENCH_LAYER=strip, a
# thin country of as many: Voronoi cells of a strip 0.7 cells wide), each laid out with the
# defaults (or the options given), wall time as the median of 5 runs where one takes under a
# minute (else one run), peak resident memory from GNU time, and the growth exponent fitted to
# time ∝ n^k between successive sizes. Prints a Markdown table for BENCHMARKS.md.
#
# Usage: scripts/bench-regions.sh [SIZES] [SNAKEGRID OPTIONS...]
#        SIZES: comma-separated, default 1000,3000,10000,33000,100000
# Needs GNU time (/usr/bin/time, Debian's `time`), Python 3 with shapely, numpy and pyogrio.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sizes="${1:-1000,3000,10000,33000,100000}"
shift || true
cli="$root/target/release/snakegrid"
[ -x "$cli" ] || cargo build --manifest-path "$root/Cargo.toml" --release --bin snakegrid
# shellcheck source=scripts/timed-runs.sh
source "$root/scripts/timed-runs.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

bench_header "$root" "$@"
echo "| regions | runs | median wall (s) | peak memory (MB) | growth k (time ∝ n^k) |"
echo "|---:|---:|---:|---:|---:|"
previous=""
kind="${BENCH_LAYER:-voronoi}"
for n in ${sizes//,/ }; do
    layer="$work/${kind}_$n.gpkg"
    python3 "$root/scripts/make-test-layers.py" "$kind" "$n" 1 "$layer"
    timed_runs "$work" "$cli" -q -overwrite "$@" "$work/out.gpkg" "$layer"
    growth="–"
    if [ -n "$previous" ]; then
        growth="$(growth_exponent "$n" "$median" "${previous% *}" "${previous#* }")"
    fi
    printf '| %s | %s | %s | %s | %s |\n' "$n" "$runs" "$median" "$((memory / 1024))" "$growth"
    previous="$n $median"
done
