#!/bin/sh
# monitor --events-open on a simulated scenario: every alert announced open ends exactly once, either
# as an event (a closed line) or as withdrawn ("withdrawn": true), never both; the closed lines are
# those monitor writes without --events-open, and no withdrawn alert is among them.
# usage: open_alerts_end.sh TWINWATCH TWIN SCENARIO WORKDIR
set -eu
tw=$1 twin=$2 scenario=$3 dir=$4
mkdir -p "$dir"
name=$(basename "$scenario" .yaml)
rec="$dir/$name.csv" open="$dir/$name.open.jsonl" closed="$dir/$name.closed.jsonl"
"$tw" simulate "$scenario" -o "$rec" -q
"$tw" monitor --twin "$twin" "$rec" --db '' --events "$open" --events-open | grep -E "WITHDRAWN|held" || true
"$tw" monitor --twin "$twin" "$rec" --db '' --events "$closed" -q
t() { sed -n 's/.*"t_detected":\([0-9.e+-]*\).*/\1/p' | sort -u; }
grep '"open":true' "$open" | t >"$dir/$name.opened"
grep '"open":false' "$open" | t >"$dir/$name.ended"
grep '"withdrawn":true' "$open" | t >"$dir/$name.withdrawn"
grep '"open":false' "$open" | grep -v '"withdrawn":true' | t >"$dir/$name.events"
echo "opened: $(wc -l <"$dir/$name.opened")"
echo "never-ended: $(comm -23 "$dir/$name.opened" "$dir/$name.ended" | wc -l)"
echo "withdrawn: $(wc -l <"$dir/$name.withdrawn")"
echo "withdrawn-and-event: $(comm -12 "$dir/$name.withdrawn" "$dir/$name.events" | wc -l)"
echo "withdrawn-in-closed: $(grep -c '"withdrawn":true' "$closed" || true)"
grep -v '"open":true' "$open" | grep -v '"withdrawn":true' | cmp - "$closed" && echo CLOSED-LINES-SAME
