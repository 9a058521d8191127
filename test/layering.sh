#!/usr/bin/env bash
# test/layering.sh: no two files of src/ call each other in a loop, and only
# the job's own layer reads struct tdc_job.
#
# Each file of src/core, src/cli and src/pg is compiled on its own to an
# object; nm gives the symbols it defines and the ones it leaves undefined.
# An undefined symbol that another src/ file defines is an edge from the user
# to the definer.  The strongly connected components of that graph are the
# loops: a file that sits in a component with another file (a calls b, b
# calls ... a) fails, and the loop is printed as a path.  Calls through a
# static inline function of a header leave no symbol and are not seen; they
# cannot make a loop between .c files either.
#
# src/pg needs the server headers: they are found through PG_CONFIG (default
# pg_config) when it is installed; without them src/core and src/cli alone
# are checked, and the output says so.  No server is needed.
#
# A second rule: struct tdc_job (src/core/job.h) is read only by the job's
# own layer, JOB_LAYER below: the files that build a triangulation and give
# access to it.  Every other file, among them the consumers of a finished
# job (Voronoi, constrained, tiles) and the front ends, reads a finished job
# through the view of src/core/mesh_view.h or the public API of tdc.h; one
# that includes job.h, directly or through another header (as the compiler's
# -MM lists them), fails.
#
#   bash test/layering.sh        prints "N passed, N failed" (one per file)
set -u
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
CC=${CC:-cc}
PG_CONFIG=${PG_CONFIG:-pg_config}
pass=0
fail=0
gdal_inc=$(pkg-config --cflags gdal 2>/dev/null || gdal-config --cflags 2>/dev/null)
JOB_LAYER="job.c job_arena.c triangulate.c subdivide.c tolerance.c leaf.c result.c emit.c"

dirs="src/core src/cli"
pg_inc=""
if command -v "$PG_CONFIG" >/dev/null 2>&1 &&
		pg_inc=$("$PG_CONFIG" --includedir-server 2>/dev/null) &&
		[ -f "$pg_inc/postgres.h" ]; then
	dirs="$dirs src/pg"
else
	echo "note: no PostgreSQL server headers (PG_CONFIG=$PG_CONFIG): src/pg not checked, src/core and src/cli only"
fi

: > "$tmp/defs"
: > "$tmp/reads_job"
: > "$tmp/uses"
for d in $dirs; do
	for f in "$d"/*.c; do
		[ -f "$f" ] || continue
		o=$tmp/$(echo "$f" | tr / _).o
		flags="-std=c11 -D_GNU_SOURCE -pthread -Isrc/core"
		# (version.c takes its version strings from the Makefile; any will do here)
		[ "$d" = src/pg ] && flags="-std=gnu11 -D_GNU_SOURCE -pthread -Isrc/core -Isrc/pg -I$pg_inc \
			-DTDC_LIB_VERSION=\"0\" -DTDC_BUILD_POSTGIS=\"unknown\""
		# (src/cli/geotiff.c includes GDAL's headers, as the Makefile finds them,
		# and takes the name of its library from the Makefile; any will do here)
		[ "$d" = src/cli ] && flags="$flags $gdal_inc -DTDC_GDAL_SONAME=\"libgdal.so\""
		# shellcheck disable=SC2086
		if ! $CC $flags -O0 -w -c -o "$o" "$f" 2> "$tmp/err"; then
			echo "FAIL: $f does not compile on its own:"
			head -5 "$tmp/err"
			fail=$((fail + 1))
			continue
		fi
		case " $JOB_LAYER " in
			*" $(basename "$f") "*) [ "$d" = src/core ] || reads_job=check ;;
			*) reads_job=check ;;
		esac
		# shellcheck disable=SC2086
		if [ "${reads_job:-}" = check ] &&
				$CC $flags -MM "$f" 2>/dev/null | tr ' \\' '\n\n' | grep -qx 'src/core/job.h'; then
			echo "FAIL: $f includes src/core/job.h: outside the job's layer, read mesh_view.h or tdc.h"
			echo "$f" >> "$tmp/reads_job"
		fi
		reads_job=
		# defined: text, data, bss, read-only data (global or weak)
		nm -P "$o" | awk -v f="$f" '$2 ~ /^[TDBRVWG]$/ { print $1, f }' >> "$tmp/defs"
		nm -P "$o" | awk -v f="$f" '$2 == "U" { print f, $1 }' >> "$tmp/uses"
	done
done

# edges "from to", one per pair of files
awk 'NR == FNR { if (!($1 in def)) def[$1] = $2; next }
	($2 in def) && def[$2] != $1 { e = $1 " " def[$2]; if (!(e in seen)) { seen[e] = 1; print e } }' \
	"$tmp/defs" "$tmp/uses" | sort > "$tmp/edges"
awk '{ print $2 }' "$tmp/defs" | sort -u > "$tmp/files"
# files that define nothing another file could call still count
for d in $dirs; do ls "$d"/*.c; done | sort -u > "$tmp/all"

# Tarjan's strongly connected components; for each component of two or more
# files, one loop through it found by a breadth-first search inside it.  A
# file fails when it is in a loop or reads struct tdc_job outside its layer.
awk '
function strong(v,    i, w) {
	index_of[v] = idx; low[v] = idx; idx++
	stack[++sp] = v; on[v] = 1
	for (i = 1; i <= nout[v]; i++) {
		w = out[v, i]
		if (!(w in index_of)) {
			strong(w)
			if (low[w] < low[v]) low[v] = low[w]
		} else if (on[w] && index_of[w] < low[v])
			low[v] = index_of[w]
	}
	if (low[v] == index_of[v]) {
		ncomp++
		do {
			w = stack[sp--]; on[w] = 0
			comp[w] = ncomp; size[ncomp]++
		} while (w != v)
	}
}
# a shortest path from s back to s inside its component
function loop_of(s,    q, head, tail, u, i, w, prev, path, x) {
	head = 1; tail = 0
	for (i = 1; i <= nout[s]; i++) {
		w = out[s, i]
		if (comp[w] == comp[s] && !(w in prev)) { prev[w] = s; q[++tail] = w }
	}
	while (head <= tail) {
		u = q[head++]
		if (u == s) break
		for (i = 1; i <= nout[u]; i++) {
			w = out[u, i]
			if (comp[w] == comp[s] && !(w in prev)) { prev[w] = u; q[++tail] = w }
		}
	}
	path = s; x = prev[s]
	while (x != s) { path = x " -> " path; x = prev[x] }
	return s " -> " path
}
FILENAME == ARGV[1] { out[$1, ++nout[$1]] = $2; next }
FILENAME == ARGV[2] { reads_job[$1] = 1; next }
{ files[++nf] = $1 }
END {
	idx = 0; sp = 0; ncomp = 0
	for (i = 1; i <= nf; i++) if (!(files[i] in index_of)) strong(files[i])
	pass = 0; fail = 0
	for (i = 1; i <= nf; i++) {
		f = files[i]
		if (size[comp[f]] > 1) {
			fail++
			if (!(comp[f] in shown)) {
				shown[comp[f]] = 1
				print "FAIL: call loop: " loop_of(f)
				m = ""
				for (j = 1; j <= nf; j++) if (comp[files[j]] == comp[f]) m = m " " files[j]
				print "      files in the loop:" m
			}
		} else if (f in reads_job)
			fail++
		else
			pass++
	}
	print pass, fail > "/dev/stderr"
}' "$tmp/edges" "$tmp/reads_job" "$tmp/all" 2> "$tmp/counts"
read -r p f < "$tmp/counts"
pass=$((pass + p))
fail=$((fail + f))
echo "checked: $dirs ($(wc -l < "$tmp/all") files, $(wc -l < "$tmp/edges") file-to-file call edges)"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
