#!/usr/bin/env bash
# bench/tiled_cli_bench.sh -- ./tdc one-shot against ./tdc --max-memory (the
# tiled run of src/core/tiles/tile_final.c) on uniform points: a program that prints
# figures and asserts nothing.
#
# 10M uniform points (gen_points uniform, seed 42: data/bench/uniform_1e7.bin,
# shared with core_bench.sh) are triangulated one-shot and with each
# --max-memory limit, the runs alternating (one-shot, limit 1, limit 2, then
# again), REPS rounds.  Every run is timed as a whole process by GNU time
# (package `time`): wall, user+sys CPU, peak RSS.  Printed per run kind: the
# medians, the tiles / tile runs / halo points of --stats, the triangle count
# (all runs must give the same; the last column says whether they do), the
# tiled run's phase times (scan, bin, gather, engine, finish, write: medians,
# wall seconds) and the ratios tiled / one-shot of the median wall and CPU
# times; beside them, for a machine whose load changes during the run, the
# median of each round's own ratio and the ratio of the best (least) walls.  With BENCH_TILED_100M=1 it then runs 100M points once with
# --max-memory 2000 (and one-shot, when `free` shows room for it), prints
# the same, whether the peak RSS stayed within 2000 MB and whether the
# triangle counts agree, and deletes the 1.6 GB input.
#
# Then the same on clustered points (gen_points clusters64: 64 Gaussian
# clusters of widths 0.1 to 20 in a 1000 square, the shape on which a grid of
# equal tiles fails), one-shot against each limit of BENCH_TILED_CLUSTERED,
# the runs alternating as above: the adaptive tiles must hold the limit
# there too, with the one-shot's triangle count.
#
# The report, docs/benchmarks/tiled.md, starts with bench_publish's header
# (date, commit, machine, load).  On a loaded machine the ratios mean more
# than the times.
#
# Environment knobs:
#   BENCH_TILED_N=1e7          points of the main case (a gen_points count label)
#   BENCH_TILED_REPS=3         alternating rounds
#   BENCH_TILED_LIMITS="400 800"   --max-memory values (MB)
#   BENCH_TILED_THREADS=0      -t for every run (0 = all CPUs)
#   BENCH_TILED_OUTPUT=none    none: no -o (the triangulation alone, as the
#                              README's figures); text: -o to a file under
#                              BENCH_TILED_TMP (deleted after each run; about
#                              2.3 GB for 10M points); null: -o /dev/null
#                              (the formatting without the disk)
#   BENCH_TILED_TMP=${TMPDIR:-/tmp}  --tmpdir of the tiled runs, and -o files
#   BENCH_TILED_100M=1         also the 100M case (needs 1.6 GB of disk for the
#                              input, 1.6 GB more for the tiles, and ~11 GB of
#                              free memory for its one-shot run, skipped if not)
#   BENCH_TILED_100M_LIMIT=2000
#   BENCH_TILED_CLUSTERED="300"   --max-memory values (MB) for the clusters64
#                              case of BENCH_TILED_N points ("" skips it)
#   BENCH_TIMEOUT=1800         seconds per single run
# Output: stdout, build/bench/tiled_cli.txt (the same), tiled_cli_runs.csv
# (every run), and docs/benchmarks/tiled.md.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

NLABEL=${BENCH_TILED_N:-1e7}
REPS=${BENCH_TILED_REPS:-3}
LIMITS=${BENCH_TILED_LIMITS:-"400 800"}
THREADS=${BENCH_TILED_THREADS:-0}
OUTPUT=${BENCH_TILED_OUTPUT:-none}
TMPD=${BENCH_TILED_TMP:-${TMPDIR:-/tmp}}
BIG=${BENCH_TILED_100M:-0}
BIG_LIMIT=${BENCH_TILED_100M_LIMIT:-2000}
CLIMITS=${BENCH_TILED_CLUSTERED-300}
TMO=${BENCH_TIMEOUT:-1800}

case $OUTPUT in none | text | null) ;; *) die "BENCH_TILED_OUTPUT must be none, text or null" ;; esac

mkdir -p "$BENCH_OUT" "$TMPD"
TXT=$BENCH_OUT/tiled_cli.txt
RUNS=$BENCH_OUT/tiled_cli_runs.csv
WORK=$(mktemp -d "$TMPD/tiled_bench.XXXXXX")
BIGIN=
trap 'rm -rf "$WORK"; [ -z "$BIGIN" ] || rm -f "$BIGIN" "$BIGIN.tmp"' EXIT

bench_tdc_copy

exec > >(tee "$TXT")
TEE_PID=$!

loadavg() { cut -d' ' -f1-3 /proc/loadavg; }
bench_begin
echo "runs: ./tdc -t $THREADS --stats, output: $OUTPUT$([ "$OUTPUT" = none ] && echo ' (no -o: the triangulation alone)'), tiles in $TMPD"
echo "timing: whole process, GNU time (wall, user+sys CPU, peak RSS); medians of $REPS alternating rounds"

echo "kind,n,limit,round,wall,cpu,rss_mb,triangles,tiles,runs,halo,scan,bin,gather,engine,finish,write" > "$RUNS"

# run_one KIND N INPUT LIMIT ROUND: one timed run, a line in $RUNS
run_one() {
	local kind=$1 n=$2 in=$3 limit=$4 round=$5 args=() out=
	args=(-t "$THREADS" --stats)
	[ "$limit" = 0 ] || args+=(--max-memory "$limit" --tmpdir "$TMPD")
	case $OUTPUT in
	text) out=$WORK/out.txt; args+=(-o "$out") ;;
	null) args+=(-o /dev/null) ;;
	esac
	if ! timeout "$TMO" /usr/bin/time -f '%e %U %S %M' -o "$WORK/time" \
		"$TDC_BIN" "${args[@]}" "$in" 2> "$WORK/stats"; then
		log "run failed: $kind $n $limit: $(tail -2 "$WORK/stats" | tr '\n' ' ')"
		[ -z "$out" ] || rm -f "$out"
		return 0
	fi
	[ -z "$out" ] || rm -f "$out"
	local wall cpu rss
	read -r wall cpu rss < <(awk '{ printf "%s %.2f %.1f\n", $1, $2 + $3, $4 / 1024 }' "$WORK/time")
	local f
	f=$(for k in triangles tiles tile_runs halo_points scan bin gather engine finish write; do
		printf ',%s' "$(kv "$WORK/stats" $k)"; done)
	echo "$kind,$n,$limit,$round,$wall,$cpu,$rss$f" >> "$RUNS"
}

# the run kind the others are compared with (table, paired)
base=oneshot

# col KIND N FIELD: median of a column of $RUNS for that kind and n
col() {
	awk -F, -v k="$1" -v n="$2" -v f="$3" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
		$1 == k && $2 == n { print $c[f] }' "$RUNS" | median
}
# distinct KIND N FIELD: the distinct values of a column (comma separated)
distinct() {
	awk -F, -v k="$1" -v n="$2" -v f="$3" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
		$1 == k && $2 == n && !s[$c[f]]++ { printf "%s%s", (m++ ? "," : ""), $c[f] }' "$RUNS"
}
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a != "" && b != "" && b > 0) printf "%.2fx", a / b; else printf "-" }'; }
# colmin KIND N FIELD: the least value of a column
colmin() {
	awk -F, -v k="$1" -v n="$2" -v f="$3" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
		$1 == k && $2 == n && (m == "" || $c[f] + 0 < m + 0) { m = $c[f] } END { print m }' "$RUNS"
}
# paired KIND N: median over rounds of (KIND's wall / the one-shot wall of the same round)
paired() {
	awk -F, -v k="$1" -v n="$2" -v b="$base" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
		$2 == n && $1 == b { o[$c["round"]] = $c["wall"] }
		$2 == n && $1 == k { t[$c["round"]] = $c["wall"] }
		END { for (r in t) if (o[r] > 0) printf "%.4f\n", t[r] / o[r] }' "$RUNS" | median |
		awk '$1 != "" { printf "%.2fx", $1 }'
}

# table N KINDS...: the medians, one line per run kind
table() {
	local n=$1
	shift
	local w0 c0 tri0
	w0=$(col "$base" "$n" wall)
	c0=$(col "$base" "$n" cpu)
	tri0=$(distinct "$base" "$n" triangles)
	printf '%-16s %9s %9s %9s %6s %6s %10s %12s %9s %9s  %s\n' run wall_s cpu_s rss_mb tiles runs halo triangles wall/1 cpu/1 same_count
	local k
	for k in "$@"; do
		local w c r tri same
		w=$(col "$k" "$n" wall)
		[ -n "$w" ] || { printf '%-16s (no successful run)\n' "$k"; continue; }
		c=$(col "$k" "$n" cpu)
		r=$(col "$k" "$n" rss_mb)
		tri=$(distinct "$k" "$n" triangles)
		same=-
		[ -z "$tri0" ] || { [ "$tri" = "$tri0" ] && same=yes || same="NO (one-shot $tri0)"; }
		printf '%-16s %9s %9s %9s %6s %6s %10s %12s %9s %9s  %s\n' "$k" "$w" "$c" "$r" \
			"$(distinct "$k" "$n" tiles)" "$(distinct "$k" "$n" runs)" "$(distinct "$k" "$n" halo)" \
			"$tri" "$(ratio "$w" "$w0")" "$(ratio "$c" "$c0")" "$same"
	done
	echo "wall/1 and cpu/1: ratios of the medians.  Less sensitive to a load that changes during the run:"
	for k in "$@"; do
		[ "$k" = "$base" ] && continue
		printf '  %-14s median of the per-round ratios %s; best runs %s s vs %s s one-shot (%s)\n' "$k" \
			"$(paired "$k" "$n")" "$(colmin "$k" "$n" wall)" "$(colmin "$base" "$n" wall)" \
			"$(ratio "$(colmin "$k" "$n" wall)" "$(colmin "$base" "$n" wall)")"
	done
	echo "tiled phases (medians, wall s): scan = box, hull, counts; bin = tile files; gather = reading tiles back; engine = tdc_triangulate; finish = tdc_tile_finish"
	for k in "$@"; do
		[ "$k" = "$base" ] && continue
		printf '  %-14s' "$k"
		local p
		for p in scan bin gather engine finish write; do printf ' %s=%s' $p "$(col "$k" "$n" $p)"; done
		echo
	done
}

# rounds PREFIX INPUT WHAT LIMITS...: REPS alternating rounds of the one-shot
# run (kind PREFIXoneshot) and each limit (PREFIXmmX); kinds := the run kinds
rounds() {
	local p=$1 in=$2 what=$3 l r
	shift 3
	kinds=("${p}oneshot")
	for l in "$@"; do kinds+=("${p}mm$l"); done
	log "$N $what points ($in): ${kinds[*]}, $REPS rounds"
	for ((r = 1; r <= REPS; r++)); do
		run_one "${p}oneshot" "$N" "$in" 0 "$r"
		for l in "$@"; do run_one "${p}mm$l" "$N" "$in" "$l" "$r"; done
	done
}

N=$(n_of "$NLABEL")
IN=$(ensure_points uniform "$NLABEL")
# shellcheck disable=SC2086
rounds "" "$IN" uniform $LIMITS
echo
echo "== $N uniform points, $REPS rounds (mmX = --max-memory X)"
table "$N" "${kinds[@]}"

if [ "$BIG" = 1 ]; then
	BN=100000000
	avail=$(free -g | awk '/Mem:/ { print $7 }')
	disk=$(df -P -k "$TMPD" | awk 'NR == 2 { printf "%d", $4 / 1048576 }')
	echo
	echo "== $BN uniform points, one run each (load $(loadavg), ${avail} GB memory available, ${disk} GB disk in $TMPD)"
	if [ "$disk" -lt 4 ]; then
		echo "skipped: needs 4 GB of disk in $TMPD for the input and the tiles"
	else
		BIGIN=$TMPD/tiled_bench_uniform_1e8.bin
		log "generating $BIGIN"
		"$BENCH_BIN/gen_points" uniform "$BN" "$POINT_SEED" "$BIGIN.tmp" && mv "$BIGIN.tmp" "$BIGIN" ||
			die "gen_points uniform $BN failed"
		run_one "mm$BIG_LIMIT" "$BN" "$BIGIN" "$BIG_LIMIT" 1
		bk=("mm$BIG_LIMIT")
		if [ "$avail" -ge 13 ]; then
			run_one oneshot "$BN" "$BIGIN" 0 1
			bk=(oneshot "${bk[@]}")
		else
			echo "one-shot skipped: it needs ~11 GB, ${avail} GB available"
		fi
		rm -f "$BIGIN"
		BIGIN=
		table "$BN" "${bk[@]}"
		rss=$(col "mm$BIG_LIMIT" "$BN" rss_mb)
		[ -z "$rss" ] || echo "peak RSS of --max-memory $BIG_LIMIT: $rss MB, $(awk -v r="$rss" -v l="$BIG_LIMIT" 'BEGIN { print (r <= l ? "within" : "OVER") }') the limit; triangles $(distinct "mm$BIG_LIMIT" "$BN" triangles) (2n - 2 - h for n distinct points with h on the hull)"
	fi
fi

if [ -n "$CLIMITS" ]; then
	CIN=$(ensure_points clusters64 "$NLABEL")
	base=c_oneshot
	# shellcheck disable=SC2086
	rounds c_ "$CIN" clustered $CLIMITS
	echo
	echo "== $N clustered points (clusters64: 64 Gaussian clusters, widths 0.1 to 20, in a 1000 square), $REPS rounds (c_mmX = --max-memory X)"
	table "$N" "${kinds[@]}"
	for l in $CLIMITS; do
		rss=$(awk -F, -v k="c_mm$l" -v n="$N" '$1 == k && $2 == n && $7 + 0 > m { m = $7 + 0 } END { print m }' "$RUNS")
		[ -z "$rss" ] || echo "largest peak RSS of --max-memory $l: $rss MB, $(awk -v r="$rss" -v l="$l" 'BEGIN { print (r <= l ? "within" : "OVER") }') the limit"
	done
fi
exec >&-
wait "$TEE_PID" 2>/dev/null || true
bench_end
bench_publish tiled "Tiles: ./tdc one-shot against ./tdc --max-memory" "$TXT" text
