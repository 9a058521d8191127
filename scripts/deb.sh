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

# roots.sh for its tree copy; it sources lib.sh.
# shellcheck source=scripts/roots.sh
. "$(dirname "${BASH_SOURCE[0]}")/roots.sh"

out=$TDC_ROOT/build/deb
log=$TDC_LOGDIR/deb.log

# A fresh machine: the build dependency that brings supported-versions first
# (postgresql-common on Debian 12, postgresql-common-dev from 13 on), to
# learn the release's major.
if [ -z "$TDC_PG_MAJOR" ]; then
	tdc_apt_install postgresql-server-dev-all
	tdc_set_major
	[ -n "$TDC_PG_MAJOR" ] || tdc_die "postgresql-common names no PostgreSQL major ($TDC_SUPPORTED_VERSIONS); set PG_CONFIG"
fi
major=$TDC_PG_MAJOR

check=0
case "${TDC_DEB_CHECK:-0}" in 1 | yes | true) check=1 ;; esac
# debian/control.in's Build-Depends for this major (PostGIS only without the
# nocheck profile), and dpkg-buildpackage; dpkg-checkbuilddeps checks the list.
TDC_PACKAGES=(dpkg-dev debhelper postgresql-server-dev-all "postgresql-server-dev-$major" libgdal-dev)
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
# the files git tracks or would track, edits included ("/" + the path)
tdc_root_copy_tree / "$src"

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

jobs=$(nproc 2>/dev/null || echo 2)
tdc_say "dpkg-buildpackage -us -uc -b -j$jobs ${profile[*]} for PostgreSQL $major (log: $log)"
if ! dpkg-buildpackage -us -uc -b -j"$jobs" "${profile[@]}" >"$log" 2>&1; then
	tail -n 40 "$log" >&2
	tdc_die "dpkg-buildpackage failed (full log: $log)"
fi
cd "$out"
mv src/*.deb src/*.buildinfo src/*.changes "$out"/
for f in "$out"/*.deb; do
	printf '%8s  %s\n' "$(du -h "$f" | cut -f1)" "build/deb/${f##*/}"
done
tdc_say "packages in $out"
