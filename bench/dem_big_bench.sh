#!/usr/bin/env bash
# bench/dem_big_bench.sh -- a billion airborne LiDAR returns to a 1 m ground
# DEM and to 1 m contour lines with ./tdc --max-memory: a program that
# prints figures (and the checks of its outputs it can afford) and asserts
# nothing.
#
# The survey: bench/gen_las.c (hills, a lake with no returns, buildings
# with no ground under them, woods) at 10 returns a square metre over a
# square of BENCH_DEMBIG_SIDE metres (10160: some 1.0e9 returns), written as
# LAS 1.4 point format BENCH_DEMBIG_FORMAT (0: 20 bytes a return, the
# smallest record; format 6 would need 30 and the disk holds the LAS file,
# the staged ground and the tiles at once).  Then, one run each, timed as a
# whole process by GNU time (wall, user+sys CPU, peak RSS):
#   dem       ./tdc --class 2 --grid 1 --method linear:max_edge=5:nodata=-9999
#             --max-memory BENCH_DEMBIG_LIMIT -o dem.tif   (a tiled DEFLATE
#             GeoTIFF, its CRS from the LAS file's WKT VLR)
#   contours  ./tdc --class 2 --contours 1 --method linear:max_edge=5
#             --max-memory BENCH_DEMBIG_LIMIT -o contours.txt
# with the staging of the LAS file's ground (read, filtered, written as the
# bounded run's input) inside the timed process, as a user runs it.  The
# DEM's gdalinfo (size, pixel size, CRS, nodata) and the count of its
# pixels with data are printed; that tiles give the one-pass pixels is
# shown at 1e7 points by bench/dem_bench.sh (part B) and in CI.
# Beside them, the published figure: Isenburg, Liu, Shewchuk, Snoeyink and
# Thirion, "Generating Raster DEMs from Mass Points via TIN Streaming"
# (GIScience 2006).
#
# Disk: about 20 GB for the LAS file, 24 bytes a ground point staged and
# about as much again for the tiles (some 62 GB at the default side);
# everything is deleted at the end.
#
# Knobs: BENCH_DEMBIG_SIDE (10160), BENCH_DEMBIG_FORMAT (0),
# BENCH_DEMBIG_LIMIT (2000), BENCH_DEMBIG_TMP ($ROOT/build/bench/dembig),
# BENCH_DEMBIG_CONTOURS (1; 0 skips the contour run), BENCH_TIMEOUT (7200 s
# a run).  Output: stdout, build/bench/dem_big.txt, docs/benchmarks/dem_big.md.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

SIDE=${BENCH_DEMBIG_SIDE:-10160}
FMT=${BENCH_DEMBIG_FORMAT:-0}
LIMIT=${BENCH_DEMBIG_LIMIT:-2000}
TMPD=${BENCH_DEMBIG_TMP:-$ROOT/build/bench/dembig}
CONTOURS=${BENCH_DEMBIG_CONTOURS:-1}
TMO=${BENCH_TIMEOUT:-7200}

mkdir -p "$BENCH_OUT" "$TMPD"
TXT=$BENCH_OUT/dem_big.txt
WORK=$(mktemp -d "$TMPD/dem_big.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

bench_tdc_copy
command -v gdalinfo > /dev/null || ensure_debs gdal-bin

exec > >(tee "$TXT")
TEE_PID=$!

LAS=$WORK/survey.las
log "generating $LAS (side $SIDE m, format $FMT)"
t0=$SECONDS
"$BENCH_BIN/gen_las" -s 2 -f "$FMT" "$SIDE" "$LAS" 2> "$WORK/gen.err" || die "gen_las: $(cat "$WORK/gen.err")"
gen_s=$((SECONDS - t0))

bench_begin
echo "runs: ./tdc --max-memory $LIMIT --class 2 from the LAS file, one run each, the staging of its ground included;"
echo "timing: whole process, GNU time (wall, user+sys CPU, peak RSS); files in $TMPD"
echo "survey: gen_las -s 2 -f $FMT $SIDE ($(cat "$WORK/gen.err")), $(( $(stat -c %s "$LAS") >> 20 )) MB of LAS, generated in $gen_s s (untimed)"
echo "disk free before the runs: $(df -P -k "$TMPD" | awk 'NR == 2 { printf "%d", $4 / 1048576 }') GB"

# run NAME ARGS...: one timed run of ./tdc ARGS; prints its line and phases
run() {
	local name=$1 wall cpu rss
	shift
	echo
	echo "== $name: tdc $* (load $(cut -d' ' -f1-3 /proc/loadavg))"
	if ! timeout "$TMO" /usr/bin/time -f '%e %U %S %M' -o "$WORK/time" \
		"$TDC_BIN" --stats --max-memory "$LIMIT" --tmpdir "$WORK" "$@" 2> "$WORK/stats"; then
		echo "$name: failed: $(tail -3 "$WORK/stats" | tr '\n' ' ')"
		return 1
	fi
	read -r wall cpu rss < <(awk '{ printf "%s %.1f %.1f\n", $1, $2 + $3, $4 / 1024 }' "$WORK/time")
	printf '%-10s wall %8.1f s (%5.1f min)  cpu %8.1f s (cpu/wall %.2f)  peak RSS %7.1f MB: %s the limit of %s MB\n' \
		"$name" "$wall" "$(awk -v w="$wall" 'BEGIN { print w / 60 }')" "$cpu" \
		"$(awk -v c="$cpu" -v w="$wall" 'BEGIN { print (w > 0 ? c / w : 0) }')" "$rss" \
		"$(awk -v r="$rss" -v l="$LIMIT" 'BEGIN { print (r <= l ? "within" : "OVER") }')" "$LIMIT"
	printf '  input: %s returns, %s ground points kept, %s distinct; %s triangles\n' \
		"$(thousands "$(kv "$WORK/stats" points)")" "$(thousands "$(kv "$WORK/stats" kept)")" \
		"$(thousands "$(kv "$WORK/stats" unique)")" "$(thousands "$(kv "$WORK/stats" triangles)")"
	printf '  bounded run: %s tiles, %s runs, %s halo points, %s tiles at once, binned on %s threads\n' \
		"$(kv "$WORK/stats" tiles)" "$(kv "$WORK/stats" tile_runs)" "$(thousands "$(kv "$WORK/stats" halo_points)")" \
		"$(kv "$WORK/stats" workers)" "$(kv "$WORK/stats" bin_threads)"
	printf '  phases (wall s): scan %.1f, bin %.1f, tiles %.1f; the rest of the %.1f s (the LAS file read and its ground staged, the output closed): %.1f\n' \
		"$(kv "$WORK/stats" scan)" "$(kv "$WORK/stats" bin)" "$(kv "$WORK/stats" tiles_wall)" "$wall" \
		"$(awk -v w="$wall" -v a="$(kv "$WORK/stats" scan)" -v b="$(kv "$WORK/stats" bin)" -v c="$(kv "$WORK/stats" tiles_wall)" 'BEGIN { print w - a - b - c }')"
	printf '  in the tiles (s, summed over the workers): gather %.1f, engine %.1f, finish %.1f, write %.1f, waiting for memory %.1f\n' \
		"$(kv "$WORK/stats" gather)" "$(kv "$WORK/stats" engine)" "$(kv "$WORK/stats" finish)" \
		"$(kv "$WORK/stats" write)" "$(kv "$WORK/stats" wait)"
	WALL=$wall RSS=$rss
}

DEM_WALL= DEM_RSS=
if run dem --class 2 --grid 1 --method linear:max_edge=5:nodata=-9999 -o "$WORK/dem.tif" "$LAS"; then
	DEM_WALL=$WALL DEM_RSS=$RSS
	printf '  grid: %s pixels, %s with data; the file %s MB\n' "$(thousands "$(kv "$WORK/stats" pixels)")" \
		"$(thousands "$(kv "$WORK/stats" valid)")" "$(( $(stat -c %s "$WORK/dem.tif") >> 20 ))"
	gdalinfo "$WORK/dem.tif" > "$WORK/gdalinfo.txt" 2>&1 || true
	printf '  gdalinfo: %s; %s; %s; CRS %s; %s; %s\n' \
		"$(grep -m1 '^Size is' "$WORK/gdalinfo.txt")" "$(grep -m1 '^Origin' "$WORK/gdalinfo.txt")" \
		"$(grep -m1 '^Pixel Size' "$WORK/gdalinfo.txt")" \
		"$(grep -m1 -oE '^PROJCRS\["[^"]*"' "$WORK/gdalinfo.txt" | cut -d'"' -f2)" \
		"$(grep -m1 -oE 'NoData Value=[-0-9.e]+' "$WORK/gdalinfo.txt")" \
		"$(grep -m1 -oE 'Block=[0-9x]+' "$WORK/gdalinfo.txt")"
	rm -f "$WORK/dem.tif"
fi
if [ "$CONTOURS" = 1 ] &&
	run contours --class 2 --contours 1 --method linear:max_edge=5 -o "$WORK/contours.txt" "$LAS"; then
	printf '  output: %s lines, %s vertices, %s MB of text\n' "$(thousands "$(kv "$WORK/stats" lines)")" \
		"$(thousands "$(kv "$WORK/stats" contour_points)")" "$(( $(stat -c %s "$WORK/contours.txt") >> 20 ))"
	rm -f "$WORK/contours.txt"
fi

echo
if [ -n "$DEM_WALL" ]; then
	echo "the issue's target (a 1e9-return survey to a 1 m DEM in at most 15 min at a peak RSS of at most 2 GB):" \
		"$(awk -v w="$DEM_WALL" -v r="$DEM_RSS" 'BEGIN { print (w <= 900 && r <= 2048 ? "met" : "NOT met") }')" \
		"($DEM_WALL s, $DEM_RSS MB)"
fi
echo "published, for comparison: Isenburg, Liu, Shewchuk, Snoeyink and Thirion, Generating Raster DEMs from"
echo "Mass Points via TIN Streaming (GIScience 2006): 500 million points to a 50,394 x 30,500 DEM in just"
echo "over an hour, in under 100 MB, on one core (2006 hardware)."
exec >&-
wait "$TEE_PID" 2>/dev/null || true
bench_end
bench_publish dem_big "A billion LiDAR returns to a 1 m DEM and contours: ./tdc --max-memory $LIMIT" "$TXT" text
