# shellcheck shell=bash
# Source me from CI:  . .ci/postgres.sh
#
# Starts a throwaway PostgreSQL server for tests/test_store_postgres.py and exports
# POSECBR_TEST_POSTGRES_URL (postgresql+psycopg://...). Debian's `postgresql` package is
# installed with apt when missing and we are root; the cluster lives in a fresh temp folder
# (initdb as the `postgres` user when root, else as the current user), listens on 127.0.0.1
# only, on a free port, with its socket in that folder. No system-wide configuration is
# touched beyond installing the package.
#
# If anything fails, one line is printed and the variable stays unset (the tests then skip).
# The server stops by itself: `posecbr_postgres_stop` (call it from an EXIT trap) stops it and
# removes the folder, and a watchdog does the same once the shell that sourced this file exits,
# so no daemon outlives CI even without the trap.
#
# Safe under `set -euo pipefail`: every step is checked inside a function whose failure is
# caught here, and the caller's shell options are restored.

posecbr_postgres_stop() {
  if [ -n "${POSECBR_PG_DIR:-}" ] && [ -d "${POSECBR_PG_DIR}" ]; then
    ${POSECBR_PG_AS:-} "${POSECBR_PG_BIN}/pg_ctl" -D "${POSECBR_PG_DIR}/data" -m immediate \
      -w -t 20 stop >/dev/null 2>&1 || true
    rm -rf "${POSECBR_PG_DIR}"
  fi
  unset POSECBR_TEST_POSTGRES_URL
}

_posecbr_postgres_start() {
  local bin dir port as="" pw url
  if ! ls -d /usr/lib/postgresql/*/bin >/dev/null 2>&1; then
    if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
      _posecbr_pg_err="postgresql is not installed (and cannot be without root and apt)"
      return 1
    fi
    if ! (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
        postgresql) >/dev/null 2>&1; then
      _posecbr_pg_err="apt-get install postgresql failed"
      return 1
    fi
  fi
  bin=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n 1)
  [ -x "$bin/initdb" ] && [ -x "$bin/pg_ctl" ] || { _posecbr_pg_err="no initdb/pg_ctl in $bin"; return 1; }
  dir=$(mktemp -d "${TMPDIR:-/tmp}/posecbr-pg.XXXXXX" 2>/dev/null) || { _posecbr_pg_err="mktemp failed"; return 1; }
  chmod 755 "$dir" 2>/dev/null
  if [ "$(id -u)" = 0 ]; then
    # initdb refuses to run as root
    id postgres >/dev/null 2>&1 || { _posecbr_pg_err="no postgres user to run the server as"; rm -rf "$dir"; return 1; }
    chown postgres "$dir" 2>/dev/null || { _posecbr_pg_err="cannot hand $dir to the postgres user"; return 1; }
    as="runuser -u postgres --"
  fi
  export POSECBR_PG_DIR="$dir" POSECBR_PG_BIN="$bin" POSECBR_PG_AS="$as"
  pw=$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')
  # the password file must be readable by the server's user; it is removed right after initdb
  printf '%s\n' "$pw" > "$dir/pw" && chmod 644 "$dir/pw"
  if ! $as "$bin/initdb" -D "$dir/data" -U posecbr --pwfile="$dir/pw" -E UTF8 --locale=C.UTF-8 \
      --auth-local=scram-sha-256 --auth-host=scram-sha-256 >"$dir/initdb.log" 2>&1; then
    _posecbr_pg_err="initdb failed: $(tail -n 1 "$dir/initdb.log")"
    return 1
  fi
  rm -f "$dir/pw"
  # a free loopback port, chosen by the kernel
  port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])') \
    || { _posecbr_pg_err="no free port"; return 1; }
  # throwaway data: durability settings off for speed (the tests kill clients, not the server)
  if ! $as "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 -o \
      "-c listen_addresses=127.0.0.1 -p $port -k $dir -c fsync=off -c synchronous_commit=off -c full_page_writes=off -c max_connections=50" \
      start >/dev/null 2>&1; then
    _posecbr_pg_err="the server did not start: $(tail -n 1 "$dir/server.log" 2>/dev/null)"
    return 1
  fi
  # the watchdog: stop the server once the shell that sourced this file is gone
  local parent=$$
  (
    trap '' HUP INT
    while kill -0 "$parent" 2>/dev/null; do sleep 2; done
    $as "$bin/pg_ctl" -D "$dir/data" -m immediate -w -t 20 stop
    rm -rf "$dir"
  ) </dev/null >/dev/null 2>&1 &
  disown 2>/dev/null || true
  url="postgresql+psycopg://posecbr:${pw}@127.0.0.1:${port}/posecbr_test"
  if ! PGPASSWORD="$pw" "$bin/psql" -h 127.0.0.1 -p "$port" -U posecbr -d postgres -qAt \
      -c "CREATE DATABASE posecbr_test" >/dev/null 2>&1; then
    _posecbr_pg_err="could not create the test database"
    return 1
  fi
  export POSECBR_TEST_POSTGRES_URL="$url"
  _posecbr_pg_ok="PostgreSQL $("$bin/pg_ctl" --version | awk '{print $3}') on 127.0.0.1:$port"
}

# remember the caller's -e/-u/pipefail (restored below)
_posecbr_pg_opts=$-
_posecbr_pg_pipefail=0
if shopt -qo pipefail 2>/dev/null; then _posecbr_pg_pipefail=1; fi
set +e +u
_posecbr_pg_t0=$(date +%s)
_posecbr_pg_err="" _posecbr_pg_ok=""
if _posecbr_postgres_start; then
  echo "$_posecbr_pg_ok for the store tests (set up in $(( $(date +%s) - _posecbr_pg_t0 )) s)"
else
  echo "PostgreSQL store tests will skip: ${_posecbr_pg_err:-setup failed}"
  posecbr_postgres_stop
fi
case $_posecbr_pg_opts in *e*) set -e ;; esac
case $_posecbr_pg_opts in *u*) set -u ;; esac
if [ "$_posecbr_pg_pipefail" = 1 ]; then set -o pipefail; fi
unset _posecbr_pg_opts _posecbr_pg_pipefail _posecbr_pg_t0 _posecbr_pg_err _posecbr_pg_ok
