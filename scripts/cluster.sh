#!/usr/bin/env bash
# scripts/cluster.sh: the throw-away PostgreSQL cluster that `make demo`
# and `make test` use, by hand.
#
#   bash scripts/cluster.sh start    start it (fresh) and print how to connect
#   bash scripts/cluster.sh stop     stop it (e.g. after `KEEP=1 make demo`)
#   bash scripts/cluster.sh status   is it running, where, on which port
#   bash scripts/cluster.sh env      print export lines: eval "$(bash scripts/cluster.sh env)"
#   bash scripts/cluster.sh psql [ARGS]   psql into it
#
# It never touches another server: the cluster lives in the project's
# .pgdata/ and .pgrun/ (or /tmp/tdc_delaunay-UID-HASH, see scripts/lib.sh),
# listens on a Unix socket in its own directory only, and on a port that was
# free when it started.
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

[ -x "$PG_CONFIG" ] || tdc_die "$(tdc_pg_name) is not installed: run \`make demo\` first"
tdc_cluster_paths

running_port() {
	tdc_cluster_running && [ -f "$TDC_PGRUN/port" ] && cat "$TDC_PGRUN/port"
}

case "${1:-status}" in
	start)
		tdc_cluster_start
		echo "connect:  psql -h $PGHOST -p $PGPORT -U $PGUSER postgres"
		echo "stop:     bash scripts/cluster.sh stop"
		;;
	stop)
		if tdc_cluster_running; then
			tdc_cluster_stop
		else
			echo "no throw-away server running in $TDC_PGDATA"
		fi
		;;
	status)
		if port=$(running_port); then
			echo "running: data $TDC_PGDATA, socket dir $TDC_PGRUN, port $port, owner $TDC_OWNER"
		else
			echo "not running (data dir $TDC_PGDATA)"
			exit 3
		fi
		;;
	env)
		port=$(running_port) || tdc_die "not running: bash scripts/cluster.sh start"
		printf 'export PGHOST=%q PGPORT=%q PGUSER=%q PGDATABASE=postgres\n' "$TDC_PGRUN" "$port" "$TDC_OWNER"
		;;
	psql)
		shift
		port=$(running_port) || tdc_die "not running: bash scripts/cluster.sh start"
		tdc_cluster_export "$port"
		exec "$TDC_PGBIN/psql" "$@"
		;;
	*)
		sed -n '2,10p' "$0"
		exit 2
		;;
esac
