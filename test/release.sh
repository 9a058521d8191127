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
# And for the package: the licence (LICENSE, META.json, debian/copyright),
# with the licence of every fixture of test/fixtures/ stated.
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
# The licence: LICENSE is the PostgreSQL License, and META.json and
# debian/copyright (its "Files: *") say so.  Test data from other projects
# keeps its own: every data file of test/fixtures/ has its licence in the
# table of test/fixtures/README.md and, unless it is this project's, a
# stanza of its own in debian/copyright; every path a stanza names is a
# file of the tree.
[ "$(head -n 1 LICENSE 2>/dev/null)" = "PostgreSQL License" ] && ok ||
	bad "LICENSE is missing or is not the PostgreSQL License"
[[ $meta == *'"license":"postgresql"'* ]] && ok || bad "META.json: license is not \"postgresql\""
# "pattern license" per path of every Files: field
copyright_files=$(awk '
	/^Files:/ { infiles = 1; n = 0; sub(/^Files:/, "") }
	/^[A-Z][A-Za-z-]*:/ && !/^Files:/ { infiles = 0 }
	infiles && /^ |^Files:|^[^ ]/ { for (i = 1; i <= NF; i++) pat[++n] = $i }
	/^License:/ && n > 0 { sub(/^License: */, ""); for (i = 1; i <= n; i++) print pat[i], $0; n = 0 }
	/^$/ { n = 0; infiles = 0 }' debian/copyright)
[[ $copyright_files == *"* PostgreSQL"* ]] && ok || bad "debian/copyright: Files: * is not License: PostgreSQL"
if git rev-parse --git-dir >/dev/null 2>&1; then
	tracked=$(git ls-files)
	while read -r pat _; do
		[ "$pat" = "*" ] && continue
		found=0
		# (a glob: the stanza's pattern)
		# shellcheck disable=SC2053
		while read -r f; do [[ $f == $pat ]] && { found=1; break; }; done <<<"$tracked"
		((found)) && ok || bad "debian/copyright names $pat, which is no file of the tree"
	done <<<"$copyright_files"
	# "name licence" of the table of test/fixtures/README.md, a line per name
	fixture_rows=$(awk -F'|' '/^\| `/ {
			lic = $(NF - 1); gsub(/^ +| +$/, "", lic)
			n = split($2, w, "`"); for (i = 2; i <= n; i += 2) print w[i], lic }' test/fixtures/README.md)
	while read -r f; do
		case $f in test/fixtures/README.md | *.sh | *.py) continue ;; esac
		lic=""
		while read -r name l; do
			# shellcheck disable=SC2053
			[[ ${f#test/fixtures/} == $name ]] && { lic=$l; break; }
		done <<<"$fixture_rows"
		if [ -z "$lic" ]; then
			bad "test/fixtures/README.md states no licence for $f"
			continue
		fi
		ok
		[ "$lic" = "this project's" ] && continue
		covered=0
		while read -r pat _; do
			# shellcheck disable=SC2053
			[ "$pat" != "*" ] && [[ $f == $pat ]] && { covered=1; break; }
		done <<<"$copyright_files"
		((covered)) && ok || bad "debian/copyright: test data $f ($lic) has no stanza of its own"
	done < <(git ls-files test/fixtures)
fi
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
		tdc_delaunay_pointcloud) want=pointcloud,tdc_delaunay,tdc_delaunay_raster ;;
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
