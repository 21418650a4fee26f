#!/usr/bin/env bash
# Builds the onboard binary for an old glibc and checks that it needs no newer one.
#
# Onboard PCs of P3-DX robots often run old distributions (CentOS 7 and Ubuntu 14.04 era:
# glibc 2.17 to 2.19). A binary built on a current system links against its newer glibc and
# refuses to start there ("version `GLIBC_2.34' not found"). cargo-zigbuild links against the
# glibc version named in the target (x86_64-unknown-linux-gnu.2.17) with zig's linker.
#
# Usage: scripts/check-glibc.sh            (builds, then checks)
#        GLIBC=2.28 scripts/check-glibc.sh (another floor)
#        scripts/check-glibc.sh --no-build (checks the binary already built)
# Needs: pip install ziglang cargo-zigbuild (or: cargo install cargo-zigbuild and a zig on
# PATH), objdump or readelf (binutils).
# Exit status: 0 when the newest GLIBC_ symbol version is at most $GLIBC, 1 when it is newer,
# 2 when a tool is missing or the build fails.
set -euo pipefail

GLIBC="${GLIBC:-2.17}"
TARGET=x86_64-unknown-linux-gnu
cd "$(dirname "$0")/.."
BIN="target/$TARGET/release/papillon"

if [[ "${1:-}" != "--no-build" ]]; then
    if ! cargo zigbuild --help >/dev/null 2>&1; then
        echo "check-glibc: cargo-zigbuild is missing: pip install ziglang cargo-zigbuild" >&2
        exit 2
    fi
    cargo zigbuild --release --locked -p papillon --bin papillon --target "$TARGET.$GLIBC" ||
        { echo "check-glibc: the build failed" >&2; exit 2; }
fi
[[ -f "$BIN" ]] || { echo "check-glibc: $BIN is missing (build it first)" >&2; exit 2; }

if command -v objdump >/dev/null; then
    versions=$(objdump -T "$BIN" | grep -o 'GLIBC_[0-9][0-9.]*' | sort -u -V)
elif command -v readelf >/dev/null; then
    versions=$(readelf --dyn-syms -W "$BIN" | grep -o 'GLIBC_[0-9][0-9.]*' | sort -u -V)
else
    echo "check-glibc: neither objdump nor readelf is installed (binutils)" >&2
    exit 2
fi
newest=$(echo "$versions" | tail -n 1)
echo "check-glibc: $BIN needs: $(echo $versions | tr '\n' ' ')"
highest=$(printf '%s\n%s\n' "${newest#GLIBC_}" "$GLIBC" | sort -V | tail -n 1)
if [[ "$highest" != "$GLIBC" ]]; then
    echo "check-glibc: FAIL: the newest symbol version is $newest, newer than GLIBC_$GLIBC" >&2
    exit 1
fi
echo "check-glibc: OK: the newest symbol version is $newest (at most GLIBC_$GLIBC)"
