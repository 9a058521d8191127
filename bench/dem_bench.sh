#!/usr/bin/env bash
# bench/dem_bench.sh -- LiDAR to a DEM with ./tdc: against gdal_grid, and in
# tiles against its one pass.  A program that prints figures; its checks
# of the answers are part of its report.
#
# The data: synthetic airborne LiDAR (bench/gen_las.c: hills, a lake with
# no returns, buildings with no ground under them, woods), its ground
# (class 2) at about 7.8 points a square metre, in UTM 32N (E 500000,
# N 5200000: the projected offsets where floating-point TINs go wrong).
#
#   A. gdal_grid -a linear against ./tdc --grid, into the same 1 m grid,
#      for each BENCH_DEM_SIZES ground count (1e6 1e7): both read the same
#      points as text (GDAL through an OGR VRT of a CSV file, ./tdc the
#      'x y z' lines, %.17g: the same doubles), both write a Float64
#      GeoTIFF, whole processes timed by GNU time.  linear:radius=0 for
#      both: GDAL's fallback outside the hull is not its nearest sample,
#      so only the hull is compared.  ./tdc from the LAS file itself
#      (--class 2) is timed too.  Then every pixel is compared, and
#      ./tdc's grid is judged by the exact arbiter (test/tin_arbiter.c:
#      each pixel centre in a triangle whose circumcircle holds no sample,
#      in rational arithmetic, the value within 1e-9 of the exact one), so
#      a pixel where GDAL differs from ours by more than that is GDAL's
#      error, but where the arbiter finds the pixel's triangle cocircular
#      with a fourth sample (another Delaunay triangle is as right there)
#      (BENCH_DEM_ARBITER_MAX: the largest size judged, 2e7; 1e7 takes
#      some 4 minutes, untimed).
#   B. ./tdc --max-memory on the largest size's ground into the 1 m DEM
#      (linear:max_edge=5: the lake and the buildings' footprints are
#      nodata; outside the hull the nearest sample, from the tiles' fringe),
#      at a limit that forces at least 20 tiles (BENCH_DEM_LIMIT, 150),
#      against its one pass: wall, CPU, peak RSS, tiles, and the pixels
#      compared (GDAL's raw Float64, byte for byte).  Its hillshade
#      (gdaldem) with ./tdc's 2 m contour lines of the same ground burnt in
#      (gdal_rasterize) is docs/benchmarks/dem.png.
#   (A billion returns, the full survey: bench/dem_big_bench.sh.)
#
# Output: stdout, build/bench/dem.txt, docs/benchmarks/dem.md.
# Knobs: BENCH_DEM_SIZES, BENCH_DEM_ROUNDS (3: medians; gdal_grid runs
# once from 5e6 points), BENCH_DEM_LIMIT, BENCH_DEM_PREPARE_ONLY=1 (the
# data only, no timing),
# BENCH_DEM_TMP (build/bench/dem).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

SIZES=${BENCH_DEM_SIZES:-"1e6 1e7"}
ROUNDS=${BENCH_DEM_ROUNDS:-3}
LIMIT=${BENCH_DEM_LIMIT:-150}
ARB_MAX=$(n_of "${BENCH_DEM_ARBITER_MAX:-2e7}")
WORK=${BENCH_DEM_TMP:-$BENCH_OUT/dem}
TXT=$BENCH_OUT/dem.txt
mkdir -p "$WORK" "$BENCH_OUT"

for t in gdal_grid gdal_translate gdalinfo; do
	command -v $t >/dev/null || ensure_debs gdal-bin
done
PY=/usr/bin/python3	# Debian's, with python3-numpy (not a python3 earlier in PATH)
$PY -c 'import numpy' 2>/dev/null || ensure_debs python3-numpy
bench_tdc_copy
command -v gcc >/dev/null || die "gcc not found"
[ -f /usr/include/gmp.h ] || ensure_debs libgmp-dev
ARB=$WORK/tin_arbiter
gcc -O2 -o "$ARB" "$ROOT/test/tin_arbiter.c" -lgmp -lm || die "cannot build the arbiter"

# the ground's side for N points: gen_las gives about 7.8 ground points a square metre
side_of() { awk -v n="$1" 'BEGIN { printf "%.0f\n", sqrt(n / 7.8) }'; }

# las_ground LAS TXT: the class-2 points of a LAS file as 'x y z' lines, the
# doubles ./tdc computes from it (X * scale + offset), %.17g
las_ground() {
	$PY - "$1" "$2" <<'EOF'
import struct, sys
import numpy as np
src, dst = sys.argv[1], sys.argv[2]
with open(src, 'rb') as f:
    h = f.read(375)
off, = struct.unpack_from('<I', h, 96)
fmt = h[104] & 0x3f
reclen, = struct.unpack_from('<H', h, 105)
n, = struct.unpack_from('<Q', h, 247) if h[25] >= 4 else struct.unpack_from('<I', h, 107)
scale = struct.unpack_from('<3d', h, 131)
offset = struct.unpack_from('<3d', h, 155)
raw = np.memmap(src, dtype=np.uint8, mode='r', offset=off, shape=(n, reclen))
cls = raw[:, 16] if fmt >= 6 else raw[:, 15] & 31
keep = cls == 2
xyz = np.ascontiguousarray(raw[keep][:, 0:12]).view('<i4').reshape(-1, 3).astype(np.float64)
for k in range(3):
    xyz[:, k] = xyz[:, k] * scale[k] + offset[k]
with open(dst, 'w') as out:
    for i in range(0, len(xyz), 1 << 20):
        out.write('\n'.join('%r %r %r' % tuple(p) for p in xyz[i:i + (1 << 20)].tolist()))
        out.write('\n')
print(len(xyz))
EOF
}

# timed LABEL CMD...: one whole-process run; appends "LABEL wall cpu rss_mb" to $RUNS
timed() {
	local label=$1; shift
	/usr/bin/time -f "%e %U %S %M" -o "$WORK/time.out" "$@" > "$WORK/cmd.out" 2> "$WORK/cmd.err" ||
		{ cat "$WORK/cmd.err" >&2; die "$label failed"; }
	awk -v l="$label" '{ printf "%s %.3f %.3f %.1f\n", l, $1, $2 + $3, $4 / 1024 }' "$WORK/time.out" | tee -a "$RUNS" >&2
}

# raw TIF OUT: its pixels as raw Float64
raw() { gdal_translate -q -of ENVI "$1" "$2"; }

RUNS=$WORK/runs.txt
: > "$RUNS"
: > "$TXT"
declare -A EXT NPTS
largest=""
for s in $SIZES; do
	n=$(n_of "$s")
	side=$(side_of "$n")
	las=$WORK/ground_$s.las
	pts=$WORK/ground_$s.xyz
	[ -s "$las" ] || { log "generating $las (side $side m)"; "$BENCH_BIN/gen_las" -s 1 "$side" "$las" 2> /dev/null; }
	if [ ! -s "$pts" ]; then
		log "its ground as text: $pts"
		las_ground "$las" "$pts" > "$WORK/count.out"
	fi
	NPTS[$s]=$(wc -l < "$pts")
	{ echo x,y,z; tr ' ' , < "$pts"; } > "$WORK/ground_$s.csv"
	cat > "$WORK/ground_$s.vrt" <<EOF
<OGRVRTDataSource><OGRVRTLayer name="ground_$s"><SrcDataSource>$WORK/ground_$s.csv</SrcDataSource>
<GeometryType>wkbPoint</GeometryType><GeometryField encoding="PointFromColumns" x="x" y="y" z="z"/>
</OGRVRTLayer></OGRVRTDataSource>
EOF
	# the grid: 1 m pixels from the whole metre below the box, covering it
	EXT[$s]=$(awk 'NR == 1 { x0 = x1 = $1; y0 = y1 = $2 } { if ($1 < x0) x0 = $1; if ($1 > x1) x1 = $1; if ($2 < y0) y0 = $2; if ($2 > y1) y1 = $2 }
		END { a = int(x0); b = int(y0); w = int(x1 - a) + 1; h = int(y1 - b) + 1; printf "%d %d %d %d\n", a, b, w, h }' "$pts")
	largest=$s
done

[ "${BENCH_DEM_PREPARE_ONLY:-0}" = 1 ] && { log "the data is ready in $WORK"; exit 0; }

bench_begin
# A: gdal_grid against ./tdc, rounds interleaved (gdal_grid once from 5e6 points: minutes a run)
for s in $SIZES; do
	read -r x0 y0 w h <<< "${EXT[$s]}"
	for ((r = 1; r <= ROUNDS; r++)); do
		log "A $s round $r"
		[ "$r" -gt 1 ] && [ "${NPTS[$s]}" -ge 5000000 ] ||
		timed "gdal_$s" gdal_grid -q -a linear:radius=0:nodata=-9999 -ot Float64 -txe "$x0" $((x0 + w)) \
			-tye "$y0" $((y0 + h)) -outsize "$w" "$h" "$WORK/ground_$s.vrt" "$WORK/gdal_$s.tif"
		timed "tdc_$s" "$TDC_BIN" --grid 1 --extent "$x0,$y0,$((x0 + w)),$((y0 + h))" \
			--method linear:radius=0:nodata=-9999 --srs EPSG:32632 -o "$WORK/tdc_$s.tif" "$WORK/ground_$s.xyz"
		timed "tdclas_$s" "$TDC_BIN" --class 2 --grid 1 --extent "$x0,$y0,$((x0 + w)),$((y0 + h))" \
			--method linear:radius=0:nodata=-9999 -o "$WORK/tdclas_$s.tif" "$WORK/ground_$s.las"
	done
done
# B: the largest size in tiles against its one pass
read -r x0 y0 w h <<< "${EXT[$largest]}"
for ((r = 1; r <= ROUNDS; r++)); do
	log "B $largest round $r"
	timed "oneshot_$largest" "$TDC_BIN" --stats --grid 1 --method linear:max_edge=5:nodata=-9999 --srs EPSG:32632 \
		-o "$WORK/one_$largest.tif" "$WORK/ground_$largest.xyz"
	timed "tiles_$largest" "$TDC_BIN" --stats --max-memory "$LIMIT" --tmpdir "$WORK" --grid 1 \
		--method linear:max_edge=5:nodata=-9999 --srs EPSG:32632 -o "$WORK/til_$largest.tif" "$WORK/ground_$largest.xyz"
	cp "$WORK/cmd.err" "$WORK/tiles_stats.txt"
done
bench_end

# The checks (untimed)
{
	printf 'Synthetic LiDAR ground (bench/gen_las.c, class 2), 1 m pixels, linear:radius=0:nodata=-9999; whole processes (GNU time), medians of %s rounds (gdal_grid: one run from 5,000,000 points).\n\n' "$ROUNDS"
	printf '| ground points | pixels | gdal_grid -a linear | ./tdc --grid (same text) | gdal_grid / ./tdc | ./tdc from the LAS file | pixels where GDAL differs from ours (beyond 1e-9 relative) |\n|--:|--:|--:|--:|--:|--:|--:|\n'
} >> "$TXT"
for s in $SIZES; do
	read -r x0 y0 w h <<< "${EXT[$s]}"
	g=$(grep "^gdal_$s " "$RUNS" | awk '{ print $2 }' | median)
	t=$(grep "^tdc_$s " "$RUNS" | awk '{ print $2 }' | median)
	l=$(grep "^tdclas_$s " "$RUNS" | awk '{ print $2 }' | median)
	raw "$WORK/gdal_$s.tif" "$WORK/gdal_$s.raw"
	raw "$WORK/tdc_$s.tif" "$WORK/tdc_$s.raw"
	cmp=$($PY - "$WORK/gdal_$s.raw" "$WORK/tdc_$s.raw" <<'EOF'
import sys
import numpy as np
g = np.fromfile(sys.argv[1], dtype='<f8')
t = np.fromfile(sys.argv[2], dtype='<f8')
nd = (g == -9999) != (t == -9999)
both = (g != -9999) & (t != -9999)
d = np.abs(g - t) > 1e-9 * (1 + np.abs(t))
print(int(np.count_nonzero(d & both)), int(np.count_nonzero(nd)), int(np.count_nonzero(both)),
      '%.3g' % float(np.max(np.abs(g - t)[both])) if both.any() else '0')
EOF
)
	read -r ndiff nnd nboth maxd <<< "$cmp"
	arb="not judged (over $ARB_MAX points)"
	if [ "${NPTS[$s]}" -le "$ARB_MAX" ]; then
		log "the arbiter on $s"
		"$TDC_BIN" -o "$WORK/tri_$s.txt" "$WORK/ground_$s.xyz"
		"$TDC_BIN" --grid 1 --extent "$x0,$y0,$((x0 + w)),$((y0 + h))" --method linear:radius=0:nodata=-9999 \
			-o "$WORK/tdc_$s.asc" "$WORK/ground_$s.xyz"
		if "$ARB" grid "$WORK/ground_$s.xyz" "$WORK/tri_$s.txt" "$WORK/tdc_$s.asc" linear:radius=0 > "$WORK/arb_$s.txt" 2>&1; then
			arb="ours is the exact Delaunay value at every pixel, so each pixel where GDAL differs is GDAL's error, but for those on cocircular triangles ($(tr '\n' ' ' < "$WORK/arb_$s.txt" | cut -c1-200))"
		else
			arb="THE ARBITER REJECTS OURS: $(tr '\n' ' ' < "$WORK/arb_$s.txt" | cut -c1-300)"
		fi
		rm -f "$WORK/tri_$s.txt" "$WORK/tdc_$s.asc"
	fi
	printf '| %s | %s | %s s | %s s | %sx | %s s | %s (of %s in the hull; largest difference %s m) |\n' \
		"$(thousands "${NPTS[$s]}")" "$(thousands $((w * h)))" "$g" "$t" "$(awk -v a="$g" -v b="$t" 'BEGIN { printf "%.1f", a / b }')" \
		"$l" "$(thousands "$ndiff")" "$(thousands "$nboth")" "$maxd" >> "$TXT"
	printf -- '- %s: %s pixels where one has nodata and the other not; the arbiter: %s\n' "$(thousands "${NPTS[$s]}")" "$nnd" "$arb" >> "$TXT.notes"
done
cat "$TXT.notes" >> "$TXT"; rm -f "$TXT.notes"

o=$(grep "^oneshot_$largest " "$RUNS" | awk '{ print $2 }' | median)
oc=$(grep "^oneshot_$largest " "$RUNS" | awk '{ print $3 }' | median)
orss=$(grep "^oneshot_$largest " "$RUNS" | awk '{ print $4 }' | median)
t=$(grep "^tiles_$largest " "$RUNS" | awk '{ print $2 }' | median)
tc=$(grep "^tiles_$largest " "$RUNS" | awk '{ print $3 }' | median)
trss=$(grep "^tiles_$largest " "$RUNS" | awk '{ print $4 }' | median)
tiles=$(grep -oE ' tiles=[0-9]+' "$WORK/tiles_stats.txt" | cut -d= -f2)
runs=$(grep -oE ' tile_runs=[0-9]+' "$WORK/tiles_stats.txt" | cut -d= -f2)
workers=$(grep -oE ' workers=[0-9]+' "$WORK/tiles_stats.txt" | cut -d= -f2)
raw "$WORK/one_$largest.tif" "$WORK/one.raw"
raw "$WORK/til_$largest.tif" "$WORK/til.raw"
same=$(cmp -s "$WORK/one.raw" "$WORK/til.raw" && echo "the same pixels, byte for byte" || echo "PIXELS DIFFER")
{
	printf '\nThe %s ground points in tiles (--max-memory %s) against one pass, the same 1 m grid, linear:max_edge=5:nodata=-9999:\n\n' "$(thousands "${NPTS[$largest]}")" "$LIMIT"
	printf '| run | wall | CPU | peak RSS | tiles / runs | tiles at once |\n|---|--:|--:|--:|--:|--:|\n'
	printf '| one pass | %s s | %s s | %s MB | | |\n' "$o" "$oc" "$orss"
	printf '| `--max-memory %s` | %s s | %s s | %s MB | %s / %s | %s |\n' "$LIMIT" "$t" "$tc" "$trss" "$tiles" "$runs" "${workers:-1}"
	printf '\nTiles against one pass: %s.\n' "$same"
} >> "$TXT"
# The picture: the hillshade of the tiled DEM with ./tdc's 2 m contour lines of the same ground
log "the picture: hillshade and contours"
"$TDC_BIN" --contours 2 -o "$WORK/contours.txt" "$WORK/ground_$largest.xyz"
awk 'BEGIN { print "level,WKT" } { s = "LINESTRING("; for (i = 2; i < NF; i += 2) s = s (i > 2 ? "," : "") $i " " $(i + 1); print $1 ",\"" s ")\"" }' \
	"$WORK/contours.txt" > "$WORK/contours.csv"
rm -f "$WORK/hs.tif"
gdaldem hillshade -q -z 2 "$WORK/til_$largest.tif" "$WORK/hs.tif"
cat > "$WORK/contours.vrt" <<EOF
<OGRVRTDataSource><OGRVRTLayer name="contours"><SrcDataSource>$WORK/contours.csv</SrcDataSource>
<GeometryType>wkbLineString</GeometryType><GeometryField encoding="WKT" field="WKT"/>
</OGRVRTLayer></OGRVRTDataSource>
EOF
gdal_rasterize -q -burn 1 -l contours "$WORK/contours.vrt" "$WORK/hs.tif"
gdal_translate -q -of PNG -outsize 1000 0 "$WORK/hs.tif" "$BENCH_OUT/dem.png"
bench_figure "$BENCH_OUT/dem.png" "hillshade of the DEM in tiles, with 2 m contour lines"

cat "$TXT"
bench_publish dem "LiDAR to a DEM: ./tdc against gdal_grid, and in tiles against one pass" "$TXT"
