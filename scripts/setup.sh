#!/usr/bin/env bash
# One-command setup on Debian 12: the system packages snakegrid builds and tests against, then a
# release build of the library and the command line. Run as root (or with sudo).
set -euo pipefail
cd "$(dirname "$0")/.."
export DEBIAN_FRONTEND=noninteractive

# Rust comes from rustup: Debian 12's own rustc (1.63) is older than snakegrid needs. Say so
# before installing anything, rather than failing halfway through the build.
needed="$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml)"
export PATH="$HOME/.cargo/bin:$PATH"
if ! command -v cargo >/dev/null 2>&1; then
    echo "setup: cargo is missing. Install Rust $needed or newer with rustup:" >&2
    echo "    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y" >&2
    echo "then open a new shell (or run: . \"\$HOME/.cargo/env\") and run scripts/setup.sh again." >&2
    exit 1
fi
have="$(rustc --version | awk '{print $2}')"
if [ "$(printf '%s\n%s\n' "$needed" "$have" | sort -V | head -n 1)" != "$needed" ]; then
    echo "setup: rustc $have is older than the $needed snakegrid needs ($(command -v rustc))." >&2
    echo "    rustup update stable    (or, with Debian's rustc first on PATH: remove it, then install rustup)" >&2
    exit 1
fi

apt-get update -qq
apt-get install -y -qq --no-install-recommends \
    libgdal-dev gdal-bin pkg-config cmake g++ valgrind python3-pip >/dev/null
# More packages for later steps (CI's QGIS), installed while the build runs, which needs only
# the ones above.
extra=""
if [ -n "${SNAKEGRID_EXTRA_PACKAGES:-}" ]; then
    # shellcheck disable=SC2086 # a list of package names
    apt-get install -y -qq --no-install-recommends $SNAKEGRID_EXTRA_PACKAGES >/dev/null &
    extra=$!
fi
# The shared judge's (../shared/eval/gridmap_eval.py) packages, for tests/judge.rs and
# scripts/bench-quality.sh. The python3 first on PATH: on Debian's own, pip needs
# --break-system-packages (its Python is externally managed).
python3 -m pip install --quiet --disable-pip-version-check shapely numpy pyogrio pyproj 2>/dev/null ||
    python3 -m pip install --quiet --disable-pip-version-check --break-system-packages \
        shapely numpy pyogrio pyproj
cargo build --release
if [ -n "$extra" ]; then
    wait "$extra" || { echo "setup: installing $SNAKEGRID_EXTRA_PACKAGES failed" >&2; exit 1; }
fi
echo "snakegrid built: target/release/snakegrid, target/release/libsnakegrid.{so,a}"
