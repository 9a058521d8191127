#!/usr/bin/env bash
# test/cli_grid_tiles.sh: ./tdc --grid under --max-memory (issue 39, point
# 2): when the one-shot run does not fit, the tiles' final triangles are
# rasterised as they come, and the grid is the one-shot grid: the same
# .asc bytes, the same GeoTIFF pixels (read back raw by GDAL), with many
# tiles and the peak under the limit.
#   - uniform samples on hills: the extent beyond the data (pixels outside
#     the hull take the nearest site), radius=0, a radius with nodata,
#     max_edge, Float32, 1 and 2 threads;
#   - synthetic LiDAR (bench/gen_las.c) with --class 2, into a GeoTIFF: the
#     lake and the buildings' holes, max_edge, the LAS file's CRS;
#   - the GSHHG coastline of Stockholm (test/fixtures): real clustered
#     data, under a tight limit;
#   - nearest: beyond the data, a radius, max_edge, the coastline;
#   - natural neighbour (terrain/raster_natural.c: each pixel's cavity
#     proven global in its tile's triangulation): beyond the data, radius=0,
#     max_edge, two tiles at once, a lattice whose pixel centres fall on
#     sites, edges and the centres of cocircular squares, the LiDAR ground
#     (GeoTIFF) and the coastline;
#   - the refusal of an input without heights,
#     each one line, with no -o written and nothing left in --tmpdir;
#     SIGINT in the middle leaves no file behind.
#   bash test/cli_grid_tiles.sh        (prints "N passed, N failed")
set -u
cd "$(dirname "$0")/.."
TDC=./tdc
pass=0; fail=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }

[ -x "$TDC" ] || make -s tdc >/dev/null || { echo "cannot build ./tdc"; echo "0 passed, 1 failed"; exit 1; }
have_gdal=0
command -v gdal_translate >/dev/null && have_gdal=1
mkdir -p "$tmp/t"

stat_of() { grep -oE "(^| )$2=[0-9.]+" "$1" | head -n 1 | sed 's/.*=//'; }
# The GeoTIFF's pixels as raw bytes (ENVI: no header in the data file)
raw() { gdal_translate -q -of ENVI "$1" "$2" && [ -s "$2" ]; }

# grid_case NAME LIMIT_MB MIN_TILES INPUT ARGS...: the one-shot grid and the
# grid in tiles, compared
grid_case() {
	local name=$1 limit=$2 mintiles=$3 input=$4; shift 4
	local ext=asc
	case " $* " in *" --tif "*) ext=tif ;; esac
	local args=()
	for a in "$@"; do [ "$a" = --tif ] || args+=("$a"); done
	rm -f "$tmp/one.$ext" "$tmp/til.$ext"
	$TDC "${args[@]}" -o "$tmp/one.$ext" --stats "$input" 2> "$tmp/one.err"
	check "$name: the one-shot grid (exit 0)" "[ $? -eq 0 ] && [ -s $tmp/one.$ext ]"
	$TDC --max-memory "$limit" --tmpdir "$tmp/t" "${args[@]}" -o "$tmp/til.$ext" --stats "$input" 2> "$tmp/til.err"
	check "$name: the grid in tiles (exit 0)" "[ $? -eq 0 ] && [ -s $tmp/til.$ext ]"
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
	check "$name: the same valid pixels" \
		"[ \"\$(grep -oE 'pixels=[0-9]+ valid=[0-9]+' $tmp/one.err)\" = \"\$(grep -oE 'pixels=[0-9]+ valid=[0-9]+' $tmp/til.err)\" ]"
	if [ $ext = asc ]; then
		check "$name: the same .asc, byte for byte" "cmp -s $tmp/one.asc $tmp/til.asc"
	elif ((have_gdal)); then
		rm -f "$tmp"/one.raw* "$tmp"/til.raw*
		check "$name: the same GeoTIFF pixels" "raw $tmp/one.tif $tmp/one.raw && raw $tmp/til.tif $tmp/til.raw && cmp -s $tmp/one.raw $tmp/til.raw"
		check "$name: the same georeferencing and CRS" \
			"[ \"\$(gdalinfo $tmp/one.tif | grep -E 'Origin|Pixel Size|Size is|NoData|ID\\[\"EPSG\",[0-9]+\\]\\]\$' )\" = \"\$(gdalinfo $tmp/til.tif | grep -E 'Origin|Pixel Size|Size is|NoData|ID\\[\"EPSG\",[0-9]+\\]\\]\$')\" ]"
	fi
	check "$name: --tmpdir left empty" "[ -z \"\$(ls -A $tmp/t)\" ]"
}

# Uniform samples on hills, 2 km square, z to the millimetre
awk 'BEGIN { srand(39); for (i = 0; i < 240000; i++) { x = 2000 * rand(); y = 2000 * rand();
	printf "%.3f %.3f %.3f\n", x, y, 100 + 40 * sin(x / 170) * cos(y / 130) + rand() } }' > "$tmp/hills.txt"
grid_case "hills, extent beyond the data" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5
grid_case "hills, radius=0" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method linear:radius=0
grid_case "hills, radius=25:nodata=-9999" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method linear:radius=25:nodata=-9999
grid_case "hills, max_edge=9" 18 20 "$tmp/hills.txt" --grid 3 --method linear:max_edge=9:nodata=-9999
grid_case "hills, 1 thread" 18 20 "$tmp/hills.txt" -t 1 --grid 5
# two tiles at once (src/core/tiles/bounded_share.c): the same pixels, under the limit
want_workers=2
grid_case "hills, two tiles at once" 30 8 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5
grid_case "hills, two tiles at once, nearest" 30 8 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method nearest
want_workers=
# nearest: the site nearest each centre, from the triangles around it (raster_nearest.c)
grid_case "hills, nearest, extent beyond the data" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method nearest
grid_case "hills, nearest:radius1=3:radius2=3" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method nearest:radius1=3:radius2=3:nodata=-9999
grid_case "hills, nearest:max_edge=9" 18 20 "$tmp/hills.txt" --grid 3 --method nearest:max_edge=9:nodata=-9999
# natural neighbour: the cavity of each centre, proven global in its tile (raster_natural.c)
grid_case "hills, natural neighbour, extent beyond the data" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method natural_neighbor
grid_case "hills, natural_neighbor:radius=0" 18 20 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method natural_neighbor:radius=0
grid_case "hills, natural_neighbor:max_edge=9" 18 20 "$tmp/hills.txt" --grid 3 --method natural_neighbor:max_edge=9:nodata=-9999
grid_case "hills, natural neighbour, a tighter limit" 16 40 "$tmp/hills.txt" --grid 5 --method natural_neighbor
want_workers=2 grid_case "hills, two tiles at once, natural neighbour" 30 8 "$tmp/hills.txt" --grid 4 --extent -60.5,-33.25,2047,2031.5 --method natural_neighbor
# a unit lattice (cocircular squares) with a lake; pixels of 0.5 centred on
# sites, on the lattice's edges and diagonals and at the squares' centres
awk 'BEGIN { for (j = 0; j < 420; j++) for (i = 0; i < 420; i++) {
	dx = i - 210; dy = j - 140; if (dx * dx + dy * dy < 900 && !(i == 210 && j == 140)) continue;
	printf "%d %d %.3f\n", i, j, (i * 7 + j * 13) % 17 + 0.125 * (i % 3) } }' > "$tmp/lattice.txt"
grid_case "lattice, natural neighbour" 18 20 "$tmp/lattice.txt" --grid 0.5 --extent -2.25,-2.25,421.25,421.25 --method natural_neighbor
grid_case "lattice, natural_neighbor:max_edge=1.5" 18 20 "$tmp/lattice.txt" --grid 0.5 --extent -2.25,-2.25,421.25,421.25 --method natural_neighbor:max_edge=1.5:nodata=-9999
if ((have_gdal)); then
	# GDAL's libraries (some 40 MB resident), its block cache and its compression
	# threads' blocks count against the limit
	grid_case "hills, GeoTIFF Float32" 76 20 "$tmp/hills.txt" --grid 2 --tif --type Float32 --srs EPSG:25832
fi

# Synthetic LiDAR: the ground (class 2) of 250 m x 250 m at 10 points a square metre
cc -O2 -o "$tmp/gen_las" bench/gen_las.c -lm || bad "cannot build bench/gen_las.c"
"$tmp/gen_las" -s 11 250 "$tmp/site.las" 2> /dev/null
if ((have_gdal)); then
	grid_case "LiDAR ground to a 1 m DEM" 76 20 "$tmp/site.las" --class 2 --grid 1 --tif
	# the same file, byte for byte, from one thread (one tile at a time, one
	# GDAL compression thread) as from two (two tiles handed over at once)
	$TDC -t 1 --max-memory 76 --tmpdir "$tmp/t" --class 2 --grid 1 -o "$tmp/t1.tif" "$tmp/site.las" 2> /dev/null
	check "LiDAR DEM: -t 1 writes the same GeoTIFF bytes as $(nproc) threads" "cmp -s $tmp/t1.tif $tmp/til.tif"
	want_workers=2 grid_case "LiDAR ground, nearest, max_edge=5" 84 20 "$tmp/site.las" --class 2 --grid 1 --method nearest:max_edge=5:nodata=-9999 --tif
	grid_case "LiDAR ground, max_edge=5" 76 20 "$tmp/site.las" --class 2 --grid 0.5 --method linear:max_edge=5:nodata=-9999 --tif
	grid_case "LiDAR ground, natural neighbour, max_edge=5" 76 20 "$tmp/site.las" --class 2 --grid 1 --method natural_neighbor:max_edge=5:nodata=-9999 --tif
	check "LiDAR: the DEM has the LAS file's CRS (EPSG:32632)" "gdalinfo $tmp/til.tif | grep -q 'ID\\[\"EPSG\",32632\\]'"
else
	grid_case "LiDAR ground to a 1 m grid" 30 20 "$tmp/site.las" --class 2 --grid 1
fi

# The coastline of Stockholm (GSHHG): its vertices and 7 points between each
# two, heights from a smooth function (130,000 points along the shores)
perl -e 'local $/; $_ = <>; while (/\(([^()]+)\)/g) { my @p = map { [split / /] } split /,/, $1;
	for my $i (0 .. $#p - 1) { my ($a, $b) = @p[$i, $i + 1]; for my $k (0 .. 7) { my $t = $k / 8;
	printf "%.10f %.10f\n", $a->[0] + $t * ($b->[0] - $a->[0]), $a->[1] + $t * ($b->[1] - $a->[1]); } } }' \
	test/fixtures/gshhg-stockholm.wkt |
	awk '!seen[$1 " " $2]++ { printf "%s %s %.6f\n", $1, $2, 10 * sin($1 * 40) + 5 * cos($2 * 60) }' > "$tmp/coast.txt"
grid_case "GSHHG Stockholm, a tight limit" 18 20 "$tmp/coast.txt" --grid 0.001
grid_case "GSHHG Stockholm, max_edge=0.01" 18 20 "$tmp/coast.txt" --grid 0.001 --method linear:max_edge=0.01:nodata=-9999
grid_case "GSHHG Stockholm, nearest" 20 12 "$tmp/coast.txt" --grid 0.001 --method nearest
grid_case "GSHHG Stockholm, natural neighbour" 22 12 "$tmp/coast.txt" --grid 0.001 --method natural_neighbor

# Refused: an input without heights, one line, no -o
awk '{ print $1, $2 }' "$tmp/hills.txt" > "$tmp/flat.txt"
rm -f "$tmp/r.out"
$TDC --max-memory 18 --tmpdir "$tmp/t" --grid 4 -o "$tmp/r.out" "$tmp/flat.txt" > /dev/null 2> "$tmp/r.err"
check "no heights: exit 1 with the reason" "[ $? -eq 1 ] && grep -q 'needs heights' $tmp/r.err && [ ! -e $tmp/r.out ]"

# SIGINT in the middle of a grid in tiles: no temporary file, no partial output
awk 'BEGIN { srand(5); for (i = 0; i < 1500000; i++) printf "%.3f %.3f %.2f\n", 5000 * rand(), 5000 * rand(), 100 * rand() }' > "$tmp/big.txt"
$TDC --max-memory 40 --tmpdir "$tmp/t" --grid 2 -o "$tmp/big.tif" "$tmp/big.txt" 2> /dev/null &
pid=$!
sleep 2
kill -INT $pid 2> /dev/null
wait $pid
check "SIGINT: the run stopped (status $?)" "true"
check "SIGINT: --tmpdir left empty" "[ -z \"\$(ls -A $tmp/t)\" ]"
check "SIGINT: no partial GeoTIFF" "[ -z \"\$(ls $tmp | grep -E '^big\\.tif')\" ]"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
