#!/usr/bin/env bash
# test/citus/run.sh: tdc_delaunay_tiled, tdc_interpolate_tiled and
# tdc_contours_tiled on a 3-node Citus cluster (a
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
#    postgis_raster, tdc_delaunay, tdc_delaunay_raster and citus on each,
#    and registers the workers;
# 3. distributes a table of uniform points by its tile column, runs
#    tdc_delaunay_tiled, and checks: the target is distributed and co-located
#    with the source, its triangles are those of ST_TDCDelaunayDump, each
#    once, and (auto_explain on the coordinator) the per-tile INSERT ...
#    SELECT ran as a pushed-down Citus plan (no "pull to coordinator");
#    and the same points in a plain table of the coordinator give the same
#    triangles, tiles and id ranks through the one C function;
# 4. an error inside a tile leaves no target behind, on any node;
# 5. tdc_interpolate_tiled and tdc_contours_tiled on sources distributed by
#    id (in one pass, and under a max_memory that takes the bounded run into
#    tens of tiles) and on a reference table: the same tiles and lines, byte
#    for byte, as on the coordinator's plain tables, which equal
#    ST_TDCInterpolate's windows and ST_TDCContours's lines; the rounds (the
#    scans of the distributed source, from citus.log_remote_commands: one
#    command per shard each) are 1 for a coverage and 2 for contours, in one
#    pass or many tiles; the targets are plain tables of the coordinator,
#    AddRasterConstraints takes the coverage (and a distributed copy of it);
#    errors after the distributed read leave no target on any node;
# 6. where pgpointcloud is installed, the procedures over a pcpatch column
#    distributed by id: the same tiles, lines and triangles as over the
#    same patches in a plain table; and tdc_delaunay_tiled with a
#    tile_column over patches refused with a hint, nothing written.
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
	q "$n" -c "CREATE EXTENSION citus; CREATE EXTENSION postgis; CREATE EXTENSION tdc_delaunay;
			   CREATE EXTENSION postgis_raster; CREATE EXTENSION tdc_delaunay_raster;" || setup_ok=0
done
q coord -c "SELECT citus_set_coordinator_host('$RUN', ${PORT[coord]});
			SELECT citus_add_node('$RUN', ${PORT[w1]}); SELECT citus_add_node('$RUN', ${PORT[w2]});" >/dev/null || setup_ok=0
nw=$(q coord -c "SELECT count(*) FROM citus_get_active_worker_nodes()")
if ((setup_ok)) && [ "$nw" = 2 ]; then
	ok "citus, postgis(_raster), tdc_delaunay(_raster) on every node; 2 active workers"
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

# 5. tdc_interpolate_tiled and tdc_contours_tiled on a distributed source.
# The clustered samples with heights of sql/tdc_raster_tiled.sql: 2,000
# (one pass) and 262,800 (under max_memory = 16 MB, the core's bounded run
# in tens of tiles), made as plain tables of the coordinator (zs_local,
# zc_local), then copied into tables distributed by id whose shells on the
# coordinator are emptied: a procedure that read the coordinator's own
# table instead of the shards would see no sample.  The checks of the
# pg_regress tests (cov_check, cov_constraints, ct_check) are read from
# their files, so both compare the same things.
t1=$SECONDS
TS="ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326)"
TC="ST_MakeEmptyRaster(331, 290, -20, 230, 1.0, -1.0, 0, 0, 3006)"
{
	sed -n '/^CREATE FUNCTION cov_check/,/^END \$\$;/p; /^CREATE FUNCTION cov_constraints/,/^END \$\$;/p' \
		"$ROOT/sql/tdc_raster_tiled.sql"
	sed -n '/^CREATE FUNCTION ct_check/,/^END \$\$;/p' "$ROOT/sql/tdc_contours_tiled.sql"
	cat <<-SQL
		SELECT setseed(0.25);
		CREATE TABLE zs_local AS
			SELECT row_number() OVER () AS id, ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
			  FROM (SELECT cx + 30 * (random() - 0.5) AS x, cy + 30 * (random() - 0.5) AS y
					  FROM (SELECT (i % 2) * 60 AS cx, (i / 2) * 50 AS cy FROM generate_series(0, 3) i) c,
						   generate_series(1, 500)) q;
		CREATE TABLE zc_local AS
			SELECT row_number() OVER () AS id, ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
			  FROM (SELECT cx + 30 * (random() - 0.5) AS x, cy + 30 * (random() - 0.5) AS y
					  FROM (SELECT (i % 3) * 100 AS cx, ((i / 3) % 3) * 100 AS cy FROM generate_series(0, 8) i) c,
						   generate_series(1, 29200)) q;
		CREATE TABLE zs AS SELECT * FROM zs_local;
		CREATE TABLE zc AS SELECT * FROM zc_local;
		CREATE TABLE zr AS SELECT * FROM zs_local;
		SELECT create_distributed_table('zs', 'id'), create_distributed_table('zc', 'id'), create_reference_table('zr');
		SELECT truncate_local_data_after_distributing_table(t) FROM unnest(ARRAY['zs', 'zc', 'zr']::regclass[]) t;
	SQL
} >"$BASE/zsetup.sql"
if q coord -f "$BASE/zsetup.sql" >"$BASE/zsetup.out" 2>&1 &&
	[ "$(q coord -c "SELECT count(*) FROM pg_dist_partition WHERE logicalrelid IN ('zs'::regclass, 'zc'::regclass, 'zr'::regclass)
					 AND pg_relation_size('zs') + pg_relation_size('zc') + pg_relation_size('zr') = 0")" = 3 ]; then
	ok "samples with heights: zs (2000) and zc (262800) distributed by id, zr (2000) a reference table; shells empty"
else
	bad "set-up of the samples with heights: $(grep -m3 ERROR "$BASE/zsetup.out")"
fi

# zcall NAME SQL: SQL in a session of the coordinator with one thread (the
# same plan on every machine) and each command it sends to a worker logged
# (citus.log_remote_commands: one NOTICE per command), into $BASE/NAME.out
zcall() {
	q coord -c "SET tdc_delaunay.threads = 1; SET citus.log_remote_commands = on; SET client_min_messages = notice;" \
		-c "$2" >"$BASE/$1.out" 2>&1
}
# rounds NAME TABLE: the commands of NAME's run that read a shard of TABLE,
# over TABLE's shard count: the number of times the run scanned the whole
# distributed source (each scan is one command per shard)
rounds() {
	local n s
	n=$(grep -c -E "issuing .*[ .]${2}_[0-9]+ " "$BASE/$1.out")
	s=$(q coord -c "SELECT count(*) FROM pg_dist_shard WHERE logicalrelid = '$2'::regclass")
	if ((s > 0 && n % s == 0)); then echo "$((n / s)) $n $s"; else echo "? $n $s"; fi
}
zrun() {	# NAME TABLE ROUNDS PASS SQL: a run on a distributed source, its summary, its rounds
	local name=$1 tbl=$2 want=$3 pass=$4 r sum
	if zcall "$name" "$5"; then
		sum=$(grep -o 'tdc_[a-z_]*_tiled: .*' "$BASE/$name.out")
		read -r -a r <<<"$(rounds "$name" "$tbl")"
		if [ "${r[0]}" = "$want" ] && grep -q -- "$pass" <<<"$sum"; then
			ok "$name on distributed $tbl: $sum; rounds: ${r[0]} (${r[1]} shard queries over ${r[2]} shards)"
		else
			bad "$name on distributed $tbl: rounds ${r[*]} (want $want), summary '$sum' (want '$pass')"
		fi
	else
		bad "$name on distributed $tbl: $(grep -m1 -A2 ERROR "$BASE/$name.out")"
	fi
}
# one pass, then the bounded run in several tiles; the interpolation reads
# the source once, the contours twice (the SRID of the target's column,
# LIMIT 1, then the samples)
zrun i_one zs 1 'in one pass' \
	"CALL tdc_interpolate_tiled('zs', 'zs_cov', 'geom', $TS, 'linear', '64BF', -9999, 30, 17)"
zrun i_run zc 1 'in [0-9]* run tiles' \
	"SET tdc_delaunay.max_memory = 16; CALL tdc_interpolate_tiled('zc', 'zc_cov', 'geom', $TC, 'linear', '32BF', -9999, 64, 50)"
zrun c_one zs 2 'in one pass' \
	"CALL tdc_contours_tiled('zs', 'zs_lines', 'geom', 2.5, 0.3)"
zrun c_run zc 2 'in [0-9]* run tiles' \
	"SET tdc_delaunay.max_memory = 16; CALL tdc_contours_tiled('zc', 'zc_lines', 'geom', 1.25)"
ntiles=$(grep -ho 'in [0-9]* run tiles' "$BASE/i_run.out" "$BASE/c_run.out" | grep -o '[0-9]*' | sort -n | head -1)
((${ntiles:-0} >= 2)) && ok "max_memory = 16 MB forced the bounded run into $ntiles or more tiles" ||
	bad "the bounded run did not take several tiles (${ntiles:-none})"

# the same procedures on the plain tables of the coordinator, and on the
# reference table
if q coord -c "SET tdc_delaunay.threads = 1;
	CALL tdc_interpolate_tiled('zs_local', 'zs_cov_local', 'geom', $TS, 'linear', '64BF', -9999, 30, 17);
	CALL tdc_contours_tiled('zs_local', 'zs_lines_local', 'geom', 2.5, 0.3);
	CALL tdc_interpolate_tiled('zr', 'zr_cov', 'geom', $TS, 'linear', '64BF', -9999, 30, 17);
	CALL tdc_contours_tiled('zr', 'zr_lines', 'geom', 2.5, 0.3);
	SET tdc_delaunay.max_memory = 16;
	CALL tdc_interpolate_tiled('zc_local', 'zc_cov_local', 'geom', $TC, 'linear', '32BF', -9999, 64, 50);
	CALL tdc_contours_tiled('zc_local', 'zc_lines_local', 'geom', 1.25);" >"$BASE/zlocal.out" 2>&1; then
	ok "the same runs on plain tables of the coordinator and on the reference table"
else
	bad "runs on the plain tables: $(grep -m1 -A2 ERROR "$BASE/zlocal.out")"
fi
# zsame A B KEY: rows of A not in B and of B not in A, by KEY, and A's rows
zsame() {
	q coord -c "SELECT (SELECT count(*) FROM (SELECT $3 FROM $1 EXCEPT ALL SELECT $3 FROM $2) x) || ' ' ||
					   (SELECT count(*) FROM (SELECT $3 FROM $2 EXCEPT ALL SELECT $3 FROM $1) x) || ' ' ||
					   (SELECT count(*) FROM $1)" 2>&1
}
for p in "zs_cov zs_cov_local" "zc_cov zc_cov_local" "zr_cov zs_cov_local" \
	"zs_lines zs_lines_local" "zc_lines zc_lines_local" "zr_lines zs_lines_local"; do
	read -r a b <<<"$p"
	case $a in *cov) key="rid, rast::bytea" what=tiles ;; *) key="id, level, ST_AsEWKB(geom)" what=lines ;; esac
	read -r ab ba n <<<"$(zsame "$a" "$b" "$key")"
	if [ "$ab" = 0 ] && [ "$ba" = 0 ] && ((${n:-0} > 0)); then
		ok "$a = $b: the same $n $what, byte for byte"
	else
		bad "$a against $b (only in $a, only in $b, rows: $ab $ba $n)"
	fi
done

# against the one-value functions over the same samples: each tile the
# same window of ST_TDCInterpolate pixel for pixel, the lines those of
# ST_TDCContours (as a set, in order, each at its level).  They run over the
# coordinator's plain tables: over a distributed table Citus gathers an
# aggregate's arguments row by row, and ST_TDCInterpolate's template, a
# constant, would come back from the workers with every sample (EXPLAIN
# VERBOSE shows it in each task's target list): 262,800 copies of 384 kB.
zcov() {	# COV SRC TEMPLATE PIXTYPE TW TH PIXELS
	local r tiles bp bc bb pixels
	r=$(q coord -c "SELECT concat_ws(' ', tiles, bad_pixels, bad_corner, bad_band, pixels)
					 FROM cov_check('$1', '$2', $3, 'linear', '$4', -9999, $5, $6)" 2>&1)
	read -r tiles bp bc bb pixels <<<"$r"
	if [ "${bp:-x}" = 0 ] && [ "$bc" = 0 ] && [ "$bb" = 0 ] && [ "$pixels" = "$7" ] && ((tiles > 1)); then
		ok "$1 = ST_TDCInterpolate over $2: $tiles tiles, $pixels pixels, each its window"
	else
		bad "$1 against ST_TDCInterpolate (tiles, bad pixels, corners, bands, pixels: $r)"
	fi
}
zcov zs_cov zs_local "$TS" 64BF 30 17 13837
zcov zc_cov zc_local "$TC" 32BF 64 50 95990
for c in "zs_lines zs_local 2.5 0.3" "zc_lines zc_local 1.25 0"; do
	read -r lines src iv b0 <<<"$c"
	r=$(q coord -c "SELECT concat_ws(' ', nlines, extra, missing, bad_id, bad_level) FROM ct_check('$lines', '$src', $iv, $b0)" 2>&1)
	read -r nl ex mi bi bl <<<"$r"
	if [ "${ex:-x}" = 0 ] && [ "$mi" = 0 ] && [ "$bi" = 0 ] && [ "$bl" = 0 ] && ((nl > 0)); then
		ok "$lines = ST_TDCContours over $src: $nl lines"
	else
		bad "$lines against ST_TDCContours (lines, extra, missing, bad id, bad level: $r)"
	fi
done

# the targets are plain tables of the coordinator; AddRasterConstraints
# takes the coverage, and a distributed copy of it too
r=$(q coord -c "SELECT (SELECT count(*) FROM pg_dist_partition WHERE logicalrelid::text IN ('zs_cov', 'zc_cov', 'zs_lines', 'zc_lines'))
				 || ' ' || (SELECT count(*) FROM pg_class WHERE relname IN ('zs_cov', 'zc_cov', 'zs_lines', 'zc_lines') AND relkind = 'r')")
nw=0
for n in w1 w2; do
	c=$(q "$n" -c "SELECT count(*) FROM pg_class WHERE relname ~ '^z[sc]_(cov|lines)'")
	nw=$((nw + ${c:-1}))
done
[ "$r" = "0 4" ] && ((nw == 0)) && ok "the targets are plain tables of the coordinator, none on the workers" ||
	bad "targets: (distributed, plain on the coordinator) $r, on the workers $nw"
r=$(q coord -c "SELECT concat_ws(' ', added, same_alignment, blocksize_x, blocksize_y, srid) FROM cov_constraints('zc_cov')" 2>&1 | tail -1)
[ "$r" = "t t 64 50 3006" ] && ok "AddRasterConstraints on the coverage: $r" || bad "AddRasterConstraints on zc_cov: $r"
r=$(q coord -c "CREATE TABLE zc_cov_dist AS SELECT * FROM zc_cov_local; SELECT create_distributed_table('zc_cov_dist', 'rid');" \
	-c "SELECT concat_ws(' ', added, same_alignment, blocksize_x, blocksize_y, srid) FROM cov_constraints('zc_cov_dist')" 2>&1 | tail -1)
ncon=0
for n in w1 w2; do
	c=$(q "$n" -c "SELECT count(*) FROM pg_constraint WHERE conrelid::regclass::text LIKE 'zc_cov_dist_%' AND conname LIKE 'enforce_%'")
	ncon=$((ncon + ${c:-0}))
done
[ "$r" = "t t 64 50 3006" ] && ((ncon > 0)) &&
	ok "AddRasterConstraints on a distributed copy: $r, $ncon constraints on the workers' shards" ||
	bad "AddRasterConstraints on a distributed copy: $r ($ncon on the shards)"

# errors after the distributed read: no target on any node (natural
# neighbour in tiles: the cavities of pixels between the nine clusters
# reach across them, more than 16 MB holds)
zcall e_nn "SET tdc_delaunay.max_memory = 16; CALL tdc_interpolate_tiled('zc', 'zerr_cov', 'geom', $TC, 'natural_neighbor')"
zcall e_method "CALL tdc_interpolate_tiled('zc', 'zerr_cov', 'geom', $TC, 'cubic')"
zcall e_mem "SET tdc_delaunay.max_memory = 1; CALL tdc_contours_tiled('zc', 'zerr_lines', 'geom', 1.25)"
left=0
for n in coord w1 w2; do
	c=$(q "$n" -c "SELECT count(*) FROM pg_class WHERE relname LIKE 'zerr%'")
	left=$((left + ${c:-1}))
done
if grep -q 'natural neighbour cavities of its pixels reach that far' "$BASE/e_nn.out" && grep -q 'invalid method' "$BASE/e_method.out" &&
	grep -q 'more than tdc_delaunay.max_memory' "$BASE/e_mem.out" && ((left == 0)); then
	ok "errors (natural_neighbor whose cavities reach past max_memory, a bad method, contours over max_memory): no target on any node"
else
	bad "error cases (left behind: $left): $(grep -h -m1 ERROR "$BASE"/e_*.out | paste -sd'|')"
fi
echo "citus: the coverage and contour part took $((SECONDS - t1)) s"

# 6. A pcpatch source (where pgpointcloud is installed): the coordinator
# reads a distributed patch table as it reads geometries, so the
# procedures give the tiles, lines and triangles of the same patches in a
# plain table; tdc_delaunay_tiled's rounds on the workers read geometries
# only, so a tile_column over patches is refused with a hint before
# anything is written.  2,000 points of sql/tdc_pointcloud_tiled.sql's
# format 21 (int32 X, Y, Z scaled by 0.01, dimensional), in patches of 400;
# each node has the format in its pointcloud_formats.
if [ -n "$(q coord -c "SELECT 1 FROM pg_available_extensions WHERE name = 'pointcloud'")" ]; then
	t1=$SECONDS
	TP="ST_MakeEmptyRaster(33, 10, 499999.5, 6000002.3, 1.0, -0.25, 0, 0, 3006)"
	# the extensions through the coordinator (Citus creates them on the
	# workers); the format, a row of each node's own pointcloud_formats, on
	# each node
	{
		echo "CREATE EXTENSION pointcloud; CREATE EXTENSION tdc_delaunay_pointcloud;"
		sed -n '/^CREATE FUNCTION tdc_pc_format/,/^FROM unnest.*\$\$;/p' "$ROOT/sql/tdc_pointcloud_tiled.sql"
		echo "SELECT tdc_pc_format('{\"X int32_t 500000\",\"Y int32_t 6000000\",\"Z int32_t 100\",\"Classification uint8_t\"}', 'dimensional');"
	} >"$BASE/pcnode.sql"
	pc_ok=1
	q coord -f "$BASE/pcnode.sql" >"$BASE/pcformat.xml" 2>"$BASE/pcnode.err" || pc_ok=0
	for n in w1 w2 coord; do
		q "$n" -v xml="$(cat "$BASE/pcformat.xml")" >>"$BASE/pcnode.err" 2>&1 <<-SQL || pc_ok=0
			INSERT INTO pointcloud_formats (pcid, srid, schema) VALUES (21, 3006, :'xml');
		SQL
	done
	q coord -c "CREATE TABLE pz_local AS
		SELECT p AS id, p % 2 AS tile, PC_Patch(PC_MakePoint(21, ARRAY[x, y,
				round((sin((x - 500000) / 7) * 10 + cos((y - 6000000) / 5) * 5)::numeric, 2), 2]) ORDER BY i) AS pa
		  FROM (SELECT i, i / 400 AS p, 500000 + (i % 180) * 0.17 + ((i::bigint * 7919) % 13) * 0.01 AS x,
					   6000000 + (i / 180) * 0.19 + ((i::bigint * 104729) % 11) * 0.01 AS y
				  FROM generate_series(0, 1999) i) s
		 GROUP BY p;
		CREATE TABLE pz AS SELECT * FROM pz_local;
		CREATE TABLE pzt AS SELECT * FROM pz_local;
		SELECT create_distributed_table('pz', 'id'), create_distributed_table('pzt', 'tile');
		SELECT truncate_local_data_after_distributing_table(t) FROM unnest(ARRAY['pz', 'pzt']::regclass[]) t;" \
		>"$BASE/pzsetup.out" 2>&1 || pc_ok=0
	if ((pc_ok)) && [ "$(q coord -c "SELECT sum(PC_NumPoints(pa)) FROM pz")" = 2000 ]; then
		ok "pointcloud and tdc_delaunay_pointcloud on every node; 2,000 points in 5 patches, distributed by id and by tile"
	else
		bad "pcpatch set-up: $(grep -h -m2 ERROR "$BASE/pcnode.err" "$BASE/pzsetup.out" | paste -sd'|')"
	fi
	zrun p_cov pz 1 'in one pass' \
		"CALL tdc_interpolate_tiled('pz', 'pz_cov', 'pa', $TP, 'linear', '64BF', -9999, 16, 4)"
	zrun p_lines pz 2 'in one pass' "CALL tdc_contours_tiled('pz', 'pz_lines', 'pa', 0.5)"
	if q coord -c "SET tdc_delaunay.threads = 1;
		CALL tdc_interpolate_tiled('pz_local', 'pz_cov_local', 'pa', $TP, 'linear', '64BF', -9999, 16, 4);
		CALL tdc_contours_tiled('pz_local', 'pz_lines_local', 'pa', 0.5);
		CALL tdc_delaunay_tiled('pz', 'pz_tri', 'pa');
		CALL tdc_delaunay_tiled('pz_local', 'pz_tri_local', 'pa');" >"$BASE/pzlocal.out" 2>&1; then
		ok "the same procedures on the patches of a plain table, and tdc_delaunay_tiled on both"
	else
		bad "pcpatch runs on the coordinator: $(grep -m1 -A2 ERROR "$BASE/pzlocal.out")"
	fi
	for p in "pz_cov pz_cov_local" "pz_lines pz_lines_local" "pz_tri pz_tri_local"; do
		read -r a b <<<"$p"
		case $a in *cov) key="rid, rast::bytea" what=tiles ;; *tri) key="ST_AsEWKB(geom)" what=triangles ;;
			*) key="id, level, ST_AsEWKB(geom)" what=lines ;; esac
		read -r ab ba n <<<"$(zsame "$a" "$b" "$key")"
		if [ "$ab" = 0 ] && [ "$ba" = 0 ] && ((${n:-0} > 0)); then
			ok "$a (distributed patches) = $b (plain): the same $n $what, byte for byte"
		else
			bad "$a against $b (only in $a, only in $b, rows: $ab $ba $n)"
		fi
	done
	q coord -c "CALL tdc_delaunay_tiled('pzt', 'pz_err', 'pa', tile_column => 'tile')" >"$BASE/pzerr.out" 2>&1
	left=0
	for n in coord w1 w2; do
		c=$(q "$n" -c "SELECT count(*) FROM pg_class WHERE relname LIKE 'pz_err%'")
		left=$((left + ${c:-1}))
	done
	if grep -q 'a pcpatch column is not read by the rounds on Citus workers' "$BASE/pzerr.out" &&
		grep -q 'HINT:.*without tile_column' "$BASE/pzerr.out" && ((left == 0)); then
		ok "tdc_delaunay_tiled over patches distributed by tile_column: refused with a hint, no target on any node"
	else
		bad "the tile_column refusal over patches (left behind: $left): $(head -3 "$BASE/pzerr.out" | paste -sd'|')"
	fi
	echo "citus: the pcpatch part took $((SECONDS - t1)) s"
else
	echo "citus: pgpointcloud is not installed: the pcpatch part is skipped"
fi

echo "citus: wall time $((SECONDS - t0)) s"
finish
