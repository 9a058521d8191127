#!/usr/bin/env bash
# test/citus/run.sh: tdc_delaunay_tiled on a 3-node Citus cluster (a
# coordinator and two workers) on this machine, throw-away like
# scripts/cluster.sh: three initdb'ed clusters listening on Unix sockets only
# (no TCP), in a fresh directory under /tmp, always stopped and removed on exit.
#
#   bash test/citus/run.sh [NPOINTS]      (default 20000)
#
# 1. builds Citus 13.2.2 from ../shared/citus, or takes it from the cache
#    (test/citus/build.sh), and installs it into PG_CONFIG's PostgreSQL (the
#    release's major by default); on a major Citus does not support (18) it
#    says "skipped" and tests nothing;
# 2. starts the nodes with shared_preload_libraries = citus, creates postgis,
#    tdc_delaunay and citus on each, and registers the workers;
# 3. distributes a table of uniform points by its tile column, runs
#    tdc_delaunay_tiled, and checks: the target is distributed and co-located
#    with the source, its triangles are those of ST_TDCDelaunayDump, each
#    once, and (auto_explain on the coordinator) the per-tile INSERT ...
#    SELECT ran as a pushed-down Citus plan (no "pull to coordinator");
#    and the same points in a plain table of the coordinator give the same
#    triangles, tiles and id ranks through the one C function;
# 4. an error inside a tile leaves no target behind, on any node.
# Prints "N passed, M failed".  Needs root or the rights to install Citus into
# PostgreSQL's directories (the build alone does not).
set -uo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
# shellcheck source=scripts/lib.sh
source "$ROOT/scripts/lib.sh"
NPTS=${1:-20000}
PASS=0
FAIL=0
ok() { PASS=$((PASS + 1)); echo "ok - $*"; }
bad() { FAIL=$((FAIL + 1)); echo "FAIL - $*"; }
finish() { echo "citus: $PASS passed, $FAIL failed"; exit $((FAIL > 0)); }

t0=$SECONDS
if ! why=$(bash "$HERE/build.sh" --supported 2>&1); then
	echo "citus: skipped: ${why#citus-build: }"
	finish
fi
if bash "$HERE/build.sh"; then
	ok "Citus 13.2.2 built/installed ($((SECONDS - t0)) s)"
else
	bad "Citus build failed"
	finish
fi

TDC_OWNER=$(tdc_cluster_owner)
PGBIN=$("$PG_CONFIG" --bindir)
BASE=$(mktemp -d /tmp/tdc-citus-XXXXXX)
chmod 755 "$BASE"
((EUID == 0)) && chown "$TDC_OWNER:" "$BASE"
RUN=$BASE/run
as_owner() { if ((EUID == 0)); then (cd / && runuser -u "$TDC_OWNER" -- "$@"); else (cd / && "$@"); fi; }
as_owner mkdir -p "$RUN"
NODES=(coord w1 w2)
declare -A PORT
cleanup() {
	for n in "${NODES[@]}"; do
		[ -f "$BASE/$n/postmaster.pid" ] && as_owner "$PGBIN/pg_ctl" -D "$BASE/$n" -m immediate -w stop >/dev/null 2>&1
	done
	rm -rf "$BASE"
}
trap cleanup EXIT

started=1
next=${TDC_CITUS_PORT_START:-5633}
for n in "${NODES[@]}"; do
	while tdc_port_busy "$next"; do next=$((next + 1)); done
	PORT[$n]=$next
	next=$((next + 1))
	as_owner "$PGBIN/initdb" -D "$BASE/$n" -U "$TDC_OWNER" -A trust --no-locale -E UTF8 --no-sync \
		>"$BASE/initdb-$n.log" 2>&1 || { cat "$BASE/initdb-$n.log"; started=0; break; }
	as_owner tee -a "$BASE/$n/postgresql.conf" >/dev/null <<-CONF
		port = ${PORT[$n]}
		listen_addresses = ''
		unix_socket_directories = '$RUN'
		unix_socket_permissions = 0700
		shared_preload_libraries = 'citus'
		citus.node_conninfo = 'sslmode=disable'
		fsync = off
		synchronous_commit = off
		full_page_writes = off
		shared_buffers = 64MB
		max_connections = 60
		log_min_messages = log
	CONF
	as_owner "$PGBIN/pg_ctl" -D "$BASE/$n" -l "$RUN/$n.log" -w -t 120 start >/dev/null ||
		{ tail -20 "$RUN/$n.log"; started=0; break; }
done
if ((started)); then
	ok "coordinator and 2 workers started (ports ${PORT[coord]} ${PORT[w1]} ${PORT[w2]}, sockets in $RUN)"
else
	bad "a node did not start"
	finish
fi

q() {	# node sql...: run as the owner, stop at the first error, unaligned output
	local n=$1
	shift
	as_owner "$PGBIN/psql" -X -q -A -t -v ON_ERROR_STOP=1 -h "$RUN" -p "${PORT[$n]}" -U "$TDC_OWNER" -d postgres "$@"
}

setup_ok=1
for n in w1 w2 coord; do
	q "$n" -c "CREATE EXTENSION citus; CREATE EXTENSION postgis; CREATE EXTENSION tdc_delaunay;" || setup_ok=0
done
q coord -c "SELECT citus_set_coordinator_host('$RUN', ${PORT[coord]});
			SELECT citus_add_node('$RUN', ${PORT[w1]}); SELECT citus_add_node('$RUN', ${PORT[w2]});" >/dev/null || setup_ok=0
nw=$(q coord -c "SELECT count(*) FROM citus_get_active_worker_nodes()")
if ((setup_ok)) && [ "$nw" = 2 ]; then
	ok "citus, postgis, tdc_delaunay on every node; 2 active workers"
else
	bad "cluster set-up (active workers: ${nw:-?})"
	finish
fi

# TDC_CITUS_BENCH=N: instead of the checks, time N uniform points in tiles
# of about N/16 (bench/tiled_sql.sh calls this)
if [ -n "${TDC_CITUS_BENCH:-}" ]; then
	N=$TDC_CITUS_BENCH
	q coord -c "SELECT setseed(0.5);
		CREATE TABLE bpts AS SELECT (floor(x / 25) * 4 + floor(y / 25))::int AS tile, ST_MakePoint(x, y) AS geom
		  FROM (SELECT random() * 100 AS x, random() * 100 AS y FROM generate_series(1, $N) i) s;
		SELECT create_distributed_table('bpts', 'tile');
		SELECT truncate_local_data_after_distributing_table('bpts');" >/dev/null 2>&1 || { bad "bench set-up"; finish; }
	t1=$(date +%s.%N)
	out=$(q coord -c "CALL tdc_delaunay_tiled('bpts', 'btri', tile_column => 'tile');" \
		-c "SELECT regexp_replace(pg_read_file('/proc/self/status'), '.*VmHWM:\s*([0-9]+ kB).*', '\1')" 2>&1)
	t2=$(date +%s.%N)
	echo "citus bench: $N points, 2 workers, 32 shards: tdc_delaunay_tiled $(echo "$t2 - $t1" | bc) s;" \
		"coordinator backend peak RSS (VmHWM) $(echo "$out" | tail -1)"
	echo "$out" | grep -o '[0-9]* triangles from .*' | sed 's/^/citus bench: /'
	q coord -c "SELECT 'citus bench: triangles on port ' || nodeport || ': ' || count(*) || ' shards, '
					  || pg_size_pretty(sum(shard_size)) FROM citus_shards WHERE table_name = 'btri'::regclass
				GROUP BY nodeport ORDER BY nodeport"
	ok "bench"
	finish
fi

# uniform points, tiles of a 4 x 4 grid, distributed by tile
q coord -c "SELECT setseed(0.5);
	CREATE TABLE pts AS SELECT i AS id, (floor(x / 25) * 4 + floor(y / 25))::int AS tile, ST_MakePoint(x, y) AS geom
	  FROM (SELECT i, random() * 100 AS x, random() * 100 AS y FROM generate_series(1, $NPTS) i) s;
	SELECT create_distributed_table('pts', 'tile');" >/dev/null &&
	ok "pts ($NPTS points) distributed by tile" || bad "create_distributed_table(pts)"

# the run, with the coordinator's plans of nested statements logged
t1=$SECONDS
if q coord -c "LOAD 'auto_explain'; SET auto_explain.log_min_duration = 0;
		SET auto_explain.log_nested_statements = on; SET auto_explain.log_level = log;
		SET client_min_messages = notice;
		CALL tdc_delaunay_tiled('pts', 'tri', tile_column => 'tile');" >"$BASE/call.out" 2>&1; then
	ok "CALL tdc_delaunay_tiled on Citus ($((SECONDS - t1)) s): $(grep -o '[0-9]* triangles from .*' "$BASE/call.out")"
else
	bad "CALL tdc_delaunay_tiled on Citus"
	grep -A8 'ERROR' "$BASE/call.out" | head -40
fi

coloc=$(q coord -c "SELECT count(DISTINCT colocationid) || '/' || count(*) FROM pg_dist_partition
					 WHERE logicalrelid IN ('pts'::regclass, 'tri'::regclass)" 2>&1)
[ "$coloc" = "1/2" ] && ok "target tri is distributed and co-located with pts" || bad "target not co-located: $coloc"

cmp=$(q coord -c "CREATE TEMP TABLE a AS SELECT ST_AsEWKB(ST_Normalize(geom)) AS g FROM tri;
	CREATE TEMP TABLE b AS SELECT ST_AsEWKB(ST_Normalize(geom)) AS g FROM ST_TDCDelaunayDump('SELECT geom FROM pts');
	SELECT (SELECT count(*) FROM a) || ' ' || (SELECT count(*) FROM b) || ' ' ||
		   (SELECT count(*) FROM (SELECT g FROM a EXCEPT ALL SELECT g FROM b) x) || ' ' ||
		   (SELECT count(*) FROM (SELECT g FROM b EXCEPT ALL SELECT g FROM a) x) || ' ' ||
		   (SELECT count(DISTINCT id) = count(*) FROM tri);" 2>&1 | tail -1)
read -r na nb ab ba uniq <<<"$cmp"
if [ -n "${na:-}" ] && [ "$na" = "$nb" ] && [ "$ab" = 0 ] && [ "$ba" = 0 ] && { [ "$uniq" = t ] || [ "$uniq" = true ]; } && ((na > 0)); then
	ok "same triangle set as ST_TDCDelaunayDump ($na triangles, ids unique)"
else
	bad "triangle sets differ (tiled, dump, only tiled, only dump, ids unique: $cmp)"
fi

# the same points in a plain table of the coordinator: the one C function
# of plain PostgreSQL, whose tiles only label; the same triangles, tiles and
# id ranks as the rounds on the workers
cmp=$(q coord -c "CREATE TABLE pts_local AS SELECT * FROM pts;
	CALL tdc_delaunay_tiled('pts_local', 'tri_local', tile_column => 'tile');
	CREATE TEMP TABLE a AS SELECT ST_AsEWKB(ST_Normalize(geom)) AS g, tile, id >> 32 AS r FROM tri;
	CREATE TEMP TABLE b AS SELECT ST_AsEWKB(ST_Normalize(geom)) AS g, tile, id >> 32 AS r FROM tri_local;
	SELECT (SELECT count(*) FROM b) || ' ' ||
		   (SELECT count(*) FROM (SELECT * FROM a EXCEPT ALL SELECT * FROM b) x) || ' ' ||
		   (SELECT count(*) FROM (SELECT * FROM b EXCEPT ALL SELECT * FROM a) x);" 2>&1 | tail -1)
read -r nl ab ba <<<"$cmp"
if [ -n "${nl:-}" ] && [ "$ab" = 0 ] && [ "$ba" = 0 ] && ((nl > 0)); then
	ok "a plain table on the coordinator: the same (triangle, tile, id rank) as the rounds ($nl triangles)"
else
	bad "plain table against the rounds (triangles, only in the rounds, only in the plain run: $cmp)"
fi

# the per-tile statement's plan on the coordinator
awk '/duration: .* plan:/ { keep = 0 } /_tdc_tile\(h\.g/ { keep = 1 } keep' "$RUN/coord.log" >"$BASE/tile-plan.txt"
if grep -q 'Custom Scan (Citus' "$BASE/tile-plan.txt" &&
	! grep -qi 'pull to coordinator\|repartition' "$BASE/tile-plan.txt"; then
	ok "per-tile INSERT ... SELECT pushed down to the workers"
	grep -E 'Custom Scan|Task Count|Tasks Shown|INSERT/SELECT|Node:|GroupAggregate|HashAggregate|Insert on' \
		"$BASE/tile-plan.txt" | head -12 | sed 's/^/    /'
else
	bad "per-tile INSERT ... SELECT was not pushed down"
	head -40 "$BASE/tile-plan.txt"
fi
cp "$BASE/tile-plan.txt" "$ROOT/build/citus-tile-plan.txt" 2>/dev/null || true
# no statement of the run moved points or triangles through the coordinator
# (the halo is built by a repartitioned INSERT ... SELECT, worker to worker);
# only the small tiles table (one row per tile) is copied from the
# coordinator into its reference table
awk '/duration: .* plan:/ { if (blk ~ /pull to coordinator/) print first; blk = ""; first = ""; next }
	 /Query Text:/ && first == "" { first = $0 } { blk = blk "\n" $0 }
	 END { if (blk ~ /pull to coordinator/) print first }' "$RUN/coord.log" >"$BASE/pulls.txt"
methods=$(grep -o 'INSERT/SELECT method: [a-z ]*' "$RUN/coord.log" | sort | uniq -c | tr -s ' ' | paste -sd, -)
if ! grep -v -q 'INSERT INTO [a-z_.]*tdc_tiled_[0-9]*_tiles SELECT' "$BASE/pulls.txt"; then
	ok "only the tiles table went through the coordinator ($(grep -c . "$BASE/pulls.txt") pulled statement(s); methods:${methods:- pushed down only})"
else
	bad "an INSERT ... SELECT pulled rows to the coordinator: $(head -3 "$BASE/pulls.txt")"
fi

# an error in a tile: no target, no staging table, on any node
q coord -c "SET tdc_delaunay.max_memory = 1; CALL tdc_delaunay_tiled('pts', 'tri_err', tile_column => 'tile');" \
	>"$BASE/err.out" 2>&1
left=0
for n in coord w1 w2; do
	c=$(q "$n" -c "SELECT count(*) FROM pg_class WHERE relname LIKE 'tri_err%' OR relname LIKE 'tdc_tiled%'")
	left=$((left + ${c:-1}))
done
if grep -q 'max_memory' "$BASE/err.out" && ((left == 0)); then
	ok "a tile over tdc_delaunay.max_memory: ERROR, no target or staging table on any node"
else
	bad "error case (left behind: $left): $(head -3 "$BASE/err.out")"
fi
# an existing target is an error
if ! q coord -c "CALL tdc_delaunay_tiled('pts', 'tri', tile_column => 'tile')" >"$BASE/exists.out" 2>&1 &&
	grep -q 'already exists' "$BASE/exists.out"; then
	ok "an existing target is an error"
else
	bad "existing target: $(head -3 "$BASE/exists.out")"
fi

echo "citus: wall time $((SECONDS - t0)) s"
finish
