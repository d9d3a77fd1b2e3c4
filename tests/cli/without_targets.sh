#!/bin/sh
# A log without the controller's targets, end to end (session 33): recordings simulated with
# `streams_targets: false`, a twin identified and its thresholds learned on them, then a figure-eight
# at 2.5x the speed-period it was learned at (slow reversals the encoder reads as 0 for tens of ms)
# raises nothing, and a 5 N·m contact on link 3 is found there. Before session 33 the slow run raised
# 3 false contacts.
# usage: without_targets.sh TWINWATCH DATA_DIR WORK_DIR
set -e
B=$1; D=$2; W=$3
mkdir -p "$W"
(cat "$D/short_exc.yaml"; echo "streams_targets: false") > "$W/exc.yaml"
(cat "$D/short_fig8.yaml"; echo "streams_targets: false") > "$W/fig.yaml"
run='robot: ur3e
trajectory: {type: figure_eight, size: [0.12, 0.08], period: 20, tilt: [0.3, 0.4, 0.5]}
payload: {mass: 0.5, com: [0, 0, 0.04]}
streams_targets: false'
printf 'name: slow\nseed: 8\nduration: 40\n%s\n' "$run" > "$W/slow.yaml"
printf 'name: hit\nseed: 9\nduration: 20\n%s\nfaults:\n  - {type: collision, link: 3, onset: 13.0, magnitude: 5, duration: 0.05, point: [0.1, 0.0, 0.05], direction: [0.0, 0.3, 1.0]}\n' "$run" > "$W/hit.yaml"
for n in exc fig slow hit; do "$B" simulate "$W/$n.yaml" -o "$W/$n.csv" -q; done
if head -1 "$W/exc.csv" | grep -q target_; then echo "FAIL: the recording has target columns"; exit 1; fi
"$B" identify "$W/exc.csv" "$W/fig.csv" --known-payload "$W/fig.csv=0.5,0,0,0.04" -o "$W/twin.json" -q
slow=$("$B" monitor --twin "$W/twin.json" "$W/slow.csv" --db '' --json | wc -l)
hit=$("$B" monitor --twin "$W/twin.json" "$W/hit.csv" --db '' --json)
echo "slow run: $slow event(s)"
echo "$hit"
[ "$slow" -eq 0 ] || { echo "FAIL: false events on the slow run"; exit 1; }
[ "$(echo "$hit" | wc -l)" -eq 1 ] || { echo "FAIL: expected one event on the contact run"; exit 1; }
echo "$hit" | grep -q '"class":"collision".*"link":3' || { echo "FAIL: not a contact on link 3"; exit 1; }
echo WITHOUT-TARGETS-OK
