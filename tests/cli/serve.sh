#!/bin/sh
# End to end over real HTTP: `twinwatch serve` replays a collision recording, curl reads its
# dashboard as a browser and a script would. The events are those `twinwatch monitor` finds with the
# same options (one loop), the page and the state are served, and Ctrl-C ends it with status 0.
# usage: serve.sh TWINWATCH TWIN RECORDING WORKDIR
set -eu
tw=$1 twin=$2 rec=$3 dir=$4
mkdir -p "$dir"
rm -f "$dir"/serve.* "$dir"/monitor.*
fail() { echo "FAIL: $*"; cat "$dir/serve.err" 2>/dev/null; kill -INT "$pid" 2>/dev/null || true; exit 1; }
"$tw" monitor --twin "$twin" "$rec" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --events "$dir/monitor.events" >"$dir/monitor.out"
# the system picks the port (0): the URL is on stderr
"$tw" serve --twin "$twin" "$rec" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --events "$dir/serve.events" \
  --speed 4 --listen 127.0.0.1:0 >"$dir/serve.out" 2>"$dir/serve.err" &
pid=$!
# whatever ends this script, the server does not outlive it (it serves until Ctrl-C)
trap 'kill -INT "$pid" 2>/dev/null || true' EXIT
url=""
for i in $(seq 1 100); do
  # (the shell may not have created serve.err yet: a missing file is no URL yet, not a failure)
  url=$(sed -n 's/^dashboard: \(http:[^ ]*\).*/\1/p' "$dir/serve.err" 2>/dev/null || true)
  [ -n "$url" ] && break
  sleep 0.1
done
[ -n "$url" ] || fail "no dashboard URL on stderr"
echo "url=$url"
# the page
curl -sf "$url" >"$dir/serve.page" || fail "GET / failed"
grep -q "twinwatch — live" "$dir/serve.page" || fail "the page is not the dashboard"
# while it replays (4x: about 2.5 s for the 10 s recording), then finished
state=""
for i in $(seq 1 200); do
  curl -sf "${url}api/state?since=0" >"$dir/serve.state" || fail "GET /api/state failed"
  grep -q '"state":"finished"' "$dir/serve.state" && { state=finished; break; }
  sleep 0.1
done
[ "$state" = finished ] || fail "the replay did not finish in 20 s"
grep -q '"class":"collision"' "$dir/serve.state" || fail "the state has no collision event"
samples=$(sed -n 's/.*"samples":\([0-9]*\).*/\1/p' "$dir/serve.state")
grep -q "^$samples samples" "$dir/monitor.out" || fail "the state counts $samples samples, monitor: $(tail -1 "$dir/monitor.out")"
# a cursor: nothing new once finished
cursor=$(sed -n 's/.*"cursor":\([0-9]*\).*/\1/p' "$dir/serve.state")
curl -sf "${url}api/state?since=$cursor" >"$dir/serve.again" || fail "GET since=$cursor failed"
grep -q '"events":\[\]' "$dir/serve.again" || fail "events again after the cursor"
grep -q '"t":\[\]' "$dir/serve.again" || fail "points again after the cursor"
code=$(curl -s -o /dev/null -w '%{http_code}' "${url}api/state?since=x")
[ "$code" = 400 ] || fail "since=x answered $code, expected 400"
# the page stays up after the replay until Ctrl-C, which ends it with status 0
kill -INT "$pid"
rc=0
wait "$pid" || rc=$?
[ "$rc" -eq 0 ] || fail "exit status $rc after Ctrl-C, expected 0"
cmp -s "$dir/monitor.events" "$dir/serve.events" || { diff "$dir/monitor.events" "$dir/serve.events"; fail "serve's events differ from monitor's"; }
[ -s "$dir/serve.events" ] || fail "no events"
curl -s "$url" >/dev/null 2>&1 && fail "still serving after Ctrl-C"
echo "events=$(wc -l <"$dir/serve.events") samples=$samples"
# an input refused at once is said without a dashboard address before it (audit of session 56)
rc=0
"$tw" serve --twin "$twin" "$rec" --rtde 127.0.0.1:1 --listen 127.0.0.1:0 --db '' >"$dir/serve.out" 2>"$dir/serve.err" || rc=$?
[ "$rc" -eq 2 ] || fail "RECORDING and --rtde: exit $rc, expected 2"
grep -q "dashboard:" "$dir/serve.err" && fail "a dashboard address before the refusal"
grep -q "give either RECORDING" "$dir/serve.err" || fail "RECORDING and --rtde not refused by name"
# ... and a recording whose header is refused (its whole-file check comes after the address)
printf 'timestamp;actual_q_0\n0;0\n' >"$dir/semi.csv"
rc=0
"$tw" serve --twin "$twin" "$dir/semi.csv" --listen 127.0.0.1:0 --db '' >"$dir/serve.out" 2>"$dir/serve.err" || rc=$?
[ "$rc" -eq 2 ] || fail "a ';' header: exit $rc, expected 2"
grep -q "dashboard:" "$dir/serve.err" && fail "a dashboard address before the header's refusal"
grep -q "separated by ';'" "$dir/serve.err" || fail "the ';' header not named"
echo "PASS"
