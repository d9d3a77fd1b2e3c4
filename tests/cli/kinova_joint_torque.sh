#!/bin/sh
# A joint-torque twin of the real Kinova Gen3 (../shared/data/real/kinova_gen3_chiha), watching a run
# in which every Torque channel holds its value for 122 samples (1553-1674 ms) while the joints move
# (audit of session 55):
# - each channel's freeze is one sensor_fault event, and no other alert takes it for its cause (an
#   alert raised at 0.05 s had become "J1 frozen for 87 samples" when J1 froze at 1.55 s);
# - identify says that J7's fit means little (its sensor reads almost nothing: a wrist roll without a
#   payload), and of no other joint;
# - each alert is printed as ALERT once, its later diagnoses as UPDATE, also when another alert's
#   lines came between (the 0.05 s alert was printed as ALERT three times), and the channels that
#   froze at one sample are each an ALERT of their own (they were printed as UPDATEs of the first).
# Usage: kinova_joint_torque.sh TWINWATCH KINOVA_DIR ROBOT_URDF WORK_DIR
set -e
B=$1; K=$2; U=$3; W=$4
mkdir -p "$W"
"$B" identify "$K/RecordTrajectory_quadratic.csv" "$K/joint_2_trapez.csv" --robot "$U" --column-map kinova_gen3_chiha \
  --signal joint_torque -o "$W/twin.json" > "$W/identify.txt" 2> /dev/null
cat "$W/identify.txt"
# J7 (the wrist roll, no payload) reads +-0.0004 N·m while it moves: its fit is said to mean little
grep -q "note: J7's fit is far worse than a constant" "$W/identify.txt" || { echo "FAIL: J7's undetermined fit not said"; exit 1; }
if grep -q "note: J[1-6]'s fit is far worse" "$W/identify.txt"; then echo "FAIL: a joint with signal said to have none"; exit 1; fi
"$B" monitor --twin "$W/twin.json" "$K/RunTrajectory1.csv" --column-map kinova_gen3_chiha --db '' > "$W/monitor.txt" 2> /dev/null
cat "$W/monitor.txt"
frozen=$(grep -c 'sensor_fault   torque channel of J[1-7] frozen at [-0-9.]* N·m while the joint moves (122 samples)' "$W/monitor.txt" || true)
[ "$frozen" -eq 7 ] || { echo "FAIL: expected each of the 7 channels' freeze once, got $frozen"; exit 1; }
if grep -q 'frozen for [0-9]* samples' "$W/monitor.txt"; then echo "FAIL: an alert took another stretch's freeze for its cause"; exit 1; fi
raised=$(grep -c 'ALERT  torque channel of J[1-7] frozen at' "$W/monitor.txt" || true)
[ "$raised" -eq 7 ] || { echo "FAIL: expected 7 frozen-channel ALERT lines, got $raised"; exit 1; }
# no alert raised twice: the times of the ALERT lines are those of distinct alerts, and the one at
# 0.051 s (J5's) is printed once
first=$(grep -c '^ *0\.051 s  ALERT' "$W/monitor.txt" || true)
[ "$first" -eq 1 ] || { echo "FAIL: the alert raised at 0.051 s printed as ALERT $first times"; exit 1; }
echo KINOVA-JOINT-TORQUE-OK
