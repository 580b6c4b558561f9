#!/usr/bin/env bash
# Fuzzes the WKB reader (`wkb`) and the option parser (`options`) with cargo-fuzz, starting from
# the corpus kept in fuzz/corpus/<target>/ (read only: new inputs go to a
# temporary folder, so a run does not churn the repository; add a useful one by hand). Exits
# non-zero on the first crash; libFuzzer leaves the crashing input in fuzz/artifacts/<target>/.
#
# Usage: scripts/fuzz.sh [LIMIT, default 60] [TARGET...]   (default: all targets)
#   LIMIT is seconds per target, or a count of inputs as `20000runs`: CI uses a count with the
#   fixed seed below, so that what it tries does not depend on the machine's speed or luck; for a
#   longer search with a fresh seed each time, give seconds and FUZZ_SEED=0.
# Needs cargo-fuzz (`cargo install cargo-fuzz`, about 2 minutes). cargo-fuzz needs nightly
# flags; RUSTC_BOOTSTRAP=1 lets the stable toolchain accept them.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
limit="${1:-60}"
shift || true
targets=("$@")
[ "${#targets[@]}" -gt 0 ] || targets=(wkb options)
command -v cargo-fuzz >/dev/null || { echo "cargo-fuzz is missing: cargo install cargo-fuzz" >&2; exit 2; }

cd "$root"
export RUSTC_BOOTSTRAP=1
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# Built once, before the clock of any target starts, as the library ships (release, no debug
# assertions: geo's relate has debug assertions that fire on degenerate but harmless input,
# e.g. subnormal coordinates) plus AddressSanitizer.
cargo fuzz build --release
case "$limit" in
    *runs) bound=(-runs="${limit%runs}") ;;
    *) bound=(-max_total_time="$limit") ;;
esac
for target in "${targets[@]}"; do
    echo "== fuzzing $target: $limit"
    mkdir -p "$work/$target"
    cargo fuzz run --release "$target" "$work/$target" "fuzz/corpus/$target" -- \
        "${bound[@]}" -seed="${FUZZ_SEED:-1}" -print_final_stats=1
done
echo "fuzz: no crash in ${targets[*]} ($limit each)"
