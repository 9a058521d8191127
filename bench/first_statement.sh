#!/usr/bin/env bash
# bench/first_statement.sh -- what a user's first try sees: the aggregate over
# one million points as the first statement of a freshly started server,
# beside the same statement once the session is warm, for ST_TDCDelaunay and
# PostGIS's ST_DelaunayTriangles(ST_Collect(...)) (issue 38).  It prints
# figures; it asserts nothing.
#
# Why a benchmark of its own.  The size sweep (sweep_bench.sh) runs every
# statement once untimed before it times it, so its figures are those of a
# warm session: the shared library loaded, the table in shared buffers, the
# catalogue caches filled.  A user's first statement pays for all of that,
# and for PostGIS's library too, and the two sides do not pay the same: the
# fixed costs weigh more against the faster statement, so the ratio of a
# first try is smaller than the warm one.  Both are reported, each from its
# own runs.
#
# The server.  A throw-away cluster of the installed PostgreSQL (initdb'd
# under a temporary directory, Unix socket only, owned by the postgres user
# when run as root), whose postmaster is started as a child of this script
# rather than through pg_ctl: the quiet-machine sampler (bench/quiet.sh)
# counts this script's descendants as the run's own, so the restarts and the
# backends belong to the run, as they should.  Server settings are Debian's
# defaults (jit on among them), since the point is what a user meets; only
# the socket, the port and the absence of TCP are set.
#
# A round: for each side in turn (the side that goes first alternates from
# round to round), stop the server, start it, open a session and time the
# statement with psql's \timing (the client's wall clock: planning, the
# libraries' loading and the catalogue look-ups included), then time it
# BENCH_FIRST_WARM more times in the same session (the warm figure).  With
# BENCH_FIRST_DROP_CACHES=1 (root) the kernel's page cache is dropped before
# each start too, as after a reboot; by default it is kept, as on a server
# that was restarted.
#
# Data: uniform points in [0,1)^2 from the sweep's formula (point i:
# x = (hashint8extended(i, 1) & (2^52 - 1)) / 2^52, y the same with seed 2),
# BENCH_FIRST_N of them (1e6), one POINT a row.
#
# Outputs: build/bench/first_statement_runs.csv  every timed statement
#          build/bench/first_statement.txt       the report's table
#          docs/benchmarks/first_statement.md    the report (bench_publish),
#                                                only from a quiet machine
# Knobs:   BENCH_FIRST_N=1e6  BENCH_FIRST_ROUNDS=5  BENCH_FIRST_WARM=3
#          BENCH_FIRST_DROP_CACHES=0  PG_CONFIG (which PostgreSQL)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

N=$(n_of "${BENCH_FIRST_N:-1e6}")
ROUNDS=${BENCH_FIRST_ROUNDS:-5}
WARM=${BENCH_FIRST_WARM:-3}
DROP=${BENCH_FIRST_DROP_CACHES:-0}
PG_CONFIG=${PG_CONFIG:-pg_config}
BIN=$("$PG_CONFIG" --bindir)
RUNS=$BENCH_OUT/first_statement_runs.csv
TXT=$BENCH_OUT/first_statement.txt
mkdir -p "$BENCH_OUT"
[ "$DROP" = 0 ] || [ "$(id -u)" = 0 ] || die "BENCH_FIRST_DROP_CACHES=1 needs root"
[ -f "$("$PG_CONFIG" --pkglibdir)/tdc_delaunay.so" ] || die "tdc_delaunay is not installed into $PG_CONFIG's PostgreSQL (make install)"

# the cluster: a directory the postgres user can reach, whoever runs this
DIR=$(mktemp -d /tmp/tdc_first.XXXXXX)
AS=()
if [ "$(id -u)" = 0 ]; then
	id postgres >/dev/null 2>&1 || die "no postgres user (package postgresql-common makes it)"
	chown postgres: "$DIR"
	AS=(runuser -u postgres --)
fi
PORT=$((20000 + $$ % 10000))
PM=""
export PGHOST=$DIR PGPORT=$PORT PGUSER=postgres PGDATABASE=postgres
PSQL=(psql -X -q -v ON_ERROR_STOP=1)

server_stop() {
	[ -n "$PM" ] || return 0
	# the postmaster itself (PM may be runuser, which does not pass the
	# signal on): SIGINT is a fast shutdown
	kill -INT "$(head -n 1 "$DIR/data/postmaster.pid" 2>/dev/null || echo "$PM")" 2>/dev/null || true
	wait "$PM" 2>/dev/null || true
	PM=""
}
cleanup() { server_stop; rm -rf "$DIR"; }
trap cleanup EXIT

server_start() {
	local i
	"${AS[@]}" "$BIN/postgres" -D "$DIR/data" -k "$DIR" -p "$PORT" -c listen_addresses='' \
		>> "$DIR/server.log" 2>&1 &
	PM=$!
	for ((i = 0; i < 300; i++)); do
		"$BIN/pg_isready" -q -h "$DIR" -p "$PORT" && return 0
		kill -0 "$PM" 2>/dev/null || { tail -n 20 "$DIR/server.log" >&2; die "the server did not start"; }
		sleep 0.1
	done
	die "the server did not accept connections in 30 s"
}

log "initdb in $DIR"
"${AS[@]}" "$BIN/initdb" -D "$DIR/data" -U postgres -A trust > "$DIR/initdb.log" 2>&1 ||
	{ cat "$DIR/initdb.log" >&2; die "initdb failed"; }
server_start
log "loading $N points"
"${PSQL[@]}" <<EOF
CREATE EXTENSION postgis;
CREATE EXTENSION tdc_delaunay;
CREATE TABLE pts AS
	SELECT ST_MakePoint((hashint8extended(i, 1) & 4503599627370495)::float8 / 4503599627370496.0,
						(hashint8extended(i, 2) & 4503599627370495)::float8 / 4503599627370496.0) AS geom
	FROM generate_series(1, $N) i;
VACUUM ANALYZE pts;
CHECKPOINT;
EOF

declare -A Q=(
	[tdc]="SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM pts"
	[postgis]="SELECT ST_DelaunayTriangles(ST_Collect(geom)) IS NOT NULL FROM pts"
)

# one_side SYS ROUND: restart, then the first statement and WARM more, one
# CSV line each: sys,round,kind,ms
one_side() {
	local sys=$1 round=$2 i script
	server_stop
	if [ "$DROP" = 1 ]; then
		sync
		echo 3 > /proc/sys/vm/drop_caches
	fi
	server_start
	script="\\timing on"$'\n'"${Q[$sys]};"
	for ((i = 0; i < WARM; i++)); do script+=$'\n'"${Q[$sys]};"; done
	"${PSQL[@]}" -t -A <<< "$script" 2>&1 |
		awk -v s="$sys" -v r="$round" '/^Time: / { printf "%s,%s,%s,%s\n", s, r, (k++ ? "warm" : "first"), $2 }' |
		tee -a "$RUNS"
}

echo "sys,round,kind,ms" > "$RUNS"
bench_begin
for ((r = 1; r <= ROUNDS; r++)); do
	if ((r % 2)); then order=(tdc postgis); else order=(postgis tdc); fi
	for s in "${order[@]}"; do
		log "round $r: $s"
		one_side "$s" "$r" >&2
	done
done
bench_end
server_stop

# medians and ranges, and the ratios PostGIS / ours of the medians
for s in tdc postgis; do
	for k in first warm; do
		[ "$(grep -c "^$s,[0-9]*,$k," "$RUNS")" -ge 1 ] || die "no $k timing of $s in $RUNS"
	done
done
awk -F, -v n="$N" -v rounds="$ROUNDS" -v warm="$WARM" -v drop="$DROP" '
	NR == 1 { next }
	{ v[$1 "," $3] = v[$1 "," $3] " " $4 }
	function med(list,   a, k, i, j, x) {
		k = split(list, a, " ")
		for (i = 2; i <= k; i++) for (j = i; j > 1 && a[j] < a[j - 1]; j--) { x = a[j]; a[j] = a[j - 1]; a[j - 1] = x }
		lo = a[1]; hi = a[k]
		return k % 2 ? a[(k + 1) / 2] : (a[k / 2] + a[k / 2 + 1]) / 2
	}
	END {
		printf "%s points, one POINT a row; %d rounds, each side restarted before its first statement%s; %d warm runs after it in the same session. Milliseconds, psql \\timing (client wall clock); median (min to max).\n\n", n, rounds, (drop == 1 ? " with the page cache dropped" : ""), warm
		printf "| statement | ST_TDCDelaunay | PostGIS ST_DelaunayTriangles(ST_Collect) | PostGIS / ours |\n|---|--:|--:|--:|\n"
		split("first warm", kinds, " ")
		for (i = 1; i <= 2; i++) {
			k = kinds[i]
			t = med(v["tdc," k]); tl = lo; th = hi
			p = med(v["postgis," k]); pl = lo; ph = hi
			printf "| %s | %.1f (%.1f to %.1f) | %.1f (%.1f to %.1f) | **%.2fx** |\n",
				(k == "first" ? "first statement of a fresh server" : "warm session"), t, tl, th, p, pl, ph, p / t
		}
	}' "$RUNS" > "$TXT"
cat "$TXT"
bench_publish first_statement "The first statement of a fresh server: the aggregate of $(thousands "$N") points against PostGIS" "$TXT"
