#!/usr/bin/env bash
# Concurrency and fault trials of `dae sweep --out` (issue 27, "done when" 3).
#
#   scripts/fault_outputs.sh [TRIALS] [DAE_BINARY]     (defaults: 50, target/debug/dae)
#
# Each trial starts from a complete set in $OUT, then does one of:
#   pair    two sweeps into the same --out, the second 0–0.5 s after the first
#   int     one sweep, SIGINT at a random moment (0–1.5 s)
#   kill    one sweep, SIGKILL at a random moment (0–1.5 s)
#   full    one sweep into a tmpfs with a random amount of free space
# and checks: $OUT holds a complete set (the same file names as a full run,
# results.json parses) that is either the previous one (byte-identical) or a
# new one, and the exit codes say which: some sweep exited 0 <=> a new set.
# A SIGKILLed sweep has no exit code of its own (137): its set is the previous
# one, or the new one if the kill landed after the exchange (then only
# completeness is checked); the staging directory it leaves is removed by the
# next sweep, which is checked at the end. The full-disk trials need root to mount a tmpfs; without
# it they are skipped and said so.
#
# Prints one line per trial and a summary; exits 1 on any violation.
set -u
TRIALS=${1:-50}
DAE=${2:-target/debug/dae}
DAE=$(realpath "$DAE")
WORK=$(mktemp -d)
trap 'umount "$WORK/tmpfs" 2>/dev/null; rm -rf "$WORK"' EXIT
SWEEP=(sweep s01 --solvers radau5 --formulations rcd1 --tols 1e-4,1e-5,1e-6 --repeats 1 --quiet)
FAILED=0

complete() { # DIR -> 0 if a complete set
    local dir=$1
    [ -d "$dir" ] || return 1
    [ "$(cd "$dir" && ls | sort | tr '\n' ' ')" = "$NAMES" ] || return 1
    python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$dir/results.json" 2>/dev/null
}
digest() { (cd "$1" && cat $(ls | sort) | md5sum | cut -d' ' -f1); }

# The names of a complete set.
"$DAE" "${SWEEP[@]}" --out "$WORK/ref" >/dev/null 2>&1 || { echo "baseline sweep failed"; exit 1; }
NAMES="$(cd "$WORK/ref" && ls | sort | tr '\n' ' ')"

CAN_MOUNT=0
mkdir -p "$WORK/tmpfs"
if mount -t tmpfs -o size=8m tmpfs "$WORK/tmpfs" 2>/dev/null; then
    CAN_MOUNT=1
    umount "$WORK/tmpfs"
fi
SET_KB=$(du -sk "$WORK/ref" | cut -f1)

declare -A COUNT
for trial in $(seq 1 "$TRIALS"); do
    kinds=(pair int kill full)
    kind=${kinds[$((RANDOM % 4))]}
    if [ "$kind" = full ] && [ $CAN_MOUNT = 0 ]; then kind=kill; fi
    if [ "$kind" = full ]; then
        # Room for the previous set and a random share (30–130 %) of a new one.
        size=$((SET_KB * 2 + 64 + SET_KB * (RANDOM % 100 - 70) / 100))
        mount -t tmpfs -o size=${size}k tmpfs "$WORK/tmpfs"
        OUT="$WORK/tmpfs/s01"
    else
        OUT="$WORK/out/s01"
    fi
    # The previous complete set.
    "$DAE" "${SWEEP[@]}" --out "$OUT" >/dev/null 2>&1
    if ! complete "$OUT"; then
        echo "trial $trial ($kind): could not make the previous set"; FAILED=1
        [ "$kind" = full ] && umount "$WORK/tmpfs"
        continue
    fi
    before=$(digest "$OUT")
    codes=()
    case $kind in
    pair)
        "$DAE" "${SWEEP[@]}" --out "$OUT" >/dev/null 2>"$WORK/e1" & p1=$!
        sleep "0.$((RANDOM % 50))"
        "$DAE" "${SWEEP[@]}" --out "$OUT" >/dev/null 2>"$WORK/e2" & p2=$!
        wait $p1; codes+=($?)
        wait $p2; codes+=($?)
        ;;
    int|kill)
        sig=INT; [ $kind = kill ] && sig=KILL
        "$DAE" "${SWEEP[@]}" --out "$OUT" >/dev/null 2>"$WORK/e1" & p1=$!
        sleep "$((RANDOM % 2)).$((RANDOM % 10))"
        kill -$sig $p1 2>/dev/null
        wait $p1; codes+=($?)
        ;;
    full)
        "$DAE" "${SWEEP[@]}" --out "$OUT" >/dev/null 2>"$WORK/e1"; codes+=($?)
        ;;
    esac
    new=0
    for c in "${codes[@]}"; do [ "$c" = 0 ] && new=1; done
    # SIGKILL leaves no exit code of dae's own: a kill after the exchange
    # leaves the new set, before it the previous one; either is whole.
    if [ "$kind" = kill ] && [ "${codes[0]}" = 137 ] && [ "$(digest "$OUT")" != "$before" ]; then
        new=1
    fi
    verdict=ok
    if ! complete "$OUT"; then
        verdict="INCOMPLETE SET"
    elif [ $new = 0 ] && [ "$(digest "$OUT")" != "$before" ]; then
        verdict="CHANGED THOUGH NO SWEEP EXITED 0"
    elif [ $new = 1 ] && [ "$(digest "$OUT")" = "$before" ]; then
        verdict="EXIT 0 BUT THE PREVIOUS SET"
    fi
    for c in "${codes[@]}"; do
        case $c in 0|4|130|137) ;; *) verdict="UNEXPECTED EXIT $c" ;; esac
    done
    which=previous; [ $new = 1 ] && which=new
    echo "trial $trial: $kind exit ${codes[*]} -> $which set: $verdict"
    [ "$verdict" = ok ] || { FAILED=1; cat "$WORK/e1" "$WORK/e2" 2>/dev/null; }
    COUNT[$kind/$which]=$(( ${COUNT[$kind/$which]:-0} + 1 ))
    [ "$kind" = full ] && umount "$WORK/tmpfs"
done

# Leftovers of killed sweeps are removed by the next one.
"$DAE" "${SWEEP[@]}" --out "$WORK/out/s01" >/dev/null 2>&1
left=$(ls -A "$WORK/out" | grep -v '^s01$')
if [ -n "$left" ]; then echo "left beside --out: $left"; FAILED=1; fi

echo "summary ($TRIALS trials, tmpfs: $([ $CAN_MOUNT = 1 ] && echo yes || echo 'no, full-disk trials skipped')):"
for k in "${!COUNT[@]}"; do echo "  $k: ${COUNT[$k]}"; done | sort
[ $FAILED = 0 ] && echo "every --out held a complete set, and the exit codes said which" || echo "VIOLATIONS above"
exit $FAILED
