#!/usr/bin/env bash
# scripts/roots.sh: cached Debian roots made with debootstrap, to build and
# test on the PostgreSQL another Debian release packages (the CI matrix of
# scripts/test.sh), or to install the Debian package on a fresh release.
#
#   bash scripts/roots.sh prepare SUITE [--no-pg]   make the root (once) and say where
#   bash scripts/roots.sh run SUITE [--no-pg] CMD...  run CMD in it, as root
#   bash scripts/roots.sh check SUITE                build, pg_regress and a smoke test
#                                                     on that root's PostgreSQL
#   bash scripts/roots.sh path SUITE [--no-pg]       where the root is (made or not)
#   bash scripts/roots.sh scratch SUITE [--no-pg] DEST  a throw-away copy of it in DEST
#                                                     (run in it: roots.sh chroot DEST CMD...)
#   bash scripts/roots.sh chroot DIR CMD...          run CMD in the root DIR, mounts as for run
#
# SUITE: bookworm (Debian 12), trixie (Debian 13), forky (testing), or any
# other suite the mirror has.  A root holds debootstrap's minbase plus, unless
# --no-pg, the PostgreSQL major the release's "postgresql" package depends on
# (15, 17, 18), its server headers, PostGIS, gcc and make.
# TDC_ROOT_PACKAGES="p q" adds packages (to a --no-pg root too).
#
# The roots live in ${TDC_ROOTS_DIR:-$HOME/.cache/tdc-roots}/SUITE (SUITE-nopg),
# and are kept: a later run reuses them and installs only what its package
# list adds.  The mirror is the one in this machine's apt sources.  Testing's
# Release file on a mirror can be past its Valid-Until (it is re-signed
# weekly): its root's apt source has check-valid-until=no, and no other's.
# No server is started by the packages (policy-rc.d) and no "main" cluster
# is created (createcluster.conf).
#
# Mounts.  Every command that mounts something in a root (debootstrap,
# apt-get, the checks) runs in a mount namespace of its own and mounts only
# there.  A namespace's mounts go away when its last process ends, however
# it ends (SIGKILL included), so nothing a root needs is ever mounted in
# this machine's namespace: an interrupted run leaves no mount behind, and
# an `rm -rf` of a root, or of a chroot holding it, cannot reach through
# into the host's /dev or /proc.  The namespace must also keep its mounts
# from propagating back into ours:
#
#  - On a machine (/ is a mount point), `unshare -m --propagation private`
#    makes every mount of the new namespace private, recursively from /.
#  - Inside a chroot (/ is a directory of some mount, as in a fresh-machine
#    check), that call fails ("cannot change root filesystem propagation":
#    only a mount point can be made private), so the namespace keeps the
#    propagation it was copied with (--propagation unchanged).  That is safe
#    only when neither a mount we can see nor the mount that holds the root
#    directory is shared (a mount made there would reappear in its peer
#    group, e.g. in the host's namespace).  A chroot's mountinfo leaves out
#    the mounts above its /, so the holding mount is looked up by its id
#    (/proc/self/fdinfo) in any process's mountinfo (pid 1's, usually); mount
#    ids are unique across namespaces.  If one is shared, or the holding
#    mount cannot be found, nothing is mounted and the command says why.
#
# Inside the namespace a root gets fresh filesystems, never a bind of the
# host's /dev: a proc, and a tmpfs on /dev holding the few device nodes
# programs use (made with mknod), /dev/shm (POSIX shared memory: PostgreSQL's
# parallel workers) as a directory on it, and a devpts of its own.  They
# are unmounted explicitly once CMD ends (a process CMD left running would
# otherwise keep them until the namespace ends); processes left running
# in the root are killed.  Only `run` and `chroot` bind this source tree,
# read-only, at its own path (the one bind; in the namespace like the rest);
# `check` builds in a copy of the tree inside the root (only files git
# tracks or would track, without build products), so the tree is not
# written to.
#
# Needs root (debootstrap, chroot, mount), util-linux's unshare and flock, and
# debootstrap (installed with apt-get when missing).  Sourced, it defines the
# functions tdc_root_* and runs nothing.
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

TDC_ROOTS_DIR=${TDC_ROOTS_DIR:-$HOME/.cache/tdc-roots}

tdc_root_dir() {	# SUITE [--no-pg]
	printf '%s/%s%s' "$TDC_ROOTS_DIR" "$1" "${2:+-nopg}"
}

# The Debian mirror of this machine's apt sources (the first non-security one).
tdc_root_mirror() {
	local m=""
	if [ -f /etc/apt/sources.list.d/debian.sources ]; then
		m=$(awk '/^URIs:/ { for (i = 2; i <= NF; i++) if ($i !~ /security/) { print $i; exit } }' \
			/etc/apt/sources.list.d/debian.sources)
	fi
	if [ -z "$m" ]; then
		m=$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
			sed -e 's/\[[^]]*\]//' | awk '$1 == "deb" && $2 !~ /security/ { print $2; exit }')
	fi
	[ -n "$m" ] || tdc_die "no Debian mirror in /etc/apt/sources.list.d/debian.sources or /etc/apt/sources.list"
	printf '%s' "$m"
}

# --- Mount namespaces (see "Mounts" in the header) -------------------------

# Is / a mount point in this process's view (not so inside a chroot)?
tdc_root_slash_is_mount() {
	awk '$5 == "/" { found = 1 } END { exit !found }' /proc/self/mountinfo
}

# The id of the mount that holds the directory DIR (from fdinfo: it names
# the mount even when mountinfo, inside a chroot, leaves it out).
tdc_root_mnt_id() {	# DIR
	local fd id
	exec {fd}<"$1" || return 1
	id=$(sed -n 's/^mnt_id:[[:space:]]*//p' "/proc/$BASHPID/fdinfo/$fd")
	exec {fd}<&-
	[ -n "$id" ] && printf '%s' "$id"
}

# The mountinfo line of mount ID: this process's view first, then any
# process's (mount ids are unique across namespaces, so the line found is
# that mount's).  Fails if no readable view shows it.
tdc_root_mountinfo_line() {	# ID
	local f
	for f in /proc/self/mountinfo /proc/1/mountinfo /proc/[0-9]*/mountinfo; do
		awk -v id="$1" '$1 == id { print; found = 1; exit } END { exit !found }' "$f" 2>/dev/null && return 0
	done
	return 1
}

# Print the mount points of the mountinfo lines on stdin that are shared
# (an optional field "shared:N" before the "-").
tdc_root_shared() {
	awk '{ for (i = 7; i <= NF && $i != "-"; i++) if ($i ~ /^shared:/) { print $5; break } }'
}

# Run CMD in a mount namespace of its own whose mounts cannot propagate into
# this one; DIR is where it will mount (the root, or the directory that will
# hold it).  Refuses (exit 1, nothing mounted) when that cannot be ensured.
tdc_root_ns() {	# DIR CMD...
	local dir=$1 id line shared
	shift
	if tdc_root_slash_is_mount; then
		unshare -m --propagation private "$@"
		return
	fi
	shared=$(tdc_root_shared </proc/self/mountinfo | tr '\n' ' ')
	[ -z "$shared" ] ||
		tdc_die "inside a chroot with shared mounts ($shared): mounts made for $dir could propagate out of it, so none is made (make them private first: mount --make-rprivate)"
	id=$(tdc_root_mnt_id "$dir") || tdc_die "no mount id for $dir in /proc/self/fdinfo"
	line=$(tdc_root_mountinfo_line "$id") ||
		tdc_die "inside a chroot, and mount $id, which holds $dir, is in no readable /proc/PID/mountinfo: cannot tell whether mounts made there would propagate out of the chroot, so none is made"
	[ -z "$(tdc_root_shared <<<"$line")" ] ||
		tdc_die "inside a chroot whose / lies in a shared mount ($line): mounts made in $dir would propagate out of it, so none is made (make it private first: mount --make-rprivate on that mount, outside the chroot)"
	unshare -m --propagation unchanged "$@"
}

# Run CMD chrooted into DIR with a clean environment, in a mount namespace
# of its own (tdc_root_ns) with fresh /proc, /dev, /dev/shm and /dev/pts
# and, given SRC, the directory SRC read-only at the same path.
tdc_root_chroot() {	# DIR [--src SRC] CMD...
	local dir=$1 src=""
	shift
	[ "${1:-}" = --src ] && { src=$2; shift 2; mkdir -p "$dir$src"; }
	mkdir -p "$dir/proc" "$dir/dev"
	# shellcheck disable=SC2016  # expanded by the inner bash
	tdc_root_ns "$dir" bash -c '
		set -e
		dir=$1 src=$2
		shift 2
		mount -t proc -o nosuid,nodev,noexec proc "$dir/proc"
		mount -t tmpfs -o nosuid,mode=755 tdc-dev "$dir/dev"
		for n in null:1:3 zero:1:5 full:1:7 random:1:8 urandom:1:9 tty:5:0; do
			IFS=: read -r name major minor <<<"$n"
			mknod -m 666 "$dir/dev/$name" c "$major" "$minor"
		done
		ln -s /proc/self/fd "$dir/dev/fd"
		ln -s /proc/self/fd/0 "$dir/dev/stdin"
		ln -s /proc/self/fd/1 "$dir/dev/stdout"
		ln -s /proc/self/fd/2 "$dir/dev/stderr"
		mkdir -m 1777 "$dir/dev/shm"
		mkdir -m 755 "$dir/dev/pts"
		# a pty for dpkg (apt-get logs through one); not needed otherwise
		if mount -t devpts -o newinstance,ptmxmode=0666,mode=0620 devpts "$dir/dev/pts" 2>/dev/null; then
			ln -s pts/ptmx "$dir/dev/ptmx"
		fi
		if [ -n "$src" ]; then
			mount --bind "$src" "$dir$src"
			mount -o remount,bind,ro "$dir$src"
		fi
		rc=0
		chroot "$dir" env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 \
			DEBIAN_FRONTEND=noninteractive "$@" || rc=$?
		# the namespace would drop them when its last process ends; a
		# process CMD left running would keep them until then
		[ -z "$src" ] || umount -l "$dir$src" || true
		umount -l "$dir/dev/pts" 2>/dev/null || true
		umount -l "$dir/dev" "$dir/proc" || true
		exit "$rc"
	' tdc-root "$dir" "$src" "$@"
}

# apt-get in the root.  dpkg without its fsyncs (--force-unsafe-io): the
# root is a cache that a crash may cost, not a system to keep; a fresh
# root's 200 packages unpack in a fraction of the time.
tdc_root_apt() {	# DIR apt-get args...
	local dir=$1
	shift
	tdc_root_chroot "$dir" apt-get -q -y --no-install-recommends \
		-o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold \
		-o Dpkg::Options::=--force-unsafe-io "$@" </dev/null
}

# Kill what still runs with the root as its /.
tdc_root_kill_procs() {	# DIR
	local dir p pids=()
	dir=$(cd "$1" && pwd -P)
	for p in /proc/[0-9]*; do
		[ "$(readlink "$p/root" 2>/dev/null)" = "$dir" ] && pids+=("${p#/proc/}")
	done
	((${#pids[@]} == 0)) || kill -KILL "${pids[@]}" 2>/dev/null || true
}

# Make the root SUITE if it is not there, and install what its package list
# adds.  Holds the root's lock while it works.  Prints progress; the path last.
tdc_root_prepare() {	# SUITE [--no-pg]
	local suite=$1 nopg=${2:-} dir mirror script="" t0=$SECONDS major="" pkgs
	((EUID == 0)) || tdc_die "roots.sh needs root (debootstrap, chroot, mount)"
	dir=$(tdc_root_dir "$suite" "$nopg")
	mkdir -p "$TDC_ROOTS_DIR"
	exec 8>"$dir.lock"
	flock 8
	# apt-get in a root skips dpkg's fsyncs (tdc_root_apt): one that a reboot
	# cut off may have left files empty that dpkg counts as installed, so
	# that root is made again (one stopped without a reboot is resumed)
	if [ -f "$dir/.tdc-installing" ] && [ "$(cat "$dir/.tdc-installing")" != "$(cat /proc/sys/kernel/random/boot_id)" ]; then
		tdc_say "the $suite root's apt-get was cut off by a reboot: making it again"
		grep -q " $dir/" /proc/self/mountinfo && tdc_die "$dir has mounts: unmount them first"
		rm -rf --one-file-system "$dir"
	fi
	if [ ! -f "$dir/.tdc-debootstrapped" ]; then
		command -v debootstrap >/dev/null || tdc_apt_install debootstrap
		if [ -e "$dir" ]; then
			# a debootstrap that was interrupted; its mounts were private to it
			grep -q " $dir/" /proc/self/mountinfo && tdc_die "$dir has mounts: unmount them first"
			rm -rf --one-file-system "$dir"
		fi
		mirror=$(tdc_root_mirror)
		[ -f "/usr/share/debootstrap/scripts/$suite" ] || script=/usr/share/debootstrap/scripts/sid
		tdc_say "debootstrap --variant=minbase $suite from $mirror into $dir"
		tdc_root_ns "$TDC_ROOTS_DIR" \
			debootstrap --variant=minbase "$suite" "$dir" "$mirror" $script >"$dir.debootstrap.log" 2>&1 ||
			{ tail -n 20 "$dir.debootstrap.log" >&2; tdc_die "debootstrap $suite failed (log: $dir.debootstrap.log)"; }
		local opt=""
		case $suite in
			testing | forky | sid | unstable) opt="[check-valid-until=no] " ;;
		esac
		rm -f "$dir/etc/apt/sources.list.d/"*
		echo "deb $opt$mirror $suite main" >"$dir/etc/apt/sources.list"
		printf '#!/bin/sh\nexit 101\n' >"$dir/usr/sbin/policy-rc.d"
		chmod 755 "$dir/usr/sbin/policy-rc.d"
		touch "$dir/.tdc-debootstrapped"
	fi
	cp /etc/resolv.conf "$dir/etc/resolv.conf"
	pkgs="${TDC_ROOT_PACKAGES:-}"
	# zlib's headers: the pcpatch reader (src/pg/formats/pcpatch_read.c) inflates zlib dimensions
	[ -n "$nopg" ] || pkgs="postgresql-common zlib1g-dev $pkgs"
	# (the major's packages below, pgpointcloud among them, are named in the marker too)
	local wanted=$pkgs
	[ -n "$nopg" ] || wanted="$wanted +major: server, dev, postgis-3, pointcloud"
	if [ ! -f "$dir/.tdc-packages" ] || [ "$(cat "$dir/.tdc-packages")" != "$wanted" ]; then
		tdc_say "apt-get in the $suite root: ${pkgs:-(update only)}"
		cat /proc/sys/kernel/random/boot_id >"$dir/.tdc-installing"
		# an earlier run may have been stopped inside dpkg
		tdc_root_chroot "$dir" dpkg --configure -a >"$dir.apt.log" 2>&1 || true
		tdc_root_apt "$dir" update >>"$dir.apt.log" 2>&1 ||
			{ tail -n 20 "$dir.apt.log" >&2; tdc_die "apt-get update in $dir failed (log: $dir.apt.log)"; }
		if [ -z "$nopg" ]; then
			tdc_root_apt "$dir" install postgresql-common >>"$dir.apt.log" 2>&1 ||
				{ tail -n 20 "$dir.apt.log" >&2; tdc_die "apt-get install postgresql-common in $dir failed (log: $dir.apt.log)"; }
			sed -i 's/^#* *create_main_cluster.*/create_main_cluster = false/' \
				"$dir/etc/postgresql-common/createcluster.conf"
			major=$(tdc_apt_default_major tdc_root_chroot "$dir")
			[ -n "$major" ] || tdc_die "apt in the $suite root knows no \"postgresql\" package to take the major from"
			pkgs="$pkgs postgresql-$major postgresql-server-dev-$major postgresql-$major-postgis-3"
			pkgs="$pkgs postgresql-$major-pointcloud make gcc"
		fi
		# shellcheck disable=SC2086  # a list of package names
		[ -z "${pkgs// /}" ] || tdc_root_apt "$dir" install $pkgs >>"$dir.apt.log" 2>&1 ||
			{ tail -n 20 "$dir.apt.log" >&2; tdc_die "apt-get install in $dir failed (log: $dir.apt.log)"; }
		tdc_root_chroot "$dir" apt-get clean
		tdc_root_kill_procs "$dir"
		[ -z "$major" ] || echo "$major" >"$dir/.tdc-pg-major"
		sync -f "$dir"
		printf '%s' "$wanted" >"$dir/.tdc-packages"
		rm -f "$dir/.tdc-installing"
	fi
	[ -n "$major" ] || major=$(cat "$dir/.tdc-pg-major" 2>/dev/null || true)
	tdc_say "root $suite ready in $((SECONDS - t0)) s${major:+ (PostgreSQL $major)}: $dir"
	exec 8>&-
}

# Run CMD in the root, in a mount namespace of its own (tdc_root_chroot),
# with the source tree read-only at its own path unless --no-src.  Holds the
# root's lock shared (several runs may share a root; tdc_root_prepare waits
# for them).
tdc_root_run() {	# SUITE [--no-pg] [--no-src] -- CMD...
	local suite=$1 nopg="" dir rc=0 src=(--src "$TDC_ROOT")
	shift
	[ "${1:-}" = --no-pg ] && { nopg=1; shift; }
	[ "${1:-}" = --no-src ] && { src=(); shift; }
	[ "${1:-}" = -- ] && shift
	dir=$(tdc_root_dir "$suite" "$nopg")
	[ -f "$dir/.tdc-packages" ] || tdc_die "no $suite root in $dir: bash scripts/roots.sh prepare $suite${nopg:+ --no-pg}"
	cp /etc/resolv.conf "$dir/etc/resolv.conf"
	(
		flock -s 9
		tdc_root_chroot "$dir" ${src[@]+"${src[@]}"} "$@"
	) 9>"$dir.lock" || rc=$?
	tdc_root_kill_procs "$dir"
	return "$rc"
}

# A throw-away copy of a prepared root (e.g. to install a package into a
# root that stays fresh); remove it with rm -rf: it has no mounts.
tdc_root_scratch() {	# SUITE [--no-pg] DEST
	local dir
	dir=$(tdc_root_dir "$1" "${3:+1}")
	[ -f "$dir/.tdc-packages" ] || tdc_die "no $1 root in $dir: bash scripts/roots.sh prepare $1${3:+ --no-pg}"
	[ ! -e "${3:-$2}" ] || tdc_die "${3:-$2} exists"
	(
		flock -s 9
		cp -a "$dir" "${3:-$2}"
	) 9>"$dir.lock"
}

# A copy of the source tree in the root, without build products: the files
# git tracks or would track, or (no git) all but the ignored kinds.
tdc_root_copy_tree() {	# DIR DEST
	local dir=$1 dest=$2
	rm -rf "${dir:?}$dest"
	mkdir -p "$dir$dest"
	chmod 755 "$dir$dest"
	if git -C "$TDC_ROOT" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
		(cd "$TDC_ROOT" && git ls-files -z -c -o --exclude-standard |
			while IFS= read -r -d '' f; do [ -e "$f" ] && printf '%s\0' "$f"; done |
			tar --null -T - -cf -) | tar -C "$dir$dest" -xf -
	else
		tar -C "$TDC_ROOT" --exclude='*.o' --exclude='*.so' --exclude='*.bc' --exclude=./build \
			--exclude=./tdc --exclude=./.pgdata --exclude=./.pgrun --exclude=./results -cf - . |
			tar -C "$dir$dest" -xf -
	fi
}

# The CI matrix's check of one release: in a copy of the tree inside the
# root, build and install against the root's PostgreSQL, start a throw-away
# cluster, run pg_regress and a smoke test.  Prints "N passed, M failed"
# (pg_regress's tests plus the smoke checks).
tdc_root_check() {	# SUITE
	local suite=$1 dir major dest=/var/tmp/tdc-check-$$ rc=0
	dir=$(tdc_root_dir "$suite")
	[ -f "$dir/.tdc-pg-major" ] || tdc_die "no $suite root with PostgreSQL in $dir: bash scripts/roots.sh prepare $suite"
	major=$(cat "$dir/.tdc-pg-major")
	tdc_say "$suite root: PostgreSQL $major; copying the tree to $dest in it"
	(
		flock -s 9
		tdc_root_copy_tree "$dir" "$dest"
	) 9>"$dir.lock"
	tdc_root_run "$suite" --no-src -- env PG_CONFIG="/usr/lib/postgresql/$major/bin/pg_config" TDC_ROOT_SUITE="$suite" \
		bash "$dest/scripts/roots.sh" inside-check || rc=$?
	rm -rf "${dir:?}$dest" "${dir:?}$dest-pg"
	return "$rc"
}

# Inside the root (tdc_root_check): the checks themselves.
tdc_root_inside_check() {
	local pass=0 fail=0 t0=$SECONDS line smoke
	ok() { pass=$((pass + 1)); echo "ok - $*"; }
	bad() { fail=$((fail + 1)); echo "FAIL - $*"; }
	cd "$TDC_ROOT"
	tdc_say "${TDC_ROOT_SUITE:-root}: $("$PG_CONFIG" --version), $(nproc) CPUs"
	# no LLVM bitcode: the JIT's inlining files are not what this checks
	if make --no-print-directory -j"$(nproc)" PG_CONFIG="$PG_CONFIG" with_llvm=no all >build.log 2>&1 &&
		make --no-print-directory PG_CONFIG="$PG_CONFIG" with_llvm=no install >>build.log 2>&1; then
		if grep -q 'warning:' build.log; then
			bad "build and install: compiler warnings"
			grep 'warning:' build.log | head -20
		else
			ok "build and install, no warning ($((SECONDS - t0)) s)"
		fi
	else
		tail -n 30 build.log
		bad "build and install"
		echo "${TDC_ROOT_SUITE:-root}: $pass passed, $fail failed"
		return 1
	fi
	TDC_PGDIR=$TDC_ROOT-pg
	export TDC_PGDIR
	trap tdc_cluster_stop EXIT
	tdc_cluster_start
	# pg_regress: its own count line, and each test in the total
	rm -f build/regress/tdc_raster_arbiter.txt build/regress/tdc_tin_jacksboro.txt
	make --no-print-directory PG_CONFIG="$PG_CONFIG" with_llvm=no installcheck 2>&1 | tee regress.log || true
	line=$(grep -Eo '(All [0-9]+ tests passed|[0-9]+ of [0-9]+ tests (failed|passed))' regress.log | tail -n 1 || true)
	case "$line" in
		All*) pass=$((pass + $(echo "$line" | awk '{print $2}'))) ;;
		*failed)
			fail=$((fail + $(echo "$line" | awk '{print $1}')))
			pass=$((pass + $(echo "$line" | awk '{print $3 - $1}')))
			;;
		*) bad "pg_regress printed no result line" ;;
	esac
	if [ -s build/regress/regression.diffs ]; then
		echo "--- regression.diffs (first 80 lines) ---"
		head -n 80 build/regress/regression.diffs
	fi
	# GDAL's 'linear' against the exact arbiter (tdc_raster_arbiter,
	# tdc_tin_jacksboro): the counts depend on GDAL's version, so the
	# expected output cannot hold them; the tests write them here
	for f in build/regress/tdc_raster_arbiter.txt build/regress/tdc_tin_jacksboro.txt; do
		if [ -s "$f" ]; then echo "--- $f ---"; cat "$f"; fi
	done
	# smoke test: a fresh database, CREATE EXTENSION ... CASCADE, 100k points
	tdc_psql -q -d postgres -c 'CREATE DATABASE tdc_smoke' >/dev/null
	if tdc_psql -q -d tdc_smoke -c 'CREATE EXTENSION tdc_delaunay CASCADE' >/dev/null; then
		ok "CREATE EXTENSION tdc_delaunay CASCADE: $(tdc_psql -At -d tdc_smoke -c "SELECT 'tdc_delaunay ' || extversion FROM pg_extension WHERE extname = 'tdc_delaunay'") on PostGIS $(tdc_psql -At -d tdc_smoke -c 'SELECT postgis_lib_version()'), GEOS $(tdc_psql -At -d tdc_smoke -c "SELECT split_part(postgis_geos_version(), '-', 1)")"
	else
		bad "CREATE EXTENSION tdc_delaunay CASCADE"
	fi
	# triangles = 2n - 2 - h for n distinct points, h of them on the hull (no
	# three hull points are collinear in doubles from random()); the triangles
	# tile the hull: their areas add up to its area
	smoke=$(tdc_psql -q -At -F ' ' -d tdc_smoke <<-'SQL'
		SELECT setseed(0.2014) \g /dev/null
		CREATE TABLE pts AS SELECT ST_MakePoint(random() * 10000, random() * 10000) AS geom
			FROM generate_series(1, 100000);
		CREATE TABLE res AS SELECT ST_TDCDelaunay(geom) AS t FROM pts;
		SELECT (SELECT count(DISTINCT (ST_X(geom), ST_Y(geom))) FROM pts),
			   (SELECT ST_NPoints(ST_ConvexHull(ST_Collect(geom))) - 1 FROM pts),
			   (SELECT ST_NumGeometries(t) FROM res),
			   abs((SELECT sum(ST_Area(d.geom)) FROM res, ST_Dump(res.t) d)
				   / (SELECT ST_Area(ST_ConvexHull(ST_Collect(geom))) FROM pts) - 1) < 1e-9;
	SQL
	) || smoke=""
	smoke=$(printf '%s\n' "$smoke" | tail -n 1)
	local n h nt area
	read -r n h nt area <<<"$smoke"
	if [ -n "${nt:-}" ] && ((n == 100000 && nt == 2 * n - 2 - h)); then
		ok "100000 points: $nt triangles = 2n - 2 - h (n $n, h $h)"
	else
		bad "100000 points: triangle count (n, h, triangles: ${smoke:-no answer})"
	fi
	if [ "${area:-}" = t ]; then
		ok "100000 points: the triangles' areas add up to the hull's"
	else
		bad "100000 points: the triangles' areas do not add up to the hull's (${area:-no answer})"
	fi
	tdc_cluster_stop
	echo "${TDC_ROOT_SUITE:-root} (PostgreSQL ${TDC_PG_MAJOR}): $((SECONDS - t0)) s; $pass passed, $fail failed"
	((fail == 0))
}

tdc_roots_usage() {
	sed -n '2,14p' "${BASH_SOURCE[0]}" >&2
	exit 2
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
	set -euo pipefail
	cmd=${1:-}
	suite=${2:-}
	[ -n "$cmd" ] || tdc_roots_usage
	[ "$cmd" = inside-check ] || [ -n "$suite" ] || tdc_roots_usage
	case $cmd in
		prepare)
			[ "${3:-}" = --no-pg ] || [ -z "${3:-}" ] || tdc_roots_usage
			tdc_root_prepare "$suite" "${3:+1}"
			;;
		run)
			shift 2
			tdc_root_run "$suite" "$@"
			;;
		check) tdc_root_check "$suite" ;;
		scratch)
			shift 2
			tdc_root_scratch "$suite" "$@"
			;;
		chroot)
			shift 2
			((EUID == 0)) || tdc_die "roots.sh needs root (chroot, mount)"
			rc=0
			tdc_root_chroot "$suite" --src "$TDC_ROOT" "$@" || rc=$?
			tdc_root_kill_procs "$suite"
			exit "$rc"
			;;
		path)
			[ "${3:-}" = --no-pg ] || [ -z "${3:-}" ] || tdc_roots_usage
			tdc_root_dir "$suite" "${3:+1}"
			echo
			;;
		inside-check) tdc_root_inside_check ;;
		*) tdc_roots_usage ;;
	esac
fi
