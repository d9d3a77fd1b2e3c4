#!/bin/sh
# A foreign log runs the whole monitoring pipeline through --column-map exactly as the same data in
# RTDE columns does: thresholds (and their debounce validation), monitor and report. The foreign log
# renames timestamp and the currents and stores the currents doubled (the map's scale 0.5 undoes it
# exactly in binary), so any column the map leaves out or any scale not applied changes the output.
# Usage: column_map_pipeline.sh TWINWATCH TWIN.json HEALTHY_A.csv HEALTHY_B.csv FAULT.csv WORKDIR
set -e
tw=$1 twin=$2 a=$3 b=$4 fault=$5 dir=$6
foreign() {  # RTDE CSV -> foreign CSV: "time", "I0_x2".."I5_x2" (current doubled), other columns as they are
  awk -F, 'BEGIN { OFS = "," }
    NR == 1 { for (k = 1; k <= NF; ++k) { if ($k == "timestamp") $k = "time";
                if ($k ~ /^actual_current_[0-9]$/) { c[k] = 1; sub(/^actual_current_/, "I", $k); $k = $k "_x2" } } print; next }
    { for (k in c) $k = sprintf("%.17g", 2 * $k); print }' "$1" > "$2"
}
foreign "$a" "$dir/cm_a.csv"; foreign "$b" "$dir/cm_b.csv"; foreign "$fault" "$dir/cm_fault.csv"
map="$dir/cm_map.csv"
{ echo "# foreign log: currents doubled"; echo "time,timestamp"
  for j in 0 1 2 3 4 5; do echo "I${j}_x2,actual_current_$j,0.5"; done; } > "$map"
cp "$twin" "$dir/cm_twin_rtde.json"; cp "$twin" "$dir/cm_twin_foreign.json"
"$tw" thresholds --twin "$dir/cm_twin_rtde.json" "$a" --payload-mass 0.5 --debounce-validation "$b" > "$dir/cm_thr_rtde.txt"
"$tw" thresholds --twin "$dir/cm_twin_foreign.json" "$dir/cm_a.csv" --payload-mass 0.5 --debounce-validation "$dir/cm_b.csv" \
  --column-map "$map" > "$dir/cm_thr_foreign.txt"
cmp "$dir/cm_twin_rtde.json" "$dir/cm_twin_foreign.json" || { echo "thresholds learned differently from the foreign log"; exit 1; }
t="$dir/cm_twin_rtde.json"
"$tw" monitor --twin "$t" "$fault" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --json > "$dir/cm_ev_rtde.jsonl"
"$tw" monitor --twin "$t" "$dir/cm_fault.csv" --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --json --column-map "$map" \
  > "$dir/cm_ev_foreign.jsonl"
[ -s "$dir/cm_ev_rtde.jsonl" ] || { echo "no event on the fault recording"; exit 1; }
cmp "$dir/cm_ev_rtde.jsonl" "$dir/cm_ev_foreign.jsonl" || { echo "monitor saw the foreign log differently"; exit 1; }
"$tw" report --twin "$t" "$dir/cm_fault.csv" --payload-mass 0.5 --payload-com 0 0 0.04 --column-map "$map" -q \
  -o "$dir/cm_report.html" > "$dir/cm_report.out"
[ -s "$dir/cm_report.html" ] && [ ! -s "$dir/cm_report.out" ] || { echo "report: no page, or printed with -q"; exit 1; }
# without the map the foreign log has no currents: refused by name
if "$tw" monitor --twin "$t" "$dir/cm_fault.csv" --db '' 2> "$dir/cm_err.txt"; then echo "foreign log read without its map"; exit 1; fi
grep -q "cm_fault.csv:1: field .timestamp.: missing required column" "$dir/cm_err.txt" || { echo "refusal does not name the missing field:"; cat "$dir/cm_err.txt"; exit 1; }
# mixed sources (session 25): the robot's own recording and a foreign log, each read with its own map
# (REC=MAP), learn what the two RTDE recordings learn; identify too (its validation on the fault
# recording is the same to the last digit)
cp "$twin" "$dir/cm_twin_mixed.json"
"$tw" thresholds --twin "$dir/cm_twin_mixed.json" "$a" --payload-mass 0.5 --debounce-validation "$dir/cm_b.csv" \
  --column-map "$dir/cm_b.csv=$map" > "$dir/cm_thr_mixed.txt"
cmp "$dir/cm_twin_rtde.json" "$dir/cm_twin_mixed.json" || { echo "thresholds learned differently from a mixed set"; exit 1; }
"$tw" identify "$a" "$b" -q -o "$dir/cm_id_rtde.json"
"$tw" identify "$a" "$dir/cm_b.csv" --column-map "$dir/cm_b.csv=$map" -q -o "$dir/cm_id_mixed.json"
# (the JSON names the twin file: left out)
"$tw" validate --twin "$dir/cm_id_rtde.json" "$fault" --json | sed 's/,"twin":"[^"]*"//' > "$dir/cm_val_rtde.json"
"$tw" validate --twin "$dir/cm_id_mixed.json" "$fault" --json | sed 's/,"twin":"[^"]*"//' > "$dir/cm_val_mixed.json"
grep -q '"joints":\[{"d_tau_pct"' "$dir/cm_val_rtde.json" || { echo "no validation"; exit 1; }
cmp "$dir/cm_val_rtde.json" "$dir/cm_val_mixed.json" || { echo "identify learned differently from a mixed set"; exit 1; }
# a map for a file that is not one of the recordings, and two maps for all, are refused by name
if "$tw" identify "$a" --column-map "nope.csv=$map" -q -o "$dir/cm_never.json" 2> "$dir/cm_err2.txt"; then echo "a map for no recording taken"; exit 1; fi
grep -q "column-map 'nope.csv=.*': no map file of that name, and 'nope.csv' before '=' is none of the recordings" "$dir/cm_err2.txt" || { cat "$dir/cm_err2.txt"; exit 1; }
if "$tw" identify "$a" --column-map "$map" --column-map kinova_gen3_chiha -q -o "$dir/cm_never.json" 2> "$dir/cm_err3.txt"; then echo "two maps for all taken"; exit 1; fi
grep -q "two maps for every recording" "$dir/cm_err3.txt" || { cat "$dir/cm_err3.txt"; exit 1; }
[ ! -e "$dir/cm_never.json" ] || { echo "a twin was written after a refused map"; exit 1; }
if "$tw" identify "$a" --column-map '' -q -o "$dir/cm_never.json" 2> "$dir/cm_err4.txt"; then echo "an empty map taken"; exit 1; fi
grep -q -- "--column-map: expected a file name, got '' (an empty value)" "$dir/cm_err4.txt" || { cat "$dir/cm_err4.txt"; exit 1; }
# a recording whose name holds a '=' gets its own map; a shipped map given by name is an input that
# -o must not replace (the file it resolves to, not the name)
cp "$dir/cm_b.csv" "$dir/run=1.csv"
"$tw" identify "$a" "$dir/run=1.csv" --column-map "$dir/run=1.csv=$map" -q -o "$dir/cm_id_eq.json"
"$tw" validate --twin "$dir/cm_id_eq.json" "$fault" --json | sed 's/,"twin":"[^"]*"//' > "$dir/cm_val_eq.json"
cmp "$dir/cm_val_rtde.json" "$dir/cm_val_eq.json" || { echo "a recording named with '=' was mapped differently"; exit 1; }
mkdir -p "$dir/data/column_maps" && cp "$map" "$dir/data/column_maps/shipped.csv"
if TWINWATCH_DATA_DIR="$dir/data" "$tw" identify "$a" "$dir/cm_b.csv" --column-map "$dir/cm_b.csv=shipped" -q \
     -o "$dir/data/column_maps/shipped.csv" 2> "$dir/cm_err5.txt"; then echo "a shipped map overwritten"; exit 1; fi
grep -q "cannot write: it is the input" "$dir/cm_err5.txt" || { cat "$dir/cm_err5.txt"; exit 1; }
cmp "$map" "$dir/data/column_maps/shipped.csv" || { echo "the shipped map changed"; exit 1; }
echo "SAME-THROUGH-THE-COLUMN-MAP: $(wc -l < "$dir/cm_ev_rtde.jsonl") event(s)"
