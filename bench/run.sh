#!/usr/bin/env bash
# bench/run.sh -- `make bench`: the core benchmark, the SQL benchmark, then
# the SQL size sweep.
#
#   A  bench/core_bench.sh   ./tdc (1 thread, all threads) vs CGAL   -> core.md
#   B  bench/sql_bench.sh    tdc_delaunay vs PostGIS in PostgreSQL   -> sql.md
#   C  bench/sweep_bench.sh  the same from 3 to 10^7 points per call -> sweep.md
#   D  bench/tiled_cli_bench.sh  ./tdc one-shot vs --max-memory 400/800 on 10M points
#                                                                     -> tiled.md
#   E  bench/constrained_bench.sh  (optional, BENCH_CONSTRAINED=1) the constrained
#      triangulation against SFCGAL and our unconstrained one, on 1M contour
#      vertices and GSHHG coastline polygons          -> constrained.md
#   F  bench/voronoi_bench.sh  (optional, BENCH_VORONOI=1) Voronoi: ours vs
#      ST_VoronoiPolygons, 10^5 and 10^6 points        -> voronoi.md
#   G  bench/tin_bench.sh  (optional, BENCH_TIN=1; alone: make bench-tin) the TIN:
#      interpolation into rasters against ST_InterpolateRaster (GDAL), draping,
#      contours and the Delaunay aggregate on 10^6 terrain samples, and a size
#      sweep of the interpolation                      -> tin.md
#   H  bench/first_statement.sh  the 1M-point aggregate as the first statement of
#      a freshly started server, and warm, ours against PostGIS (a server of its
#      own, restarted before every first statement)   -> first_statement.md
#   I  bench/coverage_bench.sh  (optional, BENCH_COVERAGE=1; alone: make bench-coverage)
#      a 1 m DEM coverage from 1e8 LiDAR ground points: CALL tdc_interpolate_tiled
#      from a geometry and a pcpatch table against ./tdc --grid, and the pcpatch
#      aggregates against PC_Explode at 1e7 points    -> coverage.md
#      and the pcpatch aggregates' size sweep (BENCH_SWEEP_SOURCE=patch
#      bench/sweep_bench.sh)                          -> sweep_patch.md
#
# Each script writes its own report, docs/benchmarks/NAME.md (BENCH_DOCS),
# with the header of bench_publish in bench/lib.sh: date, commit, machine,
# software and load.  Every run is kept in build/bench/*.csv (BENCH_OUT).
# A script refuses to write its report when the machine was not quiet
# (bench/quiet.sh: exit status 3); the others still run, and this script then
# names the refused ones and exits with status 3.  BENCH_NOISY=1 writes them
# anyway, marked "(noisy machine)".  Run nothing else beside it.
#
# B, C, E, F and G run against the server the PG* variables point at when one answers;
# otherwise a throw-away cluster is started with scripts/lib.sh and stopped
# afterwards.  Either way the extension is built and installed first.
#
#   BENCH_SKIP_CORE=1   skip A          BENCH_SKIP_SQL=1   skip B
#   BENCH_SKIP_SWEEP=1  skip C          BENCH_NO_INSTALL=1 do not run make install before B, C, E and F
#   BENCH_SKIP_FIRST=1  skip H (some 6 minutes)
#   BENCH_SKIP_TILED=1  skip D (about a minute; its 100M case only with BENCH_TILED_100M=1)
#   BENCH_CONSTRAINED=1 run E too (some 10 minutes: SFCGAL takes 5-20 s a statement, 12 times)
#   BENCH_VORONOI=1     run F too (BENCH_VOR_* knobs: see bench/voronoi_bench.sh)
#   BENCH_TIN=1         run G too (some 10 minutes; BENCH_TIN_* knobs: see bench/tin_bench.sh)
#   BENCH_COVERAGE=1    run I too (an hour or more, ~20 GB of disk; BENCH_COV_* knobs: see
#                       bench/coverage_bench.sh)
# The knobs of the scripts (BENCH_SIZES, BENCH_SQL_SIZES, BENCH_SWEEP_*, BENCH_TILED_*, BENCH_CDT_*,
# ...) pass through.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

mkdir -p "$BENCH_OUT"
log "tdc_delaunay benchmarks; results in $BENCH_OUT"

# part SCRIPT: run bench/SCRIPT; a refusal (status 3, a noisy machine) is
# noted and the run goes on, any other failure is returned
REFUSED=()
part() {
	local rc=0
	bash "$ROOT/bench/$1" || rc=$?
	if [ $rc = 3 ]; then
		log "bench/$1 refused to write its report: the machine was not quiet"
		REFUSED+=("$1")
		return 0
	fi
	return $rc
}

if [ "${BENCH_SKIP_CORE:-0}" != 1 ]; then
	log "=== A: core benchmark"
	part core_bench.sh
fi

if [ "${BENCH_SKIP_TILED:-0}" != 1 ]; then
	log "=== D: tiled command line (./tdc --max-memory)"
	part tiled_cli_bench.sh || log "the tiled benchmark failed"
fi

# sql_parts: B, C, E, F, G, H and I, against the server the PG* variables now point at
sql_parts() {
	if [ "${BENCH_SKIP_SQL:-0}" != 1 ]; then
		log "=== B: SQL benchmark"
		part sql_bench.sh
	fi
	if [ "${BENCH_SKIP_SWEEP:-0}" != 1 ]; then
		log "=== C: SQL size sweep"
		part sweep_bench.sh
	fi
	if [ "${BENCH_CONSTRAINED:-0}" = 1 ]; then
		log "=== E: constrained, against SFCGAL"
		part constrained_bench.sh
	fi
	if [ "${BENCH_VORONOI:-0}" = 1 ]; then
		log "=== F: Voronoi diagrams in SQL"
		part voronoi_bench.sh
	fi
	if [ "${BENCH_SKIP_FIRST:-0}" != 1 ]; then
		log "=== H: the first statement of a fresh server (a server of its own)"
		part first_statement.sh
	fi
	if [ "${BENCH_TIN:-0}" = 1 ]; then
		log "=== G: the TIN in SQL: interpolation, draping, contours"
		part tin_bench.sh
	fi
	if [ "${BENCH_COVERAGE:-0}" = 1 ]; then
		log "=== I: DEM coverages and pcpatch aggregates in SQL"
		part coverage_bench.sh
		log "=== I: the pcpatch aggregates from 3 points a call"
		BENCH_SWEEP_SOURCE=patch part sweep_bench.sh
	fi
}

if [ "${BENCH_SKIP_SQL:-0}" != 1 ] || [ "${BENCH_SKIP_SWEEP:-0}" != 1 ] || [ "${BENCH_CONSTRAINED:-0}" = 1 ] ||
	[ "${BENCH_VORONOI:-0}" = 1 ] || [ "${BENCH_TIN:-0}" = 1 ] || [ "${BENCH_COVERAGE:-0}" = 1 ]; then
	# shellcheck source=scripts/lib.sh
	. "$ROOT/scripts/lib.sh"
	if [ "${BENCH_NO_INSTALL:-0}" != 1 ]; then
		tdc_build_install || log "build/install of the extension failed: the SQL benchmark may run PostGIS only"
	fi
	if [ -n "${PGHOST:-}${PGPORT:-}${PGDATABASE:-}" ] && psql -X -q -c 'SELECT 1' >/dev/null 2>&1; then
		log "using the server at PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} (database ${PGDATABASE:-default})"
	else
		TDC_USE_EXISTING=0
		TDC_EXISTING=0
		# a cluster of our own: never reuse (and then stop) the one make test runs
		export TDC_PGDIR=${TDC_PGDIR:-$BENCH_OUT/pgcluster}
		trap 'tdc_server_down' EXIT
		tdc_server_up
		export PGDATABASE=postgres
	fi
	sql_parts
fi

if [ ${#REFUSED[@]} -gt 0 ]; then
	log "done, but no report from ${REFUSED[*]}: the machine was not quiet (their samples: $BENCH_OUT/*.load.csv)"
	exit 3
fi
log "done: the reports are in $BENCH_DOCS/*.md (each written by its benchmark), every run in $BENCH_OUT"
