#!/usr/bin/env bash
# test/layering.sh: the folders of src/ are layers that call only downward,
# no two files call each other in a loop, and only the job's own files read
# struct tdc_job.
#
# Each file under src/core, src/cli and src/pg is compiled on its own to an
# object; nm gives the symbols it defines and the ones it leaves undefined.
# An undefined symbol that another src/ file defines is an edge from the user
# to the definer.  Three rules, a file failing when it breaks any:
#
# Folders.  LAYERS below is the one place that says which folder may call
# which: a file may call (and include from) its own folder, the folders its
# line names (a component's name, src/core, stands for all its folders),
# and the face of its component (src/core/tdc.h, src/pg/tdc_pg.h).  A call
# or an include that goes anywhere else fails, with the symbol or header
# named; so does a file in a folder the table does not name.  Includes are
# read from the compiler's -MM list, so a static inline function of a
# header, which leaves no symbol, is checked too.
#
# Loops.  The strongly connected components of the call graph are the
# loops: a file that sits in a component with another file (a calls b, b
# calls ... a) fails, and the loop is printed as a path.
#
# The job.  struct tdc_job (src/core/engine/job_int.h) is read only by the
# job's own files, JOB_LAYER below: the ones that build a triangulation and
# give access to it.  Every other file, among them the consumers of a
# finished job (Voronoi, constrained, TIN, tiles) and the front ends, reads
# a finished job through the view of src/core/engine/mesh_view.h or the
# public API of tdc.h; one that includes job_int.h, directly or through
# another header, fails.
#
# src/pg needs the server headers: they are found through PG_CONFIG (default
# pg_config) when it is installed; without them src/core and src/cli alone
# are checked, and the output says so.  No server is needed.
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

# FOLDER  and the folders it may call (docs/design.md, "The plan"):
# the engine calls no feature; the features and the tiles stand on the
# engine, the TIN on the constrained insertion too; the terrain products of
# a bounded run on the TIN and on the tiles' proofs (a natural neighbour
# pixel's cavity is proven global as tile_final.c proves a triangle,
# tile_disk.c's boxes and tile_cells.c's cells); the front ends call the
# core; in src/pg the entry points call the formats and the runtime, the
# formats the runtime, and nothing calls an entry point.
LAYERS="
src/core/engine
src/core/cdt		src/core/engine
src/core/voronoi	src/core/engine
src/core/tin		src/core/engine src/core/cdt
src/core/tiles		src/core/engine
src/core/terrain	src/core/engine src/core/tin src/core/tiles
src/cli				src/core
src/pg/runtime		src/core
src/pg/formats		src/pg/runtime src/core
src/pg/fn			src/pg/formats src/pg/runtime src/core
"

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
: > "$tmp/bad"
: > "$tmp/uses"
: > "$tmp/incs"
for d in $dirs; do
	for f in $(find "$d" -name '*.c' | sort); do
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
		# the headers of src/ it includes, directly or not
		# shellcheck disable=SC2086
		$CC $flags -MM "$f" 2>/dev/null | tr ' \\' '\n\n' | grep '^src/.*\.h$' |
			awk -v f="$f" '{ print f, $1 }' > "$tmp/inc1"
		cat "$tmp/inc1" >> "$tmp/incs"
		case " $JOB_LAYER " in
			*" $(basename "$f") "*) [ "$(dirname "$f")" = src/core/engine ] || reads_job=check ;;
			*) reads_job=check ;;
		esac
		if [ "${reads_job:-}" = check ] && grep -q ' src/core/engine/job_int.h$' "$tmp/inc1"; then
			echo "FAIL: $f includes src/core/engine/job_int.h: outside the job's layer, read mesh_view.h or tdc.h"
			echo "$f" >> "$tmp/bad"
		fi
		reads_job=
		# defined: text, data, bss, read-only data (global or weak)
		nm -P "$o" | awk -v f="$f" '$2 ~ /^[TDBRVWG]$/ { print $1, f }' >> "$tmp/defs"
		nm -P "$o" | awk -v f="$f" '$2 == "U" { print f, $1 }' >> "$tmp/uses"
	done
done

# edges "from to symbol", one per pair of files (its first symbol)
awk 'NR == FNR { if (!($1 in def)) def[$1] = $2; next }
	($2 in def) && def[$2] != $1 { e = $1 " " def[$2]; if (!(e in seen)) { seen[e] = 1; print e, $2 } }' \
	"$tmp/defs" "$tmp/uses" | sort > "$tmp/calls"
cut -d' ' -f1,2 "$tmp/calls" > "$tmp/edges"

# The folder rule, over the calls and the includes: "from to what" lines.
for d in $dirs; do find "$d" -name '*.c'; done | sort -u > "$tmp/all"
{
	awk '{ print $1, $1, "is there" }' "$tmp/all"
	awk '{ print $1, $2, "calls " $2 " (" $3 ")" }' "$tmp/calls"
	awk '{ print $1, $2, "includes " $2 }' "$tmp/incs"
} | awk -v layers="$LAYERS" '
function dir(p) { sub(/\/[^\/]*$/, "", p); return p }
# is folder t, or a folder under t, or t itself a folder
function under(d, t) { return d == t || index(d, t "/") == 1 }
BEGIN {
	n = split(layers, line, "\n")
	for (i = 1; i <= n; i++) {
		k = split(line[i], w, /[ \t]+/)
		if (k == 0 || w[1] == "") continue
		known[w[1]] = 1
		may[w[1]] = ""
		for (j = 2; j <= k; j++) may[w[1]] = may[w[1]] " " w[j]
	}
}
{
	from = dir($1); to = dir($2)
	what = $0; sub(/^[^ ]+ [^ ]+ /, "", what)
	if (!(from in known)) {
		if (!(from in told)) {
			told[from] = 1
			print "FAIL: folder " from " is not in LAYERS (test/layering.sh): say what it may call"
		}
		print $1 > "/dev/stderr"
		next
	}
	if (to == from || under(from, to))		# its own folder, or its component face
		next
	ok = 0
	k = split(may[from], w, " ")
	for (j = 1; j <= k; j++) if (under(to, w[j])) ok = 1
	if (!ok) {
		print "FAIL: " $1 " " what ": " from " may call " (k ? "only" may[from] : "no other folder")
		print $1 > "/dev/stderr"
	}
}' 2>> "$tmp/bad"

# Tarjan's strongly connected components; for each component of two or more
# files, one loop through it found by a breadth-first search inside it.  A
# file fails when it is in a loop, or breaks the folder or the job rule.
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
FILENAME == ARGV[2] { bad[$1] = 1; next }
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
		} else if (f in bad)
			fail++
		else
			pass++
	}
	print pass, fail > "/dev/stderr"
}' "$tmp/edges" "$tmp/bad" "$tmp/all" 2> "$tmp/counts"
read -r p f < "$tmp/counts"
pass=$((pass + p))
fail=$((fail + f))
echo "checked: $dirs ($(wc -l < "$tmp/all") files, $(wc -l < "$tmp/edges") file-to-file call edges)"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
