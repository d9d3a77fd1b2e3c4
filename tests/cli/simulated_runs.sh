# Sourced by the end-to-end checks of a twin on simulated recordings (without_targets.sh,
# joint_torque_sensors.sh). simulated_runs B D W LINE PERIOD SLOW_S writes and simulates into W:
#   exc, fig  the identification's healthy runs (D's short excitation and figure-eight),
#   slow      a healthy figure-eight of PERIOD s with the 0.5 kg payload, SLOW_S s long (seed 8),
#   hit       the same figure-eight with a 5 N·m contact on link 3 at 13 s (seed 9, 20 s),
# each scenario with LINE (a YAML line, e.g. 'streams_targets: false') appended.
simulated_runs() {
  _b=$1; _d=$2; _w=$3; _line=$4; _period=$5; _slow=$6
  mkdir -p "$_w"
  (cat "$_d/short_exc.yaml"; echo "$_line") > "$_w/exc.yaml"
  (cat "$_d/short_fig8.yaml"; echo "$_line") > "$_w/fig.yaml"
  _run="robot: ur3e
trajectory: {type: figure_eight, size: [0.12, 0.08], period: $_period, tilt: [0.3, 0.4, 0.5]}
payload: {mass: 0.5, com: [0, 0, 0.04]}
$_line"
  printf 'name: slow\nseed: 8\nduration: %s\n%s\n' "$_slow" "$_run" > "$_w/slow.yaml"
  printf 'name: hit\nseed: 9\nduration: 20\n%s\nfaults:\n  - {type: collision, link: 3, onset: 13.0, magnitude: 5, duration: 0.05, point: [0.1, 0.0, 0.05], direction: [0.0, 0.3, 1.0]}\n' "$_run" > "$_w/hit.yaml"
  for _n in exc fig slow hit; do "$_b" simulate "$_w/$_n.yaml" -o "$_w/$_n.csv" -q || return 1; done
}

# slow_quiet_contact_found B W: W/twin.json watching W/slow.csv raises nothing, and W/hit.csv one
# contact, on link 3 (its JSON line left in $hit for the caller's own checks)
slow_quiet_contact_found() {
  _b=$1; _w=$2
  _events=$("$_b" monitor --twin "$_w/twin.json" "$_w/slow.csv" --db '' --json | wc -l)
  hit=$("$_b" monitor --twin "$_w/twin.json" "$_w/hit.csv" --db '' --json)
  echo "slow run: $_events event(s)"
  echo "$hit"
  [ "$_events" -eq 0 ] || { echo "FAIL: false events on the slow run"; return 1; }
  [ "$(echo "$hit" | wc -l)" -eq 1 ] || { echo "FAIL: expected one event on the contact run"; return 1; }
  echo "$hit" | grep -q '"class":"collision".*"link":3' || { echo "FAIL: not a contact on link 3"; return 1; }
}
