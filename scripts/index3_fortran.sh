#!/bin/sh
# The Fortran reference codes on the index-3 problems of the literature map
# (EXTREMES.md §5, idx10): Hairer & Wanner's RADAU5 and Abdulla & Cash's
# MEBDFI on the car axis, Andrews' squeezer and the pendulum, each in its
# index-3 form as written with NIND = (positions, velocities, the rest),
# rtol = atol = h0 = tol as the IVP Test Set runs them. Prints scd per
# tolerance (the measures of the scenes: car axis relative over positions
# and velocities, Andrews relative over the seven angles, pendulum absolute
# over all five unknowns at t = 20) and the steps.
#
# The codes are not in this repository. Give their directories:
#   RADAU5_SRC  radau5.f, decsol.f, dc_decsol.f (Hairer's, version of
#               2002-01-18, e.g. from the ELeeAstro/mini_chem repository's
#               src_mini_chem_radau5/)
#   MEBDFI_SRC  mebdfi.f and Ex_andrews.f of the CRAN package deTestSet
#               (src/; its mebdfi.f is Cash's MEBDFI of 1999 with R's
#               printing, the residual in DASPK's calling sequence)
# Usage: RADAU5_SRC=… MEBDFI_SRC=… scripts/index3_fortran.sh [tols…]
set -eu
here=$(cd "$(dirname "$0")/index3_fortran" && pwd)
tols=${*:-"1e-4 1e-5 1e-6 1e-7 1e-8 1e-9 1e-10"}
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
ff="gfortran -O2 -ffixed-line-length-none -std=legacy -w"
codes="$here/runners.f $RADAU5_SRC/radau5.f $RADAU5_SRC/decsol.f $RADAU5_SRC/dc_decsol.f $MEBDFI_SRC/mebdfi.f $here/r_stubs.f"
$ff -o "$out/caraxis" "$here/caraxis.f" $codes
$ff -o "$out/pendulum" "$here/pendulum.f" $codes
$ff -o "$out/andrews" "$here/andrews.f" "$MEBDFI_SRC/Ex_andrews.f" $codes
for prob in caraxis andrews pendulum; do
    echo "== $prob"
    for code in 1 2; do
        for t in $tols; do "$out/$prob" "$code" "$t"; done
    done
done
