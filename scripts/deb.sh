#!/bin/bash
# scripts/deb.sh (make deb): the Debian packages of this tree for this
# machine's PostgreSQL major (or PG_CONFIG's), built as Debian builds
# PostgreSQL extensions (debian/, pg_buildext), left in build/deb/:
#
#   postgresql-NN-tdc-delaunay_VERSION_ARCH.deb   the extension
#   tdc-delaunay-tools_VERSION_ARCH.deb           /usr/bin/tdc
#   (and their -dbgsym packages)
#
# It installs the build dependencies with apt-get when they are missing, and
# builds in a copy of the tree under build/deb/src/, so that nothing is
# written outside build/ (dpkg-buildpackage writes into the parent of the
# source directory, and the package's clean step removes ./tdc and build/).
#
# Settings (environment):
#   PG_CONFIG=PATH     build for that pg_config's major instead
#   TDC_DEB_CHECK=1    also run pg_regress at build time (dh_pgxs_test, in a
#                      pg_virtualenv cluster); needs PostGIS, installed then.
#                      Without it the nocheck profile skips that step:
#                      test/package/check.sh runs the suite on the installed
#                      package instead.
set -euo pipefail

# shellcheck source=scripts/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# PROTOTYPE until scripts/lib.sh has tdc_pg_major (branch h-matrix)
declare -F tdc_pg_major >/dev/null ||
	tdc_pg_major() { /usr/share/postgresql-common/supported-versions | grep -E '^[0-9]+$' | tail -n 1; }

out=$TDC_ROOT/build/deb
log=$TDC_LOGDIR/deb.log

# pg_buildext and supported-versions (postgresql-common), dpkg-buildpackage,
# dh: what it takes to know the major and read debian/.
TDC_PACKAGES=(postgresql-common dpkg-dev debhelper)
tdc_ensure_packages
major=$(tdc_pg_major)
[ -n "$major" ] || tdc_die "no PostgreSQL major: postgresql-common's supported-versions gave none (or set PG_CONFIG)"

check=0
case "${TDC_DEB_CHECK:-0}" in 1 | yes | true) check=1 ;; esac
# debian/control.in's Build-Depends for this major (the PostGIS one only
# without the nocheck profile); dpkg-checkbuilddeps below checks the list.
TDC_PACKAGES=(postgresql-server-dev-all "postgresql-server-dev-$major")
((check)) && TDC_PACKAGES+=("postgresql-$major" "postgresql-$major-postgis-3")
tdc_ensure_packages
[ -x "/usr/lib/postgresql/$major/bin/pg_config" ] ||
	tdc_die "no /usr/lib/postgresql/$major/bin/pg_config after installing postgresql-server-dev-$major"

version=$(sed -n '1s/^tdc-delaunay (\([^)-]*\)-[^)]*).*/\1/p' "$TDC_ROOT/debian/changelog")
[ -n "$version" ] || tdc_die "cannot read the upstream version from debian/changelog"
src=$out/src/tdc-delaunay-$version

tdc_say "copying the tree to $src"
rm -rf "$out"
mkdir -p "$src" "$TDC_LOGDIR"
if git -C "$TDC_ROOT" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
	# What git tracks or would track, as it is in the work tree (edits included).
	git -C "$TDC_ROOT" ls-files -z --cached --others --exclude-standard |
		(cd "$TDC_ROOT" && while IFS= read -r -d '' f; do
			[ -e "$f" ] && printf '%s\0' "$f"
		done) |
		tar -C "$TDC_ROOT" --null -T - -cf - | tar -C "$src" -xf -
else
	tar -C "$TDC_ROOT" --exclude=./build --exclude=./.git --exclude=./.pgdata --exclude=./.pgrun \
		--exclude=./debian/control -cf - . | tar -C "$src" -xf -
fi

export PG_SUPPORTED_VERSIONS=$major
profile=()
if ((check)); then
	export DEB_BUILD_OPTIONS=${DEB_BUILD_OPTIONS:-}
else
	export DEB_BUILD_OPTIONS="nocheck${DEB_BUILD_OPTIONS:+ $DEB_BUILD_OPTIONS}"
	profile=(-Pnocheck)
fi
cd "$src"
pg_buildext updatecontrol
dpkg-checkbuilddeps "${profile[@]}" ||
	tdc_die "build dependencies missing: debian/control.in and scripts/deb.sh's package list disagree"

tdc_say "dpkg-buildpackage -us -uc -b ${profile[*]} for PostgreSQL $major (log: $log)"
if ! dpkg-buildpackage -us -uc -b "${profile[@]}" >"$log" 2>&1; then
	tail -n 40 "$log" >&2
	tdc_die "dpkg-buildpackage failed (full log: $log)"
fi
cd "$out"
mv src/*.deb src/*.buildinfo src/*.changes "$out"/
shopt -s nullglob
mv src/*.ddeb "$out"/ 2>/dev/null || true
for f in "$out"/*.deb; do
	printf '%8s  %s\n' "$(du -h "$f" | cut -f1)" "build/deb/${f##*/}"
done
tdc_say "packages in $out"
