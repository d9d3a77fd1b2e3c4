# RTDE: the virtual controller and the recorder, two processes over loopback TCP.
add_test(NAME cli.rtde_serve_record
  COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/rtde_e2e.sh $<TARGET_FILE:twinwatch>
          ${PROJECT_SOURCE_DIR}/scenarios/ur3e/stream_and_sensor_faults.yaml ${PROJECT_BINARY_DIR}/cli-rtde 35917)
set_tests_properties(cli.rtde_serve_record PROPERTIES PASS_REGULAR_EXPRESSION "PASS" TIMEOUT 60)
add_test(NAME cli.rtde_record_not_found
  COMMAND twinwatch record --rtde 127.0.0.1:1 --duration 1 -o ${PROJECT_BINARY_DIR}/never.csv)
set_tests_properties(cli.rtde_record_not_found PROPERTIES WILL_FAIL TRUE)
add_test(NAME cli.rtde_record_bad_port COMMAND twinwatch record --rtde 127.0.0.1:99999 -o ${PROJECT_BINARY_DIR}/never.csv)
set_tests_properties(cli.rtde_record_bad_port PROPERTIES PASS_REGULAR_EXPRESSION "port '99999' is not a number in 1..65535")
# an address without a host (or a port with a sign) is bad usage, exit 2, not an unreachable robot
foreach(ep "" ":30004" "127.0.0.1:+80" "http://127.0.0.1:30004" "127.0.0.1:30004:5" "[::1:30004")
  string(MAKE_C_IDENTIFIER "x${ep}" epname)
  add_test(NAME cli.rtde_record_bad_address_${epname}
    COMMAND sh -c "$<TARGET_FILE:twinwatch> record --rtde '${ep}' -o ${PROJECT_BINARY_DIR}/never.csv 2>&1; echo exit=\$?")
  set_tests_properties(cli.rtde_record_bad_address_${epname} PROPERTIES
    PASS_REGULAR_EXPRESSION "(expected HOST\\[:PORT\\] \\(an IPv6 address in brackets: \\[::1\\]:30004\\), (the host is missing|not a URL|more than one ':'|the '\\[' has no '\\]')|port '\\+80' is not a number in 1..65535).*exit=2")
endforeach()
# live monitoring over RTDE: the J5 resistance of the scenario (onset 12 s + 42 s controller boot
# offset) is found from the stream, as it is from the recording, its line led by the wall-clock time
# of day (session 48) (the alert is printed when it
# closes: before the stream summary, or after it when the resistance is still on at the end)
add_test(NAME cli.rtde_monitor_live
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/j5_resistance.yaml --port 35918 --speed 8 --duration 20 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35918 --wait 10 --duration 4 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db ''; wait")
set_tests_properties(cli.rtde_monitor_live PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60 FAIL_REGULAR_EXPRESSION "is not the stream of"
  PASS_REGULAR_EXPRESSION "UTC +[45][0-9][.][0-9]+ s  note: the controller's clock runs [78][.][0-9]+ times as fast as this machine's[^\n]*events carry no wall-clock time[^\n]*\n.*\n +5[4-6]\\.[0-9]+ s  resistance +extra friction on J5")
# the stream's arm is checked on its first 10 s as a recording's is (review of session 48: a UR5e
# streamed to a UR3e's twin read as a payload change and said nothing else); the UR3e stream above
# raises no such warning
add_test(NAME cli.rtde_monitor_checks_the_arm
  COMMAND sh -c "sed 's/^robot: ur3e/robot: ur5e/' ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml > ${PROJECT_BINARY_DIR}/fig8_ur5e.yaml && \
($<TARGET_FILE:twinwatch> serve-robot ${PROJECT_BINARY_DIR}/fig8_ur5e.yaml --port 35962 --speed 8 --duration 14 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35962 --wait 10 --duration 3 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db '' -q 2>&1; wait)")
set_tests_properties(cli.rtde_monitor_checks_the_arm PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60
  PASS_REGULAR_EXPRESSION "WARNING: rtde://127.0.0.1:35962 is not the stream of a ur3e \\(the arm it is read for\\): [^\n]*reproduced by the ur5e's model \\(relative rms 0\\.[01][0-9]\\) and not by the ur3e's \\(0\\.[3-9][0-9][^\n]*identify a twin of this ur5e")
# serve-robot --wait-client waits for a client that streams (START), not one that only connects
add_test(NAME cli.serve_robot_help_wait_client COMMAND twinwatch serve-robot --help)
set_tests_properties(cli.serve_robot_help_wait_client PROPERTIES PASS_REGULAR_EXPRESSION "--wait-client[^\n]*until a client starts streaming")
# a connection lost and not restored before monitoring ends is a stream fault in the event history
# (it used to read as watched: "0 lost in 0 gaps", no event)
add_test(NAME cli.rtde_monitor_lost_until_the_end
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35919 --speed 8 --duration 2 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35919 --wait 10 --duration 3 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --json; wait")
set_tests_properties(cli.rtde_monitor_lost_until_the_end PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60
  PASS_REGULAR_EXPRESSION "\"class\":\"stream_fault\"[^\n]*no data for the last [0-9.]+ s of monitoring")
# ... and while the outage lasts, --events-open has it as an open stream fault (1.5 s after the last
# sample), closed at the end under the same t_detected (review of session 49)
add_test(NAME cli.rtde_monitor_outage_open
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35929 --speed 8 --duration 2 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35929 --wait 10 --duration 4 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --json --events-open > ${PROJECT_BINARY_DIR}/outage_open.json; wait; \
cat ${PROJECT_BINARY_DIR}/outage_open.json; grep -c . ${PROJECT_BINARY_DIR}/outage_open.json; grep -o 't_detected.:[0-9.]*' ${PROJECT_BINARY_DIR}/outage_open.json | uniq -c")
set_tests_properties(cli.rtde_monitor_outage_open PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60
  PASS_REGULAR_EXPRESSION "\"class\":\"stream_fault\"[^\n]*\"detail\":\"no data for 1[.][5-9] s [^\n]*\"open\":true[^\n]*\n[^\n]*\"class\":\"stream_fault\"[^\n]*no data for the last [0-9.]+ s of monitoring[^\n]*\"open\":false[^\n]*\n2\n +2 t_detected.:[0-9.]+\n")
# an output path that cannot be written is refused before connecting: not after a --wait spent on a
# robot that is not there yet (here: nothing listens, and the 30 s wait would run out first)
add_test(NAME cli.rtde_record_bad_output_before_connecting
  COMMAND twinwatch record --rtde 127.0.0.1:1 --wait 30 --duration 1 -o ${PROJECT_BINARY_DIR}/no-such-dir/rec.csv)
set_tests_properties(cli.rtde_record_bad_output_before_connecting PROPERTIES TIMEOUT 10
  PASS_REGULAR_EXPRESSION "no-such-dir/rec.csv: cannot write: directory [^\n]*no-such-dir does not exist")
add_test(NAME cli.rtde_monitor_bad_output_before_connecting
  COMMAND twinwatch monitor --rtde 127.0.0.1:1 --wait 30 --duration 1 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --db ''
          --events ${PROJECT_BINARY_DIR}/no-such-dir/events.jsonl)
set_tests_properties(cli.rtde_monitor_bad_output_before_connecting PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 10
  PASS_REGULAR_EXPRESSION "no-such-dir/events.jsonl: cannot write: directory [^\n]*no-such-dir does not exist")
# a path that exists in no writable sense (/proc: access(2) passes root there) is refused before connecting too
add_test(NAME cli.rtde_record_proc_output_before_connecting
  COMMAND twinwatch record --rtde 127.0.0.1:1 --wait 30 --duration 1 -o /proc/twinwatch-rec.csv)
set_tests_properties(cli.rtde_record_proc_output_before_connecting PROPERTIES TIMEOUT 10
  PASS_REGULAR_EXPRESSION "/proc/twinwatch-rec.csv: cannot write: ")
# a link to a file in a folder that does not exist: the link's target is what the write creates
# (review of session 39: the probe took the link's "file exists" as writable, and streamed first)
add_test(NAME cli.rtde_record_dangling_link_output_before_connecting
  COMMAND sh -c "cd ${PROJECT_BINARY_DIR} && rm -f dangling_rec.csv && ln -s no-such-dir/rec.csv dangling_rec.csv && \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:1 --wait 30 --duration 1 -o dangling_rec.csv; echo exit=\$?")
set_tests_properties(cli.rtde_record_dangling_link_output_before_connecting PROPERTIES TIMEOUT 10
  PASS_REGULAR_EXPRESSION "dangling_rec.csv: cannot write: directory no-such-dir does not exist \\(a link to no-such-dir/rec.csv\\)\nexit=2")
# samples served faster than real time: |interval - period| measures the pace, not jitter, and is not
# given as jitter (before: "arrival jitter p99 2.00 ms" at --speed 8, where every sample came 1.75 ms early)
add_test(NAME cli.rtde_record_fast_server_is_not_jitter
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35945 --speed 8 --duration 20 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:35945 --wait 10 --duration 0.5 --json -o ${PROJECT_BINARY_DIR}/fast_rec.csv 2>&1; kill \$! 2>/dev/null; wait")
set_tests_properties(cli.rtde_record_fast_server_is_not_jitter PROPERTIES TIMEOUT 30
  PASS_REGULAR_EXPRESSION "\"arrival_interval_ms\":0\\.2[0-9]*,\"arrival_jitter_max_ms\":null,\"arrival_jitter_p99_ms\":null")
# a scenario whose stream has no targets (streams_targets: false) is a log, not a controller: refused, named
add_test(NAME cli.serve_robot_refuses_a_stream_without_targets
  COMMAND sh -c "printf 'robot: ur3e\\nduration: 1\\nstreams_targets: false\\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 8}\\n' > ${PROJECT_BINARY_DIR}/no_targets.yaml && $<TARGET_FILE:twinwatch> serve-robot ${PROJECT_BINARY_DIR}/no_targets.yaml --port 35931 -q; echo exit=$?")
set_tests_properties(cli.serve_robot_refuses_a_stream_without_targets PROPERTIES
  PASS_REGULAR_EXPRESSION "no_targets.yaml: 'streams_targets: false' is a log without the controller's targets, which an RTDE controller always serves.*exit=2" TIMEOUT 20)
# --wait-client that runs out says so: the robot runs with nobody watching its first cycles
add_test(NAME cli.serve_robot_wait_client_timeout
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/chirp.yaml --port 0 --speed 5 --duration 0.2 --wait-client 0.2 2>&1; echo exit=\$?")
set_tests_properties(cli.serve_robot_wait_client_timeout PROPERTIES
  PASS_REGULAR_EXPRESSION "--wait-client 0.2 s: no client started streaming \\(connections so far: 0\\). the robot runs without one.*exit=0")
# --controller-version parts are whole numbers within uint32 (sscanf took -1 as 4294967295)
add_test(NAME cli.serve_robot_controller_version_negative
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/chirp.yaml --port 0 --duration 0.01 --controller-version -1.0.0.0 2>&1; echo exit=\$?")
set_tests_properties(cli.serve_robot_controller_version_negative PROPERTIES
  PASS_REGULAR_EXPRESSION "--controller-version '-1.0.0.0': expected MAJOR.MINOR.BUGFIX.BUILD, four whole numbers 0 to 4294967295.*exit=2")
# an operator's stop during an outage (here SIGHUP, as a closed SSH session sends it, 3 s after the
# virtual robot's run ended) ends an unwatched stretch: it is a stream fault in the events file, the
# summary is printed, and the status is 4 (a stop during an outage; it was 1 until session 55, which
# made a systemd stop of a switched-off robot a failed unit). Before (audit of session 38):
# SIGHUP killed the monitor with nothing written; SIGINT/SIGTERM stored the stretch as watched, exit 0
add_test(NAME cli.rtde_monitor_stopped_during_an_outage
  COMMAND sh -c "rm -f ${PROJECT_BINARY_DIR}/outage_events.jsonl; $<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35940 --speed 8 --duration 2 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35940 --wait 10 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --events ${PROJECT_BINARY_DIR}/outage_events.jsonl & mp=\$!; \
sleep 4; kill -HUP \$mp; wait \$mp; echo exit=\$?; cat ${PROJECT_BINARY_DIR}/outage_events.jsonl; wait")
set_tests_properties(cli.rtde_monitor_stopped_during_an_outage PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60
  PASS_REGULAR_EXPRESSION "stream: [0-9]+ received[^\n]*\n.*event\\(s\\)[^\n]*\nexit=4\n[^\n]*\"class\":\"stream_fault\"[^\n]*no data for the last [0-9.]+ s of monitoring")
# record stopped during an outage: the recording is written, the warning says the outage came before
# the stop, the summary (stdout, after the warning on stderr) says the run was stopped, and the status is 1
add_test(NAME cli.rtde_record_stopped_during_an_outage
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35941 --speed 8 --duration 2 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:35941 --wait 10 --duration 60 -o ${PROJECT_BINARY_DIR}/outage_rec.csv & rp=\$!; \
sleep 4; kill -INT \$rp; wait \$rp; echo exit=\$?; wait")
set_tests_properties(cli.rtde_record_stopped_during_an_outage PROPERTIES TIMEOUT 60
  PASS_REGULAR_EXPRESSION "no data for the last [0-9.]+ s before the stop \\(the connection was lost and not restored\\)[^\n]*\n[^\n]*outage_rec.csv: 1000 samples [^\n]*. stopped by a signal after [0-9.]+ of the 60 s asked for\n.*exit=1")
# a slow output rate (here 0.5 Hz, within the allowed 0 < f <= 500): the stall watchdog and the
# end-of-run silence scale with the period. Before (audit of session 38): the 1 s watchdog fired
# between every two samples, each a "gap" and a reconnection
add_test(NAME cli.rtde_record_slow_rate
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35942 --duration 12 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:35942 --wait 10 --frequency 0.5 --duration 6.5 -o ${PROJECT_BINARY_DIR}/slow_rec.csv; echo exit=\$?; kill \$! 2>/dev/null; wait")
set_tests_properties(cli.rtde_record_slow_rate PROPERTIES TIMEOUT 60
  PASS_REGULAR_EXPRESSION "slow_rec.csv: [34] samples [^\n]*. lost 0 samples in 0 gaps, 0 reconnects[^\n]*. arrival jitter p99 [0-9.]+ ms.[^\n]*\nits first sample was taken at 20[0-9][0-9]-[0-9][0-9]-[0-9][0-9]T[0-9][0-9]:[0-9][0-9]:[0-9][0-9][.][0-9][0-9][0-9]Z by this machine's clock: 'twinwatch monitor --started-at [^\n]*\nexit=0")
# a write that fails stops the recording at once, naming the file (before: the whole --duration was
# streamed, then "write error"; on a disk that fills during an hour, the hour was lost unsaid)
execute_process(COMMAND test -c /dev/full RESULT_VARIABLE no_dev_full_rtde)
if(no_dev_full_rtde EQUAL 0)
  add_test(NAME cli.rtde_record_disk_full_stops_at_once
    COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35943 --duration 60 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:35943 --wait 10 --duration 60 -o /dev/full; echo exit=\$?; kill \$! 2>/dev/null; wait")
  set_tests_properties(cli.rtde_record_disk_full_stops_at_once PROPERTIES TIMEOUT 20
    PASS_REGULAR_EXPRESSION "error: /dev/full: write error after [0-9]+ rows \\(disk full\\?\\)\nexit=1")
endif()
# a rate the controller does not stream is said: protocol v1 sends at the controller's full rate
# (before: --protocol 1 --frequency 125 recorded at 500 Hz with no word but the info line)
add_test(NAME cli.rtde_record_v1_rate_is_said
  COMMAND sh -c "$<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35944 --duration 10 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:35944 --wait 10 --protocol 1 --frequency 125 --duration 0.5 -o ${PROJECT_BINARY_DIR}/v1_rec.csv 2>&1; kill \$! 2>/dev/null; wait")
set_tests_properties(cli.rtde_record_v1_rate_is_said PROPERTIES TIMEOUT 30
  PASS_REGULAR_EXPRESSION "rtde: 125 Hz was asked for and the controller streams at 500 Hz \\(protocol v1 has no rate of its own")
# --split-every: a new file each N s of controller time, each with the header, contiguous, none lost
# (session 40: a recording left running wrote one file of 1.74 GB per robot hour)
add_test(NAME cli.rtde_record_split_every
  COMMAND sh -c "rm -rf ${PROJECT_BINARY_DIR}/split_rec; mkdir ${PROJECT_BINARY_DIR}/split_rec; $<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35946 --speed 8 --duration 20 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:35946 --wait 10 --duration 0.6 --split-every 1 --json -o ${PROJECT_BINARY_DIR}/split_rec/rec.csv > ${PROJECT_BINARY_DIR}/split_rec.json 2>/dev/null; kill \$! 2>/dev/null; wait; \
cd ${PROJECT_BINARY_DIR}/split_rec && cat ../split_rec.json && echo files=\$(ls | wc -l) headers=\$(head -qn1 rec.*.csv | sort -u | wc -l) && \
r=\$(cat rec.*.csv | grep -vc '^timestamp') && n=\$(grep -o '\"samples\":[0-9]*' ../split_rec.json | cut -d: -f2) && [ \"\$r\" = \"\$n\" ] && echo rows=samples=\$r && \
awk -v a=\$(tail -n1 rec.000.csv | cut -d, -f1) -v b=\$(sed -n 2p rec.001.csv | cut -d, -f1) 'BEGIN { print (b - a > 0.0019 && b - a < 0.0021) ? \"contiguous\" : \"apart \" b - a }'; \
$<TARGET_FILE:twinwatch> record --rtde 127.0.0.1:1 --split-every 0.5 -o x.csv 2>&1; echo exit=\$?")
set_tests_properties(cli.rtde_record_split_every PROPERTIES TIMEOUT 40
  PASS_REGULAR_EXPRESSION "\"files\":\\[\"[^\"]*split_rec/rec\\.000\\.csv\",\"[^\"]*split_rec/rec\\.001\\.csv\",[^\n]*\nfiles=[3-9] headers=1\nrows=samples=[0-9]+\ncontiguous\n.*--split-every must be a finite time >= 1 s of controller time, got 0.5\nexit=2")
# a service started again must not replace the last run's files: '{start}' in --record and --events
# is the run's start in UTC, and --events-append adds to the events file (audit of session 57: the
# example config's events file was emptied at every restart). Two runs, one after the other.
add_test(NAME cli.rtde_monitor_start_in_file_names
  COMMAND sh -c "rm -rf ${PROJECT_BINARY_DIR}/mstart; mkdir ${PROJECT_BINARY_DIR}/mstart; $<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35948 --speed 4 --duration 30 -q & \
for run in 1 2; do $<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35948 --wait 10 --duration 0.5 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db '' \
--record ${PROJECT_BINARY_DIR}/mstart/rec-{start}.csv --events ${PROJECT_BINARY_DIR}/mstart/ev-{start}.jsonl -q; sleep 1.1; done; kill \$! 2>/dev/null; wait; \
cd ${PROJECT_BINARY_DIR}/mstart && echo recordings=\$(ls rec-*.csv | grep -cE '^rec-20[0-9]{6}T[0-9]{6}Z[.]csv$') events=\$(ls ev-*.jsonl | grep -cE '^ev-20[0-9]{6}T[0-9]{6}Z[.]jsonl$')")
set_tests_properties(cli.rtde_monitor_start_in_file_names PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60
  PASS_REGULAR_EXPRESSION "recordings=2 events=2")
# monitor --record --split-every: the live monitor's copy of the stream split as record's is, every
# sample once (session 41; before, --record wrote one file whatever the run's length)
add_test(NAME cli.rtde_monitor_record_split_every
  COMMAND sh -c "rm -rf ${PROJECT_BINARY_DIR}/msplit; mkdir ${PROJECT_BINARY_DIR}/msplit; $<TARGET_FILE:twinwatch> serve-robot ${PROJECT_SOURCE_DIR}/scenarios/ur3e/nominal_figure_eight.yaml --port 35947 --speed 8 --duration 20 --wait-client 20 -q & \
$<TARGET_FILE:twinwatch> monitor --rtde 127.0.0.1:35947 --wait 10 --duration 0.6 --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --record ${PROJECT_BINARY_DIR}/msplit/rec.csv --split-every 1 > ${PROJECT_BINARY_DIR}/msplit.out 2>/dev/null; kill \$! 2>/dev/null; wait; \
cd ${PROJECT_BINARY_DIR}/msplit && grep -E '^(recorded|stream:)' ../msplit.out && echo files=\$(ls | wc -l) headers=\$(head -qn1 rec.*.csv | sort -u | wc -l) && \
r=\$(cat rec.*.csv | grep -vc '^timestamp') && n=\$(grep -o '^recorded [0-9]*' ../msplit.out | cut -d' ' -f2) && [ \"\$r\" = \"\$n\" ] && echo rows=recorded=\$r && \
awk -v a=\$(tail -n1 rec.000.csv | cut -d, -f1) -v b=\$(sed -n 2p rec.001.csv | cut -d, -f1) 'BEGIN { print (b - a > 0.0019 && b - a < 0.0021) ? \"contiguous\" : \"apart \" b - a }'; \
$<TARGET_FILE:twinwatch> monitor --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --rtde 127.0.0.1:1 --split-every 5 --db '' 2>&1; echo exit=\$?; \
$<TARGET_FILE:twinwatch> monitor --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json --rtde 127.0.0.1:1 --record x.csv --split-every 0.5 --db '' 2>&1; echo exit=\$?")
set_tests_properties(cli.rtde_monitor_record_split_every PROPERTIES FIXTURES_REQUIRED twin TIMEOUT 60
  PASS_REGULAR_EXPRESSION "recorded [0-9]+ samples to [0-9]+ files, [^\n]*msplit/rec\\.000\\.csv \\.\\.\\. [^\n]*msplit/rec\\.00[2-9]\\.csv \\(a new one every 1 s\\)\nstream: [0-9]+ received, 0 lost[^\n]*\nfiles=[3-9] headers=1\nrows=recorded=[0-9]+\ncontiguous\n[^\n]*--split-every applies only with --record\nexit=2\n[^\n]*--split-every must be a finite time >= 1 s of controller time, got 0.5\nexit=2")
