#!/bin/sh
# End to end with a real broker (Debian's mosquitto) and a real subscriber (mosquitto_sub): what
# `twinwatch monitor --mqtt` and `serve --mqtt` publish, byte for byte against --events, and what
# happens when the broker is not there yet, never comes, or the monitor is killed.
# usage: mqtt.sh TWINWATCH TWIN RECORDING WORKDIR
set -eu
tw=$1 twin=$2 rec=$3 dir=$4
mkdir -p "$dir"
rm -rf "$dir"/mqtt.*
pids=""
cleanup() { for p in $pids; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$dir"/mqtt.*.err "$dir"/mqtt.broker*.log; do [ -f "$f" ] && { echo "== $f"; cat "$f"; }; done; exit 1; }
payload="--payload-mass 0.5 --payload-com 0 0 0.04"

# a broker on a free port of the loopback (a port in use makes mosquitto exit at once: try another)
start_broker() {  # $1: log name; sets port (when empty) and broker
  for attempt in 1 2 3 4 5 6 7 8 9 10; do
    [ -n "${keep_port:-}" ] || port=$((20000 + ($$ * 7 + attempt * 131) % 30000))
    mosquitto -p "$port" >"$dir/mqtt.$1.log" 2>&1 &
    broker=$!
    sleep 0.3
    if kill -0 "$broker" 2>/dev/null; then pids="$pids $broker"; return 0; fi
    [ -n "${keep_port:-}" ] && fail "the broker did not start again on port $port"
  done
  fail "no free port for the broker"
}
subscribe() {  # $1: output name; every topic of the test, with its topic, QoS 1
  mosquitto_sub -h 127.0.0.1 -p "$port" -t 'tw/test/#' -v -q 1 >"$dir/mqtt.$1" 2>"$dir/mqtt.$1.err" &
  pids="$pids $!"
  sleep 0.3
}

conf_broker() {  # $1: name, its configuration after the listener line in $dir/mqtt.$1.body; on port+1, sets port and broker
  port=$((port + 1))
  # (run as root, mosquitto becomes the user 'mosquitto', who cannot read the test's files: it stays who runs the test)
  { printf 'user %s\nlistener %s 127.0.0.1\n' "$(id -un)" "$port"; cat "$dir/mqtt.$1.body"; } >"$dir/mqtt.$1.conf"
  mosquitto -c "$dir/mqtt.$1.conf" >"$dir/mqtt.broker_$1.log" 2>&1 &
  broker=$!
  pids="$pids $broker"
  sleep 0.5
  kill -0 "$broker" 2>/dev/null || fail "the broker '$1' did not start (port $port)"
}

# 1. a broker that is there: every event line as --events writes it, on tw/test/events/CLASS, in
#    order, between the retained states "monitoring" and "finished"
start_broker broker1
subscribe sub1
"$tw" monitor --twin "$twin" "$rec" $payload --db '' --events "$dir/mqtt.events" --mqtt "127.0.0.1:$port" --mqtt-topic tw/test \
  >"$dir/mqtt.monitor.out" 2>"$dir/mqtt.monitor.err" || fail "monitor --mqtt exited $?"
sleep 0.5
grep -q "^mqtt: connected to 127.0.0.1:$port" "$dir/mqtt.monitor.err" || fail "no 'connected' note"
[ -s "$dir/mqtt.events" ] || fail "the recording gave no events"
sed -n 's|^tw/test/events/[a-z_]* ||p' "$dir/mqtt.sub1" >"$dir/mqtt.got1"
cmp -s "$dir/mqtt.events" "$dir/mqtt.got1" || { diff "$dir/mqtt.events" "$dir/mqtt.got1"; fail "the published events differ from --events"; }
# each line on the topic of its class
while IFS= read -r line; do
  class=$(printf '%s\n' "$line" | sed -n 's/.*"class":"\([a-z_]*\)".*/\1/p')
  grep -qF "tw/test/events/$class $line" "$dir/mqtt.sub1" || fail "an event not on tw/test/events/$class: $line"
done <"$dir/mqtt.events"
head -n 1 "$dir/mqtt.sub1" | grep -q '^tw/test/status {"state":"monitoring"' || fail "the first message is not the state 'monitoring': $(head -n 1 "$dir/mqtt.sub1")"
n=$(wc -l <"$dir/mqtt.events" | tr -d ' ')
tail -n 1 "$dir/mqtt.sub1" | grep -q "^tw/test/status {\"state\":\"finished\".*\"events\":$n" ||
  fail "the last message is not the state 'finished' with $n events: $(tail -n 1 "$dir/mqtt.sub1")"
# the state is retained: a subscriber that comes later sees how the run ended
mosquitto_sub -h 127.0.0.1 -p "$port" -t tw/test/status -C 1 -W 5 >"$dir/mqtt.retained" || fail "no retained state"
grep -q '"state":"finished"' "$dir/mqtt.retained" || fail "the retained state is not 'finished': $(cat "$dir/mqtt.retained")"
echo "1: $n event(s) published as --events wrote them, states monitoring/finished"

# 2. --events-open: the open alerts' lines too, as in --events
"$tw" monitor --twin "$twin" "$rec" $payload --db '' --events "$dir/mqtt.events_open" --events-open --mqtt "127.0.0.1:$port" \
  --mqtt-topic tw/test/open >"$dir/mqtt.open.out" 2>"$dir/mqtt.open.err" || fail "monitor --events-open --mqtt exited $?"
sleep 0.5
sed -n 's|^tw/test/open/events/[a-z_]* ||p' "$dir/mqtt.sub1" >"$dir/mqtt.got_open"
cmp -s "$dir/mqtt.events_open" "$dir/mqtt.got_open" || { diff "$dir/mqtt.events_open" "$dir/mqtt.got_open"; fail "--events-open: the published lines differ"; }
grep -q '"open":true' "$dir/mqtt.got_open" || fail "--events-open published no open line"
echo "2: --events-open: $(wc -l <"$dir/mqtt.got_open" | tr -d ' ') lines, open ones included"

# 3. the broker comes only after the events happened (a restart): they wait and arrive, exit 0
kill "$broker"; wait "$broker" 2>/dev/null || true
"$tw" serve --twin "$twin" "$rec" $payload --db '' --events "$dir/mqtt.late.events" --speed 2 --exit-when-done --listen 127.0.0.1:0 \
  --mqtt "127.0.0.1:$port" --mqtt-topic tw/test >"$dir/mqtt.late.out" 2>"$dir/mqtt.late.err" &
late=$!
pids="$pids $late"
sleep 5.5  # (the replay: 10 s of recording at twice its pace; the collision is at about 6 s of it)
grep -q "warning: mqtt: cannot reach the broker at 127.0.0.1:$port: Connection refused" "$dir/mqtt.late.err" || fail "no warning while the broker is away"
keep_port=1 start_broker broker2
subscribe sub2
rc=0
wait "$late" || rc=$?
[ "$rc" -eq 0 ] || fail "serve exited $rc after the broker came back"
sleep 0.5
sed -n 's|^tw/test/events/[a-z_]* ||p' "$dir/mqtt.sub2" >"$dir/mqtt.got2"
[ -s "$dir/mqtt.late.events" ] || fail "serve wrote no events"
cmp -s "$dir/mqtt.late.events" "$dir/mqtt.got2" || { diff "$dir/mqtt.late.events" "$dir/mqtt.got2"; fail "the events that waited differ"; }
grep -q '"state":"finished"' "$dir/mqtt.sub2" || fail "no 'finished' after the broker came"
echo "3: broker late: $(wc -l <"$dir/mqtt.got2" | tr -d ' ') event(s) delivered after it came"

# 4. killed (kill -9): the broker publishes the last will, {"state":"lost"} with the run's source
"$tw" serve --twin "$twin" "$rec" $payload --db '' --speed 0.5 --listen 127.0.0.1:0 --mqtt "127.0.0.1:$port" --mqtt-topic tw/test/kill \
  >"$dir/mqtt.kill.out" 2>"$dir/mqtt.kill.err" &
victim=$!
pids="$pids $victim"
for i in $(seq 1 50); do grep -q "^mqtt: connected" "$dir/mqtt.kill.err" 2>/dev/null && break; sleep 0.1; done
kill -9 "$victim"; wait "$victim" 2>/dev/null || true
sleep 0.5
grep -q '^tw/test/kill/status {"state":"lost","source":"[^"]*collision.csv"' "$dir/mqtt.sub2" ||
  fail "no last will after kill -9: $(grep kill "$dir/mqtt.sub2" || true)"
echo "4: kill -9: the broker published the last will"

# 5. a broker that never comes: monitoring is not held up, the end waits 10 s, then an error and exit 1
kill "$broker"; wait "$broker" 2>/dev/null || true
rc=0
"$tw" monitor --twin "$twin" "$rec" $payload --db '' --events "$dir/mqtt.never.events" --mqtt "127.0.0.1:$port" \
  >"$dir/mqtt.never.out" 2>"$dir/mqtt.never.err" || rc=$?
[ "$rc" -eq 1 ] || fail "exit $rc without a broker, expected 1"
n=$(wc -l <"$dir/mqtt.never.events" | tr -d ' ')
grep -q "error: mqtt 127.0.0.1:$port: $((n + 1)) message(s) not delivered: $((n + 1)) not taken within 10 s (the events are in $dir/mqtt.never.events)" \
  "$dir/mqtt.never.err" || fail "no error for the undelivered messages: $(cat "$dir/mqtt.never.err")"
grep -q "event(s)" "$dir/mqtt.never.out" || fail "no summary without a broker"
echo "5: no broker: exit 1, $((n + 1)) messages ($n events and the last state; the first was superseded) said undelivered"

# 6. TLS: a broker with a certificate of a CA of the test's own; --mqtt-cafile checks it
tls="$dir/mqtt.tls"
mkdir -p "$tls"
openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj "/CN=twinwatch test CA" -keyout "$tls/ca.key" -out "$tls/ca.pem" 2>/dev/null
openssl req -newkey rsa:2048 -nodes -subj "/CN=localhost" -keyout "$tls/srv.key" -out "$tls/srv.csr" 2>/dev/null
printf 'subjectAltName=DNS:localhost,IP:127.0.0.1\n' >"$tls/ext"
openssl x509 -req -in "$tls/srv.csr" -CA "$tls/ca.pem" -CAkey "$tls/ca.key" -CAcreateserial -days 2 -out "$tls/srv.pem" \
  -extfile "$tls/ext" 2>/dev/null
openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj "/CN=another CA" -keyout "$tls/other.key" -out "$tls/other.pem" 2>/dev/null
printf 'allow_anonymous true\ncafile %s\ncertfile %s\nkeyfile %s\n' "$tls/ca.pem" "$tls/srv.pem" "$tls/srv.key" >"$dir/mqtt.tls.body"
conf_broker tls
mosquitto_sub -h localhost -p "$port" --cafile "$tls/ca.pem" -t 'tw/test/#' -v -q 1 >"$dir/mqtt.sub_tls" 2>"$dir/mqtt.sub_tls.err" &
pids="$pids $!"
sleep 0.5
"$tw" monitor --twin "$twin" "$rec" $payload --db '' --events "$dir/mqtt.tls.events" --mqtt "localhost:$port" --mqtt-cafile "$tls/ca.pem" \
  --mqtt-topic tw/test/tls >"$dir/mqtt.tls.out" 2>"$dir/mqtt.tls.err" || fail "monitor over TLS exited $?"
sleep 0.5
sed -n 's|^tw/test/tls/events/[a-z_]* ||p' "$dir/mqtt.sub_tls" >"$dir/mqtt.got_tls"
cmp -s "$dir/mqtt.tls.events" "$dir/mqtt.got_tls" || { diff "$dir/mqtt.tls.events" "$dir/mqtt.got_tls"; fail "over TLS the events differ"; }
# a broker whose certificate another CA signed is not spoken to: said, exit 1, nothing published
rc=0
"$tw" monitor --twin "$twin" "$rec" $payload --db '' --mqtt "localhost:$port" --mqtt-cafile "$tls/other.pem" --mqtt-topic tw/test/forged \
  >"$dir/mqtt.forged.out" 2>"$dir/mqtt.forged.err" || rc=$?
[ "$rc" -eq 1 ] || fail "exit $rc against a certificate of another CA, expected 1"
grep -q "warning: mqtt: cannot reach the broker at localhost:$port" "$dir/mqtt.forged.err" || fail "no warning for the certificate: $(cat "$dir/mqtt.forged.err")"
grep -q "tw/test/forged" "$dir/mqtt.sub_tls" && fail "published to a broker whose certificate did not check"
echo "6: TLS: $(wc -l <"$dir/mqtt.got_tls" | tr -d ' ') event(s) over TLS; a certificate of another CA refused"
kill "$broker"; wait "$broker" 2>/dev/null || true

# 7. a broker that wants a password: from $TWINWATCH_MQTT_PASSWORD with --mqtt-user; a wrong one is said
: >"$tls/passwords"
mosquitto_passwd -b "$tls/passwords" monitor 's3cret pass' || fail "mosquitto_passwd failed"
printf 'allow_anonymous false\npassword_file %s\n' "$tls/passwords" >"$dir/mqtt.auth.body"
conf_broker auth
TWINWATCH_MQTT_PASSWORD='s3cret pass' "$tw" monitor --twin "$twin" "$rec" $payload --db '' --mqtt "127.0.0.1:$port" --mqtt-user monitor \
  >"$dir/mqtt.auth.out" 2>"$dir/mqtt.auth.err" || fail "monitor with the right password exited $?"
grep -q "^mqtt: connected to 127.0.0.1:$port" "$dir/mqtt.auth.err" || fail "not connected with the right password"
rc=0
TWINWATCH_MQTT_PASSWORD=wrong "$tw" monitor --twin "$twin" "$rec" $payload --db '' --mqtt "127.0.0.1:$port" --mqtt-user monitor \
  >"$dir/mqtt.noauth.out" 2>"$dir/mqtt.noauth.err" || rc=$?
[ "$rc" -eq 1 ] || fail "exit $rc with a wrong password, expected 1"
grep -qE "warning: mqtt: the broker at 127.0.0.1:$port refused the connection: (Not authorized|not authorised) \(check the user name and password\)" \
  "$dir/mqtt.noauth.err" || fail "no refusal said: $(cat "$dir/mqtt.noauth.err")"
echo "7: a password from the environment taken, a wrong one said"
kill "$broker"; wait "$broker" 2>/dev/null || true

# 8. a broker whose access list forbids the topic refuses the messages (MQTT 5 reason 135): said, exit 1
printf 'topic readwrite allowed/#\n' >"$tls/acl"
printf 'allow_anonymous true\nacl_file %s\n' "$tls/acl" >"$dir/mqtt.acl.body"
conf_broker acl
rc=0
"$tw" monitor --twin "$twin" "$rec" $payload --db '' --events "$dir/mqtt.acl.events" --mqtt "127.0.0.1:$port" --mqtt-topic forbidden/cell \
  >"$dir/mqtt.acl.out" 2>"$dir/mqtt.acl.err" || rc=$?
[ "$rc" -eq 1 ] || fail "exit $rc when the broker refuses the messages, expected 1"
n=$(wc -l <"$dir/mqtt.acl.events" | tr -d ' ')
grep -q "warning: mqtt: the broker at 127.0.0.1:$port refused a message to forbidden/cell/[a-z/_]*: Not authorized (does its access list" \
  "$dir/mqtt.acl.err" || fail "the refusal is not said: $(cat "$dir/mqtt.acl.err")"
grep -q "error: mqtt 127.0.0.1:$port: $((n + 2)) message(s) not delivered: $((n + 2)) refused by the broker" "$dir/mqtt.acl.err" ||
  fail "the refused messages are not counted: $(cat "$dir/mqtt.acl.err")"
echo "8: an access list that forbids the topic: $((n + 2)) refusals said, exit 1"

kill "$broker"; wait "$broker" 2>/dev/null || true

# 9. a broker that restarted has lost the retained state (no persistence; the same after it published
#    the last will): once the monitor is back on it, it publishes its state again. And
#    --mqtt-status-every: the state with its counts while the run goes on, the samples growing
keep_port=""
start_broker broker9
"$tw" serve --twin "$twin" "$rec" $payload --db '' --speed 0.25 --listen 127.0.0.1:0 --mqtt "127.0.0.1:$port" --mqtt-topic allowed/nine \
  --mqtt-status-every 0 >"$dir/mqtt.nine.out" 2>"$dir/mqtt.nine.err" &
nine=$!
pids="$pids $nine"
for i in $(seq 1 50); do grep -q "^mqtt: connected" "$dir/mqtt.nine.err" 2>/dev/null && break; sleep 0.1; done
sleep 6  # (a link that lasted 5 s is retried at once when lost; the notes are printed every 500 samples: 4 s here)
kill "$broker"; wait "$broker" 2>/dev/null || true
keep_port=1 start_broker broker9b
for i in $(seq 1 200); do grep -q "^mqtt: reconnected" "$dir/mqtt.nine.err" 2>/dev/null && break; sleep 0.1; done
grep -q "^mqtt: reconnected to 127.0.0.1:$port" "$dir/mqtt.nine.err" || fail "no reconnection to the restarted broker: $(cat "$dir/mqtt.nine.err")"
mosquitto_sub -h 127.0.0.1 -p "$port" -t allowed/nine/status -C 1 -W 5 >"$dir/mqtt.states9" || fail "no retained state after the restart"
grep -q '^{"state":"monitoring"' "$dir/mqtt.states9" || fail "the retained state after the restart: $(cat "$dir/mqtt.states9")"
kill -INT "$nine"; wait "$nine" 2>/dev/null || true
mosquitto_sub -h 127.0.0.1 -p "$port" -t 'allowed/#' -v -q 1 >"$dir/mqtt.sub9" 2>"$dir/mqtt.sub9.err" &
pids="$pids $!"
sleep 0.3
"$tw" serve --twin "$twin" "$rec" $payload --db '' --speed 1 --exit-when-done --listen 127.0.0.1:0 --mqtt "127.0.0.1:$port" \
  --mqtt-topic allowed/beats --mqtt-status-every 1 >"$dir/mqtt.beats.out" 2>"$dir/mqtt.beats.err" || fail "serve with --mqtt-status-every exited $?"
sleep 0.3
sed -n 's|^allowed/beats/status {"state":"monitoring".*"updated_at":"[^"]*","samples":\([0-9]*\),"events":[0-9]*,"open_alerts":[0-9]*}$|\1|p' \
  "$dir/mqtt.sub9" >"$dir/mqtt.beats9"
[ "$(wc -l <"$dir/mqtt.beats9")" -ge 3 ] || fail "fewer than 3 states with counts: $(cat "$dir/mqtt.beats9")"
sort -n -c "$dir/mqtt.beats9" 2>/dev/null || fail "the counts of samples do not grow: $(cat "$dir/mqtt.beats9" | tr '\n' ' ')"
echo "9: the state again on a restarted broker; $(wc -l <"$dir/mqtt.beats9") states with counts (samples $(head -1 "$dir/mqtt.beats9")..$(tail -1 "$dir/mqtt.beats9"))"

# 10. two monitors with one client id take each other's connection: no flood, and it is said
"$tw" serve --twin "$twin" "$rec" $payload --db '' --speed 0.25 --listen 127.0.0.1:0 --mqtt "127.0.0.1:$port" --mqtt-topic allowed/a \
  --mqtt-client-id twin-cell3 >"$dir/mqtt.twin_a.out" 2>"$dir/mqtt.twin_a.err" &
a=$!
"$tw" serve --twin "$twin" "$rec" $payload --db '' --speed 0.25 --listen 127.0.0.1:0 --mqtt "127.0.0.1:$port" --mqtt-topic allowed/b \
  --mqtt-client-id twin-cell3 >"$dir/mqtt.twin_b.out" 2>"$dir/mqtt.twin_b.err" &
b=$!
pids="$pids $a $b"
before=$(grep -c "as twin-cell3" "$dir/mqtt.broker9b.log" || true)
sleep 12
kill -INT "$a" "$b"; wait "$a" 2>/dev/null || true; wait "$b" 2>/dev/null || true
connects=$(( $(grep -c "as twin-cell3" "$dir/mqtt.broker9b.log") - before ))
[ "$connects" -le 30 ] || fail "$connects connections in 12 s with one client id (a flood)"
cat "$dir/mqtt.twin_a.err" "$dir/mqtt.twin_b.err" | grep -q "is another client connected with the id 'twin-cell3'" ||
  fail "the shared client id is not said: $(cat "$dir/mqtt.twin_a.err" "$dir/mqtt.twin_b.err")"
echo "10: one client id for two monitors: $connects connections in 12 s, said"
echo "PASS"
