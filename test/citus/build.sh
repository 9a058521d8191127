#!/usr/bin/env bash
# test/citus/build.sh: build Citus 13.2.2 from ../shared/citus (tarball, and
# on PostgreSQL 15 its patch) and install it into PG_CONFIG's PostgreSQL
# (default: the one scripts/lib.sh picks, the major this Debian release
# packages).
#
#   bash test/citus/build.sh              build (or take from the cache) and install
#   bash test/citus/build.sh --supported  exit 0 if Citus 13.2.2 supports this
#                                         major, else say why and exit 3
#   bash test/citus/build.sh --deps       the Debian packages the build needs
#                                         (scripts/test.sh installs them with
#                                         its own, before building in the
#                                         background)
#
# Citus 13.2.2 supports PostgreSQL 15, 16 and 17 (its configure refuses 18).
# The patch is for 15 only: 15.15 and later export have_createdb_privilege(),
# which Citus still defines itself for 15.
#
# The build is cached in ${TDC_CITUS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tdc-citus}/SHA
# (SHA = sha256 of the tarball), as a staged install tree (make install
# DESTDIR=...), so that a later run only copies the files (seconds instead of
# minutes).  The cache key includes the patch and pg_config --version, since
# a server update can break the ABI, and pg_config --pkglibdir, since the
# staged tree holds the install paths: one staged for another PostgreSQL
# tree (say /opt/pgE) would be copied there, not here.
#
# Debian does not package Citus: the build needs a few -dev packages,
# installed with apt-get when missing (as root).
set -euo pipefail
CITUS_DEPS=(libkrb5-dev libzstd-dev liblz4-dev libcurl4-openssl-dev libssl-dev libicu-dev)
if [ "${1:-}" = --deps ]; then
	echo "${CITUS_DEPS[*]}"
	exit 0
fi
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
# shellcheck source=scripts/lib.sh
source "$ROOT/scripts/lib.sh"
[ -x "${PG_CONFIG:-}" ] || { echo "citus-build: no pg_config (${PG_CONFIG:-PostgreSQL not installed})" >&2; exit 1; }
major=$(tdc_pg_major)
case $major in
	15 | 16 | 17) ;;
	*)
		echo "citus-build: Citus 13.2.2 supports PostgreSQL 15 to 17, not $major"
		exit 3
		;;
esac
[ "${1:-}" = --supported ] && exit 0
SRC=${TDC_CITUS_SRC:-}
if [ -z "$SRC" ]; then
	for d in "$ROOT/../shared/citus" "$ROOT/../../shared/citus" /work/shared/citus; do
		[ -f "$d/citus-13.2.2.tar.gz" ] && { SRC=$(cd "$d" && pwd); break; }
	done
fi
[ -n "$SRC" ] && [ -f "$SRC/citus-13.2.2.tar.gz" ] || {
	echo "citus-build: citus-13.2.2.tar.gz not found (set TDC_CITUS_SRC)" >&2
	exit 1
}
TARBALL=$SRC/citus-13.2.2.tar.gz
PATCH=
[ "$major" = 15 ] && PATCH=$SRC/pg15-have_createdb_privilege.patch

key=$( { sha256sum "$TARBALL" | cut -d' ' -f1; [ -z "$PATCH" ] || sha256sum "$PATCH" | cut -d' ' -f1; "$PG_CONFIG" --version; "$PG_CONFIG" --pkglibdir; } \
	| sha256sum | cut -c1-16)
CACHE=${TDC_CITUS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tdc-citus}/$(sha256sum "$TARBALL" | cut -c1-16)-$key
STAGE=$CACHE/stage

if [ ! -f "$CACHE/done" ]; then
	need=()
	for p in "${CITUS_DEPS[@]}"; do
		dpkg -s "$p" >/dev/null 2>&1 || need+=("$p")
	done
	if ((${#need[@]})); then
		echo "citus-build: apt-get install ${need[*]}"
		if [ "$(id -u)" = 0 ]; then
			DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${need[@]}" >/dev/null ||
				{ apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${need[@]}" >/dev/null; }
		else
			sudo apt-get install -y -q "${need[@]}" >/dev/null
		fi
	fi
	rm -rf "$CACHE"
	mkdir -p "$CACHE"
	echo "citus-build: building Citus 13.2.2 for PostgreSQL $major in $CACHE (a few minutes)"
	tar -xzf "$TARBALL" -C "$CACHE"
	(
		cd "$CACHE/citus-13.2.2"
		[ -z "$PATCH" ] || patch -p1 -s <"$PATCH"
		./configure PG_CONFIG="$PG_CONFIG" >"$CACHE/configure.log" 2>&1 ||
			{ tail -30 "$CACHE/configure.log"; exit 1; }
		# with_llvm=no: no JIT bitcode, which would compile every file a
		# second time (with clang) for a test cluster that never inlines it
		make -j2 with_llvm=no >"$CACHE/make.log" 2>&1 || { tail -30 "$CACHE/make.log"; exit 1; }
		make install with_llvm=no DESTDIR="$STAGE" >"$CACHE/install.log" 2>&1 ||
			{ tail -30 "$CACHE/install.log"; exit 1; }
	)
	# the object files are not needed again
	rm -rf "$CACHE/citus-13.2.2"
	touch "$CACHE/done"
fi

# Install (copy) the staged tree when it differs from what is installed.
pkglib=$("$PG_CONFIG" --pkglibdir)
if ! cmp -s "$STAGE$pkglib/citus.so" "$pkglib/citus.so"; then
	echo "citus-build: installing from $STAGE"
	if [ -w "$pkglib" ]; then
		cp -a "$STAGE"/. /
	else
		sudo cp -a "$STAGE"/. /
	fi
fi
echo "citus-build: citus.so in $pkglib ($CACHE)"
