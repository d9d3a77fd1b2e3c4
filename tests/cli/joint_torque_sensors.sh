#!/bin/sh
# An arm with joint torque sensors, end to end (session 54): recordings simulated with
# `joint_torque_sensors: true`, a twin identified on the sensors (`identify --signal joint_torque`:
# no drive gain, the sensor's N·m), validated in N·m, a healthy run at another speed raises nothing
# and a 5 N·m contact on link 3 is found there with its residual in N·m. The refusals: a recording
# without the sensors' columns, a current-only method, an RTDE stream.
# usage: joint_torque_sensors.sh TWINWATCH DATA_DIR WORK_DIR
set -e
B=$1; D=$2; W=$3
. "$(dirname "$0")/simulated_runs.sh"
simulated_runs "$B" "$D" "$W" "joint_torque_sensors: true" 11 30
head -1 "$W/exc.csv" | grep -q 'actual_joint_torque_5' || { echo "FAIL: the recording has no actual_joint_torque columns"; exit 1; }

# the twin: identified on the sensors, gains 1, its signal in the file
"$B" identify "$W/exc.csv" "$W/fig.csv" --known-payload "$W/fig.csv=0.5,0,0,0.04" --signal joint_torque -o "$W/twin.json" > "$W/identify.txt"
cat "$W/identify.txt"
grep -q 'RMSE N·m' "$W/identify.txt" || { echo "FAIL: identify does not print the RMSE in N·m"; exit 1; }
grep -q '"signal": *"joint_torque"' "$W/twin.json" || { echo "FAIL: the twin file does not say its signal"; exit 1; }
if grep -q 'no recording with a known payload' "$W/identify.txt"; then echo "FAIL: a torque twin asked for a known payload"; exit 1; fi

# validated in N·m: the sensors' own noise (0.2 % of the torque limit) and what the model leaves
"$B" validate --twin "$W/twin.json" "$W/slow.csv" --json > "$W/validate.json"
cat "$W/validate.json"; echo
grep -q '"rmse":"N·m"' "$W/validate.json" || { echo "FAIL: validate's units are not N·m"; exit 1; }
/usr/bin/python3 - "$W/validate.json" <<'EOF'
import json, sys
v = json.load(open(sys.argv[1]))
rmse = [j["rmse"] for j in v["joints"]]
# the sensors read 0.108, 0.108, 0.056, 0.018, 0.018, 0.018 N·m of noise; a twin that missed the
# rigid body (or read the currents) is off by N·m, not tenths
limit = [0.5, 0.5, 0.3, 0.15, 0.15, 0.15]
bad = [f"J{k+1} {r:.3f} > {l}" for k, (r, l) in enumerate(zip(rmse, limit)) if not r <= l]
if bad: sys.exit("FAIL: validation RMSE " + ", ".join(bad))
print("validation RMSE N·m:", " ".join(f"{r:.3f}" for r in rmse))
EOF

slow_quiet_contact_found "$B" "$W"
echo "$hit" | grep -q '"peak_residual_units":"N·m"' || { echo "FAIL: the residual is not in N·m"; exit 1; }

# what the monitor prints names the torque, not a current
"$B" monitor --twin "$W/twin.json" "$W/hit.csv" --db '' > "$W/hit.txt" 2>&1
"$B" monitor --twin "$W/twin.json" "$W/hit.csv" --db '' -q --trace "$W/trace.csv"
head -1 "$W/trace.csv" | grep -q '^timestamp,residual_1_Nm,threshold_1_Nm,observer_1_Nm' || { echo "FAIL: the trace's columns"; head -1 "$W/trace.csv"; exit 1; }
grep -q 'torque residual above threshold' "$W/hit.txt" || { echo "FAIL: the alert does not name the torque residual"; cat "$W/hit.txt"; exit 1; }
if grep -qi 'current' "$W/hit.txt"; then echo "FAIL: the monitor speaks of a current"; cat "$W/hit.txt"; exit 1; fi

# the report: the sensors' torque, in N·m
"$B" report --twin "$W/twin.json" "$W/hit.csv" -o "$W/report.html" > /dev/null
grep -q 'RMSE N·m' "$W/report.html" || { echo "FAIL: the report's table is not in N·m"; exit 1; }
grep -q 'Measured vs predicted joint torque' "$W/report.html" || { echo "FAIL: the report's plots are not the joint torque"; exit 1; }

# the hybrid method on the sensors: the network corrects the torque, in N·m
"$B" identify "$W/exc.csv" "$W/fig.csv" --known-payload "$W/fig.csv=0.5,0,0,0.04" --signal joint_torque --method hybrid \
  -o "$W/hybrid.json" > "$W/hybrid.txt" 2>&1
grep -q 'held-out RMSE N·m' "$W/hybrid.txt" || { echo "FAIL: the hybrid's held-out RMSE is not in N·m"; cat "$W/hybrid.txt"; exit 1; }
grep -q '"signal": *"joint_torque"' "$W/hybrid.json" || { echo "FAIL: the hybrid twin does not say its signal"; exit 1; }

# refusals, each naming what is wrong
(cat "$D/short_exc.yaml") > "$W/plain.yaml"
"$B" simulate "$W/plain.yaml" -o "$W/plain.csv" -q
if "$B" identify "$W/plain.csv" --signal joint_torque -o "$W/x.json" 2> "$W/err1.txt"; then echo "FAIL: identified without sensors"; exit 1; fi
cat "$W/err1.txt"
grep -q "actual_joint_torque_0" "$W/err1.txt" || { echo "FAIL: the refusal does not name the missing column"; exit 1; }
if "$B" monitor --twin "$W/twin.json" "$W/plain.csv" --db '' 2> "$W/err2.txt"; then echo "FAIL: monitored a recording without sensors"; exit 1; fi
grep -q "actual_joint_torque_0" "$W/err2.txt" || { echo "FAIL: monitor's refusal does not name the missing column"; cat "$W/err2.txt"; exit 1; }
if "$B" identify "$W/exc.csv" --signal joint_torque --method mlp -o "$W/x.json" 2> "$W/err3.txt"; then echo "FAIL: mlp on torque"; exit 1; fi
grep -q "physics or hybrid" "$W/err3.txt" || { echo "FAIL: the method refusal"; cat "$W/err3.txt"; exit 1; }
if "$B" monitor --twin "$W/twin.json" --rtde 127.0.0.1:1 --db '' 2> "$W/err4.txt"; then echo "FAIL: RTDE with a torque twin"; exit 1; fi
grep -q "RTDE does not stream" "$W/err4.txt" || { echo "FAIL: the RTDE refusal"; cat "$W/err4.txt"; exit 1; }
echo JOINT-TORQUE-SENSORS-OK
