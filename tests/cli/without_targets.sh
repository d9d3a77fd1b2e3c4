#!/bin/sh
# A log without the controller's targets, end to end (session 33): recordings simulated with
# `streams_targets: false`, a twin identified and its thresholds learned on them, then a figure-eight
# at 2.5x the speed-period it was learned at (slow reversals the encoder reads as 0 for tens of ms)
# raises nothing, and a 5 N·m contact on link 3 is found there. Before session 33 the slow run raised
# 3 false contacts.
# usage: without_targets.sh TWINWATCH DATA_DIR WORK_DIR
set -e
B=$1; D=$2; W=$3
. "$(dirname "$0")/simulated_runs.sh"
simulated_runs "$B" "$D" "$W" "streams_targets: false" 20 40
if head -1 "$W/exc.csv" | grep -q target_; then echo "FAIL: the recording has target columns"; exit 1; fi
"$B" identify "$W/exc.csv" "$W/fig.csv" --known-payload "$W/fig.csv=0.5,0,0,0.04" -o "$W/twin.json" -q
slow_quiet_contact_found "$B" "$W"
echo WITHOUT-TARGETS-OK
