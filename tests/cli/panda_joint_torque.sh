#!/bin/sh
# The real Franka Panda log watched by its joint torque sensors (session 54; only where the shared
# real data is present): a twin identified on the first 65 % with a 25 ms acceleration window
# predicts the last 35 % to within 0.8 N·m on every joint, the monitor raises no fault alert there
# (the log's own timestamp gaps are stream faults), its thresholds on J1-J4 are below 3 N·m (the
# windowed acceleration; 5.8-8.7 with the filtered difference), and a 5 N·m half-sine added to J2's
# sensor column is found as a contact within 30 ms.
# usage: panda_joint_torque.sh TWINWATCH LOG.csv MAP WORK_DIR SOURCE_DIR
set -e
B=$1; P=$2; M=$3; W=$4; S=$5
mkdir -p "$W"
N=$(wc -l < "$P"); cut=$(( (N - 1) * 65 / 100 + 1 ))
head -n $cut "$P" > "$W/train.csv"
(head -1 "$P"; tail -n +$((cut + 1)) "$P") > "$W/test.csv"
"$B" identify "$W/train.csv" --robot panda --column-map "$M" --signal joint_torque --acceleration-window 0.025 -o "$W/twin.json" -q
"$B" validate --twin "$W/twin.json" "$W/test.csv" --column-map "$M" --json > "$W/v.json" 2> /dev/null
/usr/bin/python3 - "$W/v.json" "$W/twin.json" <<'PY'
import json, sys
v = json.load(open(sys.argv[1])); t = json.load(open(sys.argv[2]))
rmse = [j["rmse"] for j in v["joints"]]
print("held-out RMSE N·m:", " ".join(f"{r:.3f}" for r in rmse))
if not all(r < 0.8 for r in rmse): sys.exit("FAIL: held-out RMSE above 0.8 N·m")
lv = t["monitor"]["static_level_A"]
print("static thresholds N·m:", " ".join(f"{x:.2f}" for x in lv))
if not all(x < 3.0 for x in lv[:4]): sys.exit("FAIL: J1-J4 thresholds not below 3 N·m")
if t.get("acceleration_window") != 0.025 or t.get("signal") != "joint_torque": sys.exit("FAIL: the twin's signal or window")
PY
alerts=$("$B" monitor --twin "$W/twin.json" "$W/test.csv" --column-map "$M" --db '' --json 2> /dev/null | grep -vc '"class":"stream_fault"' || true)
echo "fault alerts on the held-out part: $alerts"
[ "$alerts" -eq 0 ] || { echo "FAIL: a fault alert on healthy real data"; exit 1; }
# one rule for the gaps of a recording, said once by the reader: the monitor does not widen it by the
# jitter it sees and say another (it said 1.9 and 2.1 ms and reported 1.8 ms steps as gaps; audit of
# session 55)
jit=$("$B" monitor --twin "$W/twin.json" "$W/test.csv" --column-map "$M" --db '' 2> /dev/null | grep -c "note: the stream's timestamps jitter" || true)
[ "$jit" -eq 0 ] || { echo "FAIL: the monitor's own jitter note on a recording"; exit 1; }
# a log that starts mid-motion: the windowed acceleration is held (0) until its means are whole, and
# nothing is judged on it (review of session 54: a false contact at 50 ms)
(head -1 "$W/test.csv"; tail -n +4500 "$W/test.csv") > "$W/mid.csv"
mid=$("$B" monitor --twin "$W/twin.json" "$W/mid.csv" --column-map "$M" --db '' --json 2> /dev/null | grep -vc '"class":"stream_fault"' || true)
echo "fault alerts on a log starting mid-motion: $mid"
[ "$mid" -eq 0 ] || { echo "FAIL: a fault alert where the log starts mid-motion"; exit 1; }
/usr/bin/python3 "$S/scripts/inject_torque_pulse.py" "$W/test.csv" "$W/hit.csv" --column tau2_Nm --onset 3.0 --magnitude 5
t0=$(sed -n 2p "$W/test.csv" | cut -d, -f1)
ev=$("$B" monitor --twin "$W/twin.json" "$W/hit.csv" --column-map "$M" --db '' --json 2> /dev/null | grep -v '"class":"stream_fault"' | head -1)
echo "$ev"
echo "$ev" | /usr/bin/python3 -c "
import json, sys
e = json.loads(sys.stdin.read() or 'null')
if not e or e['class'] != 'collision': sys.exit('FAIL: the 5 N·m contact on J2 was not found as a contact')
d = 1000 * (e['t_detected'] - $t0 - 3.0)
print(f'found after {d:.0f} ms')
if not 0 <= d <= 30: sys.exit('FAIL: not within 30 ms')
"
echo PANDA-JOINT-TORQUE-OK
