#!/usr/bin/env bash
# One multi-process LCM session for tests/daemon/millwatchd_lcm_test.cpp, run inside a private
# network namespace so that no packet leaves the machine:
#   unshare -n tests/daemon/lcm_session.sh MODE DIR
# with MILLWATCH_CLI and MILLWATCH_DAEMON set. DIR holds the inputs and receives the outputs:
#   live       lcm-logger records every channel while millwatchd monitors cut.csv, published by
#              `millwatch publish` → live.lcmlog, daemon.json (summary), daemon.log
#   logplayer  lcm-logplayer plays live.lcmlog's raw channel into a fresh millwatchd
#              → played.json, played.log
#   reload     millwatchd gets part1.lcmlog, SIGHUP with good.json, SIGHUP with bad.json,
#              garbage.lcmlog, part2.lcmlog (all played raw) → reload.json, reload.log
# Every wait is bounded; a straggler is killed and the session fails.
set -u
mode=$1
dir=$2
cd "$dir"
ip link set lo up
ip route add 239.0.0.0/8 dev lo
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"

start_daemon() {  # config, summary, log
  "$MILLWATCH_DAEMON" -c "$1" --lcm-url "$url" --summary "$2" 2>"$3" &
  daemon=$!
  sleep 0.5  # subscribed and listening
}

stop_daemon() {
  sleep 0.5  # the last blocks are in
  kill -TERM "$daemon"
  for _ in $(seq 100); do
    kill -0 "$daemon" 2>/dev/null || break
    sleep 0.1
  done
  if kill -0 "$daemon" 2>/dev/null; then
    echo "millwatchd did not stop within 10 s of SIGTERM" >&2
    kill -KILL "$daemon"
    exit 3
  fi
  wait "$daemon"
  echo "daemon exit $?"
}

play() {  # the raw channel of a log, at twice real time
  timeout 30 lcm-logplayer -s 2 -e '^MILLWATCH_FORCE_RAW$' --lcm-url="$url" "$1" >/dev/null
}

case "$mode" in
  live)
    lcm-logger -q --lcm-url="$url" live.lcmlog &
    logger=$!
    start_daemon monitor.json daemon.json daemon.log
    timeout 30 "$MILLWATCH_CLI" publish cut.csv --url "$url" --speed 1 >publish.log 2>&1 ||
      echo "publish failed" >&2
    stop_daemon
    sleep 1  # lcm-logger 1.3.1 can lose buffered events on a hard stop
    kill -INT "$logger"
    wait "$logger"
    ;;
  logplayer)
    start_daemon monitor.json played.json played.log
    play live.lcmlog
    stop_daemon
    ;;
  reload)
    cp good.json reloadable.json
    start_daemon reloadable.json reload.json reload.log
    play part1.lcmlog
    kill -HUP "$daemon"
    sleep 0.3
    cp bad.json reloadable.json
    kill -HUP "$daemon"
    sleep 0.3
    play garbage.lcmlog
    play part2.lcmlog
    stop_daemon
    ;;
  *)
    echo "unknown mode $mode" >&2
    exit 2
    ;;
esac
grep '^Udp:' /proc/net/snmp >udp_stats.txt  # RcvbufErrors counts kernel drops
