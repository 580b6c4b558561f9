#!/usr/bin/env bash
# Times the release `snakegrid` command on every layer of the shared data folder and prints a
# table (layer, features, mean and spread of the wall time).
#
#   scripts/bench-cli.sh [DATA_DIR]        DATA_DIR: $SNAKEGRID_DATA, else ../shared/data beside the repository
#
# RUNS (default 3) runs per layer, 1 for layers over 1000 features; extra snakegrid options go
# in SNAKEGRID_OPTS (e.g. SNAKEGRID_OPTS="-refine false"). Uses hyperfine when installed
# (apt-get install -y hyperfine), else a loop over `date +%s.%N`. Outputs go to a temporary
# folder, removed at the end.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
data=${1:-${SNAKEGRID_DATA:-$repo/../shared/data}}
runs=${RUNS:-3}
opts=${SNAKEGRID_OPTS:-}

cargo build --release --quiet --manifest-path "$repo/Cargo.toml" --bin snakegrid
bin=$(cargo metadata --format-version 1 --no-deps --manifest-path "$repo/Cargo.toml" |
    sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')/release/snakegrid
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

shopt -s nullglob
layers=("$data"/*.gpkg)
if [ ${#layers[@]} -eq 0 ]; then
    echo "no .gpkg layers in $data" >&2
    exit 1
fi

printf '%-20s %9s %5s %10s %10s\n' layer features runs "mean (s)" "± (s)"
for src in "${layers[@]}"; do
    layer=$(basename "$src" .gpkg)
    features=$(ogrinfo -so "$src" "$layer" 2>/dev/null | sed -n 's/^Feature Count: //p')
    n=$runs
    if [ "${features:-0}" -gt 1000 ]; then n=1; fi
    dst="$work/$layer.gpkg"
    # shellcheck disable=SC2086 # SNAKEGRID_OPTS is a list of options
    command=("$bin" -q -overwrite -id id $opts "$dst" "$src")
    if command -v hyperfine >/dev/null; then
        hyperfine --style none --runs "$n" --export-csv "$work/$layer.csv" \
            "$(printf '%q ' "${command[@]}")" >/dev/null
        # CSV columns: command, mean, stddev, ...; the command is quoted and may hold commas.
        read -r mean stddev < <(tail -n 1 "$work/$layer.csv" |
            awk -F, '{ printf "%.3f %.3f\n", $(NF-6), ($(NF-5) == "" ? 0 : $(NF-5)) }')
    else
        times=()
        for _ in $(seq "$n"); do
            start=$(date +%s.%N)
            "${command[@]}"
            end=$(date +%s.%N)
            times+=("$(awk -v a="$start" -v b="$end" 'BEGIN { print b - a }')")
        done
        read -r mean stddev < <(printf '%s\n' "${times[@]}" |
            awk '{ s += $1; q += $1 * $1 } END { m = s / NR; v = q / NR - m * m; printf "%.3f %.3f\n", m, (v > 0 ? sqrt(v) : 0) }')
    fi
    printf '%-20s %9s %5s %10s %10s\n' "$layer" "${features:-?}" "$n" "$mean" "$stddev"
done
