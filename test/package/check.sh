#!/usr/bin/env bash
# test/package/check.sh [SUITE]: the Debian packages that `make deb` left in
# build/deb/, installed on a fresh Debian root as a user installs them:
#
#   apt-get install ./postgresql-NN-tdc-delaunay_*.deb ./tdc-delaunay-tools_*.deb
#
# which pulls PostgreSQL and PostGIS from the mirror; then, in that root:
# pg_createcluster NN test --start, CREATE EXTENSION tdc_delaunay CASCADE, a
# triangulation whose triangle count and area are known exactly, CREATE
# EXTENSION tdc_delaunay_raster CASCADE (postgis_raster with it) and an
# interpolation whose every pixel is known exactly, postgresql-NN-pointcloud
# and CREATE EXTENSION tdc_delaunay_pointcloud CASCADE, the installed
# tdc-delaunay (--help, and debian/tests/tdc-smoke), and the pg_regress suite against
# the installed files as autopkgtest's installcheck runs it (debian/tests/
# installcheck: pg_buildext installcheck, in a pg_virtualenv cluster; every
# test of sql/, tdc_raster, tdc_raster_gdal and tdc_pointcloud included).
# Prints "package: N passed, N failed" last, with the time of each phase.
#
# SUITE defaults to this machine's own (/etc/os-release); the packages must
# have been built for its PostgreSQL major.  The root is a copy of the cached
# minbase root of scripts/roots.sh (prepare SUITE --no-pg), removed at the
# end; the .deb files apt-get downloads are kept beside the cached roots
# (SUITE-apt-archives/) for the next run.  Needs root.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)

# --- inside the fresh root -------------------------------------------------

inside() {
	local pass=0 fail=0 t0=$SECONDS t major port pkgs out line
	ok() { pass=$((pass + 1)); echo "ok - $*"; }
	bad() { fail=$((fail + 1)); echo "FAIL - $*"; }
	finish() {
		echo "inside the root: $((SECONDS - t0)) s"
		echo "$pass $fail" >/var/tmp/counts
		exit 0
	}
	as_pg() { (cd / && runuser -u postgres -- "$@"); }
	sql() { as_pg psql -X -q -At -v ON_ERROR_STOP=1 -p "$port" "$@"; }

	cd /var/tmp/debs
	t=$SECONDS
	apt-get update -q >/var/tmp/apt.log 2>&1 || { tail -n 20 /var/tmp/apt.log; bad "apt-get update"; finish; }
	# shellcheck disable=SC2046  # the two file names
	if apt-get install -y -q -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold \
		$(ls ./postgresql-*-tdc-delaunay_*.deb ./tdc-delaunay-tools_*.deb) </dev/null >>/var/tmp/apt.log 2>&1; then
		pkgs=$(dpkg-query -W -f='${db:Status-Status}\n' | grep -c '^installed$')
		ok "apt-get install ./postgresql-*-tdc-delaunay_*.deb ./tdc-delaunay-tools_*.deb ($((SECONDS - t)) s, $pkgs packages installed in the root)"
	else
		tail -n 30 /var/tmp/apt.log
		bad "apt-get install of the two packages"
		finish
	fi
	major=$(dpkg-query -W -f='${Package}\n' 'postgresql-*-tdc-delaunay' | sed -n 's/^postgresql-\([0-9]*\)-tdc-delaunay$/\1/p')
	echo "installed: $(dpkg-query -W -f='${Package} ${Version}, ' 'postgresql-*-tdc-delaunay' tdc-delaunay-tools \
		"postgresql-$major" "postgresql-$major-postgis-3")"

	# A cluster as a DBA makes one; Unix socket only (the root shares the
	# machine's network), on the port the caller found free.
	port=$TDC_PKG_PORT
	t=$SECONDS
	if pg_createcluster -p "$port" "$major" test --start -o listen_addresses= >/var/tmp/cluster.log 2>&1; then
		ok "pg_createcluster $major test --start ($((SECONDS - t)) s)"
	else
		cat /var/tmp/cluster.log
		bad "pg_createcluster $major test --start"
		finish
	fi
	sql -d postgres -c 'CREATE DATABASE pkgtest'
	if out=$(sql -d pkgtest -c 'SET client_min_messages = warning' -c 'CREATE EXTENSION tdc_delaunay CASCADE' \
		-c "SELECT string_agg(extname || ' ' || extversion, ', ' ORDER BY extname) FROM pg_extension WHERE extname <> 'plpgsql'" 2>&1); then
		ok "CREATE EXTENSION tdc_delaunay CASCADE: $out"
	else
		bad "CREATE EXTENSION tdc_delaunay CASCADE: $out"
	fi
	# A 300 x 300 grid: n = 90,000 points, h = 1,196 of them on the hull, so
	# any triangulation has 2n - 2 - h = 178,802 triangles, of area 1/2 each,
	# adding up to 299^2 = 89,401 exactly.
	out=$(sql -d pkgtest -F ' ' <<-'SQL' 2>&1
		CREATE TABLE grid AS SELECT ST_MakePoint(i, j) AS geom
			FROM generate_series(0, 299) i, generate_series(0, 299) j;
		SELECT ST_NumGeometries(t), (SELECT sum(ST_Area(d.geom)) FROM ST_Dump(t) d)
			FROM (SELECT ST_TDCDelaunayTriangles(ST_Collect(geom)) AS t FROM grid) s;
		SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM grid;
	SQL
	) || true
	if [ "$(printf '%s' "$out" | tr '\n' ' ')" = "178802 89401 178802" ]; then
		ok "300 x 300 grid: ST_TDCDelaunayTriangles and ST_TDCDelaunay give 178802 triangles, area 89401"
	else
		bad "300 x 300 grid: expected 178802 triangles of area 89401 from both, got: $out"
	fi
	# The second extension the package ships, with postgis_raster (which
	# the package's Depends on postgresql-NN-postgis-3 brings, GDAL with it).
	if out=$(sql -d pkgtest -c 'SET client_min_messages = warning' -c 'CREATE EXTENSION tdc_delaunay_raster CASCADE' \
		-c "SELECT string_agg(extname || ' ' || extversion, ', ' ORDER BY extname) FROM pg_extension WHERE extname <> 'plpgsql'" 2>&1); then
		ok "CREATE EXTENSION tdc_delaunay_raster CASCADE: $out"
	else
		bad "CREATE EXTENSION tdc_delaunay_raster CASCADE: $out"
	fi
	# The samples z = 2x + 3y + 1 on the 11 x 11 integer grid of [0, 10]^2,
	# interpolated linearly into a 10 x 10 template of 1 x 1 pixels over the
	# same square: a plane comes back exactly, so the pixel centres
	# (i + 0.5, j + 0.5) hold 2i + 3j + 3.5, from 3.5 to 48.5, adding up to
	# 2 * 500 + 3 * 500 + 100 * 1 = 2600; the aggregate gives the same raster.
	out=$(sql -d pkgtest -F ' ' <<-'SQL' 2>&1
		CREATE TABLE plane AS SELECT ST_MakePoint(i, j, 2 * i + 3 * j + 1) AS geom
			FROM generate_series(0, 10) i, generate_series(0, 10) j;
		CREATE TABLE tmpl AS
			SELECT ST_AddBand(ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), '64BF'::text, 0, -9999) AS r;
		SELECT ST_Width(t.r), ST_Height(t.r), ST_BandPixelType(t.r), s.count,
			round(s.sum::numeric, 9)::float8, round(s.min::numeric, 9)::float8,
			round(s.max::numeric, 9)::float8,
			ST_AsBinary(t.r) = (SELECT ST_AsBinary(ST_TDCInterpolate(geom, r)) FROM plane, tmpl)
		FROM (SELECT ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM plane), 'linear', r) AS r
				FROM tmpl) t, ST_SummaryStats(t.r) s;
	SQL
	) || true
	if [ "$out" = "10 10 64BF 100 2600 3.5 48.5 t" ]; then
		ok "ST_TDCInterpolateRaster of the plane z = 2x + 3y + 1: 10 x 10 64BF pixels from 3.5 to 48.5, sum 2600; ST_TDCInterpolate the same"
	else
		bad "ST_TDCInterpolateRaster of the plane z = 2x + 3y + 1: expected \"10 10 64BF 100 2600 3.5 48.5 t\", got: $out"
	fi
	# The third extension, with pgpointcloud, which the package only
	# suggests: installed by name from the mirror, as a user who wants it
	# would.  The installcheck below then runs tdc_pointcloud too.
	t=$SECONDS
	out="apt-get install failed (/var/tmp/apt.log)"
	if apt-get install -y -q --no-install-recommends "postgresql-$major-pointcloud" </dev/null >>/var/tmp/apt.log 2>&1 &&
		out=$(sql -d pkgtest -c 'SET client_min_messages = warning' -c 'CREATE EXTENSION tdc_delaunay_pointcloud CASCADE' \
			-c "SELECT string_agg(extname || ' ' || extversion, ', ' ORDER BY extname) FROM pg_extension WHERE extname <> 'plpgsql'" 2>&1); then
		ok "apt-get install postgresql-$major-pointcloud; CREATE EXTENSION tdc_delaunay_pointcloud CASCADE ($((SECONDS - t)) s): $out"
	else
		bad "postgresql-$major-pointcloud and CREATE EXTENSION tdc_delaunay_pointcloud CASCADE: $out"
	fi
	as_pg pg_dropcluster --stop "$major" test

	# The command-line tool
	if out=$(tdc-delaunay --help 2>&1) && grep -q -- '--max-memory' <<<"$out"; then
		ok "$(command -v tdc-delaunay) --help"
	else
		bad "tdc-delaunay --help: $out"
	fi
	if out=$(/var/tmp/tdc-src/debian/tests/tdc-smoke 2>&1); then
		ok "debian/tests/tdc-smoke: $(tail -n 1 <<<"$out")"
	else
		bad "debian/tests/tdc-smoke: $out"
	fi

	# autopkgtest's installcheck: its Depends (debian/tests/control), then the
	# test from the source tree.
	t=$SECONDS
	if apt-get install -y -q --no-install-recommends make postgresql-server-dev-all </dev/null >>/var/tmp/apt.log 2>&1; then
		ok "apt-get install make postgresql-server-dev-all ($((SECONDS - t)) s)"
	else
		tail -n 30 /var/tmp/apt.log
		bad "apt-get install make postgresql-server-dev-all"
		finish
	fi
	t=$SECONDS
	cd /var/tmp/tdc-src
	PGPORT=$port debian/tests/installcheck >/var/tmp/installcheck.log 2>&1 || true
	grep -E '^(test |ok |not ok |# |### |\*\*\*)' /var/tmp/installcheck.log | grep -v '^# (using|diff)' || true
	line=$(grep -Eo '(All [0-9]+ tests passed|[0-9]+ of [0-9]+ tests (failed|passed))' /var/tmp/installcheck.log | tail -n 1 || true)
	case "$line" in
		All*) pass=$((pass + $(awk '{print $2}' <<<"$line"))) ;;
		*failed)
			fail=$((fail + $(awk '{print $1}' <<<"$line")))
			pass=$((pass + $(awk '{print $3 - $1}' <<<"$line")))
			;;
		*)
			tail -n 40 /var/tmp/installcheck.log
			bad "installcheck printed no pg_regress result line"
			;;
	esac
	echo "installcheck (pg_regress, PostgreSQL $major): ${line:-no result} ($((SECONDS - t)) s)"
	if grep -q '^\*\*\*\* .*regression.diffs' /var/tmp/installcheck.log; then
		sed -n '/^\*\*\*\* .*regression.diffs/,$p' /var/tmp/installcheck.log | head -n 120
	fi
	finish
}

if [ "${1:-}" = --inside ]; then
	inside
fi

# --- on the machine ---------------------------------------------------------

# shellcheck source=scripts/roots.sh
. "$here/../../scripts/roots.sh"

suite=${1:-$(. /etc/os-release && echo "${VERSION_CODENAME:-}")}
[ -n "$suite" ] || tdc_die "no VERSION_CODENAME in /etc/os-release: give the suite (bookworm, trixie, forky)"
debs=$TDC_ROOT/build/deb
shopt -s nullglob
ext=("$debs"/postgresql-*-tdc-delaunay_*.deb)
tools=("$debs"/tdc-delaunay-tools_*.deb)
shopt -u nullglob
((${#ext[@]} == 1 && ${#tools[@]} == 1)) ||
	tdc_die "want one postgresql-NN-tdc-delaunay and one tdc-delaunay-tools .deb in $debs: run make deb"

t_all=$SECONDS
t=$SECONDS
cached=fresh
[ -f "$(tdc_root_dir "$suite" 1)/.tdc-packages" ] && cached=cached
tdc_root_prepare "$suite" --no-pg
t_prepare=$((SECONDS - t))

scratch=$TDC_ROOTS_DIR/$suite-nopg-package-$$
archives=$TDC_ROOTS_DIR/$suite-apt-archives
cleanup() {
	[ -d "$scratch" ] || return 0
	tdc_root_kill_procs "$scratch"
	rm -rf --one-file-system "$scratch"
}
trap cleanup EXIT
t=$SECONDS
tdc_root_scratch "$suite" --no-pg "$scratch"
mkdir -p "$scratch/var/tmp/debs" "$archives"
cp "${ext[0]}" "${tools[0]}" "$scratch/var/tmp/debs/"
cp -p "$archives"/*.deb "$scratch/var/cache/apt/archives/" 2>/dev/null || true
tdc_root_copy_tree "$scratch" /var/tmp/tdc-src
cp /etc/resolv.conf "$scratch/etc/resolv.conf"
# The machine's own release: its apt sources as they are (security and
# updates included, as on a user's machine: a package built here depends on
# the server minor it was built against).
if [ "$suite" = "$(. /etc/os-release && echo "${VERSION_CODENAME:-}")" ]; then
	rm -f "$scratch/etc/apt/sources.list" "$scratch/etc/apt/sources.list.d/"*
	cp -p /etc/apt/sources.list "$scratch/etc/apt/" 2>/dev/null || true
	cp -p /etc/apt/sources.list.d/* "$scratch/etc/apt/sources.list.d/" 2>/dev/null || true
fi
t_copy=$((SECONDS - t))

tdc_say "$suite root ($cached minbase: $t_prepare s; fresh copy: $t_copy s) in $scratch: installing ${ext[0]##*/} and ${tools[0]##*/}"
tdc_root_chroot "$scratch" env TDC_PKG_PORT="$(tdc_free_port)" \
	bash /var/tmp/tdc-src/test/package/check.sh --inside || true
cp -p "$scratch"/var/cache/apt/archives/*.deb "$archives/" 2>/dev/null || true
pass=0 fail=1
if [ -f "$scratch/var/tmp/counts" ]; then
	read -r pass fail <"$scratch/var/tmp/counts"
else
	echo "FAIL - the checks in the root stopped before the end"
fi
t=$SECONDS
cleanup
echo "check.sh: $suite, $cached minbase root: prepare $t_prepare s, copy $t_copy s, removal $((SECONDS - t)) s, total $((SECONDS - t_all)) s"
echo "package: $pass passed, $fail failed"
((fail == 0))
