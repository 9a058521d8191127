#!/usr/bin/env bash
# test/cli_maxedge.sh: max_edge=L in ./tdc's --method (issue 39): --grid
# leaves the triangles with an edge longer than L empty, --contours stops
# its lines there; an edge exactly L long is kept; errors are one line.
#   bash test/cli_maxedge.sh        (after `make tdc`; prints "N passed, N failed")
set -u
cd "$(dirname "$0")/.."
TDC=./tdc
pass=0; fail=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }
expect_error() {
	local name=$1; shift
	"$@" > "$tmp/e.out" 2> "$tmp/e.err"; local rc=$?
	check "$name: exit 2" "[ $rc -eq 2 ]"
	check "$name: one-line message naming the problem" \
		"[ \$(wc -l < $tmp/e.err) -eq 1 ] && grep -q '^tdc: --method: .*$EXPECT' $tmp/e.err"
}

[ -x "$TDC" ] || make -s tdc >/dev/null || { echo "cannot build ./tdc"; echo "0 passed, 1 failed"; exit 1; }

# A lake: the lattice 0..20 with no sample within 6 of (10 10) but one at
# it, heights z = x + 2 y (a plane).
awk 'BEGIN { for (x = 0; x <= 20; x++) for (y = 0; y <= 20; y++) {
	d = (x - 10) ^ 2 + (y - 10) ^ 2; if (d > 36 || d == 0) print x, y, x + 2 * y } }' > "$tmp/lake.txt"
# the pixels of a grid with -9999 (rows 7.. of the .asc)
nodata() { awk 'NR > 6 { for (c = 1; c <= NF; c++) n += ($c == -9999) } END { print n + 0 }' "$1"; }

$TDC --grid 0.5 --method linear:nodata=-9999 -o "$tmp/plain.asc" "$tmp/lake.txt"
check "grid without max_edge: no empty pixel in the hull" "[ \$(nodata $tmp/plain.asc) -eq 0 ]"
$TDC --grid 0.5 --method linear:max_edge=1.5:nodata=-9999 -o "$tmp/lin.asc" --stats "$tmp/lake.txt" 2> "$tmp/lin.err"
check "grid linear:max_edge=1.5: exit 0" "[ $? -eq 0 ]"
holes=$(nodata "$tmp/lin.asc")
# the disc of radius 6 is 113 square units, 452 pixels of 0.25; the lake's
# triangles reach a little beyond it
check "grid linear:max_edge=1.5: the lake is empty ($holes pixels)" "[ $holes -gt 400 ] && [ $holes -lt 700 ]"
check "grid linear:max_edge=1.5: --stats counts the valid pixels" \
	"grep -qE '^tin=[0-9.]+ grid=[0-9.]+ pixels=1600 valid=$((1600 - holes))\$' $tmp/lin.err"
# pixel (col, row) has its centre at (col + 0.25, 20 - row - 0.25) (0-based)
px() { awk -v r="$2" -v c="$3" 'NR == 7 + r { print $(c + 1) }' "$1"; }
check "the pixel at (10.25 10.25), beside the lake's sample, is empty" "[ \"\$(px $tmp/lin.asc 19 20)\" = -9999 ]"
check "the pixel at (2.25 2.25) has the plane's height 6.75" "[ \"\$(px $tmp/lin.asc 35 4)\" = 6.75 ]"
check "the same pixels without max_edge have values" "[ \"\$(px $tmp/plain.asc 19 20)\" != -9999 ]"
for m in nearest natural_neighbor; do
	$TDC --grid 0.5 --method $m:max_edge=1.5:nodata=-9999 -o "$tmp/$m.asc" "$tmp/lake.txt"
	check "grid $m:max_edge=1.5: the same empty pixels as linear" \
		"cmp -s <(awk 'NR > 6 { for (c = 1; c <= NF; c++) printf \"%d\", (\$c == -9999) }' $tmp/lin.asc) \
		        <(awk 'NR > 6 { for (c = 1; c <= NF; c++) printf \"%d\", (\$c == -9999) }' $tmp/$m.asc)"
done
$TDC -t 1 --grid 0.5 --method natural_neighbor:max_edge=1.5 -o "$tmp/t1.asc" "$tmp/lake.txt"
$TDC -t 3 --grid 0.5 --method natural_neighbor:max_edge=1.5 -o "$tmp/t3.asc" "$tmp/lake.txt"
check "grid with max_edge: the same for 1 and 3 threads" "cmp -s $tmp/t1.asc $tmp/t3.asc"

# the boundary, exactly: a 3-4-5 triangle keeps its pixels at max_edge 5,
# not at the double below 5
printf '0 0 1\n4 0 1\n0 3 1\n' > "$tmp/tri.txt"
$TDC --grid 1 --extent 0,0,2,1 --method linear:max_edge=5:nodata=-9999 -o "$tmp/t5.asc" "$tmp/tri.txt"
check "3-4-5 triangle, max_edge=5: kept" "[ \"\$(sed -n 7p $tmp/t5.asc | tr -s ' ')\" = '1 1' ]"
$TDC --grid 1 --extent 0,0,2,1 --method linear:max_edge=4.9999999999999991:nodata=-9999 -o "$tmp/t4.asc" "$tmp/tri.txt"
check "3-4-5 triangle, max_edge=4.9999999999999991: dropped" "[ \"\$(sed -n 7p $tmp/t4.asc | tr -s ' ')\" = '-9999 -9999' ]"

# breaklines and max_edge together: the ridge (0 1)-(4 1), 4 long, is an
# edge of both triangles of the constrained TIN
printf '0 1 10\n4 1 10\n2 0 0\n2 2 4\n' > "$tmp/ridge.txt"
printf '0 1\n' > "$tmp/ridge.seg"
$TDC --grid 1 --extent 0,0.5,4,1.5 --method linear:breaklines=true:max_edge=4:nodata=-9999 --segments "$tmp/ridge.seg" -o "$tmp/r4.asc" "$tmp/ridge.txt"
check "breaklines with max_edge=4: the ridge at 10" "[ \"\$(sed -n 7p $tmp/r4.asc | tr -s ' ' | sed 's/ *\$//')\" = '10 10 10 10' ]"
$TDC --grid 1 --extent 0,0.5,4,1.5 --method linear:breaklines=true:max_edge=3.9:nodata=-9999 --segments "$tmp/ridge.seg" -o "$tmp/r3.asc" "$tmp/ridge.txt"
check "breaklines with max_edge=3.9: both triangles dropped" "[ \"\$(sed -n 7p $tmp/r3.asc | tr -s ' ' | sed 's/ *\$//')\" = '-9999 -9999 -9999 -9999' ]"

# contours of z = x on the lake: the 20 lines x = 0.5 .. 19.5; those through
# the lake stop at its shore, in two pieces each
awk '{ print $1, $2, $1 }' "$tmp/lake.txt" > "$tmp/zx.txt"
$TDC --contours 1 --base 0.5 -o "$tmp/c0.txt" "$tmp/zx.txt"
check "contours without max_edge: 20 lines" "[ \$(wc -l < $tmp/c0.txt) -eq 20 ]"
$TDC --contours 1 --base 0.5 --method linear:max_edge=1.5 -o "$tmp/c1.txt" --stats "$tmp/zx.txt" 2> "$tmp/c1.err"
check "contours with --method linear:max_edge=1.5: exit 0" "[ $? -eq 0 ]"
n1=$(wc -l < "$tmp/c1.txt")
check "contours with max_edge: lines through the lake cut in two ($n1 lines)" "[ $n1 -gt 20 ] && [ $n1 -le 40 ]"
check "contours with max_edge: the line at 10.5 in two pieces, one below the lake and one above" \
	"[ \$(awk '\$1 == 10.5' $tmp/c1.txt | wc -l) -eq 2 ] && \
	 awk '\$1 == 10.5 { lo = 1e9; hi = -1e9; for (k = 3; k <= NF; k += 2) { if (\$k < lo) lo = \$k; if (\$k > hi) hi = \$k }
		if (!((hi < 4.5 && lo == 0) || (lo > 15.5 && hi == 20))) exit 1 }' $tmp/c1.txt"
check "contours with max_edge: the line at 0.5, away from the lake, unchanged" \
	"[ \"\$(awk '\$1 == 0.5' $tmp/c1.txt)\" = \"\$(awk '\$1 == 0.5' $tmp/c0.txt)\" ]"
check "contours with max_edge: --stats" "grep -qE '^tin=[0-9.]+ contours=[0-9.]+ lines=$n1 contour_points=[0-9]+\$' $tmp/c1.err"
$TDC -t 1 --contours 0.75 --method linear:max_edge=1.5 -o "$tmp/ct1.txt" "$tmp/lake.txt"
$TDC -t 3 --contours 0.75 --method linear:max_edge=1.5 -o "$tmp/ct3.txt" "$tmp/lake.txt"
check "contours with max_edge: the same for 1 and 3 threads" "cmp -s $tmp/ct1.txt $tmp/ct3.txt && [ -s $tmp/ct1.txt ]"
$TDC --contours 1 --base 0.5 --method linear:max_edge=inf -o "$tmp/cinf.txt" "$tmp/zx.txt"
check "contours with max_edge=inf: as without it" "cmp -s $tmp/c0.txt $tmp/cinf.txt"

# errors: usage errors (exit 2), one line naming the problem
EXPECT='must be linear, not nearest' expect_error "--contours --method nearest" \
	$TDC --contours 1 --method nearest:max_edge=2 "$tmp/zx.txt"
EXPECT='only the option max_edge: radius' expect_error "--contours --method linear:radius=0" \
	$TDC --contours 1 --method linear:radius=0:max_edge=2 "$tmp/zx.txt"
EXPECT='breaklines' expect_error "--contours --method linear:breaklines=true" \
	$TDC --contours 1 --method linear:breaklines=true "$tmp/zx.txt"
EXPECT='"max_edge" must be a length > 0, not -1' expect_error "--contours max_edge=-1" \
	$TDC --contours 1 --method linear:max_edge=-1 "$tmp/zx.txt"
EXPECT='"max_edge" must be a length > 0, not 0' expect_error "--grid max_edge=0" \
	$TDC --grid 1 --method linear:max_edge=0 "$tmp/zx.txt"
EXPECT='"max_edge": "abc" is not a number' expect_error "--grid max_edge=abc" \
	$TDC --grid 1 --method natural_neighbor:max_edge=abc "$tmp/zx.txt"
"$TDC" --method linear:max_edge=1 "$tmp/zx.txt" > /dev/null 2> "$tmp/e.err"
check "--method without --grid or --contours: exit 2" "[ $? -eq 2 ] && grep -q 'goes with --grid or --contours' $tmp/e.err"
"$TDC" --help > "$tmp/help.txt" 2>&1
check "--help documents max_edge" "grep -q 'max_edge=L' $tmp/help.txt && grep -q 'exactly L long is kept' $tmp/help.txt"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
