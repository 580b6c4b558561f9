#!/usr/bin/env bash
# Fuzzes the WKB reader (`wkb`) and the option parser (`options`) with cargo-fuzz for a bounded
# time each, starting from the corpus kept in fuzz/corpus/<target>/ (read only: new inputs go to a
# temporary folder, so a run does not churn the repository; add a useful one by hand). Exits
# non-zero on the first crash; libFuzzer leaves the crashing input in fuzz/artifacts/<target>/.
#
# Usage: scripts/fuzz.sh [SECONDS per target, default 60] [TARGET...]   (default: all targets)
# Needs cargo-fuzz (`cargo install cargo-fuzz`, about 2 minutes). cargo-fuzz needs nightly
# flags; RUSTC_BOOTSTRAP=1 lets the stable toolchain accept them.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
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
for target in "${targets[@]}"; do
    echo "== fuzzing $target for ${seconds}s"
    mkdir -p "$work/$target"
    cargo fuzz run --release "$target" "$work/$target" "fuzz/corpus/$target" -- \
        -max_total_time="$seconds" -print_final_stats=1
done
echo "fuzz: no crash in ${targets[*]} (${seconds}s each)"
