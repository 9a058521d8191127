#!/usr/bin/env bash
# test/cli_geotiff.sh: ./tdc --grid -o OUT.tif, the GeoTIFF written through
# GDAL (src/cli/geotiff.c), read back with GDAL's own tools (gdal-bin).
#   bash test/cli_geotiff.sh        prints "N passed, N failed"
#
#  (a) the .tif holds the .asc's values, pixel for pixel, for every method
#      (Float64; Float32 holds them rounded to float), also when the rows
#      reach the writer in pieces (build/geotiff_rows);
#  (b) gdalinfo shows the layout (256x256 tiles, DEFLATE, predictor 3), the
#      nodata, the extent, the pixel size and the CRS (--srs EPSG:25832, a
#      WKT; none without one, with a warning);
#  (c) it overlays gdal_grid's raster of the same -txe/-tye/-outsize: the
#      same origin, pixel size and size, and the same values (GDAL's qhull
#      TIN and ours agree on 500 random samples);
#  (d) bad --srs, --type and -o: a clear error, before any work, and no
#      file left behind; a failed write keeps the file it would replace.
# The data are random points from a fixed seed (perl's srand), made here.
set -u
cd "$(dirname "$0")/.." || exit 1
TDC=./tdc
pass=0; fail=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }

for t in gdalinfo gdal_translate gdal_grid gdalsrsinfo; do
	command -v $t >/dev/null || { echo "needs $t (Debian: gdal-bin)"; echo "0 passed, 1 failed"; exit 1; }
done
make -s tdc build/geotiff_rows >/dev/null || { echo "cannot build ./tdc"; echo "0 passed, 1 failed"; exit 1; }

# GDAL's ESRI ASCII grid of a raster: the values as %.20g (every double
# exactly), the header from its georeferencing.  An .asc is read as Float64
# (GDAL reads it as Float32 by default).
aai() { gdal_translate -q --config AAIGRID_DATATYPE Float64 -of AAIGrid "$@"; }
# the values of an ESRI ASCII grid, one per line
vals() { awk '$1 !~ /^[a-zA-Z]/ { for (i = 1; i <= NF; i++) print $i }' "$1"; }
info() { gdalinfo "$1" 2>&1; }
# nothing of name left in tmp (the file, its temporary files, sidecars)
none_left() { ! compgen -G "$tmp/$1*" > /dev/null; }

# 500 random samples on [0, 1000]^2, heights in [0, 100)
perl -e 'srand(39); for (1..500) { printf "%.17g %.17g %.17g\n", rand(1000), rand(1000), rand(100) }' > "$tmp/s.xyz"

# --- (a) the .tif's values are the .asc's -----------------------------------
# 500 x 300 pixels: two tile rows and columns, the second ones partial; the
# extent's top (599) is not on the grid, which covers it to 600
for m in linear linear:radius=0:nodata=-9999 nearest:nodata=-1 natural_neighbor natural_neighbor:nodata=-9999; do
	$TDC --grid 2 --extent 0,0,1000,599 --method "$m" -o "$tmp/a.asc" "$tmp/s.xyz"
	$TDC --grid 2 --extent 0,0,1000,599 --method "$m" --srs EPSG:25832 -o "$tmp/a.tif" "$tmp/s.xyz" 2> "$tmp/a.err"
	check "$m: exit 0, no warning" "[ $? -eq 0 ] && [ ! -s $tmp/a.err ]"
	aai "$tmp/a.asc" "$tmp/a1.asc"; aai "$tmp/a.tif" "$tmp/a2.asc"
	check "$m: the .tif's pixels, nodata and georeferencing are the .asc's" "cmp -s $tmp/a1.asc $tmp/a2.asc"
	check "$m: 150000 values, some distinct" "[ \$(vals $tmp/a2.asc | wc -l) -eq 150000 ] && [ \$(vals $tmp/a2.asc | sort -u | wc -l) -gt 200 ]"
done
$TDC --grid 2 --extent 0,0,1000,599 --method natural_neighbor:nodata=-9999 --type Float32 --srs EPSG:25832 -o "$tmp/f.tif" "$tmp/s.xyz"
gdal_translate -q --config AAIGRID_DATATYPE Float64 -ot Float32 "$tmp/a.asc" "$tmp/a32.tif"
aai "$tmp/f.tif" "$tmp/f1.asc"; aai "$tmp/a32.tif" "$tmp/f2.asc"
check "Float32: Type=Float32" "info $tmp/f.tif | grep -q 'Block=256x256 Type=Float32'"
check "Float32: the .asc's values rounded to float" "cmp -s $tmp/f1.asc $tmp/f2.asc"
check "Float32: not the Float64 values" "! cmp -s $tmp/f1.asc $tmp/a1.asc"
# the writer fed rows in pieces (1, 7, 300, ...; 255 and 2; 256 at a time)
# writes the file it writes from all rows at once, byte for byte
build/geotiff_rows "$tmp/r0.tif" 530 700 0
check "rows in pieces: the writer's file" "info $tmp/r0.tif | grep -q 'Size is 530, 700' && [ \"\$(gdallocationinfo -valonly $tmp/r0.tif 529 699)\" = 699529.25 ]"
for p in "1 7 300" "255 2" "256" "13"; do
	# shellcheck disable=SC2086  # the pieces, one argument each
	build/geotiff_rows "$tmp/r1.tif" 530 700 $p
	check "rows in pieces of $p: the same file" "cmp -s $tmp/r0.tif $tmp/r1.tif"
done

# --- (b) what gdalinfo shows ------------------------------------------------
info "$tmp/a.tif" > "$tmp/a.info"
check "gdalinfo: 256x256 tiles, Float64" "grep -q 'Band 1 Block=256x256 Type=Float64' $tmp/a.info"
check "gdalinfo: DEFLATE" "grep -q '^  COMPRESSION=DEFLATE$' $tmp/a.info"
check "gdalinfo: floating-point predictor" "grep -q '^  PREDICTOR=3$' $tmp/a.info"
check "gdalinfo: the method's nodata" "grep -q '^  NoData Value=-9999$' $tmp/a.info"
check "gdalinfo: size" "grep -q '^Size is 500, 300$' $tmp/a.info"
check "gdalinfo: origin at the upper left corner" "grep -q '^Origin = (0.000000000000000,600.000000000000000)$' $tmp/a.info"
check "gdalinfo: pixel size" "grep -q '^Pixel Size = (2.000000000000000,-2.000000000000000)$' $tmp/a.info"
check "gdalinfo: extent" "grep -Eq '^Upper Left  \( *0\.0+, *600\.0+\)' $tmp/a.info && grep -Eq '^Lower Right \( *1000\.0+, *0\.0+\)' $tmp/a.info"
check "gdalinfo: pixels are areas" "grep -q 'AREA_OR_POINT=Area' $tmp/a.info"
check "gdalinfo: EPSG:25832" "grep -q '^PROJCRS\[\"ETRS89 / UTM zone 32N\",' $tmp/a.info && grep -q '^    ID\[\"EPSG\",25832\]\]$' $tmp/a.info"
check "gdalinfo: a classic TIFF (small)" "[ \"\$(head -c 4 $tmp/a.tif | od -An -tx1 | tr -d ' ')\" = 49492a00 ]"
wkt='PROJCS["tdc test LAEA",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Lambert_Azimuthal_Equal_Area"],PARAMETER["latitude_of_center",52],PARAMETER["longitude_of_center",10],PARAMETER["false_easting",4321000],PARAMETER["false_northing",3210000],UNIT["metre",1]]'
$TDC --grid 50 --srs "$wkt" -o "$tmp/w.tif" "$tmp/s.xyz"
check "--srs WKT: its name" "info $tmp/w.tif | grep -q '^PROJCRS\[\"tdc test LAEA\",'"
check "--srs WKT: the same CRS" "[ \"\$(gdalsrsinfo -o proj4 $tmp/w.tif)\" = \"\$(gdalsrsinfo -o proj4 '$wkt')\" ] && gdalsrsinfo -o proj4 $tmp/w.tif | grep -q '+proj=laea +lat_0=52 +lon_0=10 +x_0=4321000 +y_0=3210000'"
check "--grid 50 over the samples' box: 20 x 20 pixels" "info $tmp/w.tif | grep -q '^Size is 20, 20$'"
$TDC --grid 50 -o "$tmp/n.tif" "$tmp/s.xyz" 2> "$tmp/n.err"
check "no CRS: written, with a warning" "[ $? -eq 0 ] && grep -qx 'tdc: warning: $tmp/n.tif gets no CRS: the input has none and no --srs was given' $tmp/n.err"
check "no CRS: gdalinfo shows none" "! info $tmp/n.tif | grep -q 'Coordinate System is' && info $tmp/n.tif | grep -q '^Origin'"
$TDC --grid 50 --srs EPSG:4326 -o "$tmp/U.TIFF" "$tmp/s.xyz"
check ".TIFF (any case) is a GeoTIFF" "info $tmp/U.TIFF | grep -q '^Driver: GTiff/GeoTIFF' && info $tmp/U.TIFF | grep -q 'ID\[\"EPSG\",4326\]\]$'"
umask 022; $TDC --grid 50 --srs EPSG:25832 -o "$tmp/m.tif" "$tmp/s.xyz"
check "the file's mode follows the umask (644)" "[ \"\$(stat -c %a $tmp/m.tif)\" = 644 ]"
# a stale sidecar of the file replaced would override its CRS: it goes
cp "$tmp/m.tif" "$tmp/st.tif"
printf '<PAMDataset><SRS>EPSG:4326</SRS></PAMDataset>\n' > "$tmp/st.tif.aux.xml"
check "a sidecar is read (what the next check guards against)" "info $tmp/st.tif | grep -q 'ID\[\"EPSG\",4326\]\]$'"
$TDC --grid 50 --srs EPSG:25832 -o "$tmp/st.tif" "$tmp/s.xyz"
check "the replaced file's stale .aux.xml is removed" "[ ! -e $tmp/st.tif.aux.xml ] && info $tmp/st.tif | grep -q 'ID\[\"EPSG\",25832\]\]$'"

# --- (c) the overlay with gdal_grid -------------------------------------------
# gdal_grid reads the samples through an OGR VRT of a CSV file.  linear with
# radius=0: GDAL's TIN inside the hull, nodata outside (its fallback to the
# nearest sample outside the hull is not compared: it is not always the
# nearest one).
{ echo x,y,z; tr ' ' , < "$tmp/s.xyz"; } > "$tmp/s.csv"
cat > "$tmp/s.vrt" <<EOF
<OGRVRTDataSource><OGRVRTLayer name="s"><SrcDataSource>$tmp/s.csv</SrcDataSource>
<GeometryType>wkbPoint</GeometryType><GeometryField encoding="PointFromColumns" x="x" y="y" z="z"/>
</OGRVRTLayer></OGRVRTDataSource>
EOF
overlay() {	# name  gdal_grid's -txe -tye -outsize  ./tdc's --grid --extent
	local name=$1 txe=$2 tye=$3 size=$4 cell=$5 ext=$6
	# shellcheck disable=SC2086
	gdal_grid -q -a linear:radius=0:nodata=-9999 -txe $txe -tye $tye -outsize $size "$tmp/s.vrt" "$tmp/g.tif"
	$TDC --grid "$cell" --extent "$ext" --method linear:radius=0:nodata=-9999 --srs EPSG:25832 -o "$tmp/o.tif" "$tmp/s.xyz"
	check "overlay $name: the same size, origin and pixel size" "[ -n \"\$(info $tmp/g.tif | grep -E '^(Size is|Origin|Pixel Size)')\" ] &&
		[ \"\$(info $tmp/g.tif | grep -E '^(Size is|Origin|Pixel Size)')\" = \"\$(info $tmp/o.tif | grep -E '^(Size is|Origin|Pixel Size)')\" ]"
	aai "$tmp/g.tif" "$tmp/g.asc"; aai "$tmp/o.tif" "$tmp/o.asc"
	check "overlay $name: the same values (1e-9), the same nodata pixels" "paste -d' ' <(vals $tmp/g.asc) <(vals $tmp/o.asc) | awk '
		{ n++; if (\$1 == -9999) nd++; if ((\$1 == -9999) != (\$2 == -9999)) exit 1
		  d = \$1 - \$2; if (d < 0) d = -d; a = \$1 < 0 ? -\$1 : \$1; if (d > 1e-9 * (1 + a)) exit 1 }
		END { exit !(n == $7 && nd < n / 5) }'"
}
overlay "100x100" "0 1000" "0 1000" "100 100" 10 0,0,1000,1000 10000
# -tye's order does not matter to gdal_grid (north up either way)
overlay "-tye max min" "0 1000" "1000 0" "100 100" 10 0,0,1000,1000 10000
# the grid covers an --extent to whole cells up and right: gdal_grid's
# raster of the covered extent
overlay "covered extent" "100 730" "50 450" "63 40" 10 100,50,725,441 2520
# a half-pixel shift (whitebox-tools #398) would show as values: a plane,
# whose value at any point is exact, at the pixel centres
awk '{ printf "%.17g %.17g %.17g\n", $1, $2, 3 * $1 - 2 * $2 + 5 }' "$tmp/s.xyz" > "$tmp/pl.xyz"
$TDC --grid 10 --extent 0,0,1000,1000 --method linear:radius=0:nodata=-9999 --srs EPSG:25832 -o "$tmp/pl.tif" "$tmp/pl.xyz"
aai "$tmp/pl.tif" "$tmp/pl.asc"
check "the plane at the pixel centres of the .tif's georeferencing" "awk '
	\$1 == \"xllcorner\" { x0 = \$2 } \$1 == \"yllcorner\" { y0 = \$2 } \$1 == \"cellsize\" { cs = \$2 } \$1 == \"nrows\" { h = \$2 }
	\$1 !~ /^[a-zA-Z]/ { r++; for (c = 1; c <= NF; c++) if (\$c != -9999) { n++;
	x = x0 + (c - 0.5) * cs; y = y0 + (h - r + 0.5) * cs; d = \$c - (3 * x - 2 * y + 5); if (d > 1e-9 || d < -1e-9) exit 1 } }
	END { exit !(r == 100 && h == 100 && cs == 10 && n > 8000) }' $tmp/pl.asc"

# --- (d) errors: clear, early, and nothing left ------------------------------
expect_error() {	# name code file-prefix command...
	local name=$1 code=$2 left=$3; shift 3
	"$@" > "$tmp/e.out" 2> "$tmp/e.err"; local rc=$?
	check "$name: exit $code" "[ $rc -eq $code ]"
	check "$name: one-line message" "[ \$(wc -l < $tmp/e.err) -eq 1 ] && grep -q '^tdc: ' $tmp/e.err"
	check "$name: nothing left" "none_left $left"
}
expect_error "--srs GDAL rejects" 2 bad $TDC --grid 10 --srs EPSG:999999 -o "$tmp/bad.tif" "$tmp/s.xyz"
check "--srs GDAL rejects: the value named" "grep -q \"'EPSG:999999'\" $tmp/e.err"
expect_error "--srs that is no CRS" 2 bad $TDC --grid 10 --srs 'not a CRS' -o "$tmp/bad.tif" "$tmp/s.xyz"
check "--srs that is no CRS: the value named" "grep -q \"'not a CRS'\" $tmp/e.err"
# before any work: a missing INPUT is not even looked at
expect_error "--srs rejected before the input is read" 2 bad $TDC --grid 10 --srs EPSG:0 -o "$tmp/bad.tif" "$tmp/missing.xyz"
expect_error "--srs with an .asc -o" 2 bad $TDC --grid 10 --srs EPSG:25832 -o "$tmp/bad.asc" "$tmp/s.xyz"
expect_error "--type without a .tif" 2 bad $TDC --type Float32 "$tmp/s.xyz"
expect_error "triangles to a .tif" 2 bad $TDC -o "$tmp/bad.tif" "$tmp/s.xyz"
expect_error "contours to a .tif" 2 bad $TDC --contours 10 -o "$tmp/bad.tif" "$tmp/s.xyz"
expect_error "--type Float16" 2 bad $TDC --grid 10 --type Float16 -o "$tmp/bad.tif" "$tmp/s.xyz"
expect_error "--type Float32 and a nodata no float holds" 2 bad $TDC --grid 10 --type Float32 --method linear:nodata=0.1 -o "$tmp/bad.tif" "$tmp/s.xyz"
# the temporary file is made before the work and removed when the work fails
printf '0 0 1e39\n1 0 1e39\n0 1 1e39\n' > "$tmp/huge.xyz"
expect_error "--type Float32 and values beyond its range" 1 bad $TDC --grid 0.5 --type Float32 --srs EPSG:25832 -o "$tmp/bad.tif" "$tmp/huge.xyz"
check "beyond Float32: says so" "grep -q 'beyond Float32' $tmp/e.err"
# before the work: crossing breaklines fail the constrained triangulation
printf '0 0 1\n10 0 2\n0 10 3\n10 10 4\n' > "$tmp/x.xyz"; printf '0 3\n1 2\n' > "$tmp/x.seg"
expect_error "crossing breaklines (what the next check needs)" 1 bad $TDC --grid 1 --method linear:breaklines=true --segments "$tmp/x.seg" --srs EPSG:25832 -o "$tmp/bad.tif" "$tmp/x.xyz"
expect_error "-o in a missing directory" 1 bad $TDC --grid 1 --method linear:breaklines=true --segments "$tmp/x.seg" -o "$tmp/nodir/bad.tif" "$tmp/x.xyz"
check "-o in a missing directory: the path named, before the work" "grep -q '^tdc: cannot write $tmp/nodir/bad.tif: ' $tmp/e.err"
mkdir "$tmp/dir.tif"
expect_error "-o a directory" 1 bad $TDC --grid 10 -o "$tmp/dir.tif" "$tmp/s.xyz"
rmdir "$tmp/dir.tif"
# a write that fails (a file size limit, the signal ignored so that write()
# fails with EFBIG): an error naming the file, no temporary file left, and
# the file it would have replaced untouched
cp "$tmp/m.tif" "$tmp/keep.tif"
(trap '' XFSZ; ulimit -f 64; exec $TDC --grid 1 --srs EPSG:25832 -o "$tmp/keep.tif" "$tmp/s.xyz") > /dev/null 2> "$tmp/e.err"
check "a failed write: exit 1, the file named" "[ $? -eq 1 ] && grep -q '^tdc: error writing $tmp/keep.tif' $tmp/e.err"
check "a failed write: no temporary file left" "[ \$(compgen -G '$tmp/keep*' | wc -l) -eq 1 ]"
check "a failed write: the old file untouched" "cmp -s $tmp/m.tif $tmp/keep.tif"
# SIGTERM while the grid is computed (its temporary file made): the file goes
# with the process
$TDC -t 1 --grid 0.25 --method natural_neighbor --srs EPSG:25832 -o "$tmp/sig.tif" "$tmp/s.xyz" 2> /dev/null &
pid=$!
for _ in $(seq 200); do compgen -G "$tmp/sig.tif.*.tmp" > /dev/null && break; sleep 0.05; done
seen=$(compgen -G "$tmp/sig.tif.*.tmp" | wc -l)
kill -TERM $pid; wait $pid; rc=$?
check "SIGTERM: killed by it, its temporary file seen, then gone" "[ $rc -eq 143 ] && [ $seen -eq 1 ] && none_left sig"
# the writer: rows out of order, or too few, fail and leave nothing
build/geotiff_rows --short "$tmp/sh.tif" 2> "$tmp/e.err"
check "writer: too few rows fail" "[ $? -eq 1 ] && grep -q '300 of 600 rows written' $tmp/e.err && none_left sh"
build/geotiff_rows --order "$tmp/or.tif" 2> "$tmp/e.err"
check "writer: rows out of order fail" "[ $? -eq 1 ] && grep -q 'rows from 20 written when row 10 was due' $tmp/e.err && none_left or"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
