#!/usr/bin/env bash
# The BDF family's accuracy and work against SUNDIALS IDA (a DASSL
# descendant), side by side on one machine (BENCHMARKS.md §15b; issue 25
# done-when 1, issue 26 done-when 2). Three problems:
#
# 1. The pendulum released horizontally (scenes/pendulum_wall.dae: the
#    SPEC's pendulum, period 2 s, with the event `cross = x`), index-1 form
#    rcd0, t in [0, 10] (five periods): scripts/ida_pendulum.c (IDA, dense,
#    analytic Jacobian, root finder on x) against `dae run --solver bdf
#    --formulation rcd0` (its `cross` events). One line each: steps,
#    rejected steps (IDA: error-test plus Newton failures), residual and
#    Jacobian evaluations, the orders of the accepted steps (IDA only; dae
#    does not report them) and the worst |t_k - (2k+1)T/4| over the ten
#    crossings, T from the AGM. Then the same at t = 20 (S01): the largest
#    error of x, y, v, w against the exact state (S01 ends 9.4e-10 after a
#    whole number of periods: x = 1, w = -g (20 - 10 T), the rest O(1e-17)).
# 2. The IVP Test Set's transistor amplifier (scenes/transamp.toml, M y' = f,
#    t in [0, 0.2]): scripts/ida_transamp.c (IDA, dense difference-quotient
#    Jacobian) against `dae run scenes/transamp.toml --solver bdf
#    --formulation rcd0`: steps, rejected steps, scd (the Test Set's
#    significant correct digits at t = 0.2) and dae's steps over IDA's.
# 3. The IVP Test Set's car axis (scenes/caraxis.toml, index 3, here in its
#    index-1 form rcd0, t in [0, 3]): scripts/ida_caraxis.c (IDA, dense
#    difference-quotient Jacobian) against `dae run scenes/caraxis.toml
#    --solver bdf --formulation rcd0`: steps, rejected steps, scd over the
#    positions and velocities at t = 3.
#
#   scripts/ida_pendulum.sh                       # both, default tolerances
#   PENDULUM_TOLS="1e-10 1e-12" TRANSAMP_TOLS="" CARAXIS_TOLS="" scripts/ida_pendulum.sh
#
# rtol = atol = TOL for every unknown in both (`dae run --tol`). Counts, not
# times: the runs are deterministic.
#
# Needs: gcc, python3, Debian's libsundials-dev (SUNDIALS 6.4:
# libsundials_ida, _nvecserial, _sunlinsoldense, _sunmatrixdense) and a
# release build of dae (`cargo build --release --bin dae`; or DAE=/path).
# Not part of CI: a measurement.
#
# Environment: PENDULUM_TOLS (default "1e-8 1e-10"), TRANSAMP_TOLS (default
# "1e-4 1e-5 1e-6 1e-7 1e-8"), CARAXIS_TOLS (default "1e-4 1e-6 1e-8
# 1e-10"), DAE (default target/release/dae), OUT
# (scratch directory, default a temporary one, removed at the end).
set -euo pipefail

repo="$(cd "$(dirname "$0")/.." && pwd)"
dae="${DAE:-$repo/target/release/dae}"
pendulum_tols="${PENDULUM_TOLS-1e-8 1e-10}"
transamp_tols="${TRANSAMP_TOLS-1e-4 1e-5 1e-6 1e-7 1e-8}"
caraxis_tols="${CARAXIS_TOLS-1e-4 1e-6 1e-8 1e-10}"
if [ ! -x "$dae" ]; then
    echo "$0: no dae binary at $dae: run 'cargo build --release --bin dae' or set DAE" >&2
    exit 2
fi
if [ -n "${OUT:-}" ]; then
    dir="$OUT"
    mkdir -p "$dir"
else
    dir="$(mktemp -d "${TMPDIR:-/tmp}/ida-pendulum.XXXXXX")"
    trap 'rm -rf "$dir"' EXIT
fi

libs="-lsundials_ida -lsundials_nvecserial -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lm"
# shellcheck disable=SC2086
gcc -O2 -Wall -Wextra -o "$dir/ida_pendulum" "$repo/scripts/ida_pendulum.c" $libs
# shellcheck disable=SC2086
gcc -O2 -Wall -Wextra -o "$dir/ida_transamp" "$repo/scripts/ida_transamp.c" $libs
# shellcheck disable=SC2086
gcc -O2 -Wall -Wextra -o "$dir/ida_caraxis" "$repo/scripts/ida_caraxis.c" $libs

echo "# $(uname -srm), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores"
echo "# SUNDIALS $(sed -n 's/^#define SUNDIALS_VERSION "\(.*\)"/\1/p' /usr/include/sundials/sundials_config.h); dae $(cd "$repo" && git rev-parse --short HEAD 2>/dev/null || echo '?'), $dae"

# The pendulum scene: scenes/pendulum_wall.dae without the wall's reset
# (every event only recorded), released at rest from x = 1.
for t_end in 10 20; do
    cat >"$dir/pendulum$t_end.toml" <<EOF
name = "pendulum_crossings"
model = "$repo/scenes/pendulum_wall.dae"
[initial]
x = 1.0
y = 0.0
v = 0.0
w = 0.0
[time]
end = $t_end.0
EOF
done

for tol in $pendulum_tols; do
    for t_end in 10 20; do
        "$dir/ida_pendulum" "$tol" "$t_end" >"$dir/ida_pendulum.$tol.$t_end.json"
        "$dae" run "$dir/pendulum$t_end.toml" --solver bdf --formulation rcd0 --tol "$tol" \
            --format json >"$dir/dae_pendulum.$tol.$t_end.json"
    done
done
for tol in $transamp_tols; do
    "$dir/ida_transamp" "$tol" >"$dir/ida_transamp.$tol.json"
    "$dae" run "$repo/scenes/transamp.toml" --solver bdf --formulation rcd0 --tol "$tol" \
        --format json >"$dir/dae_transamp.$tol.json"
done
for tol in $caraxis_tols; do
    "$dir/ida_caraxis" "$tol" >"$dir/ida_caraxis.$tol.json"
    "$dae" run "$repo/scenes/caraxis.toml" --solver bdf --formulation rcd0 --tol "$tol" \
        --format json >"$dir/dae_caraxis.$tol.json"
done

python3 - "$dir" "$pendulum_tols" "$transamp_tols" "$caraxis_tols" <<'PY'
import json, math, sys

d, ptols, ttols, ctols = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4].split()
G = 13.7503716373294544


def period():
    a, b = 1.0, math.sqrt(0.5)
    for _ in range(32):
        if abs(a - b) <= 4 * 2.220446049250313e-16 * a:
            break
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return 4 * math.sqrt(1 / G) * math.pi / (a + b)


T = period()


def dae_run(path):
    j = json.load(open(path))
    if j["status"] != "ok":
        sys.exit(f"dae run {path}: status {j['status']}: {j['error']}")
    return j


if ptols:
    print(f"pendulum rcd0, released horizontally, T = {T:.15f}")
    print(f"  {'tol':>6} {'run':<12} {'steps':>6} {'rej':>4} {'res':>6} {'jac':>5}"
          f" {'orders 1..5':<32} {'worst crossing':>14} {'err t=20':>9}")
for tol in ptols:
    i10 = json.load(open(f"{d}/ida_pendulum.{tol}.10.json"))
    i20 = json.load(open(f"{d}/ida_pendulum.{tol}.20.json"))
    print(f"  {tol:>6} {'ida':<12} {i10['steps']:>6} "
          f"{i10['error_test_failures'] + i10['newton_failures']:>4} {i10['residual_evals']:>6} "
          f"{i10['jacobian_evals']:>5} {str(i10['orders']):<32} "
          f"{i10['worst_crossing_error']:>14.2e} {i20['final_error']:>9.2e}")
    j10 = dae_run(f"{d}/dae_pendulum.{tol}.10.json")
    j20 = dae_run(f"{d}/dae_pendulum.{tol}.20.json")
    cross = [e for e in j10["events"] if e["name"] == "cross"]
    if len(cross) != 10:
        sys.exit(f"dae at {tol}: {len(cross)} crossings of x, expected 10")
    worst = max(abs(e["t"] - (2 * k + 1) * T / 4) for k, e in enumerate(cross))
    dt = 20.0 - 10 * T
    exact = {"x": 1.0, "y": 0.0, "v": 0.0, "w": -G * dt}
    f = j20["final"]
    err20 = max(abs(f[k] - v) for k, v in exact.items())
    s = j10["stats"]
    print(f"  {tol:>6} {'dae bdf':<12} {s['steps']:>6} {s['rejected']:>4} {s['residual_evals']:>6} "
          f"{s['jacobian_evals']:>5} {'':<32} {worst:>14.2e} {err20:>9.2e}")

if ttols:
    print("transamp (IVP Test Set), M y' = f, t in [0, 0.2]")
    print(f"  {'tol':>6} {'ida steps':>9} {'rej':>7} {'scd':>5} {'orders 1..5':<40}"
          f" {'dae steps':>9} {'rej':>7} {'scd':>5} {'dae/ida':>7}")
for tol in ttols:
    i = json.load(open(f"{d}/ida_transamp.{tol}.json"))
    j = dae_run(f"{d}/dae_transamp.{tol}.json")
    s = j["stats"]
    print(f"  {tol:>6} {i['steps']:>9} {i['error_test_failures'] + i['newton_failures']:>7} "
          f"{i['scd']:>5.2f} {str(i['orders']):<40} {s['steps']:>9} {s['rejected']:>7} "
          f"{j['scd']:>5.2f} {s['steps'] / i['steps']:>7.2f}")

if ctols:
    print("caraxis (IVP Test Set), rcd0, t in [0, 3]")
    print(f"  {'tol':>6} {'ida steps':>9} {'rej':>4} {'scd':>5} {'orders 1..5':<28}"
          f" {'dae steps':>9} {'rej':>4} {'scd':>5}")
for tol in ctols:
    i = json.load(open(f"{d}/ida_caraxis.{tol}.json"))
    j = dae_run(f"{d}/dae_caraxis.{tol}.json")
    s = j["stats"]
    print(f"  {tol:>6} {i['steps']:>9} {i['error_test_failures'] + i['newton_failures']:>4} "
          f"{i['scd']:>5.2f} {str(i['orders']):<28} {s['steps']:>9} {s['rejected']:>4} "
          f"{j['scd']:>5.2f}")
PY
