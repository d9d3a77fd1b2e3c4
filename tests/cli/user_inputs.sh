#!/bin/sh
# What a user hands the tools by mistake (the session-34 audit), on the pipeline's recordings and twin:
# each is refused or said, with the file and the value, and nothing of the user's is replaced.
# usage: user_inputs.sh TWINWATCH PIPELINE_DIR SCENARIO WORK_DIR
set -e
B=$1; D=$2; SC=$3; W=$4
rm -rf "$W"; mkdir -p "$W"
fail() { echo "FAIL: $*"; exit 1; }
# 1. validate predicts with the payload the recording declares (0.5 kg, as the monitor does): the same
#    figures as told --payload-mass 0.5; --keep-payload keeps the twin's (none) and says so
declared=$("$B" validate --twin "$D/twin.json" "$D/fig.csv" --json)
told=$("$B" validate --twin "$D/twin.json" "$D/fig.csv" --payload-mass 0.5 --payload-com 0 0 0.04 --json)
[ "$declared" = "$told" ] || fail "validate without --payload-mass: $declared, told: $told"
"$B" validate --twin "$D/twin.json" "$D/fig.csv" 2>&1 | grep -q "validated with the payload it declares, as the monitor predicts (0.50 kg at (0.000, 0.000, 0.040) m from the start" \
  || fail "no note of the declared payload"
kept=$("$B" validate --twin "$D/twin.json" "$D/fig.csv" --keep-payload --json)
[ "$kept" != "$declared" ] || fail "--keep-payload changed nothing"
"$B" validate --twin "$D/twin.json" "$D/fig.csv" --keep-payload 2>&1 | grep -q -- "--keep-payload: validated with no payload throughout" || fail "--keep-payload not said"
# 2. a dead current channel (J6 logged as 0) has no R², NRMSE or d_tau: n/a, null, and said
awk -F, -v OFS=, 'NR==1{for(i=1;i<=NF;i++) if($i=="actual_current_5") c=i} NR>1{$c=0} {print}' "$D/fig.csv" > "$W/dead.csv"
out=$("$B" validate --twin "$D/twin.json" "$W/dead.csv" 2>&1)
echo "$out" | grep -q "^R² .* n/a$" || fail "R² of the dead channel: $out"
echo "$out" | grep -q "note: J6's measured current is 0 A in every sample" || fail "dead channel not said: $out"
"$B" validate --twin "$D/twin.json" "$W/dead.csv" --json | grep -q '"measured_constant":0.0,"nrmse_pct":null,"r2":null' || fail "dead channel in JSON"
# 3. --known-payload takes plain numbers only, and no centre of mass metres away
for arg in "0.5kg" "0.5,0,0,4cm" "0.5,0,0,40"; do
  if "$B" identify "$D/exc.csv" --known-payload "$D/exc.csv=$arg" -o "$W/never.json" -q > "$W/err" 2>&1; then fail "--known-payload $arg taken"; fi
  grep -q "known-payload .*$arg" "$W/err" || fail "--known-payload $arg: $(cat "$W/err")"
done
[ ! -e "$W/never.json" ] || fail "a twin was written"
# 4. evaluate's outputs are never its inputs; nothing is touched before they are checked
cp "$SC" "$W/victim.yaml"
for opt in --trend-csv --save-twin; do
  if "$B" evaluate "$W/victim.yaml" --twin "$D/twin.json" $opt "$W/victim.yaml" > "$W/err" 2>&1; then fail "evaluate $opt over the scenario"; fi
  grep -q "victim.yaml: cannot write: it is the input" "$W/err" || fail "evaluate $opt: $(cat "$W/err")"
  cmp -s "$SC" "$W/victim.yaml" || fail "evaluate $opt changed the scenario"
done
# 5. a joint temperature no joint reads (0xFFFF/10) is a sensor fault on that channel, not a contact
awk -F, -v OFS=, 'NR==1{for(i=1;i<=NF;i++) if($i=="joint_temperatures_2") c=i} NR==1001{$c=6553.5} {print}' "$D/fig.csv" > "$W/hot.csv"
ev=$("$B" monitor --twin "$D/twin.json" "$W/hot.csv" --db '' --json)
echo "$ev"
[ "$(echo "$ev" | wc -l)" -eq 1 ] || fail "expected one event"
for want in '"class":"sensor_fault"' '"joint":3,' 'temperature reads 6553.5 °C' '"units":"°C"'; do
  echo "$ev" | grep -q "$want" || fail "not a temperature sensor fault on J3 ($want)"
done
# 6. an unknown verb is named; evaluate with every scenario skipped evaluated nothing and says so; a
#    column map that is a directory is no (empty) map
if "$B" serv > "$W/err" 2>&1; then fail "an unknown verb ran"; fi
grep -q "'serv' is not a twinwatch command; the commands are: .*serve-robot" "$W/err" || fail "unknown verb: $(cat "$W/err")"
if "$B" evaluate "$SC" --twin "$D/twin.json" --max-duration 1 --json > "$W/err" 2>&1; then fail "evaluate of nothing succeeded"; fi
grep -q "every scenario (1) is longer than --max-duration 1 s: nothing evaluated" "$W/err" || fail "evaluate of nothing: $(cat "$W/err")"
if "$B" validate --twin "$D/twin.json" "$D/fig.csv" --column-map "$W" > "$W/err" 2>&1; then fail "a directory taken as a column map"; fi
grep -q "cannot read the column map: it is a directory" "$W/err" || fail "column map directory: $(cat "$W/err")"
# 7. an option that does nothing in this run is refused (exit 2, naming it), not ignored
refused() { # EXPECTED-MESSAGE COMMAND...
  want=$1; shift
  set +e; "$B" "$@" > "$W/err" 2>&1; rc=$?; set -e
  [ "$rc" -eq 2 ] || fail "$* exited $rc, expected 2: $(cat "$W/err")"
  grep -q -- "$want" "$W/err" || fail "$*: $(cat "$W/err")"
}
refused "--robot applies only to the twin trained here" evaluate "$SC" --twin "$D/twin.json" --robot panda
refused "--links applies only with --sweep-collisions" evaluate "$SC" --twin "$D/twin.json" --links 3
refused "--links, --magnitudes apply only with --sweep-collisions" evaluate "$SC" --twin "$D/twin.json" --links 3 --magnitudes 5,2
refused "--static applies only to scenario files" evaluate --sweep-collisions --static
refused "--prune applies only to --method sequential, not physics" identify "$D/exc.csv" --prune 1e-3 -o "$W/never.json"
refused "--hidden applies only to --method mlp or hybrid, not sequential" identify "$D/exc.csv" --method sequential --hidden 8 -o "$W/never.json"
refused "--velocity-lag applies only to --method physics, mlp or hybrid" identify "$D/exc.csv" --method sequential --velocity-lag 0.01 -o "$W/never.json"
refused "--wait applies only with --rtde" monitor --twin "$D/twin.json" "$D/fig.csv" --wait 0 --db ''
refused "--friction-table applies only with --published" validate-torque "$D/exc.csv" --model "$D/twin.json" --friction-table "$W/err"
[ ! -e "$W/never.json" ] || fail "a twin was written"
refused "--trials applies only to the offline study" friction-study --closed-loop --trials 3
# 8. messages name the file: a recording too short to align or to learn from, a store that is a
#    directory, an output the disk cannot take
head -3 "$D/fig.csv" > "$W/two.csv"
refused "two.csv: 2 row(s), expected at least 4 to align" align "$D/fig.csv" "$W/two.csv"
cp "$D/twin.json" "$W/twin.json"
refused "no sample of the healthy run(s) to learn from: $W/two.csv (2 samples)" thresholds --twin "$W/twin.json" "$W/two.csv"
cmp -s "$D/twin.json" "$W/twin.json" || fail "the twin changed"
refused "$W: cannot open event store: it is a directory" events --db "$W"
if [ -w /dev/full ]; then
  if "$B" validate --twin "$D/twin.json" "$D/fig.csv" --predictions /dev/full > "$W/err" 2>&1; then fail "a full disk took the predictions"; fi
  grep -q "/dev/full: cannot write" "$W/err" || fail "predictions on a full disk: $(cat "$W/err")"
fi
# 9. a column map may start with the format's own header line (docs/recordings.md)
printf 'file_column,rtde_name,scale\nactual_q_0,actual_q_0,1\n' > "$W/head.map"
"$B" validate --twin "$D/twin.json" "$D/fig.csv" --column-map "$W/head.map" --json > "$W/mapped.json" || fail "the map's header refused"
[ "$(cat "$W/mapped.json")" = "$("$B" validate --twin "$D/twin.json" "$D/fig.csv" --json)" ] || fail "an identity map changed the figures"
# 10. an implausible temperature in a training recording is held as the monitor holds it, and said
"$B" thresholds --twin "$W/twin.json" "$W/hot.csv" "$D/fig.csv" > "$W/out" 2>&1 || fail "thresholds on hot.csv: $(cat "$W/out")"
grep -q "hot.csv: 1 joint temperature reading(s) outside -40 to 150 °C" "$W/out" || fail "the held temperature not said: $(cat "$W/out")"
# 11. one 20 A current sample on J3 (an electrical spike) is a sensor fault on that channel, not a 361 N contact
awk -F, -v OFS=, 'NR==1{for(i=1;i<=NF;i++) if($i=="actual_current_2") c=i} NR==1001{$c=20} {print}' "$D/fig.csv" > "$W/spike.csv"
ev=$("$B" monitor --twin "$D/twin.json" "$W/spike.csv" --db '' --json)
[ "$(echo "$ev" | wc -l)" -eq 1 ] || fail "expected one event: $ev"
for want in '"class":"sensor_fault"' '"joint":3,' '"magnitude":20.0' '"units":"A"' 'glitch on the J3 current channel'; do
  echo "$ev" | grep -q "$want" || fail "the spike: $want not in $ev"
done
# 12. simulate writes files: '-' and /dev/stdout are refused (they wrote a file named '-', and labels into /dev)
refused "('-' is no standard output here)" simulate "$SC" -o -
refused "not a device or pipe" simulate "$SC" -o /dev/stdout
[ ! -e ./- ] || fail "simulate wrote a file named '-'"
# 13. (session-35 audit of the other verbs) outputs are no inputs and are checked before the work
cp "$D/exc.csv" "$W/victim.csv"
refused "victim.csv: cannot write: it is the input" identify-torque "$W/victim.csv" -o "$W/victim.csv" --signal target_moment
cmp -s "$D/exc.csv" "$W/victim.csv" || fail "identify-torque wrote over its recording"
refused "are the same file" identify-torque "$W/victim.csv" "$W/victim.csv" -o "$W/m.json" --signal target_moment
refused "$W: cannot write: it is a directory" identify-torque "$W/victim.csv" -o "$W" --signal target_moment
printf '{}' > "$W/rob.json"
refused "rob.json: cannot write: it is the input" excite "$W/rob.json" -o "$W/rob.json"
[ "$(cat "$W/rob.json")" = "{}" ] || fail "excite wrote over the robot description"
refused "$W: cannot write: it is a directory" agv make-tests -o "$W"
# friction-study: values that fell back to defaults, options that did nothing, a recording twice
refused "--joint 7: the simulated joints are 1, 2 and 3" friction-study --simulated --joint 7
refused "--hops is -2, expected a count >= 0" friction-study --simulated --hops -2
refused "--l1 is nan" friction-study --simulated --l1 nan
refused "--functions is empty" friction-study --simulated --functions ''
refused "--gain applies only to recordings" friction-study --simulated --gain 2
refused "--pd-scale applies only with --closed-loop" friction-study --simulated --pd-scale 1
refused "are the same file" friction-study "$D/fig.csv" "$D/fig.csv"
# align: a search window too large for an int searched nothing; two different motions are said to be
head -1 "$D/fig.csv" > "$W/late.csv"; tail -n +12 "$D/fig.csv" >> "$W/late.csv"
"$B" align "$D/fig.csv" "$W/late.csv" --max-lag-ms 1e20 | grep -q "common lag -10.00 samples = -20.0 ms" || fail "align --max-lag-ms 1e20"
"$B" align "$D/fig.csv" "$D/exc.csv" 2> "$W/err" > /dev/null
grep -q "correlate below 0.8 at the lag found: are .* recordings of the same motion" "$W/err" || fail "align of two motions: $(cat "$W/err")"
# a recording within the monitor's start-up judged nothing, and says so
head -46 "$D/collision.csv" > "$W/c45.csv"
"$B" monitor --twin "$D/twin.json" "$W/c45.csv" --db '' 2> "$W/err" > /dev/null
grep -q "no sample was judged: the 45 sample(s)" "$W/err" || fail "a 45-sample recording: $(cat "$W/err")"
# record --outputs without the recording's own columns wrote them as nan (refused before connecting)
refused "--outputs lacks actual_qd" record --rtde 127.0.0.1:1 --outputs actual_q,timestamp --duration 1 -o "$W/o_q.csv"
# report shows the monitor's notes (here: the declaration it predicts with over --payload-mass 2);
# a labels path that is a directory and a corrupt event store are bad input (exit 2), named
"$B" report --twin "$D/twin.json" "$D/fig.csv" -o "$W/r.html" --payload-mass 2 > /dev/null
grep -q "the twin had 2.00 kg): the twin predicts with the declaration" "$W/r.html" || fail "the report hides the payload it predicted with"
refused "$W: cannot read the labels file: it is a directory" report --twin "$D/twin.json" "$D/fig.csv" --labels "$W" -o "$W/r2.html"
# (sqlite3 is installed by scripts/setup.sh)
"$B" monitor --twin "$D/twin.json" "$D/collision.csv" --db "$W/ev.db" -q
sqlite3 "$W/ev.db" "UPDATE events SET other_links = 'abc';"
refused "events row id 1: column 'other_links': expected a list of link numbers" events --db "$W/ev.db"
sqlite3 "$W/ev.db" "UPDATE events SET other_links = NULL, confidence = 7;"
refused "events row id 1: column 'confidence': expected a confidence from 0 to 1, got '7" events --db "$W/ev.db"
sqlite3 "$W/ev.db" "UPDATE events SET confidence = 1, t_end = t_start - 1;"
refused "events row id 1: column 't_end': expected a finite time \[s\] not before t_start" events --db "$W/ev.db"
# another run's labels would shade faults that never happened; a COM 100 m out is a unit slip
refused "the labels of scenario 'short_declared_pick' (8 s at 500 Hz) do not go with $D/fig.csv" \
  report --twin "$D/twin.json" "$D/fig.csv" --labels "$D/declared_pick.labels.json" -o "$W/r3.html"
refused "--payload-com 100 0 0: expected a centre of mass within 1 m of the flange" \
  report --twin "$D/twin.json" "$D/fig.csv" --payload-mass 0.5 --payload-com 100 0 0 -o "$W/r4.html"
"$B" report --twin "$D/twin.json" "$D/fig.csv" --labels "$D/collision.labels.json" -o "$W/r5.html" 2> "$W/err" > /dev/null
grep -q "is not $D/fig.csv's own labels file ($D/fig.labels.json): the spans shaded are those of scenario 'short_collision'" "$W/err" \
  || fail "labels of another run of the same length: $(cat "$W/err")"
# the robot description is an input too: identify -o and simulate -o must not replace it
cp "$(dirname "$SC")/../../../data/robots/ur3e.json" "$W/myrobot.json" || fail "no data/robots/ur3e.json beside $SC"
cp "$W/myrobot.json" "$W/myrobot.orig"
refused "cannot write: it is the input" identify "$D/fig.csv" "$D/exc.csv" -o "$W/myrobot.json" --robot "$W/myrobot.json"
printf 'robot: %s\nduration: 1\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 8}\n' "$W/myrobot.json" > "$W/rs.yaml"
refused "cannot write: it is the input" simulate "$W/rs.yaml" -o "$W/myrobot.json"
cmp -s "$W/myrobot.json" "$W/myrobot.orig" || fail "the robot description was replaced"
# unit slips in a recording's currents (mA) and its payload declaration (g, mm): refused with the scale
awk -F, 'NR>1{for(i=32;i<=37;i++)$i=$i*1000}1' OFS=, "$D/fig.csv" > "$W/mA.csv"
refused "mA.csv: J1's current is above .* are the currents in mA" identify "$W/mA.csv" "$D/exc.csv" -o "$W/t_mA.json"
refused "are the currents in mA" monitor --twin "$D/twin.json" "$W/mA.csv" --db ''
head -1 "$D/declared_pick.csv" | tr , '\n' | grep -n '^payload$' | grep -q '^59:' || fail "declared_pick.csv: payload is not column 59"
awk -F, 'NR>1{$59=$59*1000}1' OFS=, "$D/declared_pick.csv" > "$W/pay_g.csv"
awk -F, 'NR>1{$62=$62*1000}1' OFS=, "$D/declared_pick.csv" > "$W/cog_mm.csv"
cp "$D/twin.json" "$W/tw.json"
refused "column 'payload' declares 500 kg at t = 3.000 s (sample 1501), more than 3 kg (the rated payload of ur3e): is it in grams" \
  thresholds "$W/pay_g.csv" --twin "$W/tw.json"
refused "declare a centre of mass (0, 0, 40) 40 m from the flange .* is it in mm" identify "$W/cog_mm.csv" "$D/exc.csv" -o "$W/t_mm.json"
cmp -s "$W/tw.json" "$D/twin.json" || fail "thresholds on a refused recording changed the twin"
# --program '' (an unset variable) silently meant the default set
refused "--program: the program name is empty" thresholds "$D/fig.csv" --twin "$W/tw.json" --program ''
# evaluate reads every scenario before it touches an output: a bad one left --save-twin replaced
echo precious > "$W/keep.json"
printf 'robot: ur3e\nduration: 5\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 8}\nfaults: [{type: resistance, joint: 7, onset: 1, magnitude: 1}]\n' > "$W/j7.yaml"
refused "faults\[0\].joint" evaluate "$W/j7.yaml" --twin "$D/twin.json" --save-twin "$W/keep.json"
[ "$(cat "$W/keep.json")" = precious ] || fail "evaluate replaced --save-twin before failing on a scenario"
refused "are the same file" evaluate "$SC" "$SC" --twin "$D/twin.json"
# two monitor outputs on one file; a corrupted current word is a sensor fault, not an error mid-run
refused "--events and --trace name the same file" monitor --twin "$D/twin.json" "$D/collision.csv" --db '' --events "$W/same" --trace "$W/same"
head -3001 "$D/collision.csv" | awk -F, 'NR==101{$34="1.7e308"}1' OFS=, > "$W/huge.csv"
"$B" monitor --twin "$D/twin.json" "$W/huge.csv" --db '' | grep -q "sensor_fault .*J3 current is 1.7e+308, beyond" || fail "a 1.7e308 A current"
refused "column 'actual_current_2' is 1.7e+308 A at t = 0.198 s (sample 100)" thresholds "$W/huge.csv" --twin "$W/tw.json"
# friction-study: options that did nothing on recordings, and currents labelled N·m
refused "--rich-training applies only to the simulated joints" friction-study "$D/exc.csv" --rich-training
refused "--gain applies only with --torque current" friction-study "$D/exc.csv" --torque moment --gain 5
refused "--joint 2 is given twice" friction-study "$D/exc.csv" --joint 2 --joint 2
"$B" friction-study "$D/exc.csv" --joint 2 --json -q | grep -q '"torque_units":"A"' || fail "friction-study on currents without --gain: not in A"
# --quick runs the model check alone: the whole demo's options did nothing there
refused "--scenarios applies only to the whole demo, not --quick" demo --quick --scenarios "$W"
# a twin file's payload is the default payload (0 kg as identify writes it); a slip in it is named
[ "$(grep -c '"mass"' "$D/twin.json")" = 1 ] || fail "twin.json: expected one \"mass\" key (the payload's)"
sed 's/"mass": *0\.0/"mass": 500.0/' "$D/twin.json" > "$W/tw500.json"
grep -q '"mass": 500.0' "$W/tw500.json" || fail "could not set the twin file's payload"
refused "tw500.json: field 'payload.mass': expected at most 3 kg" monitor --twin "$W/tw500.json" "$D/fig.csv" --db ''
refused "sensitivity (--sensitivity) of joint 1 is 1000000000, expected a factor > 0 and at most 10" monitor --twin "$D/twin.json" "$D/fig.csv" --db '' --sensitivity 1e9
# a number option given an empty value ran with 0; a whole number beyond 64 bits was read as the largest one
refused "--duration: expected a number, got '' (an empty value)" simulate "$SC" -o "$W/empty.csv" --duration ''
refused "--seed: expected a whole number, got '99999999999999999999', beyond the range of a 64-bit integer" \
  simulate "$SC" -o "$W/big.csv" --seed 99999999999999999999
refused "--raise-after: .*got ''" monitor --twin "$D/twin.json" "$D/fig.csv" --db '' --raise-after ''
[ ! -e "$W/empty.csv" ] && [ ! -e "$W/big.csv" ] || fail "a refused simulate wrote a recording"
# --json says the units of what it prints
"$B" validate --twin "$D/twin.json" "$D/fig.csv" --json | grep -q '"units":{.*"rmse":"A"' || fail "validate --json without units"
# report: a log of another joint count is named as monitor names it; labels on another clock, empty
# file options, and an events class left empty are refused, not taken as "none given"
awk -F, 'NR==1{for(i=1;i<=NF;i++) drop[i]=($i ~ /_5$/)} {o=""; for(i=1;i<=NF;i++) if(!drop[i]) o=o (o==""?"":",") $i; print o}' \
  "$D/collision.csv" > "$W/five.csv"
refused "five.csv has 5 joints, the robot (ur3e) 6" report --twin "$D/twin.json" "$W/five.csv" -o "$W/five.html"
awk -F, -v OFS=, 'NR>1{$1=$1+42}1' "$D/collision.csv" > "$W/shifted.csv"
refused "put fault 1 (collision) at 6\.[0-9]* s, outside .*shifted.csv's timestamps 42\.[0-9]*-5[0-9]\.[0-9]* s" \
  report --twin "$D/twin.json" "$W/shifted.csv" --labels "$D/collision.labels.json" -o "$W/shifted.html"
refused "--labels: expected a file name, got '' (an empty value)" report --twin "$D/twin.json" "$D/collision.csv" --labels '' -o "$W/l.html"
refused "--column-map: expected a file name, got '' (an empty value)" validate --twin "$D/twin.json" "$D/fig.csv" --column-map ''
refused "--class is empty" events --db "$W/none.db" --class ''
[ ! -e "$W/five.html" ] && [ ! -e "$W/shifted.html" ] && [ ! -e "$W/l.html" ] || fail "a refused report wrote its page"
# align: nothing to align is said, not "in step"; a search window below half a sample is refused
awk -F, -v OFS=, 'NR==1{for(i=1;i<=NF;i++) if($i ~ /^actual_current_/) c[i]=1} NR>1{for(i in c) $i=1.5}1' "$D/fig.csv" > "$W/flat.csv"
cp "$W/flat.csv" "$W/flat2.csv"
refused "actual_current is constant on every joint in .*flat.csv or .*flat2.csv: there is nothing to align" align "$W/flat.csv" "$W/flat2.csv" --signal actual_current
refused "--max-lag-ms 0.5 is less than half the sample period (2 ms)" align "$W/flat.csv" "$W/flat2.csv" --max-lag-ms 0.5
# demo: a --max-duration that leaves nothing to evaluate is refused before the minute of training
refused "every scenario .* is longer than --max-duration 1 s: nothing would be evaluated" demo --max-duration 1 -o "$W/demo1"
[ ! -e "$W/demo1/twin.json" ] || fail "demo trained before refusing --max-duration"
# record --outputs: an empty list (an unset variable) or an empty item is refused before connecting
refused "--outputs: expected a comma-separated list of RTDE output names, got '' (an empty value)" record --rtde 127.0.0.1:1 --outputs '' -o "$W/o.csv"
refused "--outputs 'timestamp,,actual_q,actual_qd': 1 of its 4 items are empty" record --rtde 127.0.0.1:1 --outputs 'timestamp,,actual_q,actual_qd' -o "$W/o.csv"
echo USER-INPUTS-OK
