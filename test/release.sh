#!/usr/bin/env bash
# test/release.sh: what every release must hold, checked on the built tree
# without a server (after `make`; scripts/test.sh runs it after its build):
# For each extension of the package (the Makefile's EXTENSION: tdc_delaunay
# and tdc_delaunay_raster, one library):
#   - the library exports every C function that any shipped install or
#     upgrade script names ('MODULE_PATHNAME', 'symbol', and the
#     pg_finfo_symbol that PG_FUNCTION_INFO_V1 adds), so that a database made
#     by an older script keeps working between the new library's install and
#     ALTER EXTENSION ... UPDATE;
#   - every C function of a script names its symbol on the line of
#     'MODULE_PATHNAME' (the form the check above reads);
#   - the control file's default_version, the Makefile's version of it
#     (EXTVERSION, RASTER_EXTVERSION) and META.json's versions agree, the
#     control file loads the package's library, and the Makefile installs
#     every script of the tree;
#   - every shipped base script reaches default_version through shipped
#     upgrade scripts (tdc_delaunay: 0.1.0 through 1.0.0, 1.0.0 through
#     1.1.0, 1.1.0 through 1.2.0);
#   - the scripts of released versions are tracked files, and only
#     default_version's install scripts are built from src/sql;
#   - tdc_delaunay requires postgis only (not postgis_raster), and
#     tdc_delaunay_raster requires tdc_delaunay and postgis_raster.
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

SO=tdc_delaunay.so
# The Makefile's own lists, as PGXS installs them.
make_var() {
	make --no-print-directory -s PG_CONFIG="$PG_CONFIG" -f Makefile -f - print-var <<<"print-var: ; @echo \$($1)"
}
read -r -a EXTENSIONS <<<"$(make_var EXTENSION)"
read -r -a SCRIPTS <<<"$(make_var DATA) $(make_var DATA_built)"
PKGVERSION=$(make_var EXTVERSION)
if [ -z "$PKGVERSION" ] || ((${#SCRIPTS[@]} == 0 || ${#EXTENSIONS[@]} == 0)); then
	bad "the Makefile's EXTENSION, EXTVERSION, DATA and DATA_built (is PG_CONFIG=$PG_CONFIG right?)"
	done_
fi
for s in "${SCRIPTS[@]}"; do
	[ -f "$s" ] || { bad "$s is missing: run make first"; done_; }
done
[ -f "$SO" ] || { bad "$SO is missing: run make first"; done_; }
[[ " ${EXTENSIONS[*]} " == *" tdc_delaunay "* && " ${EXTENSIONS[*]} " == *" tdc_delaunay_raster "* ]] && ok ||
	bad "the Makefile's EXTENSION is '${EXTENSIONS[*]}', not tdc_delaunay and tdc_delaunay_raster"
meta=$(tr -d '\n\t ' <META.json)
[[ $meta == *"\"version\":\"$PKGVERSION\""* ]] && ok || bad "META.json: no \"version\": \"$PKGVERSION\""
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

exported=$(nm -D --defined-only "$SO" | awk '$2 == "T" { print $3 }' | sort -u)
nsym=0

for EXT in "${EXTENSIONS[@]}"; do
	# this extension's scripts
	ext_scripts=()
	for s in "${SCRIPTS[@]}"; do
		[[ $s == "$EXT--"* ]] && ext_scripts+=("$s")
	done

	# Versions.
	case $EXT in
		tdc_delaunay) var=EXTVERSION ;;
		*) var=$(tr 'a-z' 'A-Z' <<<"${EXT#tdc_delaunay_}")_EXTVERSION ;;
	esac
	version=$(make_var "$var")
	control=$(sed -n "s/^default_version *= *'\([^']*\)'.*/\1/p" "$EXT.control")
	[ -n "$version" ] && [ "$control" = "$version" ] && ok ||
		bad "$EXT.control default_version '$control' != Makefile $var '$version'"
	[[ $meta == *"\"$EXT\":{\"file\":\"$EXT.control\",\"version\":\"$control\""* ]] && ok ||
		bad "META.json: provides $EXT is not $EXT.control, version $control"
	[[ " ${ext_scripts[*]} " == *" $EXT--$control.sql "* ]] && ok || bad "no $EXT--$control.sql installed"
	grep -q "^module_pathname *= *'\$libdir/${SO%.so}'" "$EXT.control" && ok ||
		bad "$EXT.control does not load \$libdir/${SO%.so}"
	requires=$(sed -n "s/^requires *= *'\([^']*\)'.*/\1/p" "$EXT.control" | tr -d ' ')
	case $EXT in
		tdc_delaunay) want=postgis ;;
		tdc_delaunay_raster) want=tdc_delaunay,postgis_raster ;;
		*) want=$requires ;;
	esac
	[ "$requires" = "$want" ] && ok || bad "$EXT.control requires '$requires', not '$want'"

	# Every script in the tree is installed (a script left out of DATA would
	# break the upgrade path of the databases that need it).
	for s in $(git ls-files "$EXT--*.sql" 2>/dev/null); do
		[[ " ${ext_scripts[*]} " == *" $s "* ]] && ok || bad "$s is in the tree but not in the Makefile's DATA"
	done

	# Symbols.
	for s in "${ext_scripts[@]}"; do
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

	# Upgrade paths: from every base script to default_version.
	declare -A edges=()
	for s in "${ext_scripts[@]}"; do
		v=${s#"$EXT"--}
		v=${v%.sql}
		[[ $v == *--* ]] && edges[${v%%--*}]+=" ${v#*--}"
	done
	for s in "${ext_scripts[@]}"; do
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
		[[ $seen == *" $control "* ]] && ok || bad "$EXT: no upgrade path from $v to $control"
	done
	unset edges
done
echo "$nsym symbols named by ${#SCRIPTS[@]} scripts (${SCRIPTS[*]})"
done_
