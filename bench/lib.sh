# shellcheck shell=bash
# bench/lib.sh -- helpers shared by the benchmark scripts of bench/.
# Sourced, not executed.  Expects ROOT (the repository root) to be set.
#
# Data files (git-ignored) go to $BENCH_DATA (default data/bench), raw results
# (CSV, every run, the load samples) and figures to $BENCH_OUT (default
# build/bench), helper binaries to build/.  Each benchmark writes its report
# to $BENCH_DOCS/<name>.md (default docs/benchmarks/) with bench_publish, which
# gives every report the same header (date, commit, machine, software
# versions, load) and writes it only if the machine was quiet during the timed
# runs (bench/quiet.sh): nothing else writes into $BENCH_DOCS.

BENCH_DATA=${BENCH_DATA:-$ROOT/data/bench}
BENCH_OUT=${BENCH_OUT:-$ROOT/build/bench}
BENCH_BIN=$ROOT/build
BENCH_DOCS=${BENCH_DOCS:-$ROOT/docs/benchmarks}
GSHHG_SUBSET_N=1000000
GSHHG_SUBSET_SEED=7
POINT_SEED=42

log() { printf '[%s] %s\n' "$(date -u +%H:%M:%S)" "$*" >&2; }
die() { log "ERROR: $*"; exit 1; }
# shellcheck source=bench/quiet.sh
. "$ROOT/bench/quiet.sh"

# apt-get install the given Debian packages if any is missing (root only).
ensure_debs() {
	local missing=() p
	for p in "$@"; do
		dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed' || missing+=("$p")
	done
	[ ${#missing[@]} -eq 0 ] && return 0
	log "installing missing packages: ${missing[*]}"
	if [ "$(id -u)" -ne 0 ]; then
		die "packages missing (${missing[*]}) and not root: apt-get install ${missing[*]}"
	fi
	DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${missing[@]}" >&2 ||
		{ apt-get update -q >&2 && DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${missing[@]}" >&2; } ||
		die "apt-get install ${missing[*]} failed"
}

# build_tool NAME SRC COMPILER FLAGS...: (re)build $BENCH_BIN/NAME when SRC (or
# test/splitmix.h, which the C tools include) is newer
build_tool() {
	local name=$1 src=$2 compiler=$3
	shift 3
	local out=$BENCH_BIN/$name
	mkdir -p "$BENCH_BIN"
	if [ ! -x "$out" ] || [ "$src" -nt "$out" ] || [ "$ROOT/test/splitmix.h" -nt "$out" ]; then
		log "building $out"
		"$compiler" "$@" -o "$out" "$src" ${LIBS:-} || die "cannot build $out"
	fi
}

build_helpers() {
	command -v cc >/dev/null || die "cc not found"
	LIBS=-lm build_tool gen_points "$ROOT/bench/gen_points.c" cc -O2 -Wall
	LIBS=-lm build_tool gen_las "$ROOT/bench/gen_las.c" cc -O2 -Wall
	LIBS=-lm build_tool las_pg "$ROOT/bench/las_pg.c" cc -O2 -Wall
	build_tool gshhg_convert "$ROOT/bench/gshhg_convert.c" cc -O2 -Wall
	build_tool first_touch "$ROOT/bench/first_touch.c" cc -O2 -Wall
}

build_cgal() {
	if [ ! -f /usr/include/CGAL/Delaunay_triangulation_2.h ]; then
		ensure_debs libcgal-dev libgmp-dev libmpfr-dev
	fi
	command -v g++ >/dev/null || ensure_debs g++
	LIBS="-lgmp -lmpfr" build_tool cgal_dt "$ROOT/bench/cgal_dt.cpp" g++ -O2 -DNDEBUG -DCGAL_NDEBUG
}

# n_of LABEL: 1e5 -> 100000
n_of() { awk -v s="$1" 'BEGIN { printf "%.0f\n", s + 0 }'; }

# ensure_points KIND NLABEL: path of the .bin file (generated if missing)
ensure_points() {
	local kind=$1 nl=$2 f
	f=$BENCH_DATA/${kind}_${nl}.bin
	mkdir -p "$BENCH_DATA"
	if [ ! -s "$f" ] || [ "$(stat -c %s "$f")" -ne $(( $(n_of "$nl") * 16 )) ]; then
		log "generating $f"
		"$BENCH_BIN/gen_points" "$kind" "$nl" "$POINT_SEED" "$f.tmp" && mv "$f.tmp" "$f" ||
			die "gen_points $kind $nl failed"
	fi
	printf '%s\n' "$f"
}

# ensure_gshhg: GSHHG full-resolution shorelines (all levels) via GMT ->
#   $BENCH_DATA/gshhg.bin, gshhg_lines.ewkt, gshhg_sub.bin, gshhg_sub.tsv, gshhg.meta
ensure_gshhg() {
	local d=$BENCH_DATA
	if [ -s "$d/gshhg.meta" ] && [ -s "$d/gshhg.bin" ] && [ -s "$d/gshhg_lines.ewkt" ] &&
		[ -s "$d/gshhg_sub.bin" ] && [ -s "$d/gshhg_sub.tsv" ]; then
		return 0
	fi
	ensure_debs gmt gmt-gshhg-full
	mkdir -p "$d"
	local tmp
	tmp=$(mktemp -d)
	log "extracting GSHHG full resolution: gmt coast -Rd -Df -W -M"
	# GMT writes gmt.history into the working directory: run it in a temp dir
	(cd "$tmp" && gmt coast -Rd -Df -W -M > coast.txt) || die "gmt coast failed"
	"$BENCH_BIN/gshhg_convert" "$tmp/coast.txt" "$d/gshhg" "$GSHHG_SUBSET_N" "$GSHHG_SUBSET_SEED" \
		> "$d/gshhg.meta.tmp" || die "gshhg_convert failed"
	rm -rf "$tmp"
	mv "$d/gshhg.meta.tmp" "$d/gshhg.meta"
	log "GSHHG: $(cat "$d/gshhg.meta")"
}

# first_touch_note: one line on what fresh memory costs on this machine
# (bench/first_touch.c): 256 MB in 4 kB pages touched once, then again right
# away; then, after 5 s for the host to take back what was freed, 256 MB in
# transparent huge pages touched once
first_touch_note() {
	local small huge
	build_tool first_touch "$ROOT/bench/first_touch.c" cc -O2 -Wall
	small=$("$BENCH_BIN/first_touch" 256 2 | awk '
		{ r[NR] = $9; gsub(/[()]/, "", r[NR]) }
		END { printf "%s GB/s the first time, %s GB/s right after", r[1], r[2] }')
	sleep 5
	huge=$("$BENCH_BIN/first_touch" 256 1 huge | awk '{ r = $9; gsub(/[()]/, "", r); print r }')
	printf 'fresh memory: 256 MB in 4 kB pages touched at %s; in huge pages, 5 s later, at %s GB/s (see bench/first_touch.c)\n' "$small" "$huge"
}

# bench_sql_helpers SCHEMA: the SQL that creates the timing functions the SQL
# benchmarks share, in SCHEMA (feed it to psql):
#   pt(i)                 point i of one deterministic sequence, uniform in [0,1)^2
#   apply(settings)       SET "name=value ..." for the session (value DEFAULT: the server's)
#   time_query(sys, rep, q, settings)   runs q once under the settings and times
#                         its EXECUTE alone, server side.  Never raises: a failure
#                         (error or statement_timeout) becomes status/message, with
#                         the time until it happened, and marks sys as failed for
#                         the rest of the session, after which every call for it
#                         returns 'skipped' at once.
#   plan_of(q, settings)  the plan's shape as far as it matters here: parallel
#                         workers, JIT
bench_sql_helpers() {
	local S=$1
	cat <<EOF
CREATE SCHEMA IF NOT EXISTS $S;
-- earlier forms of these functions, in a schema kept between runs
DROP FUNCTION IF EXISTS $S.time_query(text, int, text), $S.time_query(text, int, text, text),
	$S.plan_of(text), $S.plan_of(text, text);

CREATE OR REPLACE FUNCTION $S.pt(i bigint) RETURNS geometry
LANGUAGE sql IMMUTABLE PARALLEL SAFE AS
\$\$ SELECT ST_MakePoint((hashint8extended(i, 1) & 4503599627370495)::float8 / 4503599627370496.0,
						(hashint8extended(i, 2) & 4503599627370495)::float8 / 4503599627370496.0) \$\$;

CREATE OR REPLACE FUNCTION $S.apply(settings text) RETURNS void
LANGUAGE plpgsql AS \$\$
DECLARE
	kv text;
	n text;
	v text;
BEGIN
	FOREACH kv IN ARRAY regexp_split_to_array(btrim(settings), '\s+') LOOP
		CONTINUE WHEN kv = '';
		n := split_part(kv, '=', 1);
		v := substr(kv, length(n) + 2);
		IF v = 'DEFAULT' THEN
			SELECT reset_val INTO v FROM pg_settings WHERE name = n;
		END IF;
		PERFORM set_config(n, v, false);
	END LOOP;
END \$\$;

CREATE OR REPLACE FUNCTION $S.time_query(sys text, rep int, q text, settings text DEFAULT '',
	OUT o_sys text, OUT o_rep int, OUT ms float8, OUT result text, OUT status text, OUT message text)
LANGUAGE plpgsql AS \$\$
DECLARE
	t0 timestamptz;
BEGIN
	o_sys := sys;
	o_rep := rep;
	status := 'ok';
	message := '';
	IF current_setting('$S.failed_' || sys, true) = '1' THEN
		status := 'skipped';
		message := 'not run: an earlier run of this statement failed';
		RETURN;
	END IF;
	PERFORM $S.apply(settings);
	BEGIN
		t0 := clock_timestamp();
		EXECUTE q INTO result;
		ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
	EXCEPTION
		WHEN query_canceled THEN
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
			status := 'timeout';
			message := SQLERRM;
		WHEN OTHERS THEN
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
			status := 'error';
			message := SQLERRM;
	END;
	IF status <> 'ok' THEN
		PERFORM set_config('$S.failed_' || sys, '1', false);
	END IF;
	-- one CSV field, one line
	message := regexp_replace(message, '[,|\t\r\n]+', ' ', 'g');
	result := regexp_replace(result, '[,|\t\r\n]+', ' ', 'g');
END \$\$;

CREATE OR REPLACE FUNCTION $S.plan_of(q text, settings text DEFAULT '') RETURNS text
LANGUAGE plpgsql AS \$\$
DECLARE
	l text;
	w text := '';
	jit bool := false;
BEGIN
	PERFORM $S.apply(settings);
	FOR l IN EXECUTE 'EXPLAIN ' || q LOOP
		IF l ~ 'Workers Planned' THEN
			w := substring(l FROM '[0-9]+');
		END IF;
		IF l ~ '^JIT:' THEN
			jit := true;
		END IF;
	END LOOP;
	RETURN CASE WHEN w = '' THEN 'serial' ELSE w || ' workers' END ||
		CASE WHEN jit THEN ' jit' ELSE '' END;
END \$\$;
EOF
}

# psql for the SQL benchmarks: unaligned, tuples only, stop on error, no notices
PSQL=(psql -X -q -A -t -v ON_ERROR_STOP=1)
case " ${PGOPTIONS:-} " in
	*" -c client_min_messages=warning "*) ;;
	*) export PGOPTIONS="${PGOPTIONS:-} -c client_min_messages=warning" ;;
esac
sql() { "${PSQL[@]}" "$@"; }

# fmt_ms MS: 3 significant digits in s, ms or µs ("-" when empty)
fmt_ms() {
	awk -v x="$1" 'function f(v, u) { return sprintf(v >= 100 ? "%.0f %s" : v >= 10 ? "%.1f %s" : "%.2f %s", v, u) }
		BEGIN { if (x == "") { print "-"; exit }
			x += 0; if (x >= 1000) print f(x / 1000, "s"); else if (x >= 1) print f(x, "ms"); else print f(x * 1000, "µs") }'
}

# thousands N: 10000 -> 10,000
thousands() { awk -v x="$1" 'BEGIN { s = sprintf("%.0f", x); while (s ~ /[0-9][0-9][0-9][0-9]/) sub(/[0-9][0-9][0-9]($|,)/, ",&", s); print s }'; }

# so_id: md5 and mtime of the installed tdc_delaunay.so ($SO), so that a run
# can tell whether the file was replaced while it ran
so_id() {
	if [ -r "$SO" ]; then
		echo "md5 $(md5sum < "$SO" | cut -c1-12), installed $(date -u -r "$SO" '+%Y-%m-%d %H:%M:%S UTC')"
	else
		echo "?"
	fi
}

# kv FILE KEY: value of KEY=value on the last line of FILE containing "KEY="
kv() {
	awk -v k="$2" '{ for (i = 1; i <= NF; i++) { n = index($i, "="); if (n > 0 && substr($i, 1, n - 1) == k) v = substr($i, n + 1) } } END { print v }' "$1"
}

# median of the numbers on stdin (empty input -> empty output)
median() {
	awk '$1 != "" { a[++n] = $1 + 0 }
		END {
			if (n == 0) exit;
			for (i = 2; i <= n; i++) { x = a[i]; j = i - 1; while (j > 0 && a[j] > x) { a[j + 1] = a[j]; j-- } a[j + 1] = x }
			if (n % 2) print a[(n + 1) / 2]; else print (a[n / 2] + a[n / 2 + 1]) / 2
		}'
}

# ensure the ./tdc CLI is built; returns 1 if it cannot be
ensure_tdc() {
	if ! make -C "$ROOT" -s tdc >&2; then
		if [ -x "$ROOT/tdc" ]; then
			log "WARNING: make tdc failed; using the existing ./tdc built $(date -u -r "$ROOT/tdc" '+%H:%M UTC')"
		else
			log "make tdc failed"
			return 1
		fi
	fi
	[ -x "$ROOT/tdc" ]
}

# bench_tdc_copy: GNU time, the point generator and ./tdc built, then a
# private copy of ./tdc in $WORK (TDC_BIN) to time: a concurrent `make tdc`
# must not swap the binary mid-run
bench_tdc_copy() {
	[ -x /usr/bin/time ] || ensure_debs time
	build_helpers
	ensure_tdc || die "cannot build ./tdc"
	TDC_BIN=$WORK/tdc
	cp -p "$ROOT/tdc" "$TDC_BIN"
}

# ---------------------------------------------------------------- reports

# bench_begin [server] [noreport], bench_end: around a benchmark's timed runs
# (bench/quiet.sh): the lock, the wait for a quiet machine (or the refusal),
# the samples during the run, the wait for its own load to settle, the
# verdict.  "server": the run's work is done by the server the PG* variables
# name too.  "noreport": a trial run that writes no report (no waiting, no
# refusal; the samples are still kept).
bench_begin() {
	local w server='' noreport=0
	for w in "$@"; do
		case $w in
			server) server=server ;;
			noreport) noreport=1 ;;
			*) die "bench_begin: unknown word '$w'" ;;
		esac
	done
	# the commit the timed runs start from: the tree may move during a long run
	BENCH_REV=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
	git -C "$ROOT" diff --quiet HEAD -- src bench 2>/dev/null ||
		BENCH_REV="$BENCH_REV, with uncommitted changes in src/ or bench/"
	if [ $noreport = 1 ]; then
		BENCH_SETTLE=0
		BENCH_NOISY=1
	fi
	quiet_begin $server
	BENCH_T0=$(date -u '+%Y-%m-%d %H:%M UTC')
}
bench_end() {
	BENCH_T1=$(date -u '+%Y-%m-%d %H:%M UTC')
	quiet_end
}

# bench_figure FILE ALT: a figure (drawn outside BENCH_DOCS, e.g. in BENCH_OUT)
# that bench_publish copies next to the report and shows after its tables
BENCH_FIGURES=()
bench_figure() { BENCH_FIGURES+=("$1|$2"); }

# pkg_ver PATTERN: "package version" of the installed Debian packages matching
# PATTERN (a dpkg-query glob), or "-"
pkg_ver() {
	dpkg-query -W -f='${db:Status-Abbrev} ${Package} ${Version}\n' "$1" 2>/dev/null |
		awk '$1 == "ii" { printf "%s%s %s", sep, $2, $3; sep = ", " } END { if (sep == "") printf "-" }'
}

# bench_header TITLE SCRIPT: the header every report under docs/benchmarks/
# starts with: what wrote it, when, on which commit, machine and software, and
# how busy the machine was before, during and after the timed runs, with the
# verdict of the quiet rule (bench_begin, bench_end, bench/quiet.sh)
bench_header() {
	local title=$1 script=$2 rev os major
	rev=${BENCH_REV:-}
	if [ -z "$rev" ]; then
		rev=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
		git -C "$ROOT" diff --quiet HEAD -- src bench 2>/dev/null || rev="$rev, with uncommitted changes in src/ or bench/"
	fi
	os=$(. /etc/os-release 2>/dev/null && echo "${PRETTY_NAME:-?}")
	major=$(pg_config --version 2>/dev/null | awk '{ split($2, v, "."); print v[1] }')
	cat <<EOF
# $title

Written by \`$script\` (part of \`make bench\`; see [the index](README.md)). Every run is in \`build/bench/\`.

| | |
|---|---|
| date | ${BENCH_T0:-?} to $BENCH_T1 |
| commit | $rev |
| CPU | $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $BENCH_CORES cores |
| memory | $(awk '/^MemTotal:/ { printf "%.0f", $2 / 1048576 }' /proc/meminfo) GB |
| kernel | $(uname -sr) |
| Debian | $os ($(cat /etc/debian_version 2>/dev/null || echo ?)) |
| PostgreSQL | $(pkg_ver "postgresql-${major:-?}") |
| PostGIS | $(pkg_ver "postgresql-${major:-?}-postgis-3") |
| GEOS | $(pkg_ver 'libgeos-c1*') |
| SFCGAL | $(pkg_ver 'libsfcgal[0-9]*') |
| CGAL | $(pkg_ver libcgal-dev) |
| load average (1, 5, 15 min) | $BENCH_LOAD0 before, $BENCH_LOAD1 after (taken $BENCH_SETTLED s after the timed runs, for their own load to settle) |
$(quiet_rows)
EOF
}

# bench_publish NAME TITLE TXT [text]: $BENCH_DOCS/NAME.md, the shared header
# then the tables in TXT as the script printed them ("text": fixed-width
# tables, put in a code block), then the figures of bench_figure, copied next
# to it.  Only if the machine was quiet (bench/quiet.sh; BENCH_NOISY=1 writes
# it anyway, titled "(noisy machine)"): a refusal exits with status 3 and
# leaves BENCH_DOCS as it was.  The report and each figure are written whole
# under a temporary name, then renamed.
bench_publish() {
	local name=$1 title=$2 txt=$3 kind=${4:-md} out f file alt
	[ -n "${BENCH_T1:-}" ] || bench_end
	quiet_gate "$name"
	[ "$BENCH_QUIET" = yes ] || title="$title (noisy machine)"
	mkdir -p "$BENCH_DOCS"
	out=$BENCH_DOCS/$name.md
	{
		bench_header "$title" "bench/$(basename "$0")"
		echo
		if [ "$kind" = text ]; then
			echo '```text'
			cat "$txt"
			echo '```'
		else
			cat "$txt"
		fi
		for f in "${BENCH_FIGURES[@]}"; do
			file=${f%%|*} alt=${f#*|}
			[ ! -s "$file" ] || printf '\n![%s](%s)\n' "$alt" "$(basename "$file")"
		done
	} > "$out.tmp" || { rm -f "$out.tmp"; die "cannot write $out"; }
	for f in "${BENCH_FIGURES[@]}"; do
		file=${f%%|*}
		[ -s "$file" ] || continue
		{ cp "$file" "$BENCH_DOCS/$(basename "$file").tmp" &&
			mv "$BENCH_DOCS/$(basename "$file").tmp" "$BENCH_DOCS/$(basename "$file")"; } ||
			die "cannot copy $file into $BENCH_DOCS"
	done
	mv "$out.tmp" "$out"
	_q_unlock
	log "wrote $out"
}
