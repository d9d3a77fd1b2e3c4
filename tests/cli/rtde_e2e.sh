#!/bin/sh
# End to end over real TCP: `twinwatch serve-robot` (the virtual controller) and
# `twinwatch record --rtde` (the client) in two processes. The scenario drops 5 samples at
# t = 6 s; the recording must show exactly that gap, marked, and nothing else lost.
# usage: rtde_e2e.sh TWINWATCH SCENARIO WORKDIR PORT
set -eu
tw=$1 scenario=$2 dir=$3 port=$4
mkdir -p "$dir"
rm -f "$dir/rec.csv" "$dir/serve.json"
"$tw" serve-robot "$scenario" --port "$port" --speed 5 --duration 8 --wait-client 20 --json >"$dir/serve.json" 2>"$dir/serve.err" &
srv=$!
# the virtual robot's 8 s run at 5x ends before the 4 s asked for: the recording is written, and the
# status says the robot stopped answering (1), as the help says
rc=0
"$tw" record --rtde "127.0.0.1:$port" --duration 4 --wait 10 --no-reconnect -o "$dir/rec.csv" --json >"$dir/record.json" || rc=$?
wait $srv
[ "$rc" -eq 1 ] || { echo "FAIL: expected exit status 1 (the robot stopped answering before the 4 s asked for), got $rc"; exit 1; }
grep -q '"silent_at_end_s":[1-9]' "$dir/record.json" || { echo "FAIL: expected silent_at_end_s > 1 s"; exit 1; }
cat "$dir/record.json" "$dir/serve.json"
rows=$(($(wc -l <"$dir/rec.csv") - 1))
gaps=$(awk -F, 'NR==1 {for (i = 1; i <= NF; i++) if ($i == "stream_gap") c = i; next} $c == 1 {n++} END {print n + 0}' "$dir/rec.csv")
echo "rows=$rows marked_gaps=$gaps"
# 8 s at 500 Hz = 4000 cycles, 5 withheld by the scenario
[ "$rows" -eq 3995 ] || { echo "FAIL: expected 3995 rows"; exit 1; }
[ "$gaps" -eq 1 ] || { echo "FAIL: expected exactly one stream_gap marker"; exit 1; }
grep -q '"lost":5,' "$dir/record.json" || { echo "FAIL: expected lost 5"; exit 1; }
echo "PASS"
