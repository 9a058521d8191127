#!/usr/bin/env bash
# test/hardening/memcap.sh: tdc_delaunay.max_memory under pressure.
#
#   PGHOST=... PGPORT=... PGUSER=... PGDATABASE=... bash test/hardening/memcap.sh
#
# (sql/tdc_guc.sql already checks that a small max_memory gives an ERROR for
# the aggregate and Dump; this goes further.)
#   1. Sweep: for POINTS (200000) points and max_memory from 1 MB up to past
#      what the input needs (coarse, then 1 MB steps around the threshold),
#      each of the aggregate, ST_TDCDelaunayTriangles(one value) and
#      ST_TDCDelaunayDump either returns the unlimited result or fails with an
#      ERROR naming tdc_delaunay.max_memory, never anything else; success is
#      monotonic in the limit.
#   2. The limit is honoured: for every successful aggregate and Dump run the
#      backend's peak RSS (VmHWM, fresh session, after a warm-up scan of the
#      table) grows by at most max_memory + 5% + 4 MB.
#   3. 20 max_memory errors (while collecting rows and before the engine) in
#      one session: private RSS (RssAnon) after 20 within 10% of after 1.
#   4. HUGE=1 only (needs ~3 GB and a minute): a real result over 1 GB
#      (7 million points) fails with the "Use ST_TDCDelaunayDump" error, and
#      the session goes on.
#   pg_postmaster_start_time() unchanged at the end.
# Prints "N passed, N failed".  About a minute without HUGE.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

POINTS=${POINTS:-200000}
TABLE=tdc_hard.pts$POINTS

echo "== memcap.sh: $POINTS points"
require_server
START0=$(postmaster_start)
make_points "${TABLE#tdc_hard.}" "$POINTS"

STATUS_HWM="SELECT 'hwm ' || substring(s FROM 'VmHWM:\\s*(\\d+)') FROM pg_read_file('/proc/' || pg_backend_pid() || '/status') s"
WARM="SELECT 'warm ' || count(*) || sum(ST_X(geom)) FROM $TABLE"
declare -A Q=(
	[agg]="SELECT 'res ' || pg_column_size(ST_TDCDelaunay(geom)) FROM $TABLE"
	[triangles]="SELECT 'res ' || pg_column_size(ST_TDCDelaunayTriangles(g)) FROM (SELECT ST_Collect(geom) AS g FROM $TABLE) s"
	[dump]="SELECT 'res ' || count(*) FROM ST_TDCDelaunayDump('SELECT geom FROM $TABLE')"
)
MODES=(agg triangles dump)

# run MODE MB -> "res N hwm0 H0 hwm H1" or "err MESSAGE"
run() {
	local mode=$1 mb=$2 out
	out=$(psql -X -q -A -t -v ON_ERROR_STOP=1 \
		-c "SET tdc_delaunay.max_memory = '${mb}MB'" -c "$WARM" -c "$STATUS_HWM" \
		-c "${Q[$mode]}" -c "$STATUS_HWM" 2>&1) || true
	if grep -q '^res ' <<<"$out"; then
		echo "res $(sed -n 's/^res //p' <<<"$out") $(sed -n 's/^hwm //p' <<<"$out" | tr '\n' ' ')"
	else
		echo "err $(grep -m1 'ERROR' <<<"$out" || echo "$out" | head -n1)"
	fi
}

# --- 1 + 2. sweep ------------------------------------------------------------
declare -A REF
for mode in "${MODES[@]}"; do
	REF[$mode]=$(psql -X -q -A -t -c "SET tdc_delaunay.max_memory = 0" -c "${Q[$mode]}" | sed -n 's/^res //p')
done
echo "unlimited results: agg ${REF[agg]} bytes, triangles ${REF[triangles]} bytes, dump ${REF[dump]} rows"

for mode in "${MODES[@]}"; do
	limits=(1 2 4 8 16 24 32 48 64 96 128 256)
	first_ok=
	bad=0
	over=0
	worst=
	declare -A OUTCOME=()
	for mb in "${limits[@]}"; do
		r=$(run "$mode" "$mb")
		OUTCOME[$mb]=$r
		if [[ $r == res* ]] && [ -z "$first_ok" ]; then first_ok=$mb; fi
	done
	# refine: 1 MB steps below the first success
	if [ -n "$first_ok" ]; then
		prev=1
		for mb in "${limits[@]}"; do
			if ((mb < first_ok)); then prev=$mb; fi
		done
		for ((mb = prev + 1; mb < first_ok; mb++)); do
			OUTCOME[$mb]=$(run "$mode" "$mb")
		done
	fi
	summary=""
	seen_ok=0
	first_ok=$(for mb in "${!OUTCOME[@]}"; do if [[ ${OUTCOME[$mb]} == res* ]]; then echo "$mb"; fi; done | sort -n | head -n1) || true
	for mb in $(printf '%s\n' "${!OUTCOME[@]}" | sort -n); do
		r=${OUTCOME[$mb]}
		if [[ $r == res* ]]; then
			read -r _ val h0 h1 <<<"$r"
			[ "$val" = "${REF[$mode]}" ] || { bad=$((bad + 1)); echo "    $mode @ ${mb} MB: wrong result $val"; }
			seen_ok=1
			summary+=" ${mb}:ok"
			if [ "$mode" != triangles ] && [ -n "${h1:-}" ]; then
				delta=$(((h1 - h0) / 1024))
				summary+="(+${delta}MB)"
				if ! awk -v d="$((h1 - h0))" -v m="$mb" 'BEGIN { exit !(d <= (m * 1.05 + 4) * 1024) }'; then
					over=$((over + 1))
					worst+=" ${mb}MB:+${delta}MB"
				fi
			fi
		else
			summary+=" ${mb}:err"
			if ! grep -q 'max_memory' <<<"$r"; then
				bad=$((bad + 1))
				echo "    $mode @ ${mb} MB: unexpected error: ${r#err }"
			fi
			if ((seen_ok)); then
				bad=$((bad + 1))
				echo "    $mode @ ${mb} MB: fails although a smaller limit worked"
			fi
		fi
	done
	echo "  $mode:$summary"
	check "$mode: every limit gives the right result or a max_memory ERROR, monotonic (first success at ${first_ok:-none} MB)" \
		test "$bad" -eq 0 -a -n "$first_ok"
	if [ "$mode" != triangles ]; then
		check "$mode: peak RSS growth within max_memory + 5% + 4 MB${worst:+ (over:$worst)}" test "$over" -eq 0
	fi
	unset OUTCOME
done

# --- 3. RSS after repeated memory errors ---------------------------------------
STATUS_ANON="SELECT 'anon ' || substring(s FROM 'RssAnon:\\s*(\\d+)') FROM pg_read_file('/proc/' || pg_backend_pid() || '/status') s"
{
	# four errors first, while the allocator settles (glibc moves its mmap
	# threshold after the first big frees), then the 20 that are measured
	for ((k = -3; k <= 20; k++)); do
		if ((k % 2)); then echo "SET tdc_delaunay.max_memory = '1MB';"; else echo "SET tdc_delaunay.max_memory = '16MB';"; fi
		echo "${Q[agg]};"
		echo "$STATUS_ANON;"
	done
} | psql -X -q -A -t -v ON_ERROR_STOP=0 >"${TMPDIR:-/tmp}/tdc_memcap.$$" 2>"${TMPDIR:-/tmp}/tdc_memcap.$$.err" || true
anons=$(sed -n 's/^anon //p' "${TMPDIR:-/tmp}/tdc_memcap.$$" | tail -n 20 | tr '\n' ' ')
nerr=$(grep -c 'ERROR.*max_memory' "${TMPDIR:-/tmp}/tdc_memcap.$$.err" || true)
rm -f "${TMPDIR:-/tmp}/tdc_memcap.$$" "${TMPDIR:-/tmp}/tdc_memcap.$$.err"
read -r a1 _ <<<"$anons"
a20=$(awk '{ print $NF }' <<<"$anons")
echo "  RssAnon (kB) after each of 20 max_memory errors (after 4 warm-up errors): $anons"
check "24 max_memory errors raised ($nerr)" test "$nerr" -eq 24
check "private RSS after 20 errors within 10% of after 1 ($a1 -> $a20 kB)" \
	awk -v a="${a1:-0}" -v b="${a20:-0}" 'BEGIN { exit !(a > 0 && b <= a * 1.10) }'

# --- 4. a real result over 1 GB --------------------------------------------------
if [ -n "${HUGE:-}" ]; then
	t0=$(date +%s%N)
	out=$(psql -X -q -A -t -c "SET tdc_delaunay.max_memory = 0" \
		-c "SELECT pg_column_size(ST_TDCDelaunay(ST_MakePoint(hashint4(i), hashint4(-i)))) FROM generate_series(1, 7000000) i" \
		-c "SELECT 'alive'" 2>&1) || true
	t1=$(date +%s%N)
	echo "  7M points, one value: $(grep -m1 ERROR <<<"$out" || echo "$out" | head -n1) ($(((t1 - t0) / 1000000)) ms)"
	check "result over 1 GB: clear ERROR pointing to Dump" grep -q 'exceeds the limit' <<<"$out"
	check "session alive after it" grep -q '^alive' <<<"$out"
fi

check "postmaster not restarted" test "$(postmaster_start)" = "$START0"
finish
