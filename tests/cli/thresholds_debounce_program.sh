#!/bin/sh
# The observer's per-joint debounce through the CLI, on two healthy recordings A and B of one program:
# chosen for the default set (thresholds on A, validated on B), then for a program's set (thresholds on
# B, validated on A) without touching the default set's choice; the monitor uses the set's own counts,
# and --raise-after alone drops them (the observer follows it, as before the per-joint choice).
# Usage: thresholds_debounce_program.sh TWINWATCH TWIN.json A.csv B.csv WORKDIR
set -e
tw=$1 twin=$2 a=$3 b=$4 dir=$5
cp "$twin" "$dir/twin_debp.json"
t="$dir/twin_debp.json"
counts_of() { sed -n 's/^observer debounce per joint:\{0,1\} \([12 ]*[12]\) .*/\1/p'; }
default=$("$tw" thresholds --twin "$t" "$a" --payload-mass 0.5 --debounce-validation "$b" | counts_of)
program=$("$tw" thresholds --twin "$t" "$b" --payload-mass 0.5 --program other --debounce-validation "$a" | counts_of)
[ -n "$default" ] && [ -n "$program" ] || { echo "no counts printed"; exit 1; }
echo "default set: $default; program 'other': $program"
case " $default " in *" 1 "*) ;; *) echo "no joint of the default set at one sample"; exit 1 ;; esac
seen_default=$("$tw" monitor --twin "$t" "$b" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' 2>&1 | counts_of)
seen_program=$("$tw" monitor --twin "$t" "$a" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --program other 2>&1 | counts_of)
[ "$seen_default" = "$default" ] || { echo "monitor uses '$seen_default' on the default set, chosen '$default'"; exit 1; }
[ "$seen_program" = "$program" ] || { echo "monitor uses '$seen_program' on program 'other', chosen '$program'"; exit 1; }
overridden=$("$tw" monitor --twin "$t" "$b" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --raise-after 3 2>&1 | counts_of)
[ -z "$overridden" ] || { echo "--raise-after 3 kept the per-joint counts '$overridden'"; exit 1; }
echo "EACH-SET-KEEPS-ITS-OWN-COUNTS"
