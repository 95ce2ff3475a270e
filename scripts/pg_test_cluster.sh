#!/usr/bin/env bash
# A throwaway PostgreSQL cluster for the records tests (issue 21), from Debian's postgresql
# package: initdb in a folder of its own, a Unix socket in that folder (no TCP port, nothing
# shared with the machine), password authentication (scram-sha-256), so a wrong password is
# refused as on a real centre.
#
#   pg_test_cluster.sh start DIR   creates and starts it; prints the lines to `eval`:
#                                  PHACO_TEST_PG_URI (superuser "phaco" with its password),
#                                  PHACO_TEST_PG_DIR and PHACO_TEST_PG_CTL (this script)
#   pg_test_cluster.sh stop DIR    stops it (immediately; the folder stays for `start` again)
#   pg_test_cluster.sh restart DIR stops and starts it (the fault tests restart the server)
#   pg_test_cluster.sh remove DIR  stops it and deletes the folder
#
# initdb refuses to run as root: as root, the cluster runs as the postgres user the package made.
set -euo pipefail
cmd="${1:-}"
dir="${2:-}"
[ -n "$cmd" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop|restart|remove DIR" >&2; exit 2; }
bin="$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)"
[ -x "$bin/initdb" ] || { echo "pg_test_cluster: no PostgreSQL server (Debian package postgresql)" >&2; exit 1; }
port=54329
as_owner() {
  if [ "$(id -u)" -eq 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi
}
ctl() { as_owner "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" "$@"; }
# fsync off: the cluster is thrown away; durability is the server's business, not under test.
serve() {
  ctl -w -t 30 -o "-k $dir -p $port -c listen_addresses='' -c fsync=off -c max_connections=60" \
    start >/dev/null
}

case "$cmd" in
  start)
    if [ ! -d "$dir/data" ]; then
      mkdir -p "$dir"
      [ "$(id -u)" -eq 0 ] && chown postgres: "$dir"
      # The password: random per cluster; the tests read it from the URI.
      password="$(head -c 12 /dev/urandom | od -An -tx1 | tr -d ' \n')"
      printf '%s\n' "$password" > "$dir/password"
      [ "$(id -u)" -eq 0 ] && chown postgres: "$dir/password"
      as_owner "$bin/initdb" -D "$dir/data" -U phaco --pwfile="$dir/password" \
        --auth=scram-sha-256 -E UTF8 --locale=C.UTF-8 >"$dir/initdb.log" 2>&1 ||
        { cat "$dir/initdb.log" >&2; exit 1; }
    fi
    ctl status >/dev/null 2>&1 || serve
    password="$(cat "$dir/password")"
    echo "PHACO_TEST_PG_URI='postgresql://phaco:$password@/postgres?host=$dir&port=$port'"
    echo "PHACO_TEST_PG_DIR='$dir'"
    echo "PHACO_TEST_PG_CTL='$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/pg_test_cluster.sh'"
    ;;
  stop)
    [ -d "$dir/data" ] && ctl -m immediate stop >/dev/null 2>&1 || true
    ;;
  restart)
    ctl -m immediate stop >/dev/null 2>&1 || true
    serve
    ;;
  remove)
    [ -d "$dir/data" ] && ctl -m immediate stop >/dev/null 2>&1 || true
    rm -rf "$dir"
    ;;
  *)
    echo "usage: $0 start|stop|restart|remove DIR" >&2; exit 2 ;;
esac
