#!/bin/bash
# Learns thresholds with two twinwatch binaries on the same ten cases and compares the twin files
# byte for byte (docs/validation.md, "Thresholds learned from a shift without holding it").
# The recordings are those the CLI tests leave in a build directory (run ctest -R cli first).
# Usage: scripts/compare_thresholds.sh OLD_TWINWATCH NEW_TWINWATCH BUILD_DIR WORKDIR
set -e
old=$(realpath "$1") new=$(realpath "$2") b=$(realpath "$3") w=$4
mkdir -p "$w" && cd "$w"
cp "$b/cli-pipeline/twin.json" twin.json && cp "$b/cli-pipeline/twin_notarget.json" twin_nt.json
cp "$b/cli-pipeline/fig.csv" fig.csv && cp "$b/cli-align/full.csv" full.csv && cp "$b/cli-pipeline/declared_pick.csv" pick.csv
cp "$b/cli-align/warm_10.csv" warm10.csv && cp "$b/cli-align/warm_20.csv" warm20.csv
col() { head -1 "$1" | tr ',' '\n' | grep -nx "$2" | cut -d: -f1; }
m=$(col fig.csv robot_mode) t2=$(col fig.csv joint_temperatures_2)
# a stop (robot_mode 5) on rows 1500-1799 and 2000-2099: two driven stretches and a short one left out
awk -F, -v OFS=, -v c="$m" 'NR>1 {r=NR-1; if ((r>=1500&&r<1800)||(r>=2000&&r<2100)) $c=5} {print}' fig.csv > stop.csv
# implausible temperatures of joint 3, inside a driven stretch and inside the stop
awk -F, -v OFS=, -v c="$t2" 'NR>1 {r=NR-1; if ((r>=3000&&r<3020)||(r>=1600&&r<1605)) $c=6553.5} {print}' stop.csv > temps.csv
# without the controller's targets (no target_* column)
keep=$(head -1 fig.csv | tr ',' '\n' | grep -vn '^target_' | cut -d: -f1 | paste -sd,)
cut -d, -f"$keep" fig.csv > nt_fig.csv && cut -d, -f"$keep" full.csv > nt_full.csv
for v in old new; do
  tw=$([ $v = old ] && echo "$old" || echo "$new"); mkdir -p $v
  run() { n=$1 t=$2; shift 2; cp "$t" $v/$n.json; "$tw" thresholds --twin $v/$n.json "$@" > $v/$n.out 2> $v/$n.err || echo "exit $?" >> $v/$n.err; }
  run A twin.json fig.csv --payload-mass 0.5 --debounce-validation full.csv
  run B twin.json warm10.csv --payload-mass 0.5
  run B2 $v/B.json warm20.csv --payload-mass 0.5 --program warm --debounce-validation full.csv
  run C twin.json pick.csv --payload-mass 0.5
  run D twin.json fig.csv full.csv warm10.csv --payload-mass 0.5 --filter fir
  run E twin.json stop.csv full.csv --payload-mass 0.5
  run F twin.json temps.csv --payload-mass 0.5 --debounce-validation stop.csv
  run G twin_nt.json nt_fig.csv --debounce-validation nt_full.csv
  run H twin.json fig.csv warm10.csv warm20.csv --payload-mass 0.5
  run I twin.json fig.csv --payload-mass 0.5 --program p1
done
same=0
for n in A B B2 C D E F G H I; do
  if cmp -s old/$n.json new/$n.json; then same=$((same + 1)); else echo "$n: twin files differ"; fi
done
echo "$same of 10 twin files identical"
