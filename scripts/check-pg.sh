#!/usr/bin/env bash
# scripts/check-pg.sh: build the extension against a newer PostgreSQL and run
# its pg_regress suite there, with that Debian release's PostGIS and GEOS.
#
# Debian 12 packages only PostgreSQL 15, so this builds a root of the Debian
# release that packages the requested major (17: Debian 13 "trixie", with
# PostGIS 3.5 and GEOS 3.13; 18: "sid", with PostGIS 3.7) with debootstrap,
# installs postgresql-N, postgresql-server-dev-N and postgresql-N-postgis-3
# from Debian's own archive inside it, clones the committed HEAD into it and
# runs `make installcheck` on a throw-away cluster.  Needs root
# (debootstrap, chroot, mount) and a Debian mirror; takes about 5 minutes.
# Not part of `make test`.  (No Debian release packages PostgreSQL 16.)
#
#   bash scripts/check-pg.sh 17           root in /tmp/tdc-pg17 (kept for reruns)
#   TDC_CHECK_ROOT=DIR bash scripts/check-pg.sh 18
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

major=${1:-17}
case $major in
	17) suite=trixie aptopt="" ;;
	# sid's Release file is valid for a week only; a mirror that lags
	# (or a snapshot) serves an expired one
	18) suite=sid aptopt="-o Acquire::Check-Valid-Until=false" ;;
	*) tdc_die "usage: check-pg.sh 17|18 (the majors a Debian release packages, besides 15)" ;;
esac
((EUID == 0)) || tdc_die "run as root: it uses debootstrap, chroot and mount"
root=${TDC_CHECK_ROOT:-/tmp/tdc-pg$major}
mirror=http://deb.debian.org/debian
pgbin=/usr/lib/postgresql/$major/bin

command -v debootstrap >/dev/null ||
	DEBIAN_FRONTEND=noninteractive apt-get install -y -q debootstrap >/dev/null
if [ ! -x "$root/usr/bin/apt-get" ]; then
	tdc_say "debootstrap $suite into $root"
	debootstrap --variant=minbase "$suite" "$root" "$mirror" >/dev/null
fi
cp /etc/resolv.conf "$root/etc/"
cleanup() {
	chroot "$root" su postgres -c "$pgbin/pg_ctl -D /tmp/pg/data stop -m fast" >/dev/null 2>&1 || true
	umount "$root/dev/shm" "$root/dev" "$root/proc" 2>/dev/null || true
}
trap cleanup EXIT
mountpoint -q "$root/proc" || mount -t proc proc "$root/proc"
mountpoint -q "$root/dev" || mount --bind /dev "$root/dev"
mountpoint -q "$root/dev/shm" || mount --bind /dev/shm "$root/dev/shm"

tdc_say "installing PostgreSQL $major and PostGIS in the $suite root"
chroot "$root" bash -c "apt-get $aptopt update -qq &&
	DEBIAN_FRONTEND=noninteractive apt-get $aptopt install -y -qq --no-install-recommends \
		make gcc git ca-certificates postgresql-$major postgresql-server-dev-$major \
		postgresql-$major-postgis-3 >/tmp/apt.log 2>&1 || { tail -20 /tmp/apt.log; exit 1; }"

rm -rf "$root/root/tdc"
git clone -q "$TDC_ROOT" "$root/root/tdc"
[ -d "$TDC_ROOT/../shared" ] && rm -rf "$root/root/shared" && cp -r "$TDC_ROOT/../shared" "$root/root/shared"

tdc_say "build, install, pg_regress on PostgreSQL $major"
chroot "$root" bash -s <<EOF
set -euo pipefail
cd /root/tdc
make -s PG_CONFIG=$pgbin/pg_config all
make -s PG_CONFIG=$pgbin/pg_config install >/dev/null
rm -rf /tmp/pg && mkdir -p /tmp/pg && chown postgres /tmp/pg
su postgres -c "$pgbin/initdb -D /tmp/pg/data -A trust >/dev/null"
su postgres -c "$pgbin/pg_ctl -D /tmp/pg/data -o '-p 5417 -k /tmp/pg' -l /tmp/pg/log -w start >/dev/null"
su postgres -c "psql -h /tmp/pg -p 5417 -X -At -c 'SELECT version()' -c 'CREATE EXTENSION postgis' -c 'SELECT postgis_full_version()'" | sed 's/^/    /'
make PG_CONFIG=$pgbin/pg_config installcheck PGHOST=/tmp/pg PGPORT=5417 PGUSER=postgres
EOF
tdc_say "PostgreSQL $major: pg_regress passed"
