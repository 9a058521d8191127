# shellcheck shell=bash disable=SC2034  # variables set here are read by the scripts that source it
# scripts/lib.sh: shared set-up for scripts/demo.sh, scripts/test.sh,
# scripts/cluster.sh, scripts/roots.sh and test/citus/.  Source it; it defines
# functions and a few variables and changes nothing until they are called.
#
#   tdc_ensure_packages   apt-get install what is missing (Debian/Ubuntu)
#   tdc_ensure_node       node and npm for test/cli_las.sh (apt-get when missing)
#   tdc_build_install     make && make install against $PG_CONFIG
#   tdc_server_up         use the user's server (PGHOST/PGPORT/PGDATABASE set,
#                         or TDC_USE_EXISTING=1) or start a throw-away cluster
#   tdc_server_down       stop the throw-away cluster (no-op for the user's)
#
# Settings (environment):
#   TDC_USE_EXISTING=1    use the server libpq's PG* variables point at
#   TDC_USE_EXISTING=0    always start a throw-away cluster, even if PGHOST etc. are set
#   TDC_PGDIR=DIR         put the throw-away cluster in DIR (default: the project
#                         dir's .pgdata/ and .pgrun/, or /tmp/tdc_delaunay-UID-HASH
#                         when the cluster's owner cannot reach the project dir)
#   TDC_PORT_START=N      first port probed for the throw-away cluster (5433)
#   TDC_EXTRA_PACKAGES="p q"  more Debian packages for tdc_ensure_packages
#   PG_CONFIG=PATH        pg_config to build against; its major picks the
#                         packages.  Default: /usr/lib/postgresql/MAJOR/bin/pg_config,
#                         MAJOR being the one this Debian release packages
#                         (postgresql-common's default: 15 on Debian 12,
#                         17 on Debian 13, 18 on testing)

TDC_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
TDC_LOGDIR=$TDC_ROOT/build/logs
# postgresql-common's list of the release's majors, the default last (in
# postgresql-client-common on Debian 12, postgresql-common-dev from 13 on)
TDC_SUPPORTED_VERSIONS=/usr/share/postgresql-common/supported-versions

# The major the release's "postgresql" metapackage depends on (postgresql-common
# derives it from supported-versions), from apt's lists: known before anything
# is installed.  A command prefix runs apt-cache elsewhere (in a root).
tdc_apt_default_major() {	# [prefix command...]
	"$@" apt-cache depends postgresql 2>/dev/null |
		sed -n 's/^ *Depends: postgresql-\([0-9][0-9]*\)$/\1/p' | head -n 1
}

# The PostgreSQL major: PG_CONFIG's when given (from its --version, or from a
# /usr/lib/postgresql/MAJOR/ path not installed yet), else the release's
# default: postgresql-common's supported-versions, or apt's metapackage.
# Empty when neither answers (no apt lists yet): tdc_ensure_packages updates
# them and asks again.
tdc_pg_major() {
	local v=""
	if [ -n "${PG_CONFIG:-}" ]; then
		v=$("$PG_CONFIG" --version 2>/dev/null | sed -n 's/^PostgreSQL \([0-9][0-9]*\).*/\1/p')
		[ -n "$v" ] || v=$(printf '%s\n' "$PG_CONFIG" | sed -n 's|^/usr/lib/postgresql/\([0-9][0-9]*\)/bin/pg_config$|\1|p')
	elif [ -x "$TDC_SUPPORTED_VERSIONS" ]; then
		v=$("$TDC_SUPPORTED_VERSIONS" 2>/dev/null | grep -E '^[0-9]+$' | tail -n 1)
	fi
	[ -n "$v" ] || [ -n "${PG_CONFIG:-}" ] || ! command -v apt-cache >/dev/null 2>&1 || v=$(tdc_apt_default_major)
	printf '%s' "$v"
}

# Set TDC_PG_MAJOR, PG_CONFIG (unless given) and TDC_PACKAGES from the major.
tdc_set_major() {
	TDC_PG_MAJOR=$(tdc_pg_major)
	if [ -z "${TDC_PG_CONFIG_GIVEN:-}" ]; then
		PG_CONFIG=${TDC_PG_MAJOR:+/usr/lib/postgresql/$TDC_PG_MAJOR/bin/pg_config}
	fi
	# Debian packages: what each one is for is in README.md ("Dependencies").
	TDC_PACKAGES=(
		postgresql-common						# the clusters' tools; supported-versions (Debian 12)
		${TDC_PG_MAJOR:+postgresql-$TDC_PG_MAJOR}				# the server, initdb, pg_ctl, psql
		${TDC_PG_MAJOR:+postgresql-server-dev-$TDC_PG_MAJOR}	# headers, pg_config, PGXS and pg_regress
		${TDC_PG_MAJOR:+postgresql-$TDC_PG_MAJOR-postgis-3}	# PostGIS 3 (the geometry type, ST_DelaunayTriangles)
		${TDC_PG_MAJOR:+postgresql-$TDC_PG_MAJOR-pointcloud}	# pgpointcloud, for tdc_delaunay_pointcloud and its test (tdc_pointcloud)
		zlib1g-dev								# zlib: the pcpatch reader's zlib-compressed dimensions (src/pg/formats/pcpatch_read.c)
		build-essential							# gcc, make, libc headers
		libgdal-dev								# ./tdc's GeoTIFF output: GDAL's headers and library (src/cli/geotiff.c)
		gdal-bin								# test/cli_geotiff.sh: gdalinfo, gdal_translate, gdal_grid read the GeoTIFFs back
		libgmp-dev								# exact rational arithmetic in the core tests' oracle
		libcgal-dev								# CGAL reference for the constrained tests (test/cgal_cdt.cpp)
		clang									# the sanitizer builds (check-core-asan, check-core-tsan)
		libclang-rt-dev							# that clang's ASan/UBSan/TSan and libFuzzer runtimes
	)
}
TDC_PG_CONFIG_GIVEN=${PG_CONFIG:+1}
tdc_set_major

# "PostgreSQL 17" in messages, or "PostgreSQL" while the major is unknown
tdc_pg_name() { printf 'PostgreSQL%s' "${TDC_PG_MAJOR:+ $TDC_PG_MAJOR}"; }

tdc_say() { printf '==> %s\n' "$*"; }
tdc_warn() { printf 'tdc: warning: %s\n' "$*" >&2; }
tdc_die() { printf 'tdc: error: %s\n' "$*" >&2; exit 1; }

# Run a command as root: directly when we are root, else through sudo if it
# works without a password prompt; otherwise fail with the command to run.
tdc_as_root() {
	if ((EUID == 0)); then
		"$@"
	elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
		sudo -n "$@"
	else
		tdc_die "needs root: run as root:  $*"
	fi
}

tdc_pkg_installed() {
	[ "$(dpkg-query -W -f='${db:Status-Status}' "$1" 2>/dev/null)" = installed ]
}

# apt-get install PACKAGES..., after an apt-get update (unless this process
# made one: TDC_APT_UPDATED=1), as root; log in build/logs/apt.log.
tdc_apt_install() {
	mkdir -p "$TDC_LOGDIR"
	local p log=$TDC_LOGDIR/apt.log unsafe=()
	# On a CI machine (CI set, as CI services and the fresh-machine check
	# do), dpkg unpacks without its fsyncs: a crash there means a new
	# machine, not a half-written system.  Never on anyone else's machine.
	[ -z "${CI:-}" ] || unsafe=(-o Dpkg::Options::=--force-unsafe-io)
	tdc_say "apt-get install $* (a few minutes on a fresh machine; log: $log)"
	if ! { ((${TDC_APT_UPDATED:-0})) || tdc_as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q </dev/null >>"$log" 2>&1; } ||
		! tdc_as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
			-o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold "${unsafe[@]}" \
			"$@" </dev/null >>"$log" 2>&1; then
		tail -n 30 "$log" >&2
		tdc_die "apt-get failed (full log: $log)"
	fi
	for p in "$@"; do
		tdc_pkg_installed "$p" || tdc_die "package $p still not installed after apt-get (log: $log)"
	done
	tdc_say "installed: $*"
}

tdc_ensure_packages() {
	local p missing=()
	command -v dpkg-query >/dev/null 2>&1 ||
		tdc_die "not a Debian system: install PostgreSQL (15, 17 or 18) with its server headers, PostGIS 3, gcc, make, GMP and clang yourself (see README.md), then run again with PG_CONFIG set"
	if [ -z "$TDC_PG_MAJOR" ]; then
		# a fresh machine: apt's lists say which major this release packages
		mkdir -p "$TDC_LOGDIR"
		tdc_say "apt-get update, to learn this release's PostgreSQL major (log: $TDC_LOGDIR/apt.log)"
		tdc_as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q </dev/null >>"$TDC_LOGDIR/apt.log" 2>&1 ||
			{ tail -n 30 "$TDC_LOGDIR/apt.log" >&2; tdc_die "apt-get update failed (log: $TDC_LOGDIR/apt.log)"; }
		TDC_APT_UPDATED=1
		tdc_set_major
		[ -n "$TDC_PG_MAJOR" ] || tdc_die "apt knows no \"postgresql\" package to take the major from; set PG_CONFIG"
	fi
	local from="the major this Debian release packages"
	[ -n "$TDC_PG_CONFIG_GIVEN" ] && from="from PG_CONFIG"
	tdc_say "$(tdc_pg_name) ($from): $PG_CONFIG"
	# shellcheck disable=SC2206  # TDC_EXTRA_PACKAGES: a list of package names
	local want=("${TDC_PACKAGES[@]}" ${TDC_EXTRA_PACKAGES:-})
	for p in "${want[@]}"; do
		tdc_pkg_installed "$p" || missing+=("$p")
	done
	if ((${#missing[@]} == 0)); then
		tdc_say "Debian packages: all ${#want[@]} present"
		return 0
	fi
	tdc_say "Debian packages missing: ${missing[*]}"
	tdc_apt_install "${missing[@]}"
}

# node and npm, which test/cli_las.sh needs for its loaders.gl cross-check
# (it installs the package with npm itself).  Looked for as commands, not as
# packages: a node from elsewhere (nodesource's nodejs carries its own npm
# and conflicts with Debian's npm package) does as well; only when one is
# missing are Debian's nodejs and npm installed.
tdc_ensure_node() {
	if command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1; then
		tdc_say "node $(node --version) and npm $(npm --version 2>/dev/null): present"
		return 0
	fi
	tdc_apt_install nodejs npm
}

# Build the extension and install it into $PG_CONFIG's directories.
# TDC_WITH_LLVM=no (make test sets it) leaves out the JIT bitcode, which
# compiles every file a second time, with clang.
tdc_build_install() {
	[ -x "$PG_CONFIG" ] ||
		tdc_die "no pg_config at ${PG_CONFIG:-<unknown>} (package postgresql-server-dev-${TDC_PG_MAJOR:-MAJOR}; or set PG_CONFIG)"
	local jobs
	jobs=$(nproc 2>/dev/null || echo 2)
	local llvm=()
	[ "${TDC_WITH_LLVM:-}" != no ] || llvm=(with_llvm=no)
	tdc_say "building the extension (make -j$jobs PG_CONFIG=$PG_CONFIG ${llvm[*]} all)"
	make -C "$TDC_ROOT" --no-print-directory -j"$jobs" PG_CONFIG="$PG_CONFIG" "${llvm[@]}" all || return 1
	tdc_say "installing into $("$PG_CONFIG" --pkglibdir) and $("$PG_CONFIG" --sharedir)/extension"
	local as=()
	[ -w "$("$PG_CONFIG" --pkglibdir)" ] || as=(tdc_as_root)
	mkdir -p "$TDC_LOGDIR"
	if ! "${as[@]}" make -C "$TDC_ROOT" --no-print-directory PG_CONFIG="$PG_CONFIG" "${llvm[@]}" install \
		>"$TDC_LOGDIR/install.log" 2>&1; then
		cat "$TDC_LOGDIR/install.log" >&2
		tdc_warn "make install failed"
		return 1
	fi
}

# --- Which server --------------------------------------------------------------

# 0: throw-away cluster; 1: the user's server (libpq PG* settings).
tdc_use_existing() {
	case "${TDC_USE_EXISTING:-}" in
		1 | yes | true) return 0 ;;
		0 | no | false) return 1 ;;
	esac
	[ -n "${PGHOST:-}${PGPORT:-}${PGDATABASE:-}${PGSERVICE:-}" ]
}

# --- Throw-away cluster ----------------------------------------------------------

TDC_CLUSTER_STARTED=0	# 1 once this process started (or adopted) the throw-away cluster

# Who owns the cluster: initdb and postgres refuse to run as root, so root
# uses the "postgres" system user that the Debian package creates.
tdc_cluster_owner() {
	if ((EUID == 0)); then
		if ! getent passwd postgres >/dev/null; then
			tdc_say "creating system user postgres"
			useradd --system --user-group --home-dir /var/lib/postgresql --shell /bin/bash postgres
		fi
		echo postgres
	else
		id -un
	fi
}

# Run a command as the cluster's owner, from / (the caller's cwd may be unreadable to it).
tdc_as_owner() {
	if ((EUID == 0)); then
		(cd / && runuser -u "$TDC_OWNER" -- "$@")
	else
		(cd / && "$@")
	fi
}

# Set TDC_OWNER, TDC_PGDATA (data dir) and TDC_PGRUN (socket dir, log, port file).
tdc_cluster_paths() {
	TDC_OWNER=$(tdc_cluster_owner)
	local base
	if [ -n "${TDC_PGDIR:-}" ]; then
		mkdir -p "$TDC_PGDIR"
		base=$(cd "$TDC_PGDIR" && pwd -P)
		TDC_PGDATA=$base/pgdata
		TDC_PGRUN=$base/run
	else
		TDC_PGDATA=$TDC_ROOT/.pgdata
		TDC_PGRUN=$TDC_ROOT/.pgrun
		# The owner must reach the project dir, and a Unix socket path is
		# limited to 107 bytes ("$TDC_PGRUN/.s.PGSQL.NNNNN").
		if ! tdc_as_owner test -x "$TDC_ROOT" -a -r "$TDC_ROOT" || ((${#TDC_PGRUN} > 90)); then
			local hash
			hash=$(printf '%s' "$TDC_ROOT" | md5sum | cut -c1-10)
			base=/tmp/tdc_delaunay-$EUID-$hash
			if [ -L "$base" ] || { [ -e "$base" ] && [ "$(stat -c %u "$base")" != "$EUID" ]; }; then
				tdc_die "$base exists but is not a directory of uid $EUID: remove it, or set TDC_PGDIR"
			fi
			mkdir -p "$base"
			chmod 755 "$base"
			TDC_PGDATA=$base/pgdata
			TDC_PGRUN=$base/run
		fi
	fi
	TDC_PGBIN=$("$PG_CONFIG" --bindir)
}

# Is something already using this port?  A PostgreSQL Unix socket of that
# port anywhere (other throw-away clusters listen on sockets only), or in the
# usual directories; a TCP listener on it (any address, or answering on the
# loopback addresses).
tdc_port_busy() {
	local port=$1 d hex
	for d in /var/run/postgresql /run/postgresql /tmp; do
		[ -e "$d/.s.PGSQL.$port" ] || [ -e "$d/.s.PGSQL.$port.lock" ] && return 0
	done
	grep -q "/\.s\.PGSQL\.$port\$" /proc/net/unix 2>/dev/null && return 0
	# /proc/net/tcp*: local address "ADDR:PORT" in hex, state 0A = LISTEN.
	hex=$(printf '%04X' "$port")
	awk -v p=":$hex" '$4 == "0A" && substr($2, length($2) - 4) == p { found = 1 } END { exit !found }' \
		/proc/net/tcp /proc/net/tcp6 2>/dev/null && return 0
	timeout 2 bash -c "exec 3<>/dev/tcp/127.0.0.1/$port" 2>/dev/null && return 0
	timeout 2 bash -c "exec 3<>/dev/tcp/::1/$port" 2>/dev/null && return 0
	return 1
}

tdc_free_port() {
	local port=${TDC_PORT_START:-5433} last
	last=$((port + 200))
	while ((port <= last)); do
		tdc_port_busy "$port" || { echo "$port"; return 0; }
		port=$((port + 1))
	done
	tdc_die "no free port in ${TDC_PORT_START:-5433}..$last"
}

tdc_cluster_running() {
	[ -f "$TDC_PGDATA/postmaster.pid" ] &&
		tdc_as_owner "$TDC_PGBIN/pg_ctl" -D "$TDC_PGDATA" status >/dev/null 2>&1
}

tdc_cluster_export() {
	export PGHOST=$TDC_PGRUN PGPORT=$1 PGUSER=$TDC_OWNER PGDATABASE=postgres
	unset PGSERVICE PGHOSTADDR PGPASSWORD
}

# Start a fresh throw-away cluster (or adopt the one a KEEP=1 run left running).
tdc_cluster_start() {
	tdc_cluster_paths
	mkdir -p "$TDC_LOGDIR"
	if tdc_cluster_running && [ -f "$TDC_PGRUN/port" ]; then
		local port
		port=$(cat "$TDC_PGRUN/port")
		tdc_cluster_export "$port"
		TDC_CLUSTER_STARTED=1
		tdc_say "reusing the running throw-away cluster in $TDC_PGDATA (socket $TDC_PGRUN, port $port)"
		return 0
	fi
	# A stopped cluster from an earlier run is re-initialised: initdb takes a
	# second or two and leaves no state behind from older builds.
	rm -rf "$TDC_PGDATA" "$TDC_PGRUN"
	mkdir -p "$TDC_PGDATA" "$TDC_PGRUN"
	chmod 700 "$TDC_PGDATA" "$TDC_PGRUN"
	((EUID == 0)) && chown "$TDC_OWNER:" "$TDC_PGDATA" "$TDC_PGRUN"

	local port
	port=$(tdc_free_port)
	tdc_say "initdb: throw-away $(tdc_pg_name) cluster in $TDC_PGDATA (owner $TDC_OWNER)"
	if ! tdc_as_owner "$TDC_PGBIN/initdb" -D "$TDC_PGDATA" -U "$TDC_OWNER" -A trust \
		--no-locale -E UTF8 --no-sync >"$TDC_LOGDIR/initdb.log" 2>&1; then
		cat "$TDC_LOGDIR/initdb.log" >&2
		tdc_die "initdb failed"
	fi
	# Unix socket only, in the cluster's own directory: it never clashes with,
	# or is reachable as, another server.  Durability is not needed here.
	tdc_as_owner tee -a "$TDC_PGDATA/postgresql.conf" >/dev/null <<-EOF

		# --- tdc_delaunay throw-away cluster (scripts/lib.sh) ---
		port = $port
		listen_addresses = ''
		unix_socket_directories = '$TDC_PGRUN'
		unix_socket_permissions = 0700
		fsync = off
		synchronous_commit = off
		full_page_writes = off
		max_wal_size = 2GB
		shared_buffers = 256MB
	EOF
	tdc_say "starting it on port $port (socket in $TDC_PGRUN, no TCP)"
	if ! tdc_as_owner "$TDC_PGBIN/pg_ctl" -D "$TDC_PGDATA" -l "$TDC_PGRUN/postgres.log" -w -t 120 start >/dev/null; then
		tail -n 30 "$TDC_PGRUN/postgres.log" >&2 || true
		tdc_die "the throw-away server did not start (log: $TDC_PGRUN/postgres.log)"
	fi
	echo "$port" | tdc_as_owner tee "$TDC_PGRUN/port" >/dev/null
	TDC_CLUSTER_STARTED=1
	tdc_cluster_export "$port"
}

# Stop the throw-away cluster if it runs (after tdc_cluster_paths).  Quiet
# when there is nothing to do, so that it can also serve as an EXIT trap.
tdc_cluster_stop() {
	[ -n "${TDC_PGDATA:-}" ] || return 0
	tdc_cluster_running || return 0
	tdc_say "stopping the throw-away server ($TDC_PGDATA)"
	tdc_as_owner "$TDC_PGBIN/pg_ctl" -D "$TDC_PGDATA" -m fast -w -t 60 stop >/dev/null 2>&1 ||
		tdc_as_owner "$TDC_PGBIN/pg_ctl" -D "$TDC_PGDATA" -m immediate -w -t 60 stop >/dev/null 2>&1 ||
		tdc_warn "could not stop the server in $TDC_PGDATA"
	TDC_CLUSTER_STARTED=0
}

# --- Either server ----------------------------------------------------------------

TDC_EXISTING=0

tdc_server_up() {
	if tdc_use_existing; then
		TDC_EXISTING=1
		tdc_say "using your server: host=${PGHOST:-<libpq default>} port=${PGPORT:-<libpq default>} dbname=${PGDATABASE:-<libpq default>} user=${PGUSER:-<libpq default>} (TDC_USE_EXISTING=0 starts a throw-away one instead)"
		"$("$PG_CONFIG" --bindir)/psql" -X -q -v ON_ERROR_STOP=1 -c 'SELECT 1' >/dev/null ||
			tdc_die "cannot connect to your server with the PG* settings above"
	else
		tdc_cluster_start
	fi
}

tdc_server_down() {
	((TDC_EXISTING)) || tdc_cluster_stop
}

tdc_psql() {
	"$("$PG_CONFIG" --bindir)/psql" -X -v ON_ERROR_STOP=1 "$@"
}
