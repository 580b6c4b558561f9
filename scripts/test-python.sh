#!/usr/bin/env bash
# Tests the Python package as a user gets it: builds the wheel (scripts/build-wheel.sh) and the
# command line to compare with, installs the wheel into a fresh venv with shapely, pyogrio,
# geopandas and pytest, all as binary wheels (nothing is compiled, so neither Rust nor GDAL's
# development files are used), then runs python/tests there with Rust and cargo off PATH.
# Needs Debian's python3-venv. Ends with pytest's summary line; extra arguments go to pytest.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cargo build --manifest-path "$root/Cargo.toml" --release --bin snakegrid
wheel="$("$root/scripts/build-wheel.sh")"

venv="$(mktemp -d)"
trap 'rm -rf "$venv"' EXIT
clean=(env -i HOME="$HOME" PATH="$venv/bin:/usr/bin:/bin" LANG=C.UTF-8)
"${clean[@]}" /usr/bin/python3 -m venv "$venv"
"${clean[@]}" "$venv/bin/pip" install -q --only-binary :all: "$wheel" shapely pyogrio geopandas pytest
cd "$root/python/tests"
"${clean[@]}" SNAKEGRID_CLI="$root/target/release/snakegrid" \
    "$venv/bin/python" -m pytest -p no:cacheprovider -ra "$@" .
