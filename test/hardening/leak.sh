#!/usr/bin/env bash
# test/hardening/leak.sh: a million small calls in one session leave the
# backend's memory where it was.
#
#   PGHOST=... PGPORT=... PGUSER=... PGDATABASE=... bash test/hardening/leak.sh
#
# Small inputs run on the backend's own thread from malloc'd and palloc'd
# memory (no threads, no mappings), so a leak there would not show up as a
# mapping left behind but as a backend that grows call by call.  In one
# session:
#   1. CALLS (1,000,000) calls of ST_TDCDelaunayTriangles on 5-point values,
#      in rounds over a 10,000-row table, with all three output flags and a
#      tolerance on a share of them; then a GROUP BY aggregate over 30,000
#      groups of 3 to 40 points, and the sizes around the inline/threaded
#      switch (19,999 and 20,001 points).
#   2. The backend's private memory (RssAnon) after the last round is within
#      GROWTH_KB (4096) of what it was after a warm-up of three rounds of
#      everything (the caches, the plans, malloc's arenas; the GROUP BY's
#      hash table alone makes RssAnon move by about a megabyte either way).
#   pg_postmaster_start_time() unchanged at the end.
# Prints "N passed, N failed".  About half a minute on a quiet machine.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

CALLS=${CALLS:-1000000}
GROWTH_KB=${GROWTH_KB:-4096}
ROWS=10000
ROUNDS=$(((CALLS + ROWS - 1) / ROWS))

echo "== leak.sh: $CALLS small calls in one session"
server_begin

hpsql -c "DROP TABLE IF EXISTS tdc_hard.leak_rows, tdc_hard.leak_groups;
	CREATE UNLOGGED TABLE tdc_hard.leak_rows AS
	SELECT i AS id, ST_Collect(ARRAY(SELECT ST_MakePoint(
			(hashint4(i * 8 + k) & 65535)::float8 / 655.35,
			(hashint4(-i * 8 - k) & 65535)::float8 / 655.35)
		FROM generate_series(1, 5) k)) AS g
	FROM generate_series(1, $ROWS) i;
	CREATE UNLOGGED TABLE tdc_hard.leak_groups AS
	SELECT i % 30000 AS grp,
		ST_MakePoint((hashint4(i) & 65535)::float8, (hashint4(-i) & 65535)::float8) AS geom
	FROM generate_series(1, 30000 * 3 + 300000) i;
	ANALYZE tdc_hard.leak_rows; ANALYZE tdc_hard.leak_groups;" >/dev/null

RSS="SELECT 'rss ' || substring(s FROM 'RssAnon:\\s*(\\d+)') FROM pg_read_file('/proc/' || pg_backend_pid() || '/status') s"
ROUND="SELECT 'round ' || sum(ST_NumGeometries(ST_TDCDelaunayTriangles(g, CASE WHEN id % 7 = 0 THEN 0.01 ELSE 0 END, id % 3))) FROM tdc_hard.leak_rows"
GROUPBY="SELECT 'groups ' || count(d) FROM (SELECT ST_TDCDelaunay(geom) d FROM tdc_hard.leak_groups GROUP BY grp) s"
SWITCH="SELECT 'switch ' || ST_NumGeometries(ST_TDCDelaunay(geom)) FROM (SELECT geom FROM tdc_hard.leak_groups LIMIT 19999) s
	UNION ALL SELECT 'switch ' || ST_NumGeometries(ST_TDCDelaunay(geom)) FROM (SELECT geom FROM tdc_hard.leak_groups LIMIT 20001) s"

WORK=$(mktemp -d "${TMPDIR:-/tmp}/tdc_leak.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
{
	echo "SET max_parallel_workers_per_gather = 0;"
	# warm-up: three of everything
	for ((r = 0; r < 3; r++)); do
		echo "$ROUND;"
		echo "$GROUPBY;"
		echo "$SWITCH;"
	done
	echo "$RSS;"
	for ((r = 3; r < ROUNDS; r++)); do
		echo "$ROUND;"
		((r % 25 == 0)) && echo "$GROUPBY;"
	done
	echo "$GROUPBY;"
	echo "$SWITCH;"
	echo "$RSS;"
} >"$WORK/session.sql"

t0=$SECONDS
out=$(hpsql -f "$WORK/session.sql" 2>&1) || true
rounds=$(grep -c '^round ' <<<"$out" || true)
check "all $ROUNDS rounds of $ROWS calls ran ($rounds did, $((SECONDS - t0)) s)" test "$rounds" = "$ROUNDS"
check "every round gave the same triangle count" test "$(grep '^round ' <<<"$out" | sort -u | wc -l)" = 1
check "every GROUP BY gave 30000 groups" test "$(grep '^groups ' <<<"$out" | sort -u)" = "groups 30000"
mapfile -t rss < <(sed -n 's/^rss //p' <<<"$out")
if ((${#rss[@]} == 2)); then
	echo "  RssAnon after the warm-up ${rss[0]} kB, after $CALLS calls ${rss[1]} kB"
	check "backend memory flat over $CALLS calls (grew $((rss[1] - rss[0])) kB, limit $GROWTH_KB)" \
		test $((rss[1] - rss[0])) -le "$GROWTH_KB"
else
	echo "$out" | grep -m5 -E 'ERROR|FATAL' || true
	fail "RssAnon read twice"
fi
check_postmaster
finish
