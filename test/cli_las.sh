#!/usr/bin/env bash
# test/cli_las.sh: ./tdc's LAS input (src/cli/las.c), --class, the CRS it
# finds, its errors, LAS through --max-memory's tiles, the benchmark's
# generator (bench/gen_las.c), and a cross-check with loaders.gl.
#   bash test/cli_las.sh        (after `make tdc`; prints "N passed, N failed")
#
# The fixtures are written here by test/las_write.pl (Perl's pack, from the
# specification; no code shared with the reader).  The points' integers,
# scales and offsets are below, and so is what each point must read as,
# worked out by hand from them (X * scale + offset).
#
# loaders.gl (@loaders.gl/las, pinned below) is installed with npm into
# TDC_NPM_DIR (default ~/.cache/tdc-npm); scripts/test.sh installs node and
# npm (scripts/lib.sh, tdc_ensure_node).  Without them the cross-check is
# skipped with the reason, except under CI (CI set), where it fails.
set -u
cd "$(dirname "$0")/.."
TDC=./tdc
pass=0; fail=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }
W() { perl test/las_write.pl "$@"; }

[ -x "$TDC" ] || make -s tdc >/dev/null || { echo "cannot build ./tdc"; echo "0 passed, 1 failed"; exit 1; }
cc -O2 -o "$tmp/gen_las" bench/gen_las.c -lm || { echo "cannot build bench/gen_las.c"; echo "0 passed, 1 failed"; exit 1; }

# the distinct vertices "x y z" of -o's triangles, as %.17g
vertices() { awk '{ for (i = 1; i <= NF; i += 3) printf "%.17g %.17g %.17g\n", $i, $(i+1), $(i+2) }' "$1" | LC_ALL=C sort -u; }
# does FILE (triangles) have a vertex within 1e-6 of X Y whose z is within 1e-9 of Z?
has_point() { awk -v x="$2" -v y="$3" -v z="$4" '{ for (i = 1; i <= NF; i += 3) { dx = $i - x; dy = $(i+1) - y; dz = $(i+2) - z
	if (dx * dx + dy * dy < 1e-12 && dz * dz < 1e-18) f = 1 } } END { exit !f }' "$1"; }
kept() { sed -n 's/^las=.* kept=\([0-9]*\) .*/\1/p' "$1"; }
srs_of() { sed -n 's/^las=.* srs=//p' "$1"; }

# --- every version and point data record format ------------------------------
#
# Seven points, integers X Y Z and the classification byte C, scale
# (0.01, 0.01, 0.001), offset (500000, 4000000, 0).  The fourth corner's
# byte is 130 in formats 0 to 5: class 2 with the withheld flag (bit 7);
# the last point's byte 40 is class 40 in formats 6 to 10 and class 8 (+
# the synthetic flag, bit 5) in formats 0 to 5.  Format F adds F to the
# fifth point's X and Y and 100 F to its Z, and F mod 3 extra bytes to
# each record; versions 1.2 and 1.3 carry a GeoKey directory before the
# points and 1.3 a gap of 7 bytes after it.
fixture_points() {	# F
	local f=$1
	printf '0 0 100 2\n100000 0 200 2\n0 100000 300 2\n100000 100000 400 %d\n' $((f < 6 ? 130 : 2))
	printf '%d %d %d 5\n' $((12345 + f)) $((67890 + f)) $((1234 + 100 * f))
	printf '50000 20000 700 9\n20000 50000 800 40\n'
}
# the fifth point of format F, by hand: x = 500000 + (12345 + F) * 0.01,
# y = 4000000 + (67890 + F) * 0.01, z = (1234 + 100 F) * 0.001
expect=(
	"500123.45 4000678.9 1.234"		# format 0
	"500123.46 4000678.91 1.334"	# 1
	"500123.47 4000678.92 1.434"	# 2
	"500123.48 4000678.93 1.534"	# 3
	"500123.49 4000678.94 1.634"	# 4
	"500123.5 4000678.95 1.734"		# 5
	"500123.51 4000678.96 1.834"	# 6
	"500123.52 4000678.97 1.934"	# 7
	"500123.53 4000678.98 2.034"	# 8
	"500123.54 4000678.99 2.134"	# 9
	"500123.55 4000679 2.234"		# 10
)
# the other six points, by hand, the same in every file
others="500000 4000000 0.1|501000 4000000 0.2|500000 4001000 0.3|501000 4001000 0.4|500500 4000200 0.7|500200 4000500 0.8"
mkdir -p "$tmp/fx"
for minor in 2 3 4; do
	for f in 0 1 2 3 4 5 6 7 8 9 10; do
		las=$tmp/fx/v1${minor}_f$f.las
		opts=(scale=0.01,0.01,0.001 offset=500000,4000000,0 extra=$((f % 3)))
		((minor < 4)) && opts+=(geokeys=1024:1,3072:32632)
		((minor == 3)) && opts+=(gap=7)
		fixture_points "$f" | W "$las" "$minor" "$f" "${opts[@]}"
		name="1.$minor format $f"
		$TDC --stats -o "$tmp/o.txt" "$las" 2> "$tmp/e.txt"
		check "$name: exit 0" "[ $? -eq 0 ]"
		check "$name: 8 triangles of x y z" "[ \$(wc -l < $tmp/o.txt) -eq 8 ] && awk 'NF != 9 { exit 1 }' $tmp/o.txt"
		check "$name: the fifth point reads as ${expect[$f]}" "has_point $tmp/o.txt ${expect[$f]}"
		all=1
		IFS='|' read -ra pts <<< "$others"
		for p in "${pts[@]}"; do
			# shellcheck disable=SC2086  # "x y z"
			has_point "$tmp/o.txt" $p || all=0
		done
		check "$name: the other six points read as written" "[ $all -eq 1 ]"
		check "$name: stats line" "grep -qx 'las=1.$minor format=$f points=7 kept=7 srs=$( ((minor < 4)) && echo EPSG:32632 || echo none)' $tmp/e.txt"
		# --class: 2 keeps the corners (the withheld one too); 5,9 two
		# points; 8 and 40 the last point as its format reads its byte
		$TDC --stats --class 2 -o "$tmp/o.txt" "$las" 2> "$tmp/e.txt"
		check "$name: --class 2 keeps the 4 corners: 2 triangles" "[ \"\$(kept $tmp/e.txt)\" = 4 ] && [ \$(wc -l < $tmp/o.txt) -eq 2 ] && has_point $tmp/o.txt 501000 4001000 0.4"
		$TDC --stats --class 5,9 "$las" 2> "$tmp/e.txt"
		check "$name: --class 5,9 keeps 2" "[ \"\$(kept $tmp/e.txt)\" = 2 ]"
		$TDC --stats --class 8 "$las" 2> "$tmp/e.txt"
		check "$name: --class 8 keeps $((f < 6 ? 1 : 0)) (byte 40 & 31 in formats 0-5)" "[ \"\$(kept $tmp/e.txt)\" = $((f < 6 ? 1 : 0)) ]"
		$TDC --stats --class 40 "$las" 2> "$tmp/e.txt"
		check "$name: --class 40 keeps $((f < 6 ? 0 : 1)) (the whole byte in formats 6-10)" "[ \"\$(kept $tmp/e.txt)\" = $((f < 6 ? 0 : 1)) ]"
	done
done
# the same file under another name case, and a 1.4 file whose 64-bit count is 0 (the legacy count holds it)
cp "$tmp/fx/v12_f1.las" "$tmp/UPPER.LAS"
$TDC -o "$tmp/o.txt" "$tmp/UPPER.LAS"
check ".LAS: read as LAS" "has_point $tmp/o.txt ${expect[1]}"
fixture_points 1 | W "$tmp/c64.las" 4 1 scale=0.01,0.01,0.001 offset=500000,4000000,0 count64=0
$TDC --stats -o "$tmp/o.txt" "$tmp/c64.las" 2> "$tmp/e.txt"
check "1.4 with only the legacy count: 7 points" "[ \"\$(kept $tmp/e.txt)\" = 7 ] && has_point $tmp/o.txt ${expect[1]}"
# scale factors that are powers of two: exact, compared as text
printf '3 -5 7 2\n-8 2 1 2\n6 6 -4 2\n' | W "$tmp/p2.las" 4 6 scale=0.5,0.25,0.125 offset=-10,20,1000
$TDC -o "$tmp/o.txt" "$tmp/p2.las"
check "scale 0.5, 0.25, 0.125: -8.5 18.75 1000.875, -14 20.5 1000.125, -7 21.5 999.5" \
	"[ \"\$(vertices $tmp/o.txt | tr '\n' '|')\" = '-14 20.5 1000.125|-7 21.5 999.5|-8.5 18.75 1000.875|' ]"
# --grid on LAS: the heights of a plane z = x + 2y over four corners (1.4, format 6)
printf '0 0 0 2\n1000 0 1000 2\n0 1000 2000 2\n1000 1000 3000 2\n' | W "$tmp/pl.las" 4 6 scale=0.01,0.01,0.01
$TDC --grid 5 -o "$tmp/pl.asc" "$tmp/pl.las"
check "--grid on LAS: the plane z = x + 2y at the pixel centres" "awk 'NR > 6 { for (c = 1; c <= NF; c++) { x = (c - 0.5) * 5; y = 10 - (NR - 6 - 0.5) * 5; d = \$c - (x + 2 * y); if (d > 1e-9 || d < -1e-9) exit 1 } n++ } END { exit n != 2 }' $tmp/pl.asc"

# --- the CRS ----------------------------------------------------------------
wkt_a='PROJCS["WGS 84 / UTM zone 32N",GEOGCS["WGS 84"],AUTHORITY["EPSG","32632"]]'
wkt_b='GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]]'
crs_case() {	# name want minor format opts...
	local name=$1 want=$2
	shift 2
	fixture_points 0 | W "$tmp/crs.las" "$@"
	$TDC --stats "$tmp/crs.las" > /dev/null 2> "$tmp/e.txt"
	check "CRS, $name: $want" "[ \"\$(srs_of $tmp/e.txt)\" = \"\$want\" ]"
}
crs_case "WKT VLR" "$wkt_a" 4 6 wktbit=1 wkt="$wkt_a"
crs_case "WKT EVLR" "$wkt_b" 4 6 wktbit=1 wkt_evlr="$wkt_b"
crs_case "WKT VLR and EVLR: the EVLR, appended later" "$wkt_b" 4 6 wktbit=1 wkt="$wkt_a" wkt_evlr="$wkt_b"
crs_case "GeoKeys, ProjectedCSTypeGeoKey" "EPSG:32632" 2 1 geokeys=1024:1,3072:32632,3076:9001
crs_case "GeoKeys, GeographicTypeGeoKey alone" "EPSG:4326" 3 3 geokeys=1024:2,2048:4326
crs_case "GeoKeys, both: the projected one" "EPSG:2056" 2 0 geokeys=2048:4150,3072:2056
crs_case "GeoKeys, projected user-defined (32767): none" "none" 2 0 geokeys=3072:32767,2048:4326
crs_case "WKT bit clear, both kinds: the GeoKeys" "EPSG:32632" 4 1 geokeys=3072:32632 wkt="$wkt_b"
crs_case "WKT bit set, both kinds: the WKT" "$wkt_b" 4 1 wktbit=1 geokeys=3072:32632 wkt="$wkt_b"
crs_case "WKT bit set, only GeoKeys: the GeoKeys" "EPSG:32632" 4 1 wktbit=1 geokeys=3072:32632
crs_case "none" "none" 4 6

# --- errors: a clear message naming the file, exit 1, nothing written ---------
# (a -o file that exists keeps its contents; with --max-memory the
# temporary directory is removed)
mkdir -p "$tmp/tiles"
las_error() {	# name reason-pattern file [tdc options...]
	local name=$1 why=$2 file=$3 rc
	shift 3
	echo "keep me" > "$tmp/prev.out"
	$TDC "$@" -o "$tmp/prev.out" "$file" > /dev/null 2> "$tmp/e.err"; rc=$?
	check "$name: exit 1" "[ $rc -eq 1 ]"
	check "$name: one line naming the file and the reason" "[ \$(wc -l < $tmp/e.err) -eq 1 ] && grep -qF \"tdc: \$file: \" $tmp/e.err && grep -qE \"\$why\" $tmp/e.err"
	check "$name: the -o file untouched" "[ \"\$(cat $tmp/prev.out)\" = 'keep me' ]"
	$TDC --max-memory 64 --tmpdir "$tmp/tiles" "$@" -o "$tmp/prev.out" "$file" > /dev/null 2> "$tmp/e.err"; rc=$?
	check "$name, --max-memory: exit 1, the -o file untouched, no temporary file left" \
		"[ $rc -eq 1 ] && grep -qE \"\$why\" $tmp/e.err && [ \"\$(cat $tmp/prev.out)\" = 'keep me' ] && [ -z \"\$(ls -A $tmp/tiles)\" ]"
}
# a fixture of FORMAT in LAS 1.MINOR written with OPTS, refused for WHY
las_bad() {	# name why file minor format opts...
	local name=$1 why=$2 file=$3 format=$5
	fixture_points "$format" | W "$file" "${@:4}"
	las_error "$name" "$why" "$file"
}
las_bad "LAZ: bit 7 of the format byte" 'LAZ \(compressed LAS\).*bit 7' "$tmp/lazbit.las" 4 6 fmtbyte=134
las_bad "LAZ named .laz" 'LAZ \(compressed LAS\)' "$tmp/lazbit.laz" 4 6 fmtbyte=134
las_bad "LAZ: LASzip's VLR" "LAZ \\(compressed LAS\\).*LASzip's VLR" "$tmp/lazvlr.las" 2 1 laszip=1
las_bad "bad signature" 'not a LAS file \(no "LASF" signature\)' "$tmp/sig.las" 2 1 sig=LASX
las_bad "version 1.1" 'LAS version 1.1 is not read \(1.2 to 1.4 are\)' "$tmp/v11.las" 1 1
las_bad "version 1.5" 'LAS version 1.5 is not read' "$tmp/v15.las" 5 6
las_bad "version 2.4" 'LAS version 2.4 is not read' "$tmp/v24.las" 4 6 major=2
las_bad "format 11" 'point data record format 11 is not read \(0 to 10 are\)' "$tmp/f11.las" 4 6 fmtbyte=11
las_bad "truncated header" 'truncated header: 100 bytes' "$tmp/th.las" 2 1 truncate=100
las_bad "1.4 header cut at 300 bytes" "truncated header: 300 bytes, LAS 1.4's header has 375" "$tmp/th14.las" 4 6 truncate=300
las_bad "1.4 header size field 227" "header size field says 227 bytes, LAS 1.4's header has 375" "$tmp/hs.las" 4 6 hsize=227
las_bad "truncated points" 'truncated: the header says 7 points of 28 bytes' "$tmp/tp.las" 2 1 cut=5
las_bad "truncated VLR" 'truncated: variable length record 0' "$tmp/tv.las" 2 1 wkt="$wkt_a" truncate=260
las_bad "truncated EVLR" 'truncated: .*extended variable length record 0' "$tmp/te.las" 4 6 wktbit=1 wkt_evlr="$wkt_a" cut=3
las_bad "record length 19 under format 0's 20" "point data record length 19 is shorter than format 0's 20 bytes" "$tmp/rl.las" 2 0 reclen=19
las_bad "record length 29 under format 6's 30" "point data record length 29 is shorter than format 6's 30 bytes" "$tmp/rl6.las" 4 6 reclen=29
: > "$tmp/empty.las"
las_error "empty file" 'not a LAS file' "$tmp/empty.las"
patch_bytes() {	# file offset pack-template value: overwrite bytes in place
	perl -e 'open(F, "+<:raw", $ARGV[0]) or die; seek(F, $ARGV[1], 0); print F pack($ARGV[2], $ARGV[3]); close F' "$@"
}
fixture_points 1 | W "$tmp/vo.las" 2 1 wkt="$wkt_a"
patch_bytes "$tmp/vo.las" 96 'L<' 240
las_error "a VLR past the offset to the points" 'variable length record 0 ends at byte [0-9]+, past the offset to the point data \(240\)' "$tmp/vo.las"
fixture_points 1 | W "$tmp/gk.las" 2 1 geokeys=3072:32632
patch_bytes "$tmp/gk.las" $((227 + 54 + 6)) 'S<' 9
las_error "a GeoKey directory shorter than its keys" 'GeoKey directory of variable length record 0 \(16 bytes\) is shorter than its header and 9 keys' "$tmp/gk.las"
rm -f "$tmp/prev.out"
$TDC "$tmp/nope.las" 2> "$tmp/e.err"
check "missing .las file: exit 1, 'cannot open' and its name" "[ $? -eq 1 ] && grep -qxF 'tdc: cannot open $tmp/nope.las' $tmp/e.err"
expect_usage() {	# name args...
	local name=$1 rc
	shift
	$TDC "$@" > /dev/null 2> "$tmp/e.err"; rc=$?
	check "$name: exit 2, one line" "[ $rc -eq 2 ] && [ \$(wc -l < $tmp/e.err) -eq 1 ] && grep -q '^tdc: ' $tmp/e.err"
}
expect_usage "--class 256" --class 256 "$tmp/fx/v14_f6.las"
expect_usage "--class a" --class a "$tmp/fx/v14_f6.las"
expect_usage "--class 2," --class 2, "$tmp/fx/v14_f6.las"
expect_usage "--class ''" --class '' "$tmp/fx/v14_f6.las"
expect_usage "--class -1" --class -1 "$tmp/fx/v14_f6.las"
printf '0 0\n1 0\n0 1\n' > "$tmp/t.txt"
expect_usage "--class with text input" --class 2 "$tmp/t.txt"

# --- the generator, and LAS through --max-memory's tiles -----------------------
# 200 m at 10 points per square metre: about 388,000 points, one return per
# cell of a 0.316 m grid, but none in the lake
"$tmp/gen_las" -s 7 200 "$tmp/g.las" 2> "$tmp/gen.err"
"$tmp/gen_las" -s 7 200 "$tmp/g2.las" 2> /dev/null
check "gen_las: the same file from the same seed" "cmp -s $tmp/g.las $tmp/g2.las"
$TDC --stats -o "$tmp/g1.out" "$tmp/g.las" 2> "$tmp/g1.err"
n=$(sed -n 's/^las=1.4 format=6 points=\([0-9]*\) .*/\1/p' "$tmp/g1.err")
check "gen_las: 1.4 format 6, 10 points per square metre less the lake's 3% (${n:-?})" "[ -n \"$n\" ] && [ $n -gt 384000 ] && [ $n -lt 392000 ]"
check "gen_las: CRS EPSG:32632 as WKT" "grep -q '^las=.* srs=PROJCS\\[\"WGS 84 / UTM zone 32N\".*AUTHORITY\\[\"EPSG\",\"32632\"\\]\\]$' $tmp/g1.err"
sum=0
for c in 2 5 6; do
	$TDC --stats --class $c "$tmp/g.las" 2> "$tmp/e.txt" > /dev/null
	k=$(kept "$tmp/e.txt")
	check "gen_las: class $c has points (${k:-?})" "[ -n \"$k\" ] && [ $k -gt 1000 ]"
	sum=$((sum + ${k:-0}))
done
check "gen_las: classes 2, 5 and 6 are all its points" "[ $sum -eq ${n:-0} ]"
check "gen_las: its counts on stderr" "grep -q '^gen_las: $n points: ' $tmp/gen.err"
check "gen_las: no point in the lake (the ellipse at (0.3, 0.6) x 200 m, radii 24 m and 16 m)" \
	"! awk '{ for (i = 1; i <= NF; i += 3) { dx = (\$i - 500060) / 24; dy = (\$(i+1) - 5200120) / 16; if (dx * dx + dy * dy < 1) exit 1 } }' $tmp/g1.out"
# the triangle over the lake's middle has its corners on the shore
check "gen_las: the lake is a hole: the triangle over its middle spans it" \
	"awk 'function side(i, j) { return (\$i - 500060) * (\$(j+1) - 5200120) - (\$(i+1) - 5200120) * (\$j - 500060) }
		{ a = side(1, 4); b = side(4, 7); c = side(7, 1); if (!(a >= 0 && b >= 0 && c >= 0)) next; found++
		  for (i = 1; i <= NF; i += 3) { dx = (\$i - 500060) / 24; dy = (\$(i+1) - 5200120) / 16; if (dx * dx + dy * dy < 0.99) exit 1 } }
		END { exit found != 1 }' $tmp/g1.out"
canon_d() { awk -v d="$2" '{ best = 0; for (k = 1; k < 3; k++) if ($(d*k+1) < $(d*best+1) || ($(d*k+1) == $(d*best+1) && $(d*k+2) < $(d*best+2))) best = k;
  s = ""; for (k = 0; k < 3; k++) { j = (best + k) % 3; for (c = 1; c <= d; c++) s = s $(d*j+c) " " } print s }' "$1" | LC_ALL=C sort; }
TDC_TILE_CHECK=1 $TDC --max-memory 20 --tmpdir "$tmp/tiles" --stats -o "$tmp/g2.out" "$tmp/g.las" 2> "$tmp/g2.err"
check "LAS, --max-memory 20: exit 0, tiled" "[ $? -eq 0 ] && grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/g2.err"
rss=$(sed -n 's/.*peak_rss_mb=\([0-9.]*\).*/\1/p' "$tmp/g2.err")
check "LAS, --max-memory 20: peak RSS ${rss:-?} MB under the limit" "awk 'BEGIN { exit !(\"${rss:-999}\" + 0 < 20) }'"
check "LAS, --max-memory 20: the one-shot triangles and z" "cmp -s <(canon_d $tmp/g1.out 3) <(canon_d $tmp/g2.out 3)"
check "LAS, --max-memory 20: the same las= line" "[ \"\$(grep '^las=' $tmp/g1.err)\" = \"\$(grep '^las=' $tmp/g2.err)\" ]"
check "LAS, --max-memory: temporary files removed" "[ -z \"\$(ls -A $tmp/tiles)\" ]"
$TDC --class 2 -o "$tmp/g3.out" "$tmp/g.las"
$TDC --class 2 --max-memory 18 --tmpdir "$tmp/tiles" --stats -o "$tmp/g4.out" "$tmp/g.las" 2> "$tmp/g4.err"
check "LAS --class 2, --max-memory 18: tiled, the one-shot triangles and z" \
	"grep -qE ' tiles=([2-9]|[1-9][0-9]+) ' $tmp/g4.err && cmp -s <(canon_d $tmp/g3.out 3) <(canon_d $tmp/g4.out 3)"
$TDC --max-memory 500 -o "$tmp/g5.out" "$tmp/g.las"
check "LAS, --max-memory 500 (fits): the same output as without" "cmp -s $tmp/g1.out $tmp/g5.out"
# the LAS file's CRS reaches a GeoTIFF (--grid -o .tif): its WKT, unless
# --srs overrides it; the pixels are those of the .asc
if command -v gdalsrsinfo > /dev/null; then
	$TDC --class 2 --grid 4 -o "$tmp/g.tif" "$tmp/g.las" 2> "$tmp/gt.err"
	check "LAS to GeoTIFF: exit 0, no warning about a missing CRS" "[ $? -eq 0 ] && [ ! -s $tmp/gt.err ]"
	check "LAS to GeoTIFF: the file's CRS, EPSG:32632" \
		"gdalsrsinfo -o epsg $tmp/g.tif 2> /dev/null | grep -qx 'EPSG:32632'"
	$TDC --class 2 --grid 4 --srs EPSG:25832 -o "$tmp/g2.tif" "$tmp/g.las"
	check "LAS to GeoTIFF: --srs overrides the file's CRS" \
		"gdalsrsinfo -o epsg $tmp/g2.tif 2> /dev/null | grep -qx 'EPSG:25832'"
	$TDC --class 2 --grid 4 -o "$tmp/g.asc" "$tmp/g.las"
	gdal_translate -q -of AAIGrid -co DECIMAL_PRECISION=17 --config AAIGRID_DATATYPE Float64 "$tmp/g.tif" "$tmp/gt.asc"
	check "LAS to GeoTIFF: the .asc's pixels" \
		"cmp -s <(tail -n +7 $tmp/g.asc | tr -s ' ' '\n' | grep . | awk '{ printf \"%.17g\\n\", \$1 }') \
				<(tail -n +7 $tmp/gt.asc | tr -s ' ' '\n' | grep . | awk '{ printf \"%.17g\\n\", \$1 }')"
else
	bad "LAS to GeoTIFF: gdalsrsinfo (gdal-bin) is not installed"
fi
# a 1.2 file of format 1 with GeoKeys
"$tmp/gen_las" -s 8 -f 1 -v 2 60 "$tmp/g12.las" 2> /dev/null
$TDC --stats -o "$tmp/g12.out" "$tmp/g12.las" 2> "$tmp/e.txt"
check "gen_las -f 1 -v 2: LAS 1.2 format 1, CRS EPSG:32632 from its GeoKeys" "grep -qE '^las=1.2 format=1 points=[0-9]+ kept=[0-9]+ srs=EPSG:32632$' $tmp/e.txt"

# --- loaders.gl reads the same x y z ----------------------------------------
LOADERSGL=4.5.1
npm_dir=${TDC_NPM_DIR:-${XDG_CACHE_HOME:-${HOME:-/tmp}/.cache}/tdc-npm}/loaders.gl-$LOADERSGL
why=""
if ! command -v node > /dev/null 2>&1 || ! command -v npm > /dev/null 2>&1; then
	why="node and npm are not installed (Debian: apt-get install nodejs npm; make test installs them)"
elif [ ! -f "$npm_dir/node_modules/@loaders.gl/las/package.json" ]; then
	mkdir -p "$npm_dir" && echo '{ "private": true }' > "$npm_dir/package.json"
	if ! (cd "$npm_dir" && timeout 300 npm install --no-audit --no-fund --loglevel=error "@loaders.gl/las@$LOADERSGL") > "$tmp/npm.log" 2>&1; then
		why="npm install @loaders.gl/las@$LOADERSGL failed: $(tail -n 1 "$tmp/npm.log")"
		rm -rf "$npm_dir"
	fi
fi
if [ -n "$why" ]; then
	if [ -n "${CI:-}" ]; then
		bad "loaders.gl cross-check not run: $why"
	else
		echo "skipped: the loaders.gl cross-check: $why"
	fi
else
	mkdir -p "$tmp/lg"
	# the public LASLoader: 1.2 and 1.3, formats 0 to 3; the laz-rs parser: all
	for parser in laz-perf laz-rs; do
		if [ $parser = laz-perf ]; then
			node test/las_loadersgl.mjs "$npm_dir" $parser "$tmp/lg" "$tmp"/fx/v1[23]_f[0-3].las "$tmp/g12.las" 2> "$tmp/lg.err"
		else
			node test/las_loadersgl.mjs "$npm_dir" $parser "$tmp/lg" "$tmp"/fx/*.las "$tmp/g12.las" "$tmp/g.las" 2> "$tmp/lg.err"
		fi
		rc=$?
		check "loaders.gl ($parser): ran" "[ $rc -eq 0 ]"
		((rc == 0)) || cat "$tmp/lg.err" >&2
	done
	# loaders.gl's points, the first of each x y kept (as ./tdc keeps the
	# first z), against the vertices of ./tdc's triangles
	first_xy() { awk '{ k = sprintf("%.17g %.17g", $1, $2); if (!(k in s)) { s[k] = 1; printf "%s %.17g\n", k, $3 } }' "$1" | LC_ALL=C sort; }
	for t in "$tmp"/lg/*.txt; do
		b=$(basename "$t"); las=${b%.*.txt}; parser=${b%.txt}; parser=${parser##*.}
		src=$tmp/fx/$las; [ -f "$src" ] || src=$tmp/$las
		$TDC -o "$tmp/o.txt" "$src"
		check "loaders.gl ($parser) and ./tdc read the same x y z: $las ($(wc -l < "$t") points)" \
			"[ -s $t ] && cmp -s <(first_xy $t) <(vertices $tmp/o.txt)"
	done
	check "loaders.gl: 9 files read by LASLoader, 35 by laz-rs" \
		"[ \$(ls $tmp/lg/*.laz-perf.txt | wc -l) -eq 9 ] && [ \$(ls $tmp/lg/*.laz-rs.txt | wc -l) -eq 35 ]"
fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
