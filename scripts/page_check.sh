#!/usr/bin/env bash
# Screenshot check of the sweep's page (issue 28, "done when" 4).
#
#   scripts/page_check.sh [OUT_DIR] [SHOT_DIR]
#
# Builds the default S01 page (`dae sweep s01 --out OUT_DIR`, default
# out/s01) unless OUT_DIR already holds an index.html, renders it with
# headless chromium (Debian's `chromium` package; installed with apt-get
# when missing and running as root) and checks what can be checked
# mechanically:
#   - the DOM has the table of contents, with a link to every section;
#   - every success-matrix cell carries an accuracy colour class
#     (acc-all / acc-some / acc-none / na), none the old completion-only
#     ones, and the colour rule is stated under the matrix;
#   - the solution figure is on the page and its PNG is legible in size;
#   - the screenshots are PNGs that are not blank (more than 4 KB and not
#     one colour: ImageMagick-free, the PNG's size says it).
# The screenshots (top of the page, the whole page) stay in SHOT_DIR
# (default target/page_check) to be looked at.
#
# Takes about 3 min on the 2-core CI machine when the page must be built
# (release build + the S01 sweep), seconds with an existing page.
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-out/s01}
shots=${2:-target/page_check}
mkdir -p "$shots"

if [ ! -f "$out/index.html" ]; then
    cargo run --release --quiet -- sweep s01 --out "$out" --quiet >/dev/null
fi

browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
    if [ "$(id -u)" = 0 ]; then
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
        browser=$(command -v chromium)
    else
        echo "page_check: chromium is not installed (apt-get install chromium)" >&2
        exit 2
    fi
fi

profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
       --disable-background-networking --disable-component-update --disable-sync
       --hide-scrollbars "--user-data-dir=$profile")
page="file://$(realpath "$out/index.html")"

fail=0
check() { # check DESCRIPTION COMMAND...
    local what=$1
    shift
    if "$@"; then
        echo "ok   $what"
    else
        echo "FAIL $what"
        fail=1
    fi
}

dom="$shots/dom.html"
"$browser" "${flags[@]}" --dump-dom "$page" >"$dom" 2>/dev/null

check "table of contents" grep -q '<nav id="toc">' "$dom"
for anchor in success trade paper figures efficiency fig-solution fig-work_precision; do
    check "contents link #$anchor and its anchor" \
        bash -c "grep -q 'href=\"#$anchor\"' '$dom' && grep -q 'id=\"$anchor\"' '$dom'"
done
cells=$(grep -o '<td class="\(acc-all\|acc-some\|acc-none\|na\)"' "$dom" | wc -l)
old=$(grep -c '<td class="[Xxo]"' "$dom" || true)
check "success-matrix cells coloured by accuracy ($cells cells, $old completion-only)" \
    test "$cells" -gt 0 -a "$old" -eq 0
check "the colour rule under the matrix" grep -q 'how many tolerances gave a usable answer' "$dom"
check "solution figure on the page" grep -q '<figure id="fig-solution">' "$dom"
check "solution.png exists and is not blank (> 20 KB)" \
    test "$(stat -c %s "$out/solution.png" 2>/dev/null || echo 0)" -gt 20000

for shot in top:1400,1800 full:1400,16000; do
    name=${shot%%:*}
    size=${shot#*:}
    png="$shots/page_$name.png"
    rm -f "$png"
    "$browser" "${flags[@]}" "--window-size=$size" "--screenshot=$png" "$page" >/dev/null 2>&1 || true
    bytes=$(stat -c %s "$png" 2>/dev/null || echo 0)
    check "screenshot $png ($bytes bytes) is a PNG and not blank" \
        bash -c "[ '$bytes' -gt 4096 ] && head -c 8 '$png' | od -An -tx1 | grep -q '89 50 4e 47'"
done

if [ "$fail" -ne 0 ]; then
    echo "page_check: FAILED" >&2
    exit 1
fi
echo "page_check: all checks passed; screenshots in $shots"
