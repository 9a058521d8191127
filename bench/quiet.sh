# shellcheck shell=bash
# bench/quiet.sh -- the quiet-machine rule: a benchmark writes no report unless
# the machine was quiet before, during and after its timed runs.  Sourced by
# bench/lib.sh; bench_begin, bench_end and bench_publish there call it.
#
# A timing taken while other work shares the CPUs measures that work as much as
# ours: on the 2-core machine where the first reports were made beside builds,
# test suites and other benchmarks, they undersold the project 2 to 4 times.
#
# What counts as other work.  The 1-minute load average counts every runnable
# thread, the benchmark's own among them: a run on 2 threads drives it towards
# 2.0 by itself.  So the load judges the machine only while the benchmark is
# not running, and during the run the harness measures the others directly:
#
#   before  once the script has prepared its data (which loads the machine
#           too), wait up to BENCH_SETTLE seconds (120) for a quiet sample:
#           the 1-minute load at most BENCH_LOAD_PER_CORE (0.5) per core, and
#           the others quiet as below.
#   during  every BENCH_SAMPLE_INTERVAL seconds (2), the CPU each process used
#           over the interval, from the utime + stime deltas of /proc/PID/stat
#           (ps's %CPU is a lifetime average).  The run's own processes are left
#           out: the script's descendants and, for the SQL benchmarks, the
#           postmaster of the server they use with its children (found through
#           a backend's parent).  Kernel threads are left out too: they work for
#           whoever makes the I/O or the memory pressure, mostly the run.  A
#           sample is noisy when any other process used more than
#           BENCH_BUSY_PCT (20) % of a CPU, or all of them together more than
#           the load limit (0.5 per core, counted in CPUs): that is the part of
#           the load that is not the run's, measured rather than guessed from a
#           load average that mixes both.  The load is recorded, not judged.
#   after   wait again up to BENCH_SETTLE seconds for the run's own load to
#           decay (by e^-1 a minute: from 2.0 to 1.0 in about 42 s); the first
#           sample that meets the "before" rule is the "after" one.
#
# A process living less than one interval is seen only if it is alive at a
# sample (with all its CPU: it is new) and through the load before and after.
# The sampler itself (one of the run's processes) uses about 1% of a CPU.
# A sample taken while waiting (phase wait-before, wait-after) is recorded but
# not judged.  With a server shared with other clients, their backends count as
# the run's own: bench_begin warns about them; use a private server (run.sh
# starts one).
#
# When the rule breaks, the script exits with status 3 and writes no report and
# no figure into BENCH_DOCS, naming the noisy samples and the processes; a noisy
# "before" stops it before the timed runs.  BENCH_NOISY=1 measures and writes
# anyway, the title ending in "(noisy machine)" and the header listing the noisy
# samples.  Every sample is kept in $BENCH_OUT/SCRIPT.load.csv.
#
# One benchmark at a time: bench_begin takes a lock (BENCH_LOCK, a directory
# holding the owner's pid and start time, so that a dead owner's lock is stale)
# and refuses while another live benchmark holds it.
#
# Test seams (test/bench_quiet.sh): BENCH_PROC, the directory the processes'
# PID/stat files are read from, and BENCH_LOADAVG_FILE.

BENCH_PROC=${BENCH_PROC:-/proc}
BENCH_LOADAVG_FILE=${BENCH_LOADAVG_FILE:-$BENCH_PROC/loadavg}
BENCH_SAMPLE_INTERVAL=${BENCH_SAMPLE_INTERVAL:-2}
BENCH_SETTLE=${BENCH_SETTLE:-120}
BENCH_LOAD_PER_CORE=${BENCH_LOAD_PER_CORE:-0.5}
BENCH_BUSY_PCT=${BENCH_BUSY_PCT:-20}
BENCH_LOCK=${BENCH_LOCK:-/tmp/tdc_delaunay_bench.lock}
BENCH_CORES=$(getconf _NPROCESSORS_ONLN 2>/dev/null || nproc)
BENCH_HZ=$(getconf CLK_TCK 2>/dev/null || echo 100)
BENCH_SAMPLES_HDR="phase,time,load1,load5,load15,others_pct,own_pct,busiest_other,others_over_limit,verdict"

# refuse MESSAGE...: the run is not fit for a report: status 3
refuse() { log "REFUSED: $*"; exit 3; }

_q_check_knobs() {
	local v
	for v in BENCH_SAMPLE_INTERVAL BENCH_LOAD_PER_CORE BENCH_BUSY_PCT; do
		[[ ${!v} =~ ^[0-9]+(\.[0-9]+)?$ ]] || die "$v='${!v}' is not a number"
	done
	[[ $BENCH_SETTLE =~ ^[0-9]+$ ]] || die "BENCH_SETTLE='$BENCH_SETTLE' is not a whole number of seconds"
	[ -r "$BENCH_LOADAVG_FILE" ] || die "cannot read the load average from $BENCH_LOADAVG_FILE"
	BENCH_LOAD_LIMIT=$(awk -v c="$BENCH_CORES" -v p="$BENCH_LOAD_PER_CORE" 'BEGIN { printf "%.2f", c * p }')
}

# _q_starttime PID: the process's start time (clock ticks after boot), or ""
_q_starttime() { sed -n 's/^.*) [A-Za-z] \([-0-9 ]*\).*$/\1/p' "/proc/$1/stat" 2>/dev/null | cut -d' ' -f19; }

# _q_lock: take BENCH_LOCK for this script, or refuse while a live one holds it
_q_lock() {
	local pid start who tries=0
	mkdir -p "$(dirname "$BENCH_LOCK")"
	while ! mkdir "$BENCH_LOCK" 2>/dev/null; do
		pid='' start='' who=''
		read -r pid start who < "$BENCH_LOCK/owner" 2>/dev/null || true
		[ "$pid" = $$ ] && return 0
		if [ -z "$pid" ] && [ $tries -lt 3 ]; then
			# just made, its owner not written yet
			tries=$((tries + 1))
			sleep 1
			continue
		fi
		if [ -n "$pid" ] && [ "$(_q_starttime "$pid")" = "$start" ]; then
			refuse "another benchmark runs: $who (pid $pid) holds $BENCH_LOCK; one benchmark at a time"
		fi
		log "removing the stale lock $BENCH_LOCK (${who:-no owner}, pid ${pid:-?}, ended)"
		rm -rf "$BENCH_LOCK"
	done
	echo "$$ $(_q_starttime $$) $0" > "$BENCH_LOCK/owner"
}

_q_unlock() {
	local pid=''
	read -r pid _ < "$BENCH_LOCK/owner" 2>/dev/null || true
	[ "$pid" != $$ ] || rm -rf "$BENCH_LOCK"
}

# _q_server_pid: the postmaster of the server the PG* variables name, as the
# parent of this session's backend (read while the backend lives), or ""
_q_server_pid() {
	"${PSQL[@]}" -d "${PGDATABASE:-postgres}" 2>/dev/null <<'EOF' | grep -E '^[0-9]+$' || true
SELECT pg_backend_pid() AS tdc_q_backend \gset
\setenv TDC_Q_BACKEND :tdc_q_backend
\! sed -n 's/^.*) [A-Za-z] \([0-9]*\) .*$/\1/p' /proc/$TDC_Q_BACKEND/stat
EOF
}

# _q_snapshot FILE: the time, then every process's stat line
_q_snapshot() {
	echo "T $(date +%s.%N)" > "$1"
	cat "$BENCH_PROC"/[0-9]*/stat >> "$1" 2>/dev/null || true
}

# _q_sample PHASE A B: one CSV line (BENCH_SAMPLES_HDR) from snapshots A and B
_q_sample() {
	local l1 l5 l15
	read -r l1 l5 l15 _ < "$BENCH_LOADAVG_FILE"
	awk -v phase="$1" -v a="$2" -v hz="$BENCH_HZ" -v roots="$BENCH_ROOTS" \
		-v lim="$BENCH_LOAD_LIMIT" -v busy="$BENCH_BUSY_PCT" -v now="$(date -u +%H:%M:%S)" \
		-v l1="$l1" -v l5="$l5" -v l15="$l15" '
		# pid (comm) state ppid ...: utime and stime are the 12th and 13th
		# fields after the last ") " (comm may hold anything), start the 20th
		function parse(line,   i, rest, f) {
			i = index(line, " (")
			pid = substr(line, 1, i - 1)
			comm = substr(line, i + 2)
			sub(/\) [^)]*$/, "", comm)
			gsub(/[^A-Za-z0-9_.:\/+-]/, "_", comm)
			rest = line
			sub(/^.*\) /, "", rest)
			split(rest, f, " ")
			ppid = f[2]
			cpu = f[12] + f[13]
			key = pid ":" f[20]
		}
		# own (the roots and their descendants), kernel (kthreadd and its
		# children) or foreign
		function cls(p) {
			if (p in memo) return memo[p]
			if (p in own) return memo[p] = "own"
			if (p + 0 == 2) return memo[p] = "kernel"
			if (p + 0 <= 1 || !(p in par)) return memo[p] = "foreign"
			memo[p] = "foreign"	# a torn read cannot loop
			return memo[p] = cls(par[p])
		}
		/^T / { if (FILENAME == a) t0 = $2; else t1 = $2; next }
		FILENAME == a { parse($0); c0[key] = cpu; next }
		{ parse($0); par[pid] = ppid; name[pid] = comm; d[pid] = cpu - ((key in c0) ? c0[key] : 0) }
		END {
			dt = t1 - t0
			if (dt <= 0) dt = 0.001
			n = split(roots, r, " ")
			for (i = 1; i <= n; i++) own[r[i]] = 1
			others = 0; mine = 0; nb = 0; top = 0; topn = "none"
			for (p in d) {
				pct = d[p] * 100 / hz / dt
				c = cls(p)
				if (c == "own") mine += pct
				if (c != "foreign") continue
				others += pct
				if (pct > top) { top = pct; topn = sprintf("%s %s %.0f%%", name[p], p, pct) }
				if (pct > busy) { bp[++nb] = pct; bn[nb] = name[p] " " p }
			}
			for (i = 2; i <= nb; i++)
				for (j = i; j > 1 && bp[j] > bp[j - 1]; j--) {
					x = bp[j]; bp[j] = bp[j - 1]; bp[j - 1] = x
					x = bn[j]; bn[j] = bn[j - 1]; bn[j - 1] = x
				}
			list = ""
			for (i = 1; i <= nb; i++) list = list (i > 1 ? " / " : "") sprintf("%s %.0f%%", bn[i], bp[i])
			why = ""
			if (phase != "during" && l1 + 0 > lim + 0) why = "load " l1 " > " lim
			if (others > lim * 100) why = why (why != "" ? " and " : "") sprintf("others together %.0f%% of a CPU > %.0f%%", others, lim * 100)
			if (nb) why = why (why != "" ? " and " : "") "over " busy "%: " list
			printf "%s,%s,%s,%s,%s,%.0f,%.0f,%s,%s,%s\n", phase, now, l1, l5, l15, others, mine, topn,
				(list == "" ? "none" : list), (why == "" ? "quiet" : "noisy: " why)
		}' "$2" "$3"
}

# _q_describe LINE: a sample for a person: "08:01:12 before: load 1.52 > 1.00 and ..."
_q_describe() {
	awk -F, '{ v = $10; sub(/^noisy: /, "", v)
		if (v == "quiet") v = sprintf("quiet (load %s, others %s%% of a CPU together)", $3, $6)
		printf "%s %s: %s\n", $2, $1, v }' <<< "$1"
}

# _q_take PHASE: one sample of BENCH_SAMPLE_INTERVAL seconds, printed
_q_take() {
	_q_snapshot "$BENCH_QDIR/a"
	sleep "$BENCH_SAMPLE_INTERVAL"
	_q_snapshot "$BENCH_QDIR/b"
	_q_sample "$1" "$BENCH_QDIR/a" "$BENCH_QDIR/b"
}

# _q_settle PHASE: wait up to BENCH_SETTLE s for a quiet sample; the last sample
# is PHASE's (in BENCH_SAMPLES and Q_LAST); 0 if it is quiet
_q_settle() {
	local phase=$1 start=$SECONDS said=-100 line
	while :; do
		line=$(_q_take "$phase")
		Q_LAST=$line
		if [ "${line##*,}" = quiet ]; then
			echo "$line" >> "$BENCH_SAMPLES"
			return 0
		fi
		if ((SECONDS - start >= BENCH_SETTLE)); then
			echo "$line" >> "$BENCH_SAMPLES"
			return 1
		fi
		echo "wait-$line" >> "$BENCH_SAMPLES"
		if ((SECONDS - said >= 10)); then
			log "waiting (at most ${BENCH_SETTLE} s in all) for a quiet machine $phase the run: $(_q_describe "$line")"
			said=$SECONDS
		fi
	done
}

# _q_sampler: the background sampler of the timed runs; ends when bench_end
# asks or the script is gone
_q_sampler() {
	local warned=0 line
	set +e
	_q_snapshot "$BENCH_QDIR/s0"
	while [ ! -e "$BENCH_QDIR/stop" ] && kill -0 "$BENCH_MAIN" 2>/dev/null; do
		sleep "$BENCH_SAMPLE_INTERVAL"
		_q_snapshot "$BENCH_QDIR/s1"
		line=$(_q_sample during "$BENCH_QDIR/s0" "$BENCH_QDIR/s1")
		echo "$line" >> "$BENCH_SAMPLES"
		if [ $warned = 0 ] && [ "${line##*,}" != quiet ]; then
			warned=1
			log "the machine is not quiet: $(_q_describe "$line")$([ "${BENCH_NOISY:-0}" = 1 ] ||
				echo "; no report will be written (BENCH_NOISY=1 keeps it)")"
		fi
		mv -f "$BENCH_QDIR/s1" "$BENCH_QDIR/s0"
	done
	kill -0 "$BENCH_MAIN" 2>/dev/null || rm -rf "$BENCH_QDIR"
}

# _q_noisy_list: the judged samples that broke the rule, one a line, described
_q_noisy_list() {
	awk -F, '$1 ~ /^(before|during|after)$/ && $10 != "quiet"' "$BENCH_SAMPLES" |
		while IFS= read -r l; do _q_describe "$l"; done
}

# quiet_begin [server]: lock, find the run's own processes, wait for a quiet
# machine (or refuse), then start the sampler
quiet_begin() {
	local pm others
	_q_check_knobs
	_q_lock
	BENCH_MAIN=$$
	BENCH_ROOTS=$$
	if [ "${1:-}" = server ]; then
		pm=$(_q_server_pid)
		if [ -n "$pm" ]; then
			BENCH_ROOTS="$BENCH_ROOTS $pm"
			log "the server's processes (postmaster $pm and its children) count as the run's own"
			others=$("${PSQL[@]}" -d "${PGDATABASE:-postgres}" -c "SELECT count(*) FROM pg_stat_activity WHERE backend_type = 'client backend' AND pid <> pg_backend_pid()" 2>/dev/null || echo 0)
			[ "${others:-0}" = 0 ] ||
				log "WARNING: $others other sessions on this server: their work counts as the run's own"
		else
			log "WARNING: no postmaster found for the server of PGHOST=${PGHOST:-} PGPORT=${PGPORT:-}: if it runs here, its work counts as other processes"
		fi
	fi
	mkdir -p "$BENCH_OUT"
	BENCH_SAMPLES=$BENCH_OUT/$(basename "$0" .sh).load.csv
	echo "$BENCH_SAMPLES_HDR" > "$BENCH_SAMPLES"
	BENCH_QDIR=$(mktemp -d "${TMPDIR:-/tmp}/tdc_quiet.XXXXXX")
	BENCH_QUIET=''
	if ! _q_settle before; then
		if [ "${BENCH_NOISY:-0}" = 1 ]; then
			log "the machine is not quiet, measuring anyway (BENCH_NOISY=1): $(_q_describe "$Q_LAST")"
		else
			rm -rf "$BENCH_QDIR"
			refuse "the machine is not quiet before the run, after waiting ${BENCH_SETTLE} s:
  $(_q_describe "$Q_LAST")
  every sample: $BENCH_SAMPLES
  Nothing was measured and no report written.  Stop the other work and run again, or set
  BENCH_NOISY=1 to write a report marked \"(noisy machine)\"."
		fi
	fi
	BENCH_LOAD0=$(cut -d, -f3-5 <<< "$Q_LAST" | tr , ' ')
	BENCH_BUSY0=$(cut -d, -f9 <<< "$Q_LAST")
	( _q_sampler ) > /dev/null &
	BENCH_SAMPLER=$!
}

# quiet_end: stop the sampler, wait for the run's own load to settle, judge
# (BENCH_QUIET yes or no)
quiet_end() {
	local t0=$SECONDS i
	[ -n "${BENCH_QDIR:-}" ] || refuse "no samples: the script did not call bench_begin before bench_end"
	touch "$BENCH_QDIR/stop"
	wait "$BENCH_SAMPLER" 2>/dev/null || true
	for ((i = 0; i < 100; i++)); do
		kill -0 "$BENCH_SAMPLER" 2>/dev/null || break
		sleep 0.1
	done
	_q_settle after || true
	BENCH_SETTLED=$((SECONDS - t0))
	BENCH_LOAD1=$(cut -d, -f3-5 <<< "$Q_LAST" | tr , ' ')
	BENCH_BUSY1=$(cut -d, -f9 <<< "$Q_LAST")
	rm -rf "$BENCH_QDIR"
	BENCH_NOISE=$(_q_noisy_list)
	if [ -z "$BENCH_NOISE" ]; then
		BENCH_QUIET=yes
		log "the machine was quiet before, during and after the run"
	else
		BENCH_QUIET=no
		log "the machine was not quiet at $(wc -l <<< "$BENCH_NOISE") samples (every sample: $BENCH_SAMPLES):"
		head -n 10 <<< "$BENCH_NOISE" | sed 's/^/  /' >&2
	fi
}

# quiet_gate NAME: return if the report NAME may be written; otherwise refuse
quiet_gate() {
	[ -n "${BENCH_QUIET:-}" ] ||
		refuse "no report without samples: the script did not call bench_begin and bench_end"
	[ "$BENCH_QUIET" = yes ] && return 0
	if [ "${BENCH_NOISY:-0}" = 1 ]; then
		log "writing $BENCH_DOCS/$1.md marked \"(noisy machine)\" (BENCH_NOISY=1)"
		return 0
	fi
	refuse "the machine was not quiet around the timed runs, so $BENCH_DOCS/$1.md is not written:
$(head -n 20 <<< "$BENCH_NOISE" | sed 's/^/  /')$(n=$(wc -l <<< "$BENCH_NOISE"); [ "$n" -le 20 ] || printf '\n  and %d more' $((n - 20)))
  every sample: $BENCH_SAMPLES
  Stop the other work and run again, or set BENCH_NOISY=1 to write it marked \"(noisy machine)\"."
}

# quiet_rows: the header rows on the samples and the rule (markdown table rows)
quiet_rows() {
	local n
	n=$(awk -F, '$1 == "during"' "$BENCH_SAMPLES" | wc -l)
	awk -F, -v n="$n" -v iv="$BENCH_SAMPLE_INTERVAL" -v f="${BENCH_SAMPLES#"$ROOT"/}" '
		$1 ~ /^(before|during|after)$/ && ($6 + 0 > m || !seen) { m = $6 + 0; b = $8; seen = 1 }
		$1 == "during" && $3 + 0 > l { l = $3 + 0 }
		END { printf "| samples | %d during the run, every %s s (`%s`): other processes at most %d%% of a CPU together (busiest then: %s); 1-minute load at most %.2f, the run'"'"'s own threads included |\n", n, iv, f, m, b, l }' "$BENCH_SAMPLES"
	printf '| other processes over %s%% of a CPU | before: %s; during: %s; after: %s |\n' "$BENCH_BUSY_PCT" \
		"${BENCH_BUSY0:-?}" "$(awk -F, '$1 == "during" && $9 != "none" { k = split($9, e, " / ");
			for (i = 1; i <= k; i++) { p = e[i]; sub(/ [0-9]+%$/, "", p); v = e[i]; sub(/^.* /, "", v); sub(/%/, "", v)
				if (!(p in mx)) o[++no] = p; if (v + 0 > mx[p]) mx[p] = v + 0; c[p]++ } }
		END { for (i = 1; i <= no && i <= 8; i++)
				printf "%s%s up to %d%% (%d sample%s)", (i > 1 ? ", " : ""), o[i], mx[o[i]], c[o[i]], (c[o[i]] > 1 ? "s" : "")
			if (no > 8) printf " and %d more", no - 8
			if (!no) printf "none" }' "$BENCH_SAMPLES")" "${BENCH_BUSY1:-?}"
	if [ "$BENCH_QUIET" = yes ]; then
		printf '| quiet rule | held: load at most %s (%s per core) before and after; at every sample no other process over %s%% of a CPU, and all others together at most %s CPUs |\n' \
			"$BENCH_LOAD_LIMIT" "$BENCH_LOAD_PER_CORE" "$BENCH_BUSY_PCT" "$BENCH_LOAD_LIMIT"
	else
		printf '| quiet rule | broken at %d samples, written with BENCH_NOISY=1: %s%s |\n' "$(wc -l <<< "$BENCH_NOISE")" \
			"$(head -n 8 <<< "$BENCH_NOISE" | paste -sd';' | sed 's/;/; /g; s/|/\\|/g')" \
			"$(n=$(wc -l <<< "$BENCH_NOISE"); [ "$n" -le 8 ] || echo "; and $((n - 8)) more")"
	fi
}
