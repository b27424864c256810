#!/usr/bin/env bash
# A crate that depends on this checkout's `dae` as a library, the way a user
# would: `default-features = false`, one `dae!` model, a radau5 solve in
# main. It is created in a temporary directory and built from clean in its
# own target directory; the script counts the crates of its dependency graph
# and the crates compiled, times the build, runs the binary, and fails if
# more than MAX_CRATES crates are compiled or if the graph holds a crate that
# needs a system library.
#
#   scripts/downstream.sh            # the full check: clean debug build
#   scripts/downstream.sh --count    # the dependency graph only (seconds)
#
# Environment: MAX_CRATES (default 40), KEEP=1 keeps the temporary crate.
set -euo pipefail

repo="$(cd "$(dirname "$0")/.." && pwd)"
max="${MAX_CRATES:-40}"
mode="${1:-build}"
case "$mode" in
    build | --build) mode=build ;;
    --count) mode=count ;;
    *) echo "usage: $0 [--count]" >&2; exit 2 ;;
esac

dir="$(mktemp -d "${TMPDIR:-/tmp}/dae-downstream.XXXXXX")"
if [ "${KEEP:-0}" != 1 ]; then
    trap 'rm -rf "$dir"' EXIT
fi
mkdir -p "$dir/src"
cat >"$dir/Cargo.toml" <<TOML
[package]
name = "downstream"
version = "0.1.0"
edition = "2021"
publish = false

[dependencies]
dae = { path = "$repo", default-features = false }

[workspace]
TOML
# Its main is the README's example (examples/quickstart.rs), which uses the
# library alone.
cp "$repo/examples/quickstart.rs" "$dir/src/main.rs"

cd "$dir"
# Start from this checkout's lock file, so the crates counted are the
# versions the repository tests with (cargo drops the entries not needed).
cp "$repo/Cargo.lock" Cargo.lock

# The dependency graph of a normal build (build scripts and proc-macros
# included, each crate once), the downstream crate itself included.
cargo tree -e normal,build --prefix none --no-dedupe \
    | sed -e 's/ (\*)$//' -e 's/ (proc-macro)//' -e 's/ (\/.*)$//' \
    | sort -u >crates.txt
graph=$(wc -l <crates.txt)
echo "downstream: $graph crates in the dependency graph (limit $max)"
system=$(grep -E '^(pkg-config|cmake|cc|[a-z0-9_-]+-sys|font-kit|[a-z-]*fontconfig[a-z-]*|[a-z-]*freetype[a-z-]*) v' crates.txt || true)
if [ -n "$system" ]; then
    echo "downstream: crates that build or link system libraries:" >&2
    echo "$system" >&2
    exit 1
fi
if [ "$graph" -gt "$max" ]; then
    echo "downstream: more than $max crates:" >&2
    cat crates.txt >&2
    exit 1
fi
[ "$mode" = count ] && exit 0

# A clean debug build in the crate's own target directory.
export CARGO_TARGET_DIR="$dir/target"
unset RUSTFLAGS CARGO_BUILD_RUSTFLAGS
# Wall time, and the CPU time of cargo and every compiler it ran (the
# figure that does not move with the machine's other load).
TIMEFORMAT='%R %U %S'
{ time cargo build --color never 2>build.log; } 2>time.txt \
    || { cat build.log >&2; exit 1; }
read -r wall user sys <time.txt
compiled=$(grep -c '^ *Compiling ' build.log)
cpu=$(echo "$user + $sys" | bc)
size=$(du -sh "$CARGO_TARGET_DIR" | cut -f1)
echo "downstream: $compiled crates compiled; clean debug build: ${wall%.*} s wall," \
    "${cpu%.*} s CPU (user+sys) on $(nproc) cores; target/ $size"
"$CARGO_TARGET_DIR/debug/downstream"
if [ "$compiled" -gt "$max" ]; then
    echo "downstream: more than $max crates compiled:" >&2
    grep '^ *Compiling ' build.log >&2
    exit 1
fi
