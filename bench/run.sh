#!/usr/bin/env bash
# bench/run.sh -- `make bench`: the core benchmark, then the SQL benchmark.
#
#   A  bench/core_bench.sh   ./tdc (1 thread, all threads) vs CGAL   -> build/bench/core*.csv
#   B  bench/sql_bench.sh    tdc_delaunay vs PostGIS in PostgreSQL   -> build/bench/sql*.csv, docs/*.png
#
# B runs against the server the PG* variables point at when one answers;
# otherwise the extension is built and installed and a throw-away cluster is
# started with scripts/lib.sh (or, if that is absent, in build/bench/pg as the
# postgres user on a free port) and stopped afterwards.
#
#   BENCH_SKIP_CORE=1   only B          BENCH_SKIP_SQL=1   only A
#   BENCH_NO_INSTALL=1  do not run make install before B
# The knobs of the two scripts (BENCH_SIZES, BENCH_SQL_SIZES, ...) pass through.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

mkdir -p "$BENCH_OUT"
log "tdc_delaunay benchmarks; results in $BENCH_OUT"

if [ "${BENCH_SKIP_CORE:-0}" != 1 ]; then
	log "=== A: core benchmark"
	bash "$ROOT/bench/core_bench.sh"
fi

[ "${BENCH_SKIP_SQL:-0}" = 1 ] && exit 0

log "=== B: SQL benchmark"
PGBIN=/usr/lib/postgresql/15/bin
OWN_PGDIR=""
stop_own() {
	if [ -n "$OWN_PGDIR" ] && [ -f "$OWN_PGDIR/data/postmaster.pid" ]; then
		log "stopping the benchmark's throw-away server ($OWN_PGDIR)"
		su postgres -c "$PGBIN/pg_ctl -D '$OWN_PGDIR/data' -m fast -w stop" >/dev/null 2>&1 || true
	fi
}

install_ext() {
	[ "${BENCH_NO_INSTALL:-0}" = 1 ] && return 0
	if declare -F tdc_build_install >/dev/null; then
		tdc_build_install || log "build/install of the extension failed: the SQL benchmark may run PostGIS only"
	else
		{ make -C "$ROOT" -s && make -C "$ROOT" -s install; } >&2 ||
			log "build/install of the extension failed: the SQL benchmark may run PostGIS only"
	fi
}

if [ -n "${PGHOST:-}${PGPORT:-}${PGDATABASE:-}" ] && psql -X -q -c 'SELECT 1' >/dev/null 2>&1; then
	log "using the server at PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} (database ${PGDATABASE:-default})"
	[ -f "$ROOT/scripts/lib.sh" ] && . "$ROOT/scripts/lib.sh"
	install_ext
	bash "$ROOT/bench/sql_bench.sh"
elif [ -f "$ROOT/scripts/lib.sh" ]; then
	# the infrastructure's throw-away cluster (scripts/lib.sh)
	. "$ROOT/scripts/lib.sh"
	install_ext
	TDC_USE_EXISTING=0
	TDC_EXISTING=0
	trap 'tdc_server_down' EXIT
	tdc_server_up
	export PGDATABASE=postgres
	bash "$ROOT/bench/sql_bench.sh"
else
	# fallback: our own throw-away cluster, postgres user, first free port from 5492
	install_ext
	OWN_PGDIR=$BENCH_OUT/pg
	port=5492
	while (echo > /dev/tcp/127.0.0.1/$port) 2>/dev/null || [ -e "/tmp/.s.PGSQL.$port" ]; do
		port=$((port + 1))
	done
	log "starting a throw-away PostgreSQL 15 in $OWN_PGDIR on port $port"
	rm -rf "$OWN_PGDIR"
	mkdir -p "$OWN_PGDIR"
	chown postgres "$OWN_PGDIR"
	su postgres -c "$PGBIN/initdb -D '$OWN_PGDIR/data' -A trust --no-sync" >/dev/null
	trap stop_own EXIT
	su postgres -c "$PGBIN/pg_ctl -D '$OWN_PGDIR/data' -w -l '$OWN_PGDIR/log' -o \"-p $port -k '$OWN_PGDIR' -c listen_addresses='' -c max_wal_size=4GB -c fsync=off -c shared_buffers=256MB\" start" >/dev/null
	export PGHOST=$OWN_PGDIR PGPORT=$port PGUSER=postgres PGDATABASE=postgres
	bash "$ROOT/bench/sql_bench.sh"
fi
log "done: $BENCH_OUT/core.txt, $BENCH_OUT/sql.txt, docs/bench.png, docs/coast_tin.png"
