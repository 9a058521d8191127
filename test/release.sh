#!/usr/bin/env bash
# test/release.sh: what every release must hold, checked on the built tree
# without a server (after `make`; scripts/test.sh runs it after its build):
#   - the library exports every C function that any shipped install or
#     upgrade script names ('MODULE_PATHNAME', 'symbol', and the
#     pg_finfo_symbol that PG_FUNCTION_INFO_V1 adds), so that a database made
#     by an older script keeps working between the new library's install and
#     ALTER EXTENSION tdc_delaunay UPDATE;
#   - every C function of a script names its symbol on the line of
#     'MODULE_PATHNAME' (the form the check above reads);
#   - the control file's default_version, the Makefile's EXTVERSION and
#     META.json's versions agree, and the Makefile installs every script of
#     the tree;
#   - every shipped base script reaches default_version through shipped
#     upgrade scripts (0.1.0 through 1.0.0, 1.0.0 through 1.1.0);
#   - the scripts of released versions are tracked files, and only
#     default_version's install script is built from src/sql.
#   PG_CONFIG=... bash test/release.sh      (prints "N passed, N failed")
set -u
cd "$(dirname "$0")/.."
PG_CONFIG=${PG_CONFIG:-pg_config}
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() {
	fail=$((fail + 1))
	echo "FAIL: $*"
}
done_() {
	echo "$pass passed, $fail failed"
	((fail == 0))
	exit
}

EXT=tdc_delaunay
SO=$EXT.so
# The Makefile's own lists, as PGXS installs them.
make_var() {
	make --no-print-directory -s PG_CONFIG="$PG_CONFIG" -f Makefile -f - print-var <<<"print-var: ; @echo \$($1)"
}
EXTVERSION=$(make_var EXTVERSION)
read -r -a SCRIPTS <<<"$(make_var DATA) $(make_var DATA_built)"
if [ -z "$EXTVERSION" ] || ((${#SCRIPTS[@]} == 0)); then
	bad "the Makefile's EXTVERSION, DATA and DATA_built (is PG_CONFIG=$PG_CONFIG right?)"
	done_
fi
for s in "${SCRIPTS[@]}"; do
	[ -f "$s" ] || { bad "$s is missing: run make first"; done_; }
done
[ -f "$SO" ] || { bad "$SO is missing: run make first"; done_; }

# Versions.
control=$(sed -n "s/^default_version *= *'\([^']*\)'.*/\1/p" $EXT.control)
[ "$control" = "$EXTVERSION" ] && ok || bad "$EXT.control default_version '$control' != Makefile EXTVERSION '$EXTVERSION'"
meta=$(tr -d '\n\t ' <META.json)
[[ $meta == *"\"version\":\"$EXTVERSION\""* ]] && ok || bad "META.json: no \"version\": \"$EXTVERSION\""
[[ $meta == *"\"provides\":{\"$EXT\":{\"file\":\"$EXT.control\",\"version\":\"$EXTVERSION\""* ]] && ok ||
	bad "META.json: provides $EXT is not $EXT.control, version $EXTVERSION"
[[ " ${SCRIPTS[*]} " == *" $EXT--$EXTVERSION.sql "* ]] && ok || bad "no $EXT--$EXTVERSION.sql installed"

# Every script in the tree is installed (a script left out of DATA would
# break the upgrade path of the databases that need it).
for s in $(git ls-files "$EXT--*.sql" 2>/dev/null); do
	[[ " ${SCRIPTS[*]} " == *" $s "* ]] && ok || bad "$s is in the tree but not in the Makefile's DATA"
done

# The scripts of released versions (DATA: the older base scripts, among them
# 1.0.0's, and every upgrade script) ship as they were released: tracked
# files, never rebuilt from src/sql, which only makes default_version's.
if git rev-parse --git-dir >/dev/null 2>&1; then
	read -r -a STATIC <<<"$(make_var DATA)"
	for s in "${STATIC[@]}"; do
		git ls-files --error-unmatch "$s" >/dev/null 2>&1 && ok ||
			bad "$s ships as released but is not a tracked file of the tree"
	done
	for s in $(make_var DATA_built); do
		git ls-files --error-unmatch "$s" >/dev/null 2>&1 &&
			bad "$s is built from src/sql but also tracked" || ok
	done
fi

# Symbols.
exported=$(nm -D --defined-only "$SO" | awk '$2 == "T" { print $3 }' | sort -u)
nsym=0
for s in "${SCRIPTS[@]}"; do
	nc=$(grep -ci "LANGUAGE C\b" "$s")
	nm_=$(grep -c "'MODULE_PATHNAME', *'" "$s")
	[ "$nc" = "$nm_" ] && ok || bad "$s: $nc functions in LANGUAGE C but $nm_ 'MODULE_PATHNAME', 'symbol' lines"
	for sym in $(grep -o "'MODULE_PATHNAME', *'[^']*'" "$s" | sed "s/.*, *'\([^']*\)'/\1/" | sort -u); do
		nsym=$((nsym + 1))
		for want in "$sym" "pg_finfo_$sym"; do
			grep -qx "$want" <<<"$exported" && ok || bad "$s names $want, which $SO does not export"
		done
	done
done
echo "$nsym symbols named by ${#SCRIPTS[@]} scripts (${SCRIPTS[*]})"

# Upgrade paths: from every base script to default_version.
declare -A edges=()
for s in "${SCRIPTS[@]}"; do
	v=${s#"$EXT"--}
	v=${v%.sql}
	[[ $v == *--* ]] && edges[${v%%--*}]+=" ${v#*--}"
done
for s in "${SCRIPTS[@]}"; do
	v=${s#"$EXT"--}
	v=${v%.sql}
	[[ $v == *--* ]] && continue
	seen=" $v " frontier=$v
	while [ -n "$frontier" ]; do
		next=""
		for f in $frontier; do
			for t in ${edges[$f]:-}; do
				[[ $seen == *" $t "* ]] || { seen+="$t "; next+=" $t"; }
			done
		done
		frontier=$next
	done
	[[ $seen == *" $control "* ]] && ok || bad "no upgrade path from $v to $control"
done
done_
