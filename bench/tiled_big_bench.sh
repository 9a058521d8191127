#!/usr/bin/env bash
# bench/tiled_big_bench.sh -- ./tdc --max-memory on a billion uniform points
# and a hundred million clustered ones: a program that prints figures and
# asserts nothing.
#
# One run each, timed as a whole process by GNU time (wall, user+sys CPU,
# peak RSS), without -o (the triangulation alone: two billion triangles as
# text would be some 450 GB):
#   - BENCH_BIG_N (1e9) uniform points (gen_points uniform, 16 GB) under
#     --max-memory BENCH_BIG_LIMIT (2000).  No one-shot run: it would need
#     some 110 GB.  The count is checked against 2n - 2 - h: with u distinct
#     points and T triangles the hull has h = 2u - 2 - T vertices, which for
#     uniform points in a square is a few dozen; the script prints h.
#   - BENCH_BIG_CN (1e8) clustered points (gen_points clusters64: 64
#     Gaussian clusters of widths 0.1 to 20 in a 1000 square) under the same
#     limit, and one-shot when `free` shows room for it (some 11 GB): the
#     two counts must agree.
# Beside them, the published figure this is compared with: Isenburg, Liu,
# Shewchuk and Snoeyink, "Streaming computation of Delaunay triangulations"
# (SIGGRAPH 2006), a billion triangles from 11.2 GB of LIDAR (Neuse River,
# some 500M points) in 48 minutes with 70 MB of memory on a 2006 laptop,
# writing its mesh to disk.
#
# The inputs are generated into BENCH_BIG_TMP and deleted after their runs;
# the tiles go there too.  Disk: 16 GB for the input and about as much for the
# tiles and halos of the 1e9 run.
#
# Environment knobs:
#   BENCH_BIG_N=1e9        uniform points ("" skips the case)
#   BENCH_BIG_CN=1e8       clustered points ("" skips the case)
#   BENCH_BIG_LIMIT=2000   --max-memory (MB)
#   BENCH_BIG_TMP=$ROOT/build/bench/big   inputs and tiles
#   BENCH_TIMEOUT=7200     seconds per run
# Output: stdout, build/bench/tiled_big.txt (the same) and
# docs/benchmarks/tiled_big.md.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

UN=${BENCH_BIG_N-1e9}
CN=${BENCH_BIG_CN-1e8}
LIMIT=${BENCH_BIG_LIMIT:-2000}
TMPD=${BENCH_BIG_TMP:-$ROOT/build/bench/big}
TMO=${BENCH_TIMEOUT:-7200}

mkdir -p "$BENCH_OUT" "$TMPD"
TXT=$BENCH_OUT/tiled_big.txt
WORK=$(mktemp -d "$TMPD/big_bench.XXXXXX")
INPUT=
trap 'rm -rf "$WORK"; [ -z "$INPUT" ] || rm -f "$INPUT" "$INPUT.tmp"' EXIT

bench_tdc_copy

exec > >(tee "$TXT")
TEE_PID=$!

bench_begin
echo "runs: ./tdc --stats without -o (the triangulation alone), one run each; tiles in $TMPD"
echo "timing: whole process, GNU time (wall, user+sys CPU, peak RSS)"

# gen KIND N: the input file, generated (its path in INPUT)
gen() {
	INPUT=$TMPD/big_$1_$2.bin
	log "generating $INPUT"
	local t0=$SECONDS
	"$BENCH_BIN/gen_points" "$1" "$2" "$POINT_SEED" "$INPUT.tmp" && mv "$INPUT.tmp" "$INPUT" ||
		die "gen_points $1 $2 failed"
	echo "input: gen_points $1 $2 (seed $POINT_SEED), $(( $(stat -c %s "$INPUT") >> 20 )) MB, generated in $((SECONDS - t0)) s"
}

# run NAME LIMIT: one timed run of $INPUT (LIMIT 0: one-shot); prints a line
# and leaves the triangle count in TRI, the distinct points in UNIQ
run() {
	local name=$1 limit=$2 args=(--stats)
	[ "$limit" = 0 ] || args+=(--max-memory "$limit" --tmpdir "$WORK")
	TRI= UNIQ=
	if ! timeout "$TMO" /usr/bin/time -f '%e %U %S %M' -o "$WORK/time" \
		"$TDC_BIN" "${args[@]}" "$INPUT" 2> "$WORK/stats"; then
		echo "$name: failed: $(tail -2 "$WORK/stats" | tr '\n' ' ')"
		return 0
	fi
	local wall cpu rss
	read -r wall cpu rss < <(awk '{ printf "%s %.1f %.1f\n", $1, $2 + $3, $4 / 1024 }' "$WORK/time")
	TRI=$(kv "$WORK/stats" triangles)
	UNIQ=$(kv "$WORK/stats" unique)
	printf '%-22s wall %9.1f s (%5.1f min)  cpu %9.1f s (cpu/wall %.2f)  peak RSS %8.1f MB  triangles %s  distinct points %s' \
		"$name" "$wall" "$(awk -v w="$wall" 'BEGIN { print w / 60 }')" "$cpu" \
		"$(awk -v c="$cpu" -v w="$wall" 'BEGIN { print (w > 0 ? c / w : 0) }')" "$rss" "$TRI" "$UNIQ"
	if [ "$limit" != 0 ]; then
		printf '  tiles %s, runs %s, halo points %s; %s the limit\n' "$(kv "$WORK/stats" tiles)" \
			"$(kv "$WORK/stats" tile_runs)" "$(kv "$WORK/stats" halo_points)" \
			"$(awk -v r="$rss" -v l="$limit" 'BEGIN { print (r <= l ? "within" : "OVER") }')"
		printf '  phases (wall s): scan %s, bin %s on %s threads, tiles %s on %s workers\n' "$(kv "$WORK/stats" scan)" \
			"$(kv "$WORK/stats" bin)" "$(kv "$WORK/stats" bin_threads)" "$(kv "$WORK/stats" tiles_wall)" \
			"$(kv "$WORK/stats" workers)"
		printf '  in the tiles (s, summed over the workers): gather %s, engine %s, finish %s, write %s, waiting for memory %s\n' \
			"$(kv "$WORK/stats" gather)" "$(kv "$WORK/stats" engine)" "$(kv "$WORK/stats" finish)" \
			"$(kv "$WORK/stats" write)" "$(kv "$WORK/stats" wait)"
	else
		echo
	fi
}

if [ -n "$UN" ]; then
	n=$(n_of "$UN")
	echo
	echo "== $n uniform points, --max-memory $LIMIT (load $(cut -d' ' -f1-3 /proc/loadavg), $(df -P -k "$TMPD" | awk 'NR == 2 { printf "%d", $4 / 1048576 }') GB free in $TMPD)"
	gen uniform "$UN"
	run "mm$LIMIT" "$LIMIT"
	if [ -n "$TRI" ]; then
		echo "hull vertices h = 2u - 2 - T = $(awk -v u="$UNIQ" -v t="$TRI" 'BEGIN { printf "%.0f", 2 * u - 2 - t }') (u distinct points, T triangles)"
	fi
	rm -f "$INPUT"
	INPUT=
fi

if [ -n "$CN" ]; then
	n=$(n_of "$CN")
	echo
	echo "== $n clustered points (clusters64), --max-memory $LIMIT and one-shot (load $(cut -d' ' -f1-3 /proc/loadavg))"
	gen clusters64 "$CN"
	run "c_mm$LIMIT" "$LIMIT"
	ctri=$TRI
	avail=$(free -g | awk '/Mem:/ { print $7 }')
	if [ "$avail" -ge 13 ]; then
		run c_oneshot 0
		[ -z "$ctri" ] || [ -z "$TRI" ] ||
			echo "same triangle count as one-shot: $([ "$ctri" = "$TRI" ] && echo yes || echo "NO ($ctri against $TRI)")"
	else
		echo "one-shot skipped: it needs ~11 GB, $avail GB available"
	fi
	rm -f "$INPUT"
	INPUT=
fi

echo
echo "published, for comparison: Isenburg, Liu, Shewchuk, Snoeyink, Streaming computation of Delaunay"
echo "triangulations (SIGGRAPH 2006): a billion triangles (Neuse River LIDAR, 11.2 GB) in 48 minutes with"
echo "70 MB of memory, on a 2006 laptop with two hard drives, the mesh written to disk."
exec >&-
wait "$TEE_PID" 2>/dev/null || true
bench_end
what=
[ -z "$UN" ] || what="$UN uniform"
[ -z "$CN" ] || what="${what:+$what and }$CN clustered"
bench_publish tiled_big "Tiles at scale: ./tdc --max-memory $LIMIT on $what points" "$TXT" text
