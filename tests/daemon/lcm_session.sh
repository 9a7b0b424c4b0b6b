#!/usr/bin/env bash
# One multi-process LCM session for tests/daemon/millwatchd_lcm_test.cpp, run inside a private
# network namespace so that no packet leaves the machine:
#   unshare -n tests/daemon/lcm_session.sh MODE DIR
# with MILLWATCH_CLI and MILLWATCH_DAEMON set. DIR holds the inputs and receives the outputs:
#   live       two recorders record while millwatchd monitors cut.csv, published by
#              `millwatch publish` in 250-sample blocks: the raw channel → live.lcmlog, every other
#              channel → outputs.lcmlog; daemon.json (summary), daemon.log
#   logplayer  lcm-logplayer plays live.lcmlog's raw channel into a fresh millwatchd on
#              monitor_lcm_receive.json (LCM's receive thread), stopped with SIGINT → played.json,
#              played.log
#   split      millwatchd takes its raw blocks on one URL and publishes on another
#              (--lcm-output-url); a logger on each records what it hears while cut.lcmlog's raw
#              channel is played → in.lcmlog, out.lcmlog, split.json, split.log
#   reload     millwatchd starts on initial.json and gets part1.lcmlog, SIGHUP with good.json,
#              SIGHUP with bad.json, garbage.lcmlog, part2.lcmlog (all played raw) while
#              a recorder records → reload.lcmlog, reload.json, reload.log
# Every wait is bounded; a straggler is killed and the session fails. Background programs
# write to files only, so that none can hold the caller's pipe open.
set -u
mode=$1
dir=$2
cd "$dir"
trap 'kill -KILL $(jobs -p) 2>/dev/null' EXIT
ip link set lo up
ip route add 239.0.0.0/8 dev lo
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
out_url="udpm://239.255.76.67:7668?ttl=0&recv_buf_size=4194304"

start_daemon() {  # config, summary, log, [options]
  "$MILLWATCH_DAEMON" -c "$1" --lcm-url "$url" --summary "$2" "${@:4}" >"$3" 2>&1 &
  daemon=$!
  # Subscribed and listening: it logs "millwatchd running" once its source is open (a fixed
  # 0.5 s was once too short on a machine busy with other tests, and the first blocks were
  # played to nobody). The loggers, started before it, have had at least as long.
  for _ in $(seq 100); do
    grep -q "millwatchd running" "$3" 2>/dev/null && break
    kill -0 "$daemon" 2>/dev/null || break
    sleep 0.1
  done
  grep -q "millwatchd running" "$3" || echo "millwatchd did not start listening within 10 s" >&2
  sleep 0.2
}

await_exit() {  # pid, tenths of a second, message: a straggler is killed and the session fails
  for _ in $(seq "$2"); do
    kill -0 "$1" 2>/dev/null || return 0
    sleep 0.1
  done
  echo "$3" >&2
  kill -KILL "$1"
  exit 3
}

stop_daemon() {  # [signal]
  local sig=${1:-TERM}
  sleep 0.5  # the last blocks are in
  kill -"$sig" "$daemon"
  # On SIGTERM the daemon first fits identification's last windows: a sanitized build on a busy
  # 2-core machine once took more than 10 s. 30 s is what systemd gives it (the unit's
  # TimeoutStopSec, packaging/millwatchd.service.in).
  await_exit "$daemon" 300 "millwatchd did not stop within 30 s of SIG$sig"
  wait "$daemon"
  echo "daemon exit $?"
}

# The recorder is `millwatch record`: lcm-logger's log format, with no limit on the messages its
# subscription queues. lcm-logger queues 30 and drops the
# rest, and millwatchd publishes a burst of ~90 when it starts measuring (the revolutions since
# the lock): on a busy 2-core VM lcm-logger lost runs of results and once a raw block, though at
# real-time priority. The recorder runs at that priority too, so that it reads as they come.
if chrt -f 10 true 2>/dev/null; then
  logger_priority=(chrt -f 10)
else
  logger_priority=(nice -n -5)
fi

start_logger() {  # log file, [URL], [channels' regular expression], [--invert]
  local before
  before=$(grep -c "recording " logger.out 2>/dev/null)
  "${logger_priority[@]}" "$MILLWATCH_CLI" record "$1" --url "${2:-$url}" --channels "${3:-.*}" \
    ${4:+"$4"} >>logger.out 2>&1 &
  logger=$!
  for _ in $(seq 100); do  # subscribed: it says so
    [ "$(grep -c "recording " logger.out 2>/dev/null)" -gt "${before:-0}" ] && return
    kill -0 "$logger" 2>/dev/null || break
    sleep 0.1
  done
  echo "the recorder of $1 did not start within 10 s" >&2
}

stop_logger() {  # [pid]
  local pid=${1:-$logger}
  sleep 1  # the last messages in flight
  kill -INT "$pid"
  await_exit "$pid" 50 "the recorder did not stop within 5 s of SIGINT"
  wait "$pid"
  echo "logger exit $?"
}

raw_channel='^MILLWATCH_FORCE_RAW$'  # a regular expression, as the recorder and lcm-logplayer take

play() {  # the raw channel of a log, at twice real time
  timeout 30 lcm-logplayer -s 2 -e "$raw_channel" --lcm-url="$url" "$1" >/dev/null
}

case "$mode" in
  live)
    # The raw channel on a recorder of its own, as the README advises for lcm-logger.
    start_logger live.lcmlog "$url" "$raw_channel"
    raw_logger=$logger
    start_logger outputs.lcmlog "$url" "$raw_channel" --invert
    start_daemon monitor.json daemon.json daemon.log
    # Blocks of 5 ms: about two revolutions' messages per block.
    timeout 30 "$MILLWATCH_CLI" publish cut.csv --url "$url" --speed 1 --block 250 \
      >publish.log 2>&1 ||
      echo "publish failed" >&2
    stop_daemon TERM
    stop_logger
    stop_logger "$raw_logger"
    ;;
  logplayer)
    start_daemon monitor_lcm_receive.json played.json played.log
    play live.lcmlog
    stop_daemon INT
    ;;
  split)
    start_logger out.lcmlog "$out_url"
    out_logger=$logger
    start_logger in.lcmlog
    start_daemon monitor.json split.json split.log --lcm-output-url "$out_url"
    play cut.lcmlog
    stop_daemon TERM
    stop_logger
    stop_logger "$out_logger"
    ;;
  reload)
    cp initial.json reloadable.json
    start_logger reload.lcmlog
    start_daemon reloadable.json reload.json reload.log
    play head.lcmlog
    play part1.lcmlog
    sleep 0.3  # processed
    cp good.json reloadable.json
    kill -HUP "$daemon"
    sleep 0.3
    cp bad.json reloadable.json
    kill -HUP "$daemon"
    sleep 0.3
    play garbage.lcmlog
    play part2.lcmlog
    play tail.lcmlog
    sleep 0.1  # its oversized block handled (and dropped) before the stop
    stop_daemon TERM
    stop_logger
    ;;
  *)
    echo "unknown mode $mode" >&2
    exit 2
    ;;
esac
grep '^Udp:' /proc/net/snmp >udp_stats.txt  # RcvbufErrors counts kernel drops
