#!/usr/bin/env bash
# `dae run --solver bdf --formulation rcd0` against SUNDIALS IDA + KLU on the
# N-link pendulum chain (scripts/chain.py), side by side on one machine
# (issue 24 done-when 2; BENCHMARKS.md §16). For each N the script writes
# the chain's scene, then runs, REPEATS times and alternately, the IDA
# driver scripts/ida_chain.c (the chain's rcd0 written as an IDA residual
# with its analytic sparse Jacobian, KLU) and `dae run` (release build), and
# prints one line per run: steps, rejected steps, residual evaluations,
# Jacobian evaluations, factorisations, CPU seconds of the integration and
# CPU milliseconds per accepted step. Then, per N, the minimum CPU per step
# of each (the runs are deterministic: interference only adds time), their
# ratio, and the largest difference of the final positions x_i, y_i at
# t_end between IDA and dae (a check that both integrate the same problem).
#
#   scripts/ida_chain.sh 50 200          # N = 50, then N = 200
#   DENSE=1 scripts/ida_chain.sh 10 50   # also IDA with its dense solver
#
# CPU time: dae's `tsim_s` (CPU time of the thread that ran Solver::run:
# integrator set-up, initial derivative, steps); IDA's `cpu_s`
# (CLOCK_THREAD_CPUTIME_ID from IDACreate to IDASolve's return at t_end:
# set-up, KLU's symbolic analysis, steps). Neither counts parsing, deriving
# or consistent initialisation before it. rtol = atol = TOL for every
# unknown in both (`dae run --tol` sets both), t in [0, 1], from the chain
# stretched out horizontally at rest.
#
# Needs: gcc, python3, Debian's libsundials-dev (SUNDIALS 6.4: libsundials_ida,
# _sunlinsolklu, _sunmatrixsparse, _nvecserial, _sunlinsoldense,
# _sunmatrixdense) and libsuitesparse-dev (KLU), and a release build of dae
# (`cargo build --release`; or DAE=/path/to/dae). Not part of CI: a
# benchmark.
#
# Environment: REPEATS (default 3), TOL (default 1e-6), DENSE=1,
# DAE (default target/release/dae), OUT (scratch directory, default a
# temporary one, removed at the end).
set -euo pipefail

repo="$(cd "$(dirname "$0")/.." && pwd)"
repeats="${REPEATS:-3}"
tol="${TOL:-1e-6}"
dae="${DAE:-$repo/target/release/dae}"
if [ $# -eq 0 ]; then
    echo "usage: $0 N [N ...]   (environment: REPEATS, TOL, DENSE=1, DAE, OUT)" >&2
    exit 2
fi
if [ ! -x "$dae" ]; then
    echo "$0: no dae binary at $dae: run 'cargo build --release' or set DAE" >&2
    exit 2
fi
if [ -n "${OUT:-}" ]; then
    dir="$OUT"
    mkdir -p "$dir"
else
    dir="$(mktemp -d "${TMPDIR:-/tmp}/ida-chain.XXXXXX")"
    trap 'rm -rf "$dir"' EXIT
fi

driver="$dir/ida_chain"
gcc -O2 -Wall -Wextra -I/usr/include/suitesparse -o "$driver" "$repo/scripts/ida_chain.c" \
    -lsundials_ida -lsundials_nvecserial -lsundials_sunlinsolklu -lsundials_sunmatrixsparse \
    -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lklu -lm

echo "# $(uname -srm), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores"
echo "# SUNDIALS $(sed -n 's/^#define SUNDIALS_VERSION "\(.*\)"/\1/p' /usr/include/sundials/sundials_config.h); dae $(cd "$repo" && git rev-parse --short HEAD 2>/dev/null || echo '?'), $dae"
echo "# $(uptime)"

for n in "$@"; do
    python3 "$repo/scripts/chain.py" "$n" "$dir/chain$n"
    # The IDA driver checks its analytic Jacobian against differences first.
    "$driver" "$n" klu "$tol" 1 check >"$dir/check$n.json" || {
        echo "$0: the driver's Jacobian disagrees with its residual at N = $n" >&2
        cat "$dir/check$n.json" >&2
        exit 1
    }
    for r in $(seq 1 "$repeats"); do
        "$driver" "$n" klu "$tol" 1 >"$dir/ida$n.$r.json"
        "$dae" run "$dir/chain$n.toml" --solver bdf --formulation rcd0 --tol "$tol" \
            --format json >"$dir/dae$n.$r.json"
        if [ "${DENSE:-0}" = 1 ]; then
            "$driver" "$n" dense "$tol" 1 >"$dir/idadense$n.$r.json"
        fi
    done
    python3 - "$dir" "$n" "$repeats" <<'PY'
import json, sys

d, n, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])


def ida(path):
    j = json.load(open(path))
    return dict(steps=j["steps"], rejected=j["error_test_failures"] + j["newton_failures"],
                res=j["residual_evals"], jac=j["jacobian_evals"], lu=j["factorizations"],
                cpu=j["cpu_s"], final=j["final"])


def dae(path):
    j = json.load(open(path))
    if j["status"] != "ok":
        sys.exit(f"dae run at N = {n}: status {j['status']}: {j['error']}")
    s = j["stats"]
    return dict(steps=s["steps"], rejected=s["rejected"], res=s["residual_evals"],
                jac=s["jacobian_evals"], lu=s["factorizations"], cpu=j["tsim_s"],
                final=j["final"])


kinds = [("ida+klu", "ida", ida), ("dae bdf(rcd0)", "dae", dae)]
try:
    open(f"{d}/idadense{n}.1.json").close()
    kinds.append(("ida+dense", "idadense", ida))
except OSError:
    pass
best = {}
print(f"N = {n} ({5 * n} unknowns)")
print(f"  {'run':<14} {'#':>2} {'steps':>6} {'rej':>4} {'res':>6} {'jac':>5} {'LU':>5} {'CPU s':>10} {'ms/step':>9}")
runs = {}
for r in range(1, repeats + 1):
    for name, stem, read in kinds:
        x = read(f"{d}/{stem}{n}.{r}.json")
        runs[name] = x
        per = 1e3 * x["cpu"] / x["steps"]
        best[name] = min(best.get(name, per), per)
        print(f"  {name:<14} {r:>2} {x['steps']:>6} {x['rejected']:>4} {x['res']:>6} {x['jac']:>5} "
              f"{x['lu']:>5} {x['cpu']:>10.6f} {per:>9.4f}")
a, b = runs["ida+klu"]["final"], runs["dae bdf(rcd0)"]["final"]
diff = max(abs(a[k] - b[k]) for k in a)
ratio = best["dae bdf(rcd0)"] / best["ida+klu"]
line = ", ".join(f"{k} {v:.4f}" for k, v in best.items())
print(f"  min ms/step: {line}; dae / ida+klu = {ratio:.2f}"
      f" ({'dae no slower' if ratio <= 1 else 'dae slower'})")
if "ida+dense" in best:
    print(f"  ida+dense / ida+klu per step = {best['ida+dense'] / best['ida+klu']:.2f}")
print(f"  max |position difference| at t_end, ida+klu vs dae: {diff:.2e}")
PY
done
