#!/usr/bin/env bash
# bdf against SUNDIALS IDA (a DASSL descendant) on the index-1 problems of
# the literature map that scripts/ida_pendulum.sh does not cover (issue 26,
# done-when 2: "bdf on index-1 problems needs no more steps than DASSL-class
# codes report for the same problem and tolerance (within 2x)"; EXTREMES.md
# section 5, "Session 13"): the IVP Test Set's chemakzo as written (index
# 1), and the rcd0 forms of jay_index2, gear_hsu_petzold, cstr and
# mna_cv_loop, each scripts/ida_index1.c (IDA, dense difference-quotient
# Jacobian), and of Andrews' squeezer, a driver scripts/ida_derive.py
# writes from `dae derive`'s rows (27 unknowns), each beside `dae run scenes/literature/SCENE.toml --solver bdf
# --formulation rcd0`. rtol = atol = TOL for every unknown in both. One
# line per problem and tolerance: steps and scd of each, and dae's steps
# over IDA's. IDA's scd is scored here against the scene's reference CSV at
# the scene's check times that it holds (relative errors for chemakzo and jay_index2,
# absolute for the others, as the scenes say).
#
#   scripts/ida_index1.sh                      # tolerances 1e-4 ... 1e-10
#   TOLS="1e-6 1e-8" PROBLEMS="chemakzo cstr" scripts/ida_index1.sh
#
# Needs: gcc, python3, Debian's libsundials-dev (SUNDIALS 6.4) and a
# release build of dae (`cargo build --release --bin dae`; or DAE=/path).
# Not part of CI: a measurement (counts; the runs are deterministic).
set -euo pipefail

repo="$(cd "$(dirname "$0")/.." && pwd)"
dae="${DAE:-$repo/target/release/dae}"
tols="${TOLS-1e-4 1e-5 1e-6 1e-7 1e-8 1e-9 1e-10}"
problems="${PROBLEMS-chemakzo jay ghp cstr mna andrews}"
if [ ! -x "$dae" ]; then
    echo "$0: no dae binary at $dae: run 'cargo build --release --bin dae' or set DAE" >&2
    exit 2
fi
dir="$(mktemp -d "${TMPDIR:-/tmp}/ida-index1.XXXXXX")"
trap 'rm -rf "$dir"' EXIT
gcc -O2 -Wall -Wextra -o "$dir/ida_index1" "$repo/scripts/ida_index1.c" \
    -lsundials_ida -lsundials_nvecserial -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lm

scene_of() {
    case "$1" in
        chemakzo) echo chemakzo ;;
        jay) echo jay_index2 ;;
        ghp) echo gear_hsu_petzold ;;
        cstr) echo cstr ;;
        mna) echo mna_cv_loop ;;
        andrews) echo andrews ;;
    esac
}

libs="-lsundials_ida -lsundials_nvecserial -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lm"
for p in $problems; do
    s="$(scene_of "$p")"
    driver=("$dir/ida_index1" "$p")
    if [ "$p" = andrews ]; then
        DAE="$dae" python3 "$repo/scripts/ida_derive.py" "$repo/scenes/literature/andrews.toml" rcd0 \
            >"$dir/ida_andrews.c"
        # shellcheck disable=SC2086
        gcc -O2 -Wall -Wextra -I"$repo/scripts" -o "$dir/ida_andrews" "$dir/ida_andrews.c" $libs
        driver=("$dir/ida_andrews")
    fi
    for tol in $tols; do
        "${driver[@]}" "$tol" >"$dir/ida.$p.$tol.json"
        "$dae" run "$repo/scenes/literature/$s.toml" --solver bdf --formulation rcd0 \
            --tol "$tol" --format json >"$dir/dae.$p.$tol.json" || true
    done
done

python3 - "$dir" "$repo" "$tols" "$problems" <<'PY'
import csv, json, math, sys, tomllib

d, repo, tols, problems = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4].split()
scene = {"chemakzo": "chemakzo", "jay": "jay_index2", "ghp": "gear_hsu_petzold",
         "cstr": "cstr", "mna": "mna_cv_loop", "andrews": "andrews"}
relative = {"chemakzo", "jay", "andrews"}

def columns(p):
    """The unknowns the scene scores (its reference's `columns`)."""
    with open(f"{repo}/scenes/literature/{scene[p]}.toml", "rb") as f:
        return tomllib.load(f)["reference"]["columns"]

def reference(p):
    """Reference rows by time: the scored columns, in the scene's order."""
    rows = [r for r in open(f"{repo}/scenes/{scene[p]}_reference.csv") if not r.startswith("#")]
    table = list(csv.reader(rows))
    at = [table[0].index(c) for c in columns(p)]
    return {round(float(row[0]), 9): [float(row[i]) for i in at] for row in table[1:]}

def ida_scd(p, run):
    # The drivers print every unknown, the scored ones first and in the
    # scene's order (Andrews: its seven angles of 27).
    ref, k = reference(p), len(columns(p))
    worst = 0.0
    for t, y in zip(run["t"], run["y"]):
        want = ref.get(round(t, 9))
        if want is None:  # a check time the reference does not hold
            continue
        for a, b in zip(y[:k], want):
            e = abs(a - b) / abs(b) if p in relative else abs(a - b)
            worst = max(worst, e)
    return -math.log10(worst) if worst > 0 else float("inf")

print(f"{'problem':9} {'tol':>6} {'IDA steps':>9} {'IDA scd':>7} {'dae steps':>9} {'dae scd':>7} {'dae/IDA':>7}")
for p in problems:
    for tol in tols:
        i = json.load(open(f"{d}/ida.{p}.{tol}.json"))
        j = json.load(open(f"{d}/dae.{p}.{tol}.json"))
        steps = j["stats"]["steps"] if j.get("status") == "ok" else None
        scd = j.get("scd")
        ratio = f"{steps / i['steps']:.2f}" if steps else "-"
        dscd = f"{scd:.2f}" if scd is not None else j.get("status", "?")
        print(f"{p:9} {tol:>6} {i['steps']:9d} {ida_scd(p, i):7.2f} {steps if steps else '-':>9} {dscd:>7} {ratio:>7}")
PY
