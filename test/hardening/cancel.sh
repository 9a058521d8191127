#!/usr/bin/env bash
# test/hardening/cancel.sh: query cancel, statement_timeout and backend
# termination arriving during every phase of a big ST_TDCDelaunay.
#
#   PGHOST=... PGPORT=... PGUSER=... PGDATABASE=... bash test/hardening/cancel.sh
#
# Input: tdc_hard.pts5m, 5 million points, one row each (created once and
# reused; POINTS=N for another size).  The statement is
#   SELECT pg_column_size(ST_TDCDelaunay(geom)) FROM tdc_hard.pts...
# so its phases are: reading the rows into the state, the engine (sort,
# subdivision, leaves, merge, with worker threads), writing the ~800 MB
# result value.  An uncancelled run is timed first (T); the signals then
# arrive at 50 ms .. 3 s and at 45% .. 97% of T after the statement started.
#
# Checked:
#   latency   from pg_cancel_backend / pg_terminate_backend (or the moment
#             statement_timeout fires) until the backend has left the
#             statement (pg_stat_activity no longer shows it active; for a
#             terminate, until the backend is gone), <= MAX_LATENCY_MS (200)
#   errors    the session saw the cancel / timeout error (or lost its
#             connection for a terminate), and then still works
#   threads   the backend has no engine threads left after a cancel
#   RSS       backend VmRSS after RSS_RUNS (20) cancelled runs within 10% of
#             after the first one (one session, signals at varying phases)
#   postmaster  pg_postmaster_start_time() unchanged: no backend crashed
#
# QUICK=1: 1M points, fewer delays, 6 runs for the RSS comparison.
# Prints the figures and "N passed, N failed"; exits non-zero on a failure.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

QUICK=${QUICK:-0}
if ((QUICK)); then
	POINTS=${POINTS:-1000000}
	RSS_RUNS=${RSS_RUNS:-6}
else
	POINTS=${POINTS:-5000000}
	RSS_RUNS=${RSS_RUNS:-20}
fi
MAX_LATENCY_MS=${MAX_LATENCY_MS:-200}
TABLE=tdc_hard.pts$((POINTS / 1000000))m
((POINTS % 1000000 == 0)) || TABLE=tdc_hard.pts$POINTS
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tdc_cancel.XXXXXX")
BG=()
cleanup() {
	local p
	for p in "${BG[@]+"${BG[@]}"}"; do
		kill "$p" 2>/dev/null || true
	done
	rm -rf "$WORK"
}
trap cleanup EXIT

echo "== cancel.sh: $POINTS points ($TABLE), latency limit ${MAX_LATENCY_MS} ms"
require_server
START0=$(postmaster_start)
make_points "${TABLE#tdc_hard.}" "$POINTS"

# hit(tag, delay_ms, kind): find the active statement whose text holds tag;
# kind cancel/terminate: signal it delay_ms after it started and return the
# ms until it left the statement; kind timeout: return the ms from
# query_start + delay_ms until it left; -1 when it ended before the signal.
# The second word is the phase at the signal, from the backend's thread
# count sampled every 2 ms: "reading" (no engine threads seen yet),
# "engine" (worker threads running), "writing" (after them).
hpsql >/dev/null <<'EOF'
CREATE OR REPLACE FUNCTION tdc_hard.threads(p int) RETURNS int LANGUAGE plpgsql AS $$
BEGIN
	RETURN coalesce(substring(pg_read_file('/proc/' || p || '/status', 0, 8192, true) FROM 'Threads:\s*(\d+)')::int, 0);
EXCEPTION WHEN others THEN
	RETURN 0;					-- the process is gone (ESRCH)
END $$;

CREATE OR REPLACE FUNCTION tdc_hard.hit(tag text, delay_ms float8, kind text)
RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	p int;
	qs timestamptz;
	t0 timestamptz;
	th int;
	seen_engine bool := false;
	phase text;
	pat text := '%''' || tag || ''' <>%';
	deadline timestamptz := clock_timestamp() + interval '300 s';
BEGIN
	LOOP
		PERFORM pg_stat_clear_snapshot();
		SELECT a.pid, a.query_start INTO p, qs FROM pg_stat_activity a
		WHERE a.pid <> pg_backend_pid() AND a.state = 'active' AND a.query LIKE pat;
		EXIT WHEN p IS NOT NULL;
		IF clock_timestamp() > deadline THEN
			RAISE EXCEPTION 'no active statement tagged %', tag;
		END IF;
		PERFORM pg_sleep(0.001);
	END LOOP;
	t0 := qs + delay_ms * interval '1 ms';
	LOOP
		th := tdc_hard.threads(p);
		seen_engine := seen_engine OR th > 1;
		EXIT WHEN clock_timestamp() >= t0;
		PERFORM pg_sleep(least(0.002, greatest(0, extract(epoch FROM t0 - clock_timestamp()))));
	END LOOP;
	phase := CASE WHEN th > 1 THEN 'engine' WHEN seen_engine THEN 'writing' ELSE 'reading' END;
	IF kind <> 'timeout' THEN
		PERFORM pg_stat_clear_snapshot();
		IF NOT EXISTS (SELECT 1 FROM pg_stat_activity a
					   WHERE a.pid = p AND a.state = 'active' AND a.query_start = qs) THEN
			RETURN '-1 ' || phase;
		END IF;
		t0 := clock_timestamp();
		IF kind = 'cancel' THEN
			PERFORM pg_cancel_backend(p);
		ELSE
			PERFORM pg_terminate_backend(p);
		END IF;
	END IF;
	LOOP
		PERFORM pg_stat_clear_snapshot();
		EXIT WHEN NOT EXISTS (SELECT 1 FROM pg_stat_activity a
							  WHERE a.pid = p AND a.state = 'active' AND a.query_start = qs);
		IF clock_timestamp() > t0 + interval '300 s' THEN
			RAISE EXCEPTION 'statement tagged % still running', tag;
		END IF;
		PERFORM pg_sleep(0.0005);
	END LOOP;
	RETURN round((extract(epoch FROM clock_timestamp() - t0) * 1000)::numeric, 1) || ' ' || phase;
END $$;

-- The session under test calls this before each tagged statement, so that
-- the statement starts only once hit() is watching for it.
CREATE OR REPLACE FUNCTION tdc_hard.wait_for_watcher(tag text)
RETURNS void LANGUAGE plpgsql AS $$
DECLARE
	pat text := '%hit(''' || tag || '%';
	deadline timestamptz := clock_timestamp() + interval '300 s';
BEGIN
	LOOP
		PERFORM pg_stat_clear_snapshot();
		EXIT WHEN EXISTS (SELECT 1 FROM pg_stat_activity a
						  WHERE a.pid <> pg_backend_pid() AND a.state = 'active' AND a.query LIKE pat);
		IF clock_timestamp() > deadline THEN
			RAISE EXCEPTION 'nobody watches %', tag;
		END IF;
		PERFORM pg_sleep(0.001);
	END LOOP;
END $$;
EOF

BIGQ="SELECT pg_column_size(ST_TDCDelaunay(geom)) FROM $TABLE"
PROBE="SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 1 1)'))"
STATUS="SELECT substring(s FROM 'VmRSS:\\s*(\\d+)') || ' ' || substring(s FROM 'Threads:\\s*(\\d+)') || ' ' || substring(s FROM 'RssAnon:\\s*(\\d+)') FROM pg_read_file('/proc/' || pg_backend_pid() || '/status') s"

# --- 1. one uncancelled run: T, the triangle count --------------------------
t_start=$(date +%s%N)
size=$(hpsql -c "$BIGQ")
t_end=$(date +%s%N)
T_MS=$(((t_end - t_start) / 1000000))
echo "uncancelled run: $T_MS ms, result $size bytes"
check "uncancelled run returns a result" test "${size:-0}" -gt 1000

frac() { echo $((T_MS * $1 / 100)); }
if ((QUICK)); then
	DELAYS=(50 1000 "$(frac 60)")
	TERM_DELAYS=(300 "$(frac 70)")
else
	DELAYS=(50 200 500 1000 2000 3000 "$(frac 45)" "$(frac 60)" "$(frac 75)" "$(frac 90)" "$(frac 97)")
	TERM_DELAYS=(50 1000 3000 "$(frac 60)" "$(frac 90)")
fi

# --- 2. cancel and statement_timeout in one session -------------------------
script=$WORK/sweep.sql
runs=()
{
	echo "SELECT 'pid ' || pg_backend_pid();"
	k=0
	for d in "${DELAYS[@]}"; do
		for kind in cancel timeout; do
			# a timeout must fire before the statement ends on its own
			if [ "$kind" = timeout ] && ((d > T_MS * 90 / 100)); then
				continue
			fi
			k=$((k + 1))
			runs+=("$k $kind $d")
			echo "SELECT tdc_hard.wait_for_watcher('run:$k:');"
			if [ "$kind" = timeout ]; then
				echo "SET statement_timeout = $d;"
			fi
			echo "$BIGQ WHERE 'run:$k:' <> '';"
			echo "RESET statement_timeout;"
			echo "SELECT 'after $k ' || ($PROBE) || ' ' || ($STATUS);"
		done
	done
} >"$script"

psql -X -A -t -v ON_ERROR_STOP=0 -f "$script" >"$WORK/sweep.out" 2>"$WORK/sweep.err" &
BG+=($!)
sweep_pid=$!
lat_cancel=()
lat_timeout=()
lat_phase=()
missed=0
for r in "${runs[@]}"; do
	read -r k kind d <<<"$r"
	read -r lat phase <<<"$(hpsql -c "SELECT tdc_hard.hit('run:$k:', $d, '$kind')" || true)"
	if [ -z "${lat:-}" ]; then
		fail "$kind at $d ms: the watcher failed"
		continue
	fi
	if [ "$lat" = "-1" ]; then
		echo "  run $k: $kind at $d ms: the statement had already finished"
		missed=$((missed + 1))
		continue
	fi
	if [ "$kind" = cancel ]; then lat_cancel+=("$lat"); else lat_timeout+=("$lat"); fi
	lat_phase+=("$phase $lat")
	if awk -v l="$lat" -v m="$MAX_LATENCY_MS" 'BEGIN { exit !(l <= m) }'; then
		pass "$kind at $d ms ($phase): answered in $lat ms"
	else
		fail "$kind at $d ms ($phase): answered in $lat ms (> $MAX_LATENCY_MS ms)"
	fi
done
wait "$sweep_pid" || true
ncancel=$(grep -c 'canceling statement due to user request\|triangulation canceled' "$WORK/sweep.err" || true)
ntimeout=$(grep -c 'canceling statement due to statement timeout' "$WORK/sweep.err" || true)
nafter=$(grep -c '^after [0-9]* 2 ' "$WORK/sweep.out" || true)
other=$(grep 'ERROR\|FATAL' "$WORK/sweep.err" | grep -v 'canceling statement due to\|triangulation canceled' || true)
echo "  session saw $ncancel cancel errors, $ntimeout timeout errors; $nafter of ${#runs[@]} follow-up probes worked"
check "cancel/timeout errors seen by the session ($((ncancel + ntimeout)) + $missed finished early = ${#runs[@]})" \
	test $((ncancel + ntimeout + missed)) -eq "${#runs[@]}"
check "no other errors in the session" test -z "$other"
[ -z "$other" ] || echo "$other" | head -5 | sed 's/^/        /'
check "session usable after every cancel" test "$nafter" -eq "${#runs[@]}"
threads_left=$(awk '/^after/ { print $5 }' "$WORK/sweep.out" | sort -u | tr '\n' ' ')
check "no engine threads left after a cancel (Threads: $threads_left)" test "$threads_left" = "1 "

# --- 3. terminate, one session per run ---------------------------------------
lat_term=()
k=100
for d in "${TERM_DELAYS[@]}"; do
	k=$((k + 1))
	psql -X -A -t -v ON_ERROR_STOP=1 -c "$BIGQ WHERE 'run:$k:' <> ''" >"$WORK/term$k.out" 2>"$WORK/term$k.err" &
	BG+=($!)
	tp=$!
	read -r lat phase <<<"$(hpsql -c "SELECT tdc_hard.hit('run:$k:', $d, 'terminate')" || true)"
	rc=0
	wait "$tp" || rc=$?
	if [ -z "${lat:-}" ]; then
		fail "terminate at $d ms: the watcher failed"
		continue
	fi
	if [ "$lat" = "-1" ]; then
		echo "  run $k: terminate at $d ms: the statement had already finished"
		continue
	fi
	lat_term+=("$lat")
	lat_phase+=("$phase $lat")
	if awk -v l="$lat" -v m="$MAX_LATENCY_MS" 'BEGIN { exit !(l <= m) }' &&
		grep -q 'terminating connection due to administrator command' "$WORK/term$k.err"; then
		pass "terminate at $d ms ($phase): backend gone after $lat ms"
	else
		fail "terminate at $d ms ($phase): backend gone after $lat ms, psql exit $rc: $(head -n1 "$WORK/term$k.err")"
	fi
done

# --- 4. RSS after 1 and after RSS_RUNS cancelled runs ------------------------
script=$WORK/rss.sql
{
	echo "SELECT 'start ' || ($STATUS);"
	# one complete run first: the allocator (glibc raises its mmap threshold
	# after freeing big blocks, worker threads get their arenas) settles
	echo "$BIGQ;"
	echo "SELECT 'warm ' || ($STATUS);"
	for ((k = 1; k <= RSS_RUNS; k++)); do
		echo "SELECT tdc_hard.wait_for_watcher('rss:$k:');"
		echo "$BIGQ WHERE 'rss:$k:' <> '';"
		echo "SELECT 'rss $k ' || ($STATUS);"
	done
} >"$script"
psql -X -A -t -v ON_ERROR_STOP=0 -f "$script" >"$WORK/rss.out" 2>"$WORK/rss.err" &
BG+=($!)
rss_pid=$!
rss_cancelled=0
# phases cycle: engine, reading, late engine, writing
RSS_PCTS=(40 20 60 80)
for ((k = 1; k <= RSS_RUNS; k++)); do
	pct=${RSS_PCTS[$(((k - 1) % ${#RSS_PCTS[@]}))]}
	d=$((T_MS * pct / 100))
	read -r lat phase <<<"$(hpsql -c "SELECT tdc_hard.hit('rss:$k:', $d, 'cancel')" || true)"
	echo "  rss run $k: cancel at $d ms (${phase:-?}): ${lat:-?} ms"
	if [ -n "${lat:-}" ] && [ "$lat" != "-1" ]; then
		rss_cancelled=$((rss_cancelled + 1))
		lat_cancel+=("$lat")
		lat_phase+=("$phase $lat")
	fi
done
wait "$rss_pid" || true
rss_start=$(awk '/^start/ { print $2 }' "$WORK/rss.out")
rss_warm=$(awk '/^warm/ { print $2 }' "$WORK/rss.out")
anon_warm=$(awk '/^warm/ { print $4 }' "$WORK/rss.out")
rss1=$(awk '/^rss 1 / { print $3 }' "$WORK/rss.out")
rssN=$(awk -v n="$RSS_RUNS" '$1 == "rss" && $2 == n { print $3 }' "$WORK/rss.out")
anon1=$(awk '/^rss 1 / { print $5 }' "$WORK/rss.out")
anonN=$(awk -v n="$RSS_RUNS" '$1 == "rss" && $2 == n { print $5 }' "$WORK/rss.out")
echo "  backend VmRSS: start ${rss_start:-?} kB, after a complete run ${rss_warm:-?} kB (RssAnon ${anon_warm:-?} kB), after 1 cancelled run ${rss1:-?} kB, after $RSS_RUNS ${rssN:-?} kB ($rss_cancelled of $RSS_RUNS runs cancelled)"
echo "  backend RssAnon: after 1 ${anon1:-?} kB, after $RSS_RUNS ${anonN:-?} kB"
echo "  VmRSS by run (kB):   $(awk '/^rss/ { printf "%s ", $3 }' "$WORK/rss.out")"
echo "  RssAnon by run (kB): $(awk '/^rss/ { printf "%s ", $5 }' "$WORK/rss.out")"
# VmRSS also counts the shared buffers this backend has touched: every
# large sequential scan uses a fresh 256 kB ring of them, so VmRSS creeps up
# by 256 kB per scan (plain array_agg does the same) until all of
# shared_buffers is mapped.  Private memory (RssAnon) is what a leak grows.
check "private RSS (RssAnon) after $RSS_RUNS cancelled runs within 10% of after 1 (${anon1:-?} -> ${anonN:-?} kB)" \
	awk -v a="${anon1:-0}" -v b="${anonN:-0}" 'BEGIN { exit !(a > 0 && b > 0 && b <= a * 1.10) }'
if awk -v a="${rss1:-0}" -v b="${rssN:-0}" 'BEGIN { exit !(a > 0 && b > 0 && b <= a * 1.10) }'; then
	echo "  (VmRSS also within 10%)"
else
	echo "  note: VmRSS grew by more than 10% (${rss1:-?} -> ${rssN:-?} kB); see RssAnon for private memory"
fi
check "RSS runs were cancelled ($rss_cancelled of $RSS_RUNS)" test "$rss_cancelled" -ge $((RSS_RUNS * 3 / 4))

# --- 5. figures, postmaster ---------------------------------------------------
echo "latency cancel (ms):    $(printf '%s\n' "${lat_cancel[@]+"${lat_cancel[@]}"}" | stats_line)"
echo "latency timeout (ms):   $(printf '%s\n' "${lat_timeout[@]+"${lat_timeout[@]}"}" | stats_line)"
echo "latency terminate (ms): $(printf '%s\n' "${lat_term[@]+"${lat_term[@]}"}" | stats_line)"
 for ph in reading engine writing; do
	echo "latency in phase $ph (ms): $(printf '%s\n' "${lat_phase[@]+"${lat_phase[@]}"}" | awk -v p="$ph" '$1 == p { print $2 }' | stats_line)"
done
check "postmaster not restarted" test "$(postmaster_start)" = "$START0"
if [ -z "${KEEP:-}" ]; then
	hpsql -c "DROP FUNCTION tdc_hard.hit(text, float8, text), tdc_hard.wait_for_watcher(text), tdc_hard.threads(int)" >/dev/null
fi
finish
