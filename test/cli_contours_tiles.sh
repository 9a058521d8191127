#!/usr/bin/env bash
# test/cli_contours_tiles.sh: ./tdc --contours under --max-memory (issue
# 39, point 2): when the one-shot run does not fit, each tile's final
# triangles are cut into pieces of contour lines, joined after the last
# tile, and the -o file is the one-shot file, byte for byte, with many
# tiles and the peak under the limit.
#   - uniform samples on hills: intervals and bases, max_edge, 1 thread;
#   - synthetic LiDAR (bench/gen_las.c) with --class 2: the lake and the
#     buildings' holes, max_edge;
#   - the GSHHG coastline of Stockholm (test/fixtures): real clustered
#     data, under a tight limit;
#   - --stats' counts the same as the one-shot's; --tmpdir left empty; an
#     interval too small refused with the one-shot's message and no -o;
#     SIGINT in the middle leaves no file behind.
#   bash test/cli_contours_tiles.sh        (prints "N passed, N failed")
set -u
cd "$(dirname "$0")/.."
TDC=./tdc
pass=0; fail=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }

[ -x "$TDC" ] || make -s tdc >/dev/null || { echo "cannot build ./tdc"; echo "0 passed, 1 failed"; exit 1; }
mkdir -p "$tmp/t"

stat_of() { grep -oE "(^| )$2=[0-9.]+" "$1" | head -n 1 | sed 's/.*=//'; }

# contour_case NAME LIMIT_MB MIN_TILES INPUT ARGS...: the one-shot lines and
# the lines in tiles, compared
contour_case() {
	local name=$1 limit=$2 mintiles=$3 input=$4; shift 4
	rm -f "$tmp/one.txt" "$tmp/til.txt"
	$TDC "$@" -o "$tmp/one.txt" --stats "$input" 2> "$tmp/one.err"
	check "$name: the one-shot lines (exit 0)" "[ $? -eq 0 ] && [ -s $tmp/one.txt ]"
	$TDC --max-memory "$limit" --tmpdir "$tmp/t" "$@" -o "$tmp/til.txt" --stats "$input" 2> "$tmp/til.err"
	check "$name: the lines in tiles (exit 0)" "[ $? -eq 0 ] && [ -s $tmp/til.txt ]"
	local tiles peak
	tiles=$(stat_of "$tmp/til.err" tiles)
	peak=$(stat_of "$tmp/til.err" peak_rss_mb)
	check "$name: in tiles ($tiles, at least $mintiles)" "[ -n '$tiles' ] && [ '$tiles' -ge $mintiles ]"
	# tiles two at a time where the case asks for it (want_workers=2: two
	# threads and a budget that dwarfs a second worker's scratch), else one
	local workers want=${want_workers:-1}
	workers=$(stat_of "$tmp/til.err" workers)
	[ "$(nproc)" -ge 2 ] || want=1
	check "$name: $workers tile workers ($want expected)" "[ '$workers' = $want ]"
	check "$name: peak RSS $peak MB under --max-memory $limit" "awk 'BEGIN { exit !(\"$peak\" + 0 > 0 && \"$peak\" + 0 < $limit) }'"
	check "$name: the same counts in --stats" \
		"[ \"\$(grep -oE 'lines=[0-9]+ contour_points=[0-9]+' $tmp/one.err)\" = \"\$(grep -oE 'lines=[0-9]+ contour_points=[0-9]+' $tmp/til.err)\" ]"
	check "$name: the same -o, byte for byte ($(wc -l < "$tmp/one.txt") lines)" "cmp -s $tmp/one.txt $tmp/til.txt"
	check "$name: --tmpdir left empty" "[ -z \"\$(ls -A $tmp/t)\" ]"
}

# Uniform samples on hills, 2 km square, z to the millimetre
awk 'BEGIN { srand(39); for (i = 0; i < 240000; i++) { x = 2000 * rand(); y = 2000 * rand();
	printf "%.3f %.3f %.3f\n", x, y, 100 + 40 * sin(x / 170) * cos(y / 130) + rand() } }' > "$tmp/hills.txt"
contour_case "hills, every 5" 18 12 "$tmp/hills.txt" --contours 5
contour_case "hills, every 0.5 from 0.25" 18 12 "$tmp/hills.txt" --contours 0.5 --base 0.25
contour_case "hills, max_edge=9" 18 12 "$tmp/hills.txt" --contours 2 --method linear:max_edge=9
contour_case "hills, 1 thread" 18 12 "$tmp/hills.txt" -t 1 --contours 3
# two tiles at once (src/core/tiles/bounded_share.c): the same lines, under the limit
want_workers=2
contour_case "hills, two tiles at once" 30 8 "$tmp/hills.txt" --contours 3
want_workers=

# Synthetic LiDAR: the ground (class 2) of 250 m x 250 m at 10 points a square metre
cc -O2 -o "$tmp/gen_las" bench/gen_las.c -lm || bad "cannot build bench/gen_las.c"
"$tmp/gen_las" -s 11 250 "$tmp/site.las" 2> /dev/null
contour_case "LiDAR ground, every 0.5 m" 16 20 "$tmp/site.las" --class 2 --contours 0.5
contour_case "LiDAR ground, max_edge=5" 16 20 "$tmp/site.las" --class 2 --contours 0.25 --method linear:max_edge=5

# The coastline of Stockholm (GSHHG): its vertices and 7 points between each
# two, heights from a smooth function (130,000 points along the shores)
perl -e 'local $/; $_ = <>; while (/\(([^()]+)\)/g) { my @p = map { [split / /] } split /,/, $1;
	for my $i (0 .. $#p - 1) { my ($a, $b) = @p[$i, $i + 1]; for my $k (0 .. 7) { my $t = $k / 8;
	printf "%.10f %.10f\n", $a->[0] + $t * ($b->[0] - $a->[0]), $a->[1] + $t * ($b->[1] - $a->[1]); } } }' \
	test/fixtures/gshhg-stockholm.wkt |
	awk '!seen[$1 " " $2]++ { printf "%s %s %.6f\n", $1, $2, 10 * sin($1 * 40) + 5 * cos($2 * 60) }' > "$tmp/coast.txt"
contour_case "GSHHG Stockholm, a tight limit" 16 8 "$tmp/coast.txt" --contours 1
contour_case "GSHHG Stockholm, max_edge=0.01" 16 8 "$tmp/coast.txt" --contours 2 --method linear:max_edge=0.01

# An interval too small: the one-shot's message, no -o, nothing left
rm -f "$tmp/r.out"
$TDC --contours 1e-15 -o "$tmp/r.out" "$tmp/hills.txt" > /dev/null 2> "$tmp/one.err"
$TDC --max-memory 18 --tmpdir "$tmp/t" --contours 1e-15 -o "$tmp/r.out" "$tmp/hills.txt" > /dev/null 2> "$tmp/r.err"
check "a tiny interval in tiles: exit 1" "[ $? -eq 1 ]"
check "a tiny interval: the one-shot's message" "grep -q 'too small' $tmp/r.err && cmp -s $tmp/one.err $tmp/r.err"
check "a tiny interval: no -o written" "[ ! -e $tmp/r.out ]"
check "a tiny interval: --tmpdir left empty" "[ -z \"\$(ls -A $tmp/t)\" ]"

# SIGINT in the middle of contours in tiles: no temporary file, no partial output
awk 'BEGIN { srand(5); for (i = 0; i < 1500000; i++) printf "%.3f %.3f %.2f\n", 5000 * rand(), 5000 * rand(), 100 * rand() }' > "$tmp/big.txt"
$TDC --max-memory 40 --tmpdir "$tmp/t" --contours 10 -o "$tmp/big.txt.out" "$tmp/big.txt" 2> /dev/null &
pid=$!
sleep 2
kill -INT $pid 2> /dev/null
wait $pid
st=$?
check "SIGINT: the run stopped (status $st)" "[ $st -ne 0 ]"
check "SIGINT: --tmpdir left empty" "[ -z \"\$(ls -A $tmp/t)\" ]"
check "SIGINT: no partial output" "[ ! -e $tmp/big.txt.out ]"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
