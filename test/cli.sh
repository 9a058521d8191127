#!/usr/bin/env bash
# test/cli.sh: the fixed command-line interface of ./tdc.
#   bash test/cli.sh        (after `make tdc`; prints "N passed, N failed")
set -u
cd "$(dirname "$0")/.."
TDC=./tdc
pass=0; fail=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }

[ -x "$TDC" ] || make -s tdc >/dev/null || { echo "cannot build ./tdc"; echo "0 passed, 1 failed"; exit 1; }
# the exact arbiter of grids and contours (GMP; test/tin_arbiter.c)
ARB=build/tin_arbiter
make -s "$ARB" >/dev/null || { echo "cannot build $ARB"; echo "0 passed, 1 failed"; exit 1; }

# text input, 4 points, one per line; -o writes CCW triangles with %.17g
printf '0 0\n1 0\n0 1\n1 1\n' > "$tmp/sq.txt"
$TDC -o "$tmp/sq.out" --stats "$tmp/sq.txt" 2> "$tmp/sq.err"
check "square: exit 0" "[ $? -eq 0 ]"
check "square: 2 triangles written" "[ \$(wc -l < $tmp/sq.out) -eq 2 ]"
check "square: stats line fields" "grep -qE '^n=4 unique=4 triangles=2 threads=[0-9]+ sort=[0-9.]+ subdivide=[0-9.]+ leaves=[0-9.]+ merge=[0-9.]+ total=[0-9.]+ peak_rss_mb=[0-9.]+$' $tmp/sq.err"
check "square: each line has 6 numbers" "awk 'NF != 6 { exit 1 }' $tmp/sq.out"
check "square: counter-clockwise" "awk '{ if ((\$3-\$1)*(\$6-\$2) - (\$4-\$2)*(\$5-\$1) <= 0) exit 1 }' $tmp/sq.out"

# z values follow the first input point with that x,y
printf '0 0 5\n1 0 6\n0 1 7\n0 0 99\n' > "$tmp/z.txt"
$TDC -o "$tmp/z.out" "$tmp/z.txt"
check "z: 9 numbers per line" "awk 'NF != 9 { exit 1 }' $tmp/z.out"
check "z: first occurrence kept" "grep -q ' 5\\b\\|^0 0 5' $tmp/z.out && ! grep -q 99 $tmp/z.out"

# stdin, comments, blank lines, %.17g round trip
printf '# a comment\n\n0.1 0.2\n0.30000000000000004 0.2\n0.1 0.7\n' | $TDC -o "$tmp/in.out" -
check "stdin: one triangle" "[ \$(wc -l < $tmp/in.out) -eq 1 ]"
check "stdin: %.17g output" "grep -q '0.30000000000000004' $tmp/in.out"

# .bin input equals the same points as text
printf '0 0\n2 0\n1 3\n1 1\n' > "$tmp/b.txt"
python3 -c 1 2>/dev/null && true
awk '{ printf "%s %s\n", $1, $2 }' "$tmp/b.txt" > /dev/null
perl -e 'open F, "<", $ARGV[0]; while (<F>) { @a = split; print pack("d<d<", @a) }' "$tmp/b.txt" > "$tmp/b.bin"
$TDC -o "$tmp/b1.out" "$tmp/b.bin"; $TDC -o "$tmp/b2.out" "$tmp/b.txt"
check ".bin equals text" "cmp -s <(sort $tmp/b1.out) <(sort $tmp/b2.out)"
check ".bin: 3 triangles" "[ \$(wc -l < $tmp/b1.out) -eq 3 ]"

# .xyz.bin input (float64 x,y,z triples) equals the same points as text 'x y z'
printf '0 0 5\n2 0 6.5\n1 3 -7\n1 1 0.1\n0 0 99\n' > "$tmp/b3.txt"
perl -e 'open F, "<", $ARGV[0]; while (<F>) { @a = split; print pack("d<d<d<", @a) }' "$tmp/b3.txt" > "$tmp/b3.xyz.bin"
$TDC -o "$tmp/b31.out" "$tmp/b3.xyz.bin"; $TDC -o "$tmp/b32.out" "$tmp/b3.txt"
check ".xyz.bin equals text x y z" "[ -s $tmp/b31.out ] && cmp -s $tmp/b31.out $tmp/b32.out && awk 'NF != 9 { exit 1 }' $tmp/b31.out"
check ".xyz.bin: z of the first copy of (0 0)" "grep -qE '(^| )0 0 5( |\$)' $tmp/b31.out && ! grep -q 99 $tmp/b31.out"

# options: same triangle set for threads / grid / levels
perl -e 'srand(7); for (1..20000) { printf "%.17g %.17g\n", rand(1000), rand(1000) }' > "$tmp/r.txt"
$TDC -t 1 -o "$tmp/r1.out" "$tmp/r.txt"
$TDC -t 2 -g 16 -l 3 -o "$tmp/r2.out" "$tmp/r.txt"
$TDC -t 4 -l -1 -o "$tmp/r3.out" "$tmp/r.txt"
canon() { awk '{ # rotate so the smallest vertex comes first
  best = 0; for (k = 1; k < 3; k++) if ($(2*k+1) < $(2*best+1) || ($(2*k+1) == $(2*best+1) && $(2*k+2) < $(2*best+2))) best = k;
  s = ""; for (k = 0; k < 3; k++) { j = (best + k) % 3; s = s $(2*j+1) " " $(2*j+2) " " } print s }' "$1" | sort; }
check "threads/grid/levels give one triangle set" "cmp -s <(canon $tmp/r1.out) <(canon $tmp/r2.out) && cmp -s <(canon $tmp/r1.out) <(canon $tmp/r3.out)"
check "2n-2-h bound" "[ \$(wc -l < $tmp/r1.out) -gt 39900 ] && [ \$(wc -l < $tmp/r1.out) -lt 39998 ]"

# --validate runs the exact validator on the result
$TDC --validate "$tmp/r.txt" 2> "$tmp/v.err"
check "--validate: exit 0 and says valid" "[ $? -eq 0 ] && grep -q '^valid: 20000 sites' $tmp/v.err"

# tolerance (PostGIS case: (8 9) within 2 of (7 9) is dropped)
printf '5 5\n6 0\n7 9\n8 9\n' > "$tmp/t.txt"
$TDC --tolerance 2 -o "$tmp/t.out" "$tmp/t.txt"
check "tolerance 2: one triangle" "[ \$(wc -l < $tmp/t.out) -eq 1 ] && ! grep -q '^8 9\\| 8 9' $tmp/t.out"

# errors: non-zero exit and a one-line message
expect_error() {
	local name=$1; shift
	"$@" > "$tmp/e.out" 2> "$tmp/e.err"; local rc=$?
	check "$name: non-zero exit" "[ $rc -ne 0 ]"
	check "$name: one-line message" "[ \$(wc -l < $tmp/e.err) -eq 1 ] && grep -q '^tdc: ' $tmp/e.err"
}
expect_error "no input" $TDC
expect_error "unknown option" $TDC --frobnicate "$tmp/sq.txt"
expect_error "missing file" $TDC "$tmp/nope.txt"
expect_error "bad -t" $TDC -t abc "$tmp/sq.txt"
expect_error "negative tolerance" $TDC --tolerance -1 "$tmp/sq.txt"
printf '1 2\nfoo bar\n' > "$tmp/bad.txt"; expect_error "garbage line" $TDC "$tmp/bad.txt"
printf '1 2\n3 4 5\n' > "$tmp/mix.txt"; expect_error "mixed dimensions" $TDC "$tmp/mix.txt"
printf '1 2\nnan 4\n5 5\n' > "$tmp/nan.txt"; expect_error "NaN" $TDC "$tmp/nan.txt"
printf '1 2 3 4\n' > "$tmp/four.txt"; expect_error "four columns" $TDC "$tmp/four.txt"
head -c 17 /dev/zero > "$tmp/odd.bin"; expect_error "truncated .bin" $TDC "$tmp/odd.bin"
head -c 40 /dev/zero > "$tmp/odd.xyz.bin"; expect_error "truncated .xyz.bin" $TDC "$tmp/odd.xyz.bin"
check "truncated .xyz.bin: says 24 bytes" "grep -q 'odd.xyz.bin: size is not a multiple of 24 bytes' $tmp/e.err"
expect_error "truncated .xyz.bin, --max-memory" $TDC --max-memory 10 "$tmp/odd.xyz.bin"

# degenerate input: no output lines, exit 0
printf '1 1\n2 2\n3 3\n' > "$tmp/col.txt"; $TDC -o "$tmp/col.out" "$tmp/col.txt"
check "collinear: exit 0, no triangles" "[ $? -eq 0 ] && [ ! -s $tmp/col.out ]"
: > "$tmp/empty.txt"; $TDC -o "$tmp/empty.out" "$tmp/empty.txt"
check "empty input: exit 0, no triangles" "[ $? -eq 0 ] && [ ! -s $tmp/empty.out ]"

# --voronoi: one cell per distinct point, input order, areas add up to the
# default envelope (the input box [0,2]x[0,1] grown by 2: 6 x 5)
printf '0 0\n2 0\n0 1\n2 0\n' > "$tmp/v.txt"
$TDC --voronoi -o "$tmp/v.out" --stats "$tmp/v.txt" 2> "$tmp/v.err"
check "voronoi: exit 0" "[ $? -eq 0 ]"
check "voronoi: 3 cells" "[ \$(wc -l < $tmp/v.out) -eq 3 ]"
check "voronoi: stats line" "grep -qE '^voronoi=[0-9.]+ cell_vertices=13$' $tmp/v.err"
check "voronoi: first cell is (0 0)'s" "awk 'NR == 1 { exit !(\$0 == \"1 0.5 -2 0.5 -2 -2 1 -2\") }' $tmp/v.out"
check "voronoi: areas sum to 30" "awk '{ for (i = 1; i <= NF; i += 2) { j = (i + 2 > NF) ? 1 : i + 2; a += \$i * \$(j + 1) - \$j * \$(i + 1) } } END { exit !(a / 2 == 30) }' $tmp/v.out"

# --max-memory: an input whose one-shot run needs several times the limit is
# triangulated in tiles on disk, with the same triangle set and a peak RSS
# under the limit (getrusage, reported by --stats)
canon_d() { awk -v d="$2" '{ best = 0; for (k = 1; k < 3; k++) if ($(d*k+1) < $(d*best+1) || ($(d*k+1) == $(d*best+1) && $(d*k+2) < $(d*best+2))) best = k;
  s = ""; for (k = 0; k < 3; k++) { j = (best + k) % 3; for (c = 1; c <= d; c++) s = s $(d*j+c) " " } print s }' "$1" | LC_ALL=C sort; }
# (uniform, 40 Gaussian clusters, and an integer lattice with duplicates)
perl -e 'srand(11); for (1..600000) { print pack("d<d<", rand(1000), rand(1000)) }
  for $c (1..40) { $cx = 50 + rand(900); $cy = 50 + rand(900); for (1..10000) { $a = rand(6.2832); $r = 15 * sqrt(-2 * log(1 - rand())); print pack("d<d<", $cx + $r * cos($a), $cy + $r * sin($a)) } }
  for (1..2000) { print pack("d<d<", 100 + int(rand(50)), 100 + int(rand(50))) }' > "$tmp/big.bin"
$TDC -o "$tmp/big1.out" --stats "$tmp/big.bin" 2> "$tmp/big1.err"
mkdir -p "$tmp/tiles"
# (TDC_TILE_CHECK: each tile's first run checks that its tile and halo files
# hold exactly the points of its first known region, K and its hull bands)
TDC_TILE_CHECK=1 $TDC --max-memory 24 --tmpdir "$tmp/tiles" -o "$tmp/big2.out" --stats "$tmp/big.bin" 2> "$tmp/big2.err"
check "--max-memory: exit 0" "[ $? -eq 0 ]"
one_rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/big1.err")
til_rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/big2.err")
check "--max-memory: one-shot needs > 3x the limit ($one_rss MB)" "awk 'BEGIN { exit !($one_rss > 72) }'"
check "--max-memory: peak RSS $til_rss MB under 24" "awk 'BEGIN { exit !($til_rss < 24) }'"
check "--max-memory: stats has tiles= (>1) and halo_points=" "grep -qE ' tiles=([2-9]|[1-9][0-9]+) halo_points=[1-9][0-9]* ' $tmp/big2.err"
check "--max-memory: same triangle set as one-shot" "cmp -s <(canon_d $tmp/big1.out 2) <(canon_d $tmp/big2.out 2)"
check "--max-memory: same triangle count" "[ \$(wc -l < $tmp/big1.out) -eq \$(wc -l < $tmp/big2.out) ]"
check "--max-memory: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"
# without -o the tiles' order shows nowhere: two run at a time (two threads),
# in the same limit, with the same counts
TDC_TILE_CHECK=1 $TDC --max-memory 24 -t 2 --tmpdir "$tmp/tiles" --stats "$tmp/big.bin" 2> "$tmp/big3.err"
check "--max-memory, no -o: exit 0" "[ $? -eq 0 ]"
w_rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/big3.err")
check "--max-memory, no -o: two tile workers" "grep -q ' workers=2 ' $tmp/big3.err"
check "--max-memory, no -o: peak RSS $w_rss MB under 24" "awk 'BEGIN { exit !($w_rss < 24) }'"
check "--max-memory, no -o: the one-shot's triangle and site counts" \
	"[ \"\$(grep -oE '^n=[0-9]+ unique=[0-9]+ triangles=[0-9]+' $tmp/big1.err)\" = \"\$(grep -oE '^n=[0-9]+ unique=[0-9]+ triangles=[0-9]+' $tmp/big3.err)\" ]"
check "--max-memory, no -o: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"

# hull_edge_walk: uniform points in a square with its four corners, so that
# each side is one hull edge past every tile along it.  A border tile's own
# hull is P's only once the far corners are known, and the slivers under a
# side have lenses thinner than a spacing running along it: the tiles along
# the sides ran again and again, each run naming the next few cells along
# the side (323 runs of 218 tiles).  Each is final in its first run now.
perl -e 'srand(5); print pack("d<d<", 0, 0), pack("d<d<", 1000, 0), pack("d<d<", 1000, 1000), pack("d<d<", 0, 1000);
  for (5..4000000) { print pack("d<d<", rand(1000), rand(1000)) }' > "$tmp/sq.bin"
TDC_TILE_CHECK=1 $TDC --max-memory 24 --tmpdir "$tmp/tiles" --stats "$tmp/sq.bin" 2> "$tmp/sq.err"
check "--max-memory, hull edges along whole sides: exit 0" "[ $? -eq 0 ]"
check "--max-memory, hull edges along whole sides: 2n - 2 - 4 triangles" "grep -q ' triangles=7999994 ' $tmp/sq.err"
sq_tiles=$(sed -n 's/.* tiles=\([0-9]*\) .*/\1/p' "$tmp/sq.err")
sq_runs=$(sed -n 's/.* tile_runs=\([0-9]*\) .*/\1/p' "$tmp/sq.err")
check "--max-memory, hull edges along whole sides: $sq_runs runs of $sq_tiles tiles, at most 2% again" \
	"[ \"$sq_tiles\" -gt 150 ] && [ \"$sq_runs\" -le \$(( $sq_tiles + $sq_tiles / 50 )) ]"
check "--max-memory, hull edges along whole sides: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"

# an integer lattice over [0, 512]: the fine grid's cells are 1 wide, so
# points lie on cell sides, tile sides, and the sides of the first known
# boxes (halo 8 spacings), which are closed; with duplicates
perl -e 'use List::Util qw(shuffle); srand(3); @p = (); for $x (0..512) { for $y (0..512) { push @p, [$x, $y] } }
  push @p, [int(rand(513)), int(rand(513))] for 1..2000; print pack("d<d<", @$_) for shuffle(@p)' > "$tmp/lat.bin"
$TDC -o "$tmp/lat1.out" "$tmp/lat.bin"
TDC_TILE_CHECK=1 $TDC --max-memory 14 --tmpdir "$tmp/tiles" -o "$tmp/lat2.out" --stats "$tmp/lat.bin" 2> "$tmp/lat2.err"
check "--max-memory, lattice on cell sides: tiled" "grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/lat2.err"
check "--max-memory, lattice on cell sides: same triangle set" "cmp -s <(canon_d $tmp/lat1.out 2) <(canon_d $tmp/lat2.out 2)"

# the counting grid comes from a sample of the file: points the sample
# misses just beyond its box (the outer cells widen) and far beyond it (the
# cells are counted again on the true box)
for far in 1.005 1.05; do
	perl -e 'srand(9); $f = $ARGV[0]; for $i (1..300000) { print pack("d<d<", rand(1), rand(1));
	  if ($i == 1000) { print pack("d<d<", $f, 0.5), pack("d<d<", 0.5, -$f + 1), pack("d<d<", $f, $f) } }' $far > "$tmp/out.bin"
	$TDC -o "$tmp/out1.out" "$tmp/out.bin"
	TDC_TILE_CHECK=1 $TDC --max-memory 20 --tmpdir "$tmp/tiles" -o "$tmp/out2.out" --stats "$tmp/out.bin" 2> "$tmp/out2.err"
	check "--max-memory, outliers at $far: tiled" "grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/out2.err"
	check "--max-memory, outliers at $far: same triangle set" "cmp -s <(canon_d $tmp/out1.out 2) <(canon_d $tmp/out2.out 2)"
done

# a NaN in the second half of the input, which the second thread of step 1 reads
perl -e 'srand(4); $nan = unpack("d<", pack("Q<", 0x7ff8000000000000)); for $i (1..300000) {
  print pack("d<d<", rand(1), $i == 250000 ? $nan : rand(1)) }' > "$tmp/nanbig.bin"
expect_error "--max-memory: NaN in the second half" $TDC --max-memory 14 --tmpdir "$tmp/tiles" "$tmp/nanbig.bin"
check "--max-memory: NaN: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"

# text with z through the tiles: z of the first point with those x,y, as one-shot
# (more than 2^18 points: binned in two parts, the z file read in two
# ranges; the integer points' copies lie in both halves of the input)
perl -e 'srand(5); for $i (1..270000) { printf "%.17g %.17g %.17g\n", rand(100), rand(100), rand(9);
  printf "%d %d %d\n", int(rand(60)), int(rand(60)), 50 + int(rand(9)) if $i % 90 == 0 }' > "$tmp/z3.txt"
$TDC -o "$tmp/z31.out" "$tmp/z3.txt"
TDC_TILE_CHECK=1 $TDC --max-memory 16 --tmpdir "$tmp/tiles" -o "$tmp/z32.out" --stats "$tmp/z3.txt" 2> "$tmp/z32.err"
z_rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/z32.err")
check "--max-memory, text with z: tiled" "grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/z32.err"
check "--max-memory, text with z: same triangles and z" "cmp -s <(canon_d $tmp/z31.out 3) <(canon_d $tmp/z32.out 3)"
check "--max-memory 16, text with z: peak RSS ${z_rss:-?} MB under the limit" "awk 'BEGIN { exit !(\"${z_rss:-999999}\" + 0 < 16) }'"
# the same points as .xyz.bin through the tiles: the same triangles and z
perl -e 'open F, "<", $ARGV[0]; while (<F>) { @a = split; print pack("d<d<d<", @a) }' "$tmp/z3.txt" > "$tmp/z3.xyz.bin"
TDC_TILE_CHECK=1 $TDC --max-memory 16 --tmpdir "$tmp/tiles" -o "$tmp/z33.out" --stats "$tmp/z3.xyz.bin" 2> "$tmp/z33.err"
check "--max-memory, .xyz.bin: tiled" "grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/z33.err"
check "--max-memory, .xyz.bin: the one-shot triangles and z of the text" "cmp -s <(canon_d $tmp/z31.out 3) <(canon_d $tmp/z33.out 3)"
check "--max-memory, .xyz.bin: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"
# a limit below what the run holds before its first tile (read buffers, the
# counting grid, the halo index: some 12 MB here) is refused, not overrun
# (it peaked at 12.6 MB under --max-memory 10 before; under 10 the plan's
# floor, which counts the process's resident MB, refuses it first now)
expect_error "--max-memory 11, text with z: below the run's own buffers" $TDC --max-memory 11 --tmpdir "$tmp/tiles" "$tmp/z3.txt"
check "--max-memory 11: the message says what it held" "grep -qE 'below the [0-9]+ MB this run held before its first tile' $tmp/e.err"
check "--max-memory 10: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"

# adaptive tiles on clustered data (issue 28): under half of what the
# one-shot run needs, the same triangle set, the peak under the limit, in
# seconds: the Stockholm shoreline fixture with 19 jittered copies of each
# vertex, 9 tight clusters, a dense town in sparse country, a strip with
# gaps (about 300,000 points each).  TDC_TILE_CHECK: each first run's files
# hold exactly its first region (K, bands and hull cells).
perl -e 'srand(21); local $/; open(F, "<", $ARGV[0]) or die; $t = <F>; @v = ($t =~ /(-?[0-9.]+(?:e-?[0-9]+)?) (-?[0-9.]+(?:e-?[0-9]+)?)/g);
  for ($i = 0; $i < @v; $i += 2) { for $k (0..19) { print pack("d<d<", $v[$i] + ($k ? (rand() - 0.5) * 2e-4 : 0), $v[$i+1] + ($k ? (rand() - 0.5) * 2e-4 : 0)) } }' \
  "$(dirname "$0")/fixtures/gshhg-stockholm.wkt" > "$tmp/c_coast.bin"
perl -e 'srand(22); for $c (1..9) { $cx = 50 + rand(900); $cy = 50 + rand(900); for (1..35000) {
  print pack("d<d<", $cx + (rand() + rand() + rand() - 1.5) * 0.6, $cy + (rand() + rand() + rand() - 1.5) * 0.6) } }' > "$tmp/c_clusters.bin"
perl -e 'srand(23); for $i (1..310000) { print pack("d<d<", $i <= 10000 ? (rand(1000), rand(1000)) : (400 + rand(10), 600 + rand(10))) }' > "$tmp/c_town.bin"
perl -e 'srand(24); for (1..300000) { $x = rand(650); print pack("d<d<", $x < 200 ? $x : $x < 350 ? $x + 100 : $x + 350, rand(20)) }' > "$tmp/c_strip.bin"
for d in coast clusters town strip; do
	$TDC -o "$tmp/c1.out" --stats "$tmp/c_$d.bin" 2> "$tmp/c1.err"
	one_rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/c1.err")
	lim=$(awk -v r="$one_rss" 'BEGIN { printf "%d", r * 0.5 }')
	t0=$(date +%s)
	TDC_TILE_CHECK=1 $TDC --max-memory "$lim" --tmpdir "$tmp/tiles" -o "$tmp/c2.out" --stats "$tmp/c_$d.bin" 2> "$tmp/c2.err"
	rc=$?
	secs=$(( $(date +%s) - t0 ))
	til_rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/c2.err")
	check "--max-memory $lim (0.5 of one-shot $one_rss MB), $d: exit 0, tiled" "[ $rc -eq 0 ] && grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/c2.err"
	check "--max-memory $lim, $d: peak RSS ${til_rss:-?} MB under the limit" "awk 'BEGIN { exit !(\"${til_rss:-999999}\" + 0 < $lim) }'"
	check "--max-memory $lim, $d: same triangle set as one-shot" "cmp -s <(canon_d $tmp/c1.out 2) <(canon_d $tmp/c2.out 2)"
	check "--max-memory $lim, $d: $secs s, under 120 s" "[ $secs -lt 120 ]"
	# reruns read only the cells of other tiles that meet their regions
	# (bounded_cells.c): 0.3 to 6 times the input here, against 19 to 77
	# times when they read the other tiles' whole files
	reread=$(sed -n 's/.* reread_points=\([0-9]*\) .*/\1/p' "$tmp/c2.err")
	npts=$(sed -n 's/^n=\([0-9]*\) .*/\1/p' "$tmp/c2.err")
	check "--max-memory $lim, $d: reruns read ${reread:-?} points of other tiles, under 10 times the input" \
		"[ -n \"$reread\" ] && [ -n \"$npts\" ] && [ $reread -lt \$(( 10 * $npts )) ]"
	[ -n "${TDC_CLI_VERBOSE:-}" ] && echo "$d: limit $lim MB, $secs s, $(grep -oE 'peak_rss_mb=[0-9.]+ tiles=[0-9]+ halo_points=[0-9]+ tile_runs=[0-9]+' $tmp/c2.err)" >&2
done

# labels far from the origin at tiny tile sizes: 5e6 + [0, 1e-3)^2
perl -e 'srand(25); for (1..300000) { print pack("d<d<", 5e6 + rand(1e-3), 5e6 + rand(1e-3)) }' > "$tmp/far.bin"
$TDC -o "$tmp/far1.out" "$tmp/far.bin"
$TDC --max-memory 16 --tmpdir "$tmp/tiles" -o "$tmp/far2.out" --stats "$tmp/far.bin" 2> "$tmp/far2.err"
check "--max-memory, 5e6 + sub-millimetre: tiled" "grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/far2.err"
check "--max-memory, 5e6 + sub-millimetre: same triangle set" "cmp -s <(canon_d $tmp/far1.out 2) <(canon_d $tmp/far2.out 2)"

# the floor: 300,000 exact copies of one point cannot be split; the refusal
# comes before any tile, with the floor in MB and the number of copies
perl -e 'srand(26); for $i (1..301000) { print pack("d<d<", $i <= 300000 ? (5, 5) : (rand(10), rand(10))) }' > "$tmp/dup.bin"
expect_error "--max-memory below the floor (copies of one point)" $TDC --max-memory 16 --tmpdir "$tmp/tiles" "$tmp/dup.bin"
check "floor message: the floor in MB, the cell's count" "grep -qE 'below this input.s floor of [0-9]+ MB: .* holds [0-9]+ points' $tmp/e.err"
check "floor message: 300000 exact copies of (5 5)" "grep -q '300000 of them are exact copies of (5 5)' $tmp/e.err"
check "floor: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"

# when it fits, it runs as without the option
$TDC --max-memory 500 -o "$tmp/r4.out" --stats "$tmp/r.txt" 2> "$tmp/r4.err"
check "--max-memory, input fits: one tile, same output" "grep -q ' tiles=1 halo_points=0' $tmp/r4.err && cmp -s <(canon $tmp/r1.out) <(canon $tmp/r4.out)"
expect_error "bad --max-memory" $TDC --max-memory abc "$tmp/sq.txt"
expect_error "--max-memory with --tolerance" $TDC --max-memory 10 --tolerance 0.1 "$tmp/big.bin"
expect_error "--max-memory with --validate" $TDC --max-memory 10 --validate "$tmp/big.bin"
expect_error "--max-memory with --voronoi" $TDC --max-memory 10 --voronoi "$tmp/big.bin"

# --segments: constrained Delaunay; the thin rhombus gets edge (0 0)-(10 0),
# which its Delaunay triangulation lacks; crossing segments exit 1
printf '0 0\n10 0\n5 1\n5 -1\n5 5\n5 -5\n' > "$tmp/rh.txt"
printf '0 1\n' > "$tmp/rh.seg"
$TDC -o "$tmp/rh.dt" "$tmp/rh.txt"
$TDC -o "$tmp/rh.out" --segments "$tmp/rh.seg" --validate --stats "$tmp/rh.txt" 2> "$tmp/rh.err"
check "segments: exit 0" "[ $? -eq 0 ]"
check "segments: 6 triangles" "[ \$(wc -l < $tmp/rh.out) -eq 6 ]"
check "segments: the constraint is an edge" "grep -qE '(^| )0 0 10 0( |$)|(^| )10 0 0 0( |$)|^10 0 .* 0 0$|^0 0 .* 10 0$' $tmp/rh.out"
check "segments: the plain DT lacks it" "! grep -qE '(^| )0 0 10 0( |$)|(^| )10 0 0 0( |$)|^10 0 .* 0 0$|^0 0 .* 10 0$' $tmp/rh.dt"
check "segments: stats line" "grep -qE '^segments=1 constraint_edges=1 constrain=[0-9.]+ parallel=0 deferred=0 two_stripes=0$' $tmp/rh.err"
check "segments: validated" "grep -q 'constrained Delaunay' $tmp/rh.err"
printf '0 1\n2 3\n' > "$tmp/x.seg"
$TDC --segments "$tmp/x.seg" "$tmp/rh.txt" 2> "$tmp/x.err"
check "crossing segments: exit 1" "[ $? -eq 1 ]"
check "crossing segments: both named" "grep -q 'segment 0 from (0 0) to (10 0) and segment 1 from (5 1) to (5 -1)' $tmp/x.err"
printf '0 9\n' > "$tmp/bad.seg"
$TDC --segments "$tmp/bad.seg" "$tmp/rh.txt" 2> /dev/null
check "segment index out of range: exit 1" "[ $? -eq 1 ]"
expect_error "--max-memory with --segments" $TDC --max-memory 10 --segments "$tmp/rh.seg" "$tmp/big.bin"
expect_error "--segments with --voronoi" $TDC --segments "$tmp/rh.seg" --voronoi "$tmp/rh.txt"

# --contours: z = x on a 5 x 4 lattice, levels at 0.5 + k: one straight
# open line per level (7 points: it crosses 3 horizontal edges and 4
# diagonals), each vertex's x its level, higher ground (east) on the left,
# so each line runs south
perl -e 'for $x (0..4) { for $y (0..3) { print "$x $y $x\n" } }' > "$tmp/zx.txt"
$TDC --contours 1 --base 0.5 -o "$tmp/zx.out" --stats "$tmp/zx.txt" 2> "$tmp/zx.err"
check "contours: exit 0" "[ $? -eq 0 ]"
check "contours: 4 lines, levels 0.5 .. 3.5" "[ \"\$(cut -d' ' -f1 $tmp/zx.out | tr '\n' ' ')\" = '0.5 1.5 2.5 3.5 ' ]"
check "contours: every x is the level" "awk '{ for (i = 2; i < NF; i += 2) if (\$i != \$1) exit 1 }' $tmp/zx.out"
check "contours: each line from y 3 to y 0" "awk '{ if (\$3 != 3 || \$NF != 0) exit 1 }' $tmp/zx.out"
check "contours: stats line" "grep -qE '^tin=[0-9.]+ contours=[0-9.]+ lines=4 contour_points=28$' $tmp/zx.err"
# a hill: closed rings, the first point repeated
perl -e 'for $x (-10..10) { for $y (-10..10) { printf "%d %d %.17g\n", $x, $y, 100 * exp(-($x*$x + $y*$y) / 20) } }' > "$tmp/hill.txt"
$TDC --contours 20 -o "$tmp/hill.out" "$tmp/hill.txt"
check "contours: a hill gives 4 closed rings" "[ \$(wc -l < $tmp/hill.out) -eq 4 ] && awk '{ if (\$2 != \$(NF-1) || \$3 != \$NF) exit 1 }' $tmp/hill.out"
# and its vertices are the level crossings of the (lattice's, cocircular)
# Delaunay triangulation's edges, each once: the arbiter (below), which
# once only counted the rings; the peak at 100 is exactly at a level
$TDC -o "$tmp/hill.tri" "$tmp/hill.txt"
check "contours: the hill's vertices are the TIN's level crossings" \
	"$ARB contours $tmp/hill.txt $tmp/hill.tri $tmp/hill.out 0 20 > /dev/null"
$TDC -t 1 --contours 7 -o "$tmp/r1.cont" "$tmp/hill.txt"
$TDC -t 3 --contours 7 -o "$tmp/r3.cont" "$tmp/hill.txt"
check "contours: the same lines for 1 and 3 threads" "cmp -s $tmp/r1.cont $tmp/r3.cont"

# --grid: an ESRI ASCII grid; on a plane every method but nearest gives the
# plane at the pixel centres; outside the hull radius=0 gives nodata
perl -e 'srand(3); for (1..400) { $x = rand(100); $y = rand(50); printf "%.17g %.17g %.17g\n", $x, $y, 2 * $x - $y + 7 }
	for ([0,0],[100,0],[0,50],[100,50]) { printf "%d %d %d\n", $_->[0], $_->[1], 2 * $_->[0] - $_->[1] + 7 }' > "$tmp/pl.txt"
for m in linear natural_neighbor; do
	$TDC --grid 5 --method "$m" -o "$tmp/pl.$m.asc" --stats "$tmp/pl.txt" 2> "$tmp/pl.err"
	check "grid $m: exit 0" "[ $? -eq 0 ]"
	check "grid $m: header" "head -6 $tmp/pl.$m.asc | tr -s ' ' | tr '\n' ';' | grep -qx 'ncols 20;nrows 10;xllcorner 0;yllcorner 0;cellsize 5;NODATA_value 0;'"
	check "grid $m: the plane at every pixel centre" "awk 'NR > 6 { for (c = 1; c <= NF; c++) { x = (c - 0.5) * 5; y = 50 - (NR - 6 - 0.5) * 5;
		d = \$c - (2 * x - y + 7); if (d > 1e-9 || d < -1e-9) exit 1 } n++ } END { if (n != 10) exit 1 }' $tmp/pl.$m.asc"
	check "grid $m: stats line" "grep -qE '^tin=[0-9.]+ grid=[0-9.]+ pixels=200 valid=200$' $tmp/pl.err"
done
$TDC --grid 5 --extent -50,0,100,50 --method linear:radius=0:nodata=-9999 -o "$tmp/out.asc" "$tmp/pl.txt"
check "grid: outside the hull, radius=0 gives nodata" "awk 'NR > 6 { for (c = 1; c <= 10; c++) if (\$c != -9999) exit 1; if (\$11 == -9999) exit 1 }' $tmp/out.asc && grep -q '^NODATA_value -9999' $tmp/out.asc"
# nearest everywhere, outside the hull too: the brute-force nearest sample
# (build/tin_arbiter, below; this check once asked only for a value)
$TDC --grid 5 --extent -50,0,100,50 --method nearest -o "$tmp/nn.asc" "$tmp/pl.txt"
$TDC -o "$tmp/pl.tri" "$tmp/pl.txt"
check "grid: nearest is the nearest sample, inside and outside the hull" \
	"$ARB grid $tmp/pl.txt $tmp/pl.tri $tmp/nn.asc nearest > /dev/null"
$TDC -t 1 --grid 0.5 --method natural_neighbor -o "$tmp/g1.asc" "$tmp/hill.txt"
$TDC -t 3 --grid 0.5 --method natural_neighbor -o "$tmp/g3.asc" "$tmp/hill.txt"
check "grid: the same values for 1 and 3 threads" "cmp -s $tmp/g1.asc $tmp/g3.asc"
# --grid with breaklines: a ridge (0 1)-(4 1) at 10 between (2 0) at 0 and
# (2 2) at 4; the Delaunay TIN crosses it with (2 0)-(2 2), so the pixel
# centres on it (y = 1) sag to 8 4 4 8; as a breakline (--segments) they stay 10
printf '0 1 10\n4 1 10\n2 0 0\n2 2 4\n' > "$tmp/ridge.txt"
printf '0 1\n' > "$tmp/ridge.seg"
$TDC --grid 1 --extent 0,0.5,4,1.5 --method linear -o "$tmp/ridge0.asc" "$tmp/ridge.txt"
check "grid without breaklines: the ridge sags" "[ \"\$(sed -n 7p $tmp/ridge0.asc | tr -s ' ' | sed 's/ *\$//')\" = '8 4 4 8' ]"
$TDC --grid 1 --extent 0,0.5,4,1.5 --method linear:breaklines=true --segments "$tmp/ridge.seg" -o "$tmp/ridge1.asc" "$tmp/ridge.txt"
check "grid with breaklines: the ridge stays at 10" "[ \"\$(sed -n 7p $tmp/ridge1.asc | tr -s ' ' | sed 's/ *\$//')\" = '10 10 10 10' ]"

# Values against independent references (issue 36), at a projected offset:
# test/fixtures/tin-reference.txt (1,056 samples around (500000, 4000000),
# 48 breakline segments, CGAL's values at the 1,024 pixel centres of 31.25 m
# pixels).  nearest and linear against build/tin_arbiter (brute force and
# the exact Delaunay value, GMP; test/tin_arbiter.c), natural neighbour and
# breaklines against CGAL's values within 1e-9, contours against every
# crossing of the certified Delaunay triangulation's edges; a lattice for
# nearest ties and cocircular squares; a plane at the offset.
awk '/^#/ { next } /^[a-z]/ { part = $1; next }
	{ print > ("'"$tmp"'/ref." part) }' test/fixtures/tin-reference.txt
$TDC -o "$tmp/ref.tri" "$tmp/ref.samples"
refgrid() { $TDC --grid 31.25 --extent 500000,4000000,501000,4001000 "$@"; }
for m in nearest linear linear:radius=0; do
	refgrid --method "$m" -o "$tmp/ref.asc" "$tmp/ref.samples"
	check "grid $m at an offset: the arbiter's values" "$ARB grid $tmp/ref.samples $tmp/ref.tri $tmp/ref.asc $m > /dev/null"
done
# the pixels in order against column col of the queries, within 1e-9
against_cgal() {
	tail -n +7 "$1" | tr ' ' '\n' | grep . | paste - "$tmp/ref.queries" |
		awk -v col="$2" '{ d = $1 - $(col + 1); if (d > 1e-9 || d < -1e-9) bad++ } END { exit bad || NR != 1024 }'
}
refgrid --method natural_neighbor -o "$tmp/ref.nn.asc" "$tmp/ref.samples"
check "grid natural_neighbor at an offset: CGAL's values" "against_cgal $tmp/ref.nn.asc 3"
refgrid --method linear:breaklines=true --segments "$tmp/ref.segments" -o "$tmp/ref.brk.asc" "$tmp/ref.samples"
check "grid breaklines at an offset: CGAL's constrained values" "against_cgal $tmp/ref.brk.asc 4"
check "grid breaklines at an offset: not the plain TIN's" "! against_cgal $tmp/ref.nn.asc 4"
$TDC --contours 7 --base 2.5 -o "$tmp/ref.cont" "$tmp/ref.samples"
check "contours at an offset: every crossing of the Delaunay edges, once" \
	"$ARB contours $tmp/ref.samples $tmp/ref.tri $tmp/ref.cont 2.5 7 > /dev/null"
awk '{ printf "%s %s %.17g\n", $1, $2, 0.5 * ($1 - 500000) - 0.25 * ($2 - 4000000) + 100 }' "$tmp/ref.samples" > "$tmp/refpl.txt"
for m in linear natural_neighbor; do
	refgrid --method "$m" -o "$tmp/refpl.asc" "$tmp/refpl.txt"
	check "grid $m at an offset: a plane" "awk 'NR > 6 { for (c = 1; c <= NF; c++) { x = 500000 + (c - 0.5) * 31.25;
		y = 4001000 - (NR - 6 - 0.5) * 31.25; d = \$c - (0.5 * (x - 500000) - 0.25 * (y - 4000000) + 100);
		if (d > 1e-9 || d < -1e-9) exit 1 } n++ } END { if (n != 32) exit 1 }' $tmp/refpl.asc"
done
# a 12 x 12 lattice 10 m apart, then 12 of its points again with other
# heights (the first counts); pixel centres every 5 m: at the samples,
# between two (two equally near) and at the squares' centres (four)
awk 'BEGIN { for (i = 0; i < 12; i++) for (j = 0; j < 12; j++) print 500000 + 10 * i, 4000000 + 10 * j, (i * 37 + j * 91) % 50 / 4
	for (i = 0; i < 12; i += 3) for (j = 0; j < 12; j += 4) print 500000 + 10 * i, 4000000 + 10 * j, -1000 }' > "$tmp/lat.txt"
$TDC -o "$tmp/lat.tri" "$tmp/lat.txt"
for m in nearest linear; do
	$TDC --grid 5 --extent 499997.5,3999997.5,500112.5,4000112.5 --method "$m" -o "$tmp/lat.asc" "$tmp/lat.txt"
	$ARB grid "$tmp/lat.txt" "$tmp/lat.tri" "$tmp/lat.asc" "$m" >> "$tmp/lat.arb"
	check "grid $m on a lattice: the arbiter's values" "[ $? -eq 0 ]"
done
check "grid on a lattice: 385 nearest ties and cocircular triangles were there" \
	"grep -q 'nearest: 529 pixels.* 385 nearest ties' $tmp/lat.arb && grep -q 'linear: 529 pixels, 529 inside, 0 wrong.* 529 on cocircular' $tmp/lat.arb"
$ARB grid "$tmp/lat.txt" "$tmp/lat.tri" "$tmp/lat.asc" nearest > /dev/null 2>&1
check "arbiter: a linear grid is not a nearest one" "[ $? -eq 1 ]"

expect_error "--grid breaklines=true without --segments" $TDC --grid 1 --method linear:breaklines=true "$tmp/ridge.txt"
expect_error "--grid with --segments without breaklines" $TDC --grid 1 --segments "$tmp/ridge.seg" "$tmp/ridge.txt"
expect_error "--grid natural_neighbor:breaklines=true" $TDC --grid 1 --method natural_neighbor:breaklines=true --segments "$tmp/ridge.seg" "$tmp/ridge.txt"
expect_error "--contours with --segments" $TDC --contours 1 --segments "$tmp/ridge.seg" "$tmp/ridge.txt"
expect_error "--contours of x y input (no z)" $TDC --contours 1 "$tmp/sq.txt"
expect_error "--contours with --voronoi" $TDC --contours 1 --voronoi "$tmp/zx.txt"
expect_error "--contours and --grid" $TDC --contours 1 --grid 1 "$tmp/zx.txt"
expect_error "--grid with a bad method" $TDC --grid 1 --method cubic "$tmp/zx.txt"
expect_error "--grid with an elliptic nearest" $TDC --grid 1 --method nearest:radius1=1:radius2=2 "$tmp/zx.txt"
expect_error "--grid 0" $TDC --grid 0 "$tmp/zx.txt"
expect_error "--extent without --grid" $TDC --extent 0,0,1,1 "$tmp/zx.txt"
expect_error "--grid with a bad extent" $TDC --grid 1 --extent 1,0,0,1 "$tmp/zx.txt"
expect_error "--max-memory with --contours of x y input" $TDC --max-memory 10 --contours 1 "$tmp/big.bin"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
