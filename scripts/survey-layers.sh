#!/usr/bin/env bash
# Lays out every GeoPackage layer in a directory with the command line, as a user would, and
# prints one Markdown row per layer: the core's metrics (method.md §8, which the shared judge
# computes the same) or the message it was refused with, then how many were laid out and the
# metrics' means over the layers of 30 regions or more (the smaller ones are mostly swaps of a
# handful of cells). For trying snakegrid on layers it was not tuned on: the npm collections of
# scripts/make-npm-layers.sh (`all` makes some 200 of them), or any other set.
#
# Usage: scripts/survey-layers.sh DIR [SNAKEGRID OPTIONS...]
#        e.g. scripts/survey-layers.sh /tmp/npml/hc -refine_w_far 1
# Each layer needs an id field `id` (make-npm-layers.sh writes one). Needs a release build and
# Python 3 (standard library only).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dir="${1:?usage: survey-layers.sh DIR [SNAKEGRID OPTIONS...]}"
shift
cli="$root/target/release/snakegrid"
[ -x "$cli" ] || cargo build --manifest-path "$root/Cargo.toml" --release --bin snakegrid
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
touch "$work/rows.tsv"

echo "snakegrid $(git -C "$root" rev-parse --short HEAD), options: ${*:-the defaults}, $(date -u +%F), load $(cut -d' ' -f1 /proc/loadavg)"
echo
echo "| layer | regions | wall s | adjacency | orientation ° | location | p90 | max | shape | pieces | holes |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for src in "$dir"/*.gpkg; do
    name="$(basename "$src" .gpkg)"
    start=$(date +%s.%N)
    if "$cli" -q -overwrite -id id "$@" --json "$work/$name.json" "$work/$name.gpkg" "$src" \
        2>"$work/$name.err"; then
        status=ok
    else
        status=refused
    fi
    end=$(date +%s.%N)
    python3 - "$name" "$status" "$start" "$end" "$work/$name.json" "$work/$name.err" \
        "$work/rows.tsv" <<'EOF'
import json, sys
name, status, start, end, report, errors, rows = sys.argv[1:]
wall = float(end) - float(start)
if status == "ok":
    r = json.load(open(report))
    m = r["metrics"]
    values = [m[k] for k in ("adjacent", "orientation", "location", "location_p90",
                             "location_max", "shape")]
    print(f"| {name} | {len(r['regions'])} | {wall:.2f} | {values[0]:.3f} | {values[1]:.1f} | "
          f"{values[2]:.3f} | {values[3]:.2f} | {values[4]:.2f} | {values[5]:.3f} | "
          f"{m['pieces']} | {m['holes']} |")
    with open(rows, "a") as out:
        out.write("\t".join(map(str, [len(r["regions"])] + values)) + "\n")
else:
    lines = open(errors).read().strip().splitlines()
    message = (lines[-1] if lines else "no message (the run ended without one)").replace("|", "/")
    print(f"| {name} | | {wall:.2f} | refused: {message} |||||||")
EOF
done
python3 - "$work/rows.tsv" <<'EOF'
import sys
rows = [list(map(float, line.split("\t"))) for line in open(sys.argv[1])]
large = [r for r in rows if r[0] >= 30]
print()
if not large:
    print(f"{len(rows)} layers laid out; none of 30 regions or more")
    sys.exit()
print(f"{len(rows)} layers laid out; over the {len(large)} of 30 regions or more, means: "
      + ", ".join(f"{name} {sum(r[k] for r in large) / len(large):.3f}"
                  for k, name in enumerate(["regions", "adjacency", "orientation", "location",
                                            "p90", "max", "shape"])))
EOF
