#!/usr/bin/env bash
# test/citus/build.sh: build Citus 13.2.2 from ../shared/citus (tarball +
# patch) and install it into this machine's PostgreSQL 15.
#
# The build is cached in ${TDC_CITUS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tdc-citus}/SHA
# (SHA = sha256 of the tarball), as a staged install tree (make install
# DESTDIR=...), so that a later run only copies the files (seconds instead of
# minutes).  The cache key includes the patch and pg_config --version, since
# a server update can break the ABI, and pg_config --pkglibdir, since the
# staged tree holds the install paths: one staged for another PostgreSQL
# tree (say /opt/pgE) would be copied there, not here.
#
# Citus is not in Debian 12: the build needs a few -dev packages, installed
# with apt-get when missing (as root).
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PG_CONFIG=${PG_CONFIG:-$(command -v pg_config || echo /usr/lib/postgresql/15/bin/pg_config)}
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
PATCH=$SRC/pg15-have_createdb_privilege.patch

key=$( { sha256sum "$TARBALL" | cut -d' ' -f1; sha256sum "$PATCH" | cut -d' ' -f1; "$PG_CONFIG" --version; "$PG_CONFIG" --pkglibdir; } \
	| sha256sum | cut -c1-16)
CACHE=${TDC_CITUS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tdc-citus}/$(sha256sum "$TARBALL" | cut -c1-16)-$key
STAGE=$CACHE/stage

if [ ! -f "$CACHE/done" ]; then
	need=()
	for p in libkrb5-dev libzstd-dev liblz4-dev libcurl4-openssl-dev libssl-dev libicu-dev; do
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
	echo "citus-build: building Citus 13.2.2 in $CACHE (a few minutes)"
	tar -xzf "$TARBALL" -C "$CACHE"
	(
		cd "$CACHE/citus-13.2.2"
		patch -p1 -s <"$PATCH"
		./configure PG_CONFIG="$PG_CONFIG" >"$CACHE/configure.log" 2>&1 ||
			{ tail -30 "$CACHE/configure.log"; exit 1; }
		make -j2 >"$CACHE/make.log" 2>&1 || { tail -30 "$CACHE/make.log"; exit 1; }
		make install DESTDIR="$STAGE" >"$CACHE/install.log" 2>&1 || { tail -30 "$CACHE/install.log"; exit 1; }
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
