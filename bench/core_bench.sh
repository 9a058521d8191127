#!/usr/bin/env bash
# bench/core_bench.sh -- core benchmark: ./tdc (1 thread and all threads)
# against CGAL's Delaunay_triangulation_2 (Epick, range insert) on the same
# points, in the same run, alternating, several repetitions; medians reported.
#
# Point sets (deterministic, generated into data/bench/ on first use):
#   uniform, clustered, grid (exact integer lattice)  at n = 1e5, 1e6, 1e7
#   gshhg     all GSHHG full-resolution shoreline vertices (~10.64M, via GMT)
#   gshhg_1m  a 1M random subset of those vertices
#
# Outputs (build/bench/):
#   core_runs.csv  every single run
#   core.csv       medians per set
#   phases.csv     phase times for threads 1..N on the phase set (1e7 uniform)
#   core.txt       the printed tables
#   core.png       seconds vs n for the synthetic sets
# and docs/benchmarks/core.md (bench_publish's header, then core.txt and the
# figure, copied beside it) if the machine was quiet (bench/quiet.sh).
#
# Environment knobs:
#   BENCH_SIZES="1e5 1e6 1e7"  BENCH_SETS="uniform clustered grid"
#   BENCH_COAST=1 (0: skip the GSHHG sets)
#   BENCH_REPS_SMALL=5 (n < 5e6)  BENCH_REPS_BIG=3
#   BENCH_PHASE_SET=uniform_1e7   BENCH_PHASE_REPS=3
#   BENCH_TIMEOUT=900 (seconds per single run)
#   BENCH_NO_TDC=1   only CGAL
#   BENCH_DOCS=DIR   where core.md and core.png go (default docs/benchmarks/)
#   BENCH_PLOT_ONLY=1  only redraw build/bench/core.png from build/bench/core.csv
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

SIZES=${BENCH_SIZES:-"1e5 1e6 1e7"}
SETS=${BENCH_SETS:-"uniform clustered grid"}
COAST=${BENCH_COAST:-1}
REPS_SMALL=${BENCH_REPS_SMALL:-5}
REPS_BIG=${BENCH_REPS_BIG:-3}
PHASE_SET=${BENCH_PHASE_SET:-uniform_1e7}
PHASE_REPS=${BENCH_PHASE_REPS:-3}
TMO=${BENCH_TIMEOUT:-900}
NCPU=$(nproc)

mkdir -p "$BENCH_OUT"
RUNS=$BENCH_OUT/core_runs.csv
CSV=$BENCH_OUT/core.csv
PHASES=$BENCH_OUT/phases.csv
TXT=$BENCH_OUT/core.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

[ -x /usr/bin/time ] || ensure_debs time
build_helpers
build_cgal

HAVE_TDC=1
if [ "${BENCH_NO_TDC:-0}" = 1 ]; then
	HAVE_TDC=0
elif ! ensure_tdc; then
	log "running the CGAL half only"
	HAVE_TDC=0
fi
# time a private copy: a concurrent `make tdc` must not swap the binary mid-run
TDC_BIN=$WORK/tdc
[ $HAVE_TDC = 1 ] && cp -p "$ROOT/tdc" "$TDC_BIN"

# make_plot: $BENCH_OUT/core.png (seconds vs n, log-log) from core.csv, per synthetic set:
# tdc 1 thread / all threads / CGAL
make_plot() {
	rm -f "$BENCH_OUT/core.png"
	if command -v gnuplot >/dev/null; then
		pl=()
		colors=("#1f77b4" "#2ca02c" "#9467bd")
		ci=0
		for k in $SETS; do
			awk -F, -v k="$k" 'NR > 1 && index($1, k "_") == 1 { print $2, $8, $11, $13 }' "$CSV" | sort -g > "$WORK/plot.$k"
			[ -s "$WORK/plot.$k" ] || continue
			c=${colors[$((ci % 3))]}
			ci=$((ci + 1))
			[ $HAVE_TDC = 1 ] && pl+=("'$WORK/plot.$k' using 1:2 with linespoints lw 2 pt 7 lc rgb '$c' title 'tdc 1 thread, $k'"
				"'$WORK/plot.$k' using 1:3 with linespoints lw 1 dt 2 pt 6 lc rgb '$c' title 'tdc $NCPU threads, $k'")
			pl+=("'$WORK/plot.$k' using 1:4 with linespoints lw 2 dt 3 pt 4 lc rgb '$c' title 'CGAL, $k'")
		done
		if [ ${#pl[@]} -gt 0 ]; then
			{
				echo "set terminal pngcairo size 800,560 font 'DejaVu Sans,10'"
				echo "set output '$BENCH_OUT/core.png'"
				echo "set logscale xy"
				echo "set format x '10^{%L}'"
				echo "set xlabel 'points n'"
				echo "set ylabel 'seconds'"
				echo "set title 'Core: ./tdc vs CGAL Delaunay\\_triangulation\\_2 (medians, $NCPU CPUs)'"
				echo "set grid"
				echo "set key top left"
				printf 'plot '
				(IFS=,; echo "${pl[*]}")
			} > "$WORK/core.gp"
			gnuplot "$WORK/core.gp" || log "gnuplot failed"
		fi
	fi
}

if [ "${BENCH_PLOT_ONLY:-0}" = 1 ]; then
	make_plot
	exit 0
fi

# ---------------------------------------------------------------- inputs
declare -a SET_NAMES=() SET_FILES=()
for nl in $SIZES; do
	for k in $SETS; do
		SET_NAMES+=("${k}_${nl}")
		SET_FILES+=("$(ensure_points "$k" "$nl")")
	done
done
if [ "$COAST" = 1 ]; then
	ensure_gshhg
	GSHHG_META=$(cat "$BENCH_DATA/gshhg.meta")
	SET_NAMES+=(gshhg_1m gshhg)
	SET_FILES+=("$BENCH_DATA/gshhg_sub.bin" "$BENCH_DATA/gshhg.bin")
fi

# ---------------------------------------------------------------- running
RUNS_HDR="set,rep,tool,threads_req,n,unique,triangles,threads,sort,subdivide,leaves,merge,total,peak_rss_mb,time_rss_mb,wall,cpu,status"

# run_tdc SET FILE REP THREADS: one ./tdc --stats run, appended to $RUNS
run_tdc() {
	local set=$1 file=$2 rep=$3 thr=$4 st=ok
	timeout "$TMO" /usr/bin/time -f 'time_rss_kb=%M time_wall=%e time_user=%U time_sys=%S' -o "$WORK/time" \
		"$TDC_BIN" -t "$thr" --stats "$file" > /dev/null 2> "$WORK/err" || st=fail
	grep -q '^n=' "$WORK/err" || st=fail
	if [ $st = fail ]; then
		log "tdc -t $thr $set failed: $(tail -3 "$WORK/err" | tr '\n' ' ')"
		echo "$set,$rep,tdc,$thr,,,,,,,,,,,,,,fail" >> "$RUNS"
		return 0
	fi
	grep '^n=' "$WORK/err" | tail -1 > "$WORK/stats"
	local f
	printf '%s,%s,tdc,%s' "$set" "$rep" "$thr" >> "$RUNS"
	for f in n unique triangles threads sort subdivide leaves merge total peak_rss_mb; do
		printf ',%s' "$(kv "$WORK/stats" $f)" >> "$RUNS"
	done
	printf ',%s,%s,%s,ok\n' "$(awk '{ print $1 / 1024 }' <<< "$(kv "$WORK/time" time_rss_kb)")" \
		"$(kv "$WORK/time" time_wall)" \
		"$(awk -v u="$(kv "$WORK/time" time_user)" -v s="$(kv "$WORK/time" time_sys)" 'BEGIN { print u + s }')" >> "$RUNS"
}

# run_cgal SET FILE REP
run_cgal() {
	local set=$1 file=$2 rep=$3 st=ok
	timeout "$TMO" /usr/bin/time -f 'time_rss_kb=%M time_wall=%e' -o "$WORK/time" \
		"$BENCH_BIN/cgal_dt" "$file" > "$WORK/out" 2> "$WORK/err" || st=fail
	grep -q '^n=' "$WORK/out" || st=fail
	if [ $st = fail ]; then
		log "cgal $set failed: $(tail -3 "$WORK/err" | tr '\n' ' ')"
		echo "$set,$rep,cgal,1,,,,,,,,,,,,,,fail" >> "$RUNS"
		return 0
	fi
	local o=$WORK/out
	printf '%s,%s,cgal,1,%s,%s,%s,1,,,,,%s,%s,%s,%s,%s,ok\n' "$set" "$rep" \
		"$(kv "$o" n)" "$(kv "$o" vertices)" "$(kv "$o" faces)" "$(kv "$o" seconds)" \
		"$(kv "$o" peak_rss_mb)" "$(awk '{ print $1 / 1024 }' <<< "$(kv "$WORK/time" time_rss_kb)")" \
		"$(kv "$WORK/time" time_wall)" "$(kv "$o" cpu_seconds)" >> "$RUNS"
}

# med SET TOOL THREADS_REQ FIELD: median of a column over the ok runs
med() {
	awk -F, -v s="$1" -v t="$2" -v r="$3" -v col="$4" '
		NR == 1 { for (i = 1; i <= NF; i++) if ($i == col) c = i; next }
		$1 == s && $3 == t && $4 == r && $NF == "ok" { print $c }' "$RUNS" | median
}
# first value of a column (counts that do not vary between runs)
first() {
	awk -F, -v s="$1" -v t="$2" -v r="$3" -v col="$4" '
		NR == 1 { for (i = 1; i <= NF; i++) if ($i == col) c = i; next }
		$1 == s && $3 == t && $4 == r && $NF == "ok" { print $c; exit }' "$RUNS"
}
nfail() {
	awk -F, -v s="$1" -v t="$2" -v r="$3" '$1 == s && $3 == t && $4 == r && $NF == "fail" { k++ } END { print k + 0 }' "$RUNS"
}
fmt() { awk -v x="$1" -v f="$2" 'BEGIN { if (x == "") print "-"; else printf f "\n", x }'; }
div() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b == "" || b + 0 == 0) print ""; else printf "%.6g\n", a / b }'; }

echo "$RUNS_HDR" > "$RUNS"
bench_begin

{
	echo "# ./tdc: make tdc of this tree (copied before the runs)"
	echo "# CGAL $(awk '$2 == "CGAL_VERSION" { print $3 }' /usr/include/CGAL/version.h 2>/dev/null), Epick, range insert; g++ -O2 -DNDEBUG -DCGAL_NDEBUG"
	if [ "$COAST" = 1 ]; then echo "# GSHHG full resolution (gmt coast -Rd -Df -W -M): $GSHHG_META"; fi
	echo "# times: tdc = engine 'total' from --stats (file reading excluded), CGAL = dt.insert only; both single-process, medians"
} | tee "$TXT"

log "core runs: ${SET_NAMES[*]}"
for i in "${!SET_NAMES[@]}"; do
	set=${SET_NAMES[$i]}
	file=${SET_FILES[$i]}
	n=$(( $(stat -c %s "$file") / 16 ))
	reps=$REPS_SMALL
	[ "$n" -ge 5000000 ] && reps=$REPS_BIG
	log "$set (n=$n, $reps repetitions)"
	for rep in $(seq 1 "$reps"); do
		# alternate the order so that no tool is always first after a cold start
		if [ $((rep % 2)) = 1 ]; then
			if [ $HAVE_TDC = 1 ]; then
				run_tdc "$set" "$file" "$rep" 1
				run_tdc "$set" "$file" "$rep" 0
			fi
			run_cgal "$set" "$file" "$rep"
		else
			run_cgal "$set" "$file" "$rep"
			if [ $HAVE_TDC = 1 ]; then
				run_tdc "$set" "$file" "$rep" 0
				run_tdc "$set" "$file" "$rep" 1
			fi
		fi
	done
done

# phase table: threads 1..N on the phase set
if [ $HAVE_TDC = 1 ]; then
	pfile=""
	for i in "${!SET_NAMES[@]}"; do
		[ "${SET_NAMES[$i]}" = "$PHASE_SET" ] && pfile=${SET_FILES[$i]}
	done
	if [ -z "$pfile" ]; then
		pfile=$(ensure_points "${PHASE_SET%_*}" "${PHASE_SET##*_}")
	fi
	log "phase runs on $PHASE_SET, threads 1..$NCPU, $PHASE_REPS repetitions"
	for rep in $(seq 1 "$PHASE_REPS"); do
		for t in $(seq 1 "$NCPU"); do
			run_tdc "phase:$PHASE_SET" "$pfile" "$rep" "$t"
		done
	done
fi

# ---------------------------------------------------------------- tables
echo "set,n,unique,triangles,cgal_faces,triangles_match,reps,tdc1_total_s,tdc1_ns_per_point,tdcN_threads,tdcN_total_s,speedup,cgal_s,cgal_ns_per_point,ratio_tdc1_cgal,ratio_tdcN_cgal,tdc1_peak_rss_mb,tdcN_peak_rss_mb,cgal_peak_rss_mb,tdc1_sort,tdc1_subdivide,tdc1_leaves,tdc1_merge,tdcN_sort,tdcN_subdivide,tdcN_leaves,tdcN_merge,tdc1_wall_s,tdcN_wall_s,cgal_wall_s,tdc1_cpu_s,cgal_cpu_s,ratio_cpu_tdc1_cgal,failures" > "$CSV"

{
	echo
	echo "Core benchmark (medians; seconds; RSS = peak resident set of the whole process, /usr/bin/time)"
	printf '%-15s %9s %9s %6s %9s %7s %9s %8s %8s %8s %7s %7s %7s %7s %s\n' \
		set n unique tri=? tdc1_s tdc1_ns tdcN_s speedup cgal_s cgal_ns 1/cgal cpu1/cg rss1MB rssCG "phases_1thread(sort/sub/leaves/merge)"
} | tee -a "$TXT"

for set in "${SET_NAMES[@]}"; do
	n=$(first "$set" cgal 1 n)
	[ -z "$n" ] && n=$(first "$set" tdc 1 n)
	uniq=$(first "$set" tdc 1 unique)
	[ -z "$uniq" ] && uniq=$(first "$set" cgal 1 unique)
	tri=$(first "$set" tdc 1 triangles)
	cf=$(first "$set" cgal 1 triangles)
	match=""
	[ -n "$tri" ] && [ -n "$cf" ] && { [ "$tri" = "$cf" ] && match=yes || match=NO; }
	reps=$(awk -F, -v s="$set" '$1 == s { if ($2 > m) m = $2 } END { print m + 0 }' "$RUNS")
	t1=$(med "$set" tdc 1 total); tN=$(med "$set" tdc 0 total); cg=$(med "$set" cgal 1 total)
	thrN=$(first "$set" tdc 0 threads)
	t1ns=$(div "$t1" "$n"); [ -n "$t1ns" ] && t1ns=$(awk -v x="$t1ns" 'BEGIN { printf "%.1f", x * 1e9 }')
	cgns=$(div "$cg" "$n"); [ -n "$cgns" ] && cgns=$(awk -v x="$cgns" 'BEGIN { printf "%.1f", x * 1e9 }')
	sp=$(div "$t1" "$tN"); r1=$(div "$t1" "$cg"); rN=$(div "$tN" "$cg")
	rss1=$(med "$set" tdc 1 time_rss_mb); rssc=$(med "$set" cgal 1 time_rss_mb)
	declare -A ph=()
	for p in sort subdivide leaves merge; do
		ph[1$p]=$(med "$set" tdc 1 $p); ph[N$p]=$(med "$set" tdc 0 $p)
	done
	w1=$(med "$set" tdc 1 wall); wN=$(med "$set" tdc 0 wall); wc=$(med "$set" cgal 1 wall)
	c1=$(med "$set" tdc 1 cpu); cc=$(med "$set" cgal 1 cpu); rc=$(div "$c1" "$cc")
	fails=$(( $(nfail "$set" tdc 1) + $(nfail "$set" tdc 0) + $(nfail "$set" cgal 1) ))
	echo "$set,$n,$uniq,$tri,$cf,$match,$reps,$t1,$t1ns,$thrN,$tN,$sp,$cg,$cgns,$r1,$rN,$(med "$set" tdc 1 peak_rss_mb),$(med "$set" tdc 0 peak_rss_mb),$(med "$set" cgal 1 peak_rss_mb),${ph[1sort]},${ph[1subdivide]},${ph[1leaves]},${ph[1merge]},${ph[Nsort]},${ph[Nsubdivide]},${ph[Nleaves]},${ph[Nmerge]},$w1,$wN,$wc,$c1,$cc,$rc,$fails" >> "$CSV"
	printf '%-15s %9s %9s %6s %9s %7s %9s %8s %8s %8s %7s %7s %7s %7s %s/%s/%s/%s%s\n' "$set" "$n" "${uniq:--}" "${match:--}" \
		"$(fmt "$t1" %.3f)" "$(fmt "$t1ns" %.0f)" "$(fmt "$tN" %.3f)" "$(fmt "$sp" %.2fx)" \
		"$(fmt "$cg" %.3f)" "$(fmt "$cgns" %.0f)" "$(fmt "$r1" %.2f)" "$(fmt "$rc" %.2f)" "$(fmt "$rss1" %.0f)" "$(fmt "$rssc" %.0f)" \
		"$(fmt "${ph[1sort]}" %.3f)" "$(fmt "${ph[1subdivide]}" %.3f)" "$(fmt "${ph[1leaves]}" %.3f)" "$(fmt "${ph[1merge]}" %.3f)" \
		"$([ "$fails" -gt 0 ] && echo "  ($fails failed runs)")" | tee -a "$TXT"
	unset ph
done

{
	echo
	echo "columns: tri=? tdc triangle count equals CGAL's finite face count; tdc1 = ./tdc -t 1, tdcN = ./tdc -t 0 (all $NCPU CPUs);"
	echo "         *_ns = ns per input point; 1/cgal = tdc1_s / cgal_s (< 1: tdc faster); rss = /usr/bin/time max RSS (MB);"
	echo "         cpu1/cg = CPU seconds of the whole ./tdc -t 1 process (user+sys, file reading included) / CPU seconds of CGAL's insert"
	echo "                   (less sensitive than wall time to other load on the machine)"
} | tee -a "$TXT"

if [ $HAVE_TDC = 1 ]; then
	echo "set,threads,reps,sort,subdivide,leaves,merge,total,speedup,efficiency,peak_rss_mb" > "$PHASES"
	{
		echo
		echo "Phase times on $PHASE_SET (medians of $PHASE_REPS runs, seconds; as Table 1 of Wu et al. 2014)"
		printf '%8s %9s %9s %9s %9s %9s %8s %6s\n' threads sort subdivide leaves merge total speedup eff
	} | tee -a "$TXT"
	base=$(med "phase:$PHASE_SET" tdc 1 total)
	for t in $(seq 1 "$NCPU"); do
		s="phase:$PHASE_SET"
		tot=$(med "$s" tdc "$t" total)
		sp=$(div "$base" "$tot")
		eff=$(div "$sp" "$t")
		echo "$PHASE_SET,$t,$PHASE_REPS,$(med "$s" tdc "$t" sort),$(med "$s" tdc "$t" subdivide),$(med "$s" tdc "$t" leaves),$(med "$s" tdc "$t" merge),$tot,$sp,$eff,$(med "$s" tdc "$t" peak_rss_mb)" >> "$PHASES"
		printf '%8s %9s %9s %9s %9s %9s %8s %6s\n' "$t" \
			"$(fmt "$(med "$s" tdc "$t" sort)" %.3f)" "$(fmt "$(med "$s" tdc "$t" subdivide)" %.3f)" \
			"$(fmt "$(med "$s" tdc "$t" leaves)" %.3f)" "$(fmt "$(med "$s" tdc "$t" merge)" %.3f)" \
			"$(fmt "$tot" %.3f)" "$(fmt "$sp" %.2fx)" "$(fmt "$eff" %.2f)" | tee -a "$TXT"
	done
fi

bench_end

make_plot
bench_figure "$BENCH_OUT/core.png" "engine time against n"
bench_publish core "The engine: ./tdc against CGAL" "$TXT" text
log "wrote $CSV, $RUNS$([ $HAVE_TDC = 1 ] && echo ", $PHASES"), $TXT"
