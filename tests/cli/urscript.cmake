# urscript: a scenario's joint-space motion as a URScript program for a real UR arm. The swing
# scenario's sine starts and ends moving (its clock is ramped), an excitation starts and ends at rest;
# a Cartesian path has no closed form and is refused by name, as are options servoj does not take, a
# ramp of 0 s under a moving start, and an output that is the scenario.
set(d ${PROJECT_BINARY_DIR}/cli-urscript)
file(MAKE_DIRECTORY ${d})
set(S ${PROJECT_SOURCE_DIR}/scenarios/ur3e)
add_test(NAME cli.urscript_swing
  COMMAND sh -c "$<TARGET_FILE:twinwatch> urscript ${S}/train/swing_train.yaml -o ${d}/swing.script && grep -c 'servoj(\\[tw_q0, tw_q1, tw_q2, tw_q3, tw_q4, tw_q5\\], t=0.002, lookahead_time=0.1, gain=300.0)' ${d}/swing.script && head -n 2 ${d}/swing.script")
set_tests_properties(cli.urscript_swing PROPERTIES PASS_REGULAR_EXPRESSION
  "swing_train -> [^\n]*swing.script: URScript for a ur3e \\(e-Series\\), 42\\.0 s of motion, servoj every 2 ms\n  the target's clock rises over 2\\.0 s and falls over 2\\.0 s[^\n]*\n  start pose \\[rad\\] +J1 0\\.000  J2 -1\\.000  J3 1\\.000  J4 -1\\.570[^\n]*\n  start pose \\[deg\\] +J1 0\\.0  J2 -57\\.3  J3 57\\.3  J4 -90\\.0[^\n]*\n  \\(jog the arm within 0\\.5 rad of it[^\n]*\n  peak speed \\[rad/s\\] +J1 2\\.639 \\(84 %\\)[^@]*payload: not changed[^@]*\n1\ndef twinwatch_swing_train\\(\\):\n  # twinwatch: [^\n]*swing_train.yaml on a Universal Robots e-Series arm \\(ur3e\\)\n")
add_test(NAME cli.urscript_excitation_json
  COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/exc.yaml -q --harmonics 4 --global-evals 200 --local-evals 200 --duration 20 && $<TARGET_FILE:twinwatch> urscript ${d}/exc.yaml -o ${d}/exc.script --json")
set_tests_properties(cli.urscript_excitation_json PROPERTIES PASS_REGULAR_EXPRESSION
  "\"motion_s\": 20\\.0,[^@]*\"payload_declared\": false,[^@]*\"ramp_in_s\": 0\\.0,\n  \"ramp_out_s\": 0\\.0,")
add_test(NAME cli.urscript_cartesian_refused
  COMMAND sh -c "$<TARGET_FILE:twinwatch> urscript ${S}/nominal_figure_eight.yaml -o ${d}/f8.script 2>&1; echo exit \$?; test -e ${d}/f8.script && echo FILE-EXISTS")
set_tests_properties(cli.urscript_cartesian_refused PROPERTIES
  PASS_REGULAR_EXPRESSION "error: [^\n]*nominal_figure_eight.yaml:[0-9]+: trajectory 'figure_eight' has no closed form that a robot program can evaluate: programs are made of the joint-space trajectories fourier, fourier_series, sine and chirp[^\n]*\nexit 2\n"
  FAIL_REGULAR_EXPRESSION "FILE-EXISTS")
add_test(NAME cli.urscript_bad_options
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T urscript ${S}/train/swing_train.yaml -o ${d}/x.script --lookahead 0.5 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/x.script --ramp 0 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/x.script --duration 1 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${S}/train/swing_train.yaml 2>&1; echo exit \$?")
set_tests_properties(cli.urscript_bad_options PROPERTIES PASS_REGULAR_EXPRESSION
  "error: [^\n]*swing_train.yaml: --lookahead: expected 0\\.03 to 0\\.2 s \\(servoj's range\\), got 0\\.5\nexit 2\nerror: [^\n]*swing_train.yaml: --ramp: the target does not start at rest, and a ramp of 0 s would make the arm take a step of velocity[^\n]*\nexit 2\nerror: [^\n]*swing_train.yaml: --duration: 1 s is shorter than half the ramps take \\(2 s\\)[^\n]*\nexit 2\nerror: [^\n]*swing_train.yaml: cannot write: it is the input [^\n]*\nexit 2\n")
# the virtual robot rehearses the program: 40 s of the swing in 42 s, from rest (J1's first measured
# velocity ~0, where the scenario starts it at 2.6 rad/s); --ramp only with --as-program, and a
# Cartesian path has no program to rehearse
add_test(NAME cli.simulate_as_program
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T simulate ${S}/train/swing_train.yaml -o ${d}/swr.csv --as-program && awk -F, 'NR==1{for(i=1;i<=NF;i++) if(\$i==\"actual_qd_0\") c=i} NR==2{v=\$c; if (v<0) v=-v; print (v < 0.01 ? \"AT-REST\" : \"MOVING \" \$c)}' ${d}/swr.csv; \$T simulate ${S}/excitation.yaml -o ${d}/x.csv --ramp 3 2>&1; echo exit \$?; \$T simulate ${S}/nominal_figure_eight.yaml -o ${d}/x.csv --as-program 2>&1; echo exit \$?")
set_tests_properties(cli.simulate_as_program PROPERTIES PASS_REGULAR_EXPRESSION
  "swing_train: rehearsed as its URScript program runs it: started at rest, the clock rising over 2\\.0 s and falling over 2\\.0 s \\(40\\.0 s of the trajectory in 42\\.0 s[^\n]*\nswing_train: 21000 samples[^\n]*\nAT-REST\nerror: --ramp applies only with --as-program\nexit 2\nerror: [^\n]*nominal_figure_eight.yaml:[0-9]+: trajectory 'figure_eight' has no closed form[^\n]*\nexit 2\n")
# the installation's safety limits: the swing's flange reaches 1.463 m/s (a tool point 0.1 m out
# 1.693 m/s), refused under a limit below that, no file written; within them each is reported as a
# share of its limit; an unchecked one says which option checks it
add_test(NAME cli.urscript_safety_limits
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; rm -f ${d}/lim.script; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --tool-speed-limit 1.0 2>&1; echo exit \$?; test -e ${d}/lim.script && echo FILE-EXISTS; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --tool-point 0 0 0.1 --tool-point 0.05 0 0.02 --tool-speed-limit 2 --momentum-limit 25 | grep -E 'peak (tool|elbow|momentum)'; grep -c 'if tw_far > 0.5:' ${d}/lim.script; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --tool-point 0 0 5 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --max-approach 7 2>&1; echo exit \$?")
set_tests_properties(cli.urscript_safety_limits PROPERTIES
  PASS_REGULAR_EXPRESSION "error: [^\n]*swing_train.yaml: the program's tool speed reaches 1\\.463 m/s at 19\\.61 s \\(the flange's centre\\), beyond --tool-speed-limit 1 m/s: the arm would stop or slow mid-run. no program written[^\n]*\nexit 2\n  peak tool speed +1\\.693 m/s at 19\\.59 s \\(tool point 1 \\(0, 0, 0\\.1\\) m\\): within --tool-speed-limit 2 \\(85 %\\)\n  peak elbow speed +0\\.491 m/s at [0-9.]+ s: not checked \\(the installation's limit: --elbow-speed-limit\\)\n  peak momentum +4\\.[0-9]+ kg·m/s at [0-9.]+ s: within --momentum-limit 25 \\([0-9]+ %\\)\n1\nerror: --tool-point \\(number 1 of 1\\): expected a point within 2 m of the flange[^\n]*\nexit 2\nerror: [^\n]*--max-approach: expected > 0 and at most 2 pi rad, got 7\nexit 2\n"
  FAIL_REGULAR_EXPRESSION "FILE-EXISTS")
# a slow-down fits the same path within the limits: refused at 1 m/s with the factor that fits (1.47,
# and the program's time with it), written with it (the flange at 0.995 m/s), and rehearsed with it
add_test(NAME cli.urscript_slow_down
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T urscript ${S}/train/swing_train.yaml -o ${d}/slow.script --tool-speed-limit 1.0 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/slow.script --tool-speed-limit 1.0 --slow-down 1.47 | grep -E 'URScript|peak tool'; grep -c 'runs 1.47 times slower' ${d}/slow.script; \$T simulate ${S}/train/swing_train.yaml -o ${d}/slow.csv --as-program --slow-down 1.47")
set_tests_properties(cli.urscript_slow_down PROPERTIES PASS_REGULAR_EXPRESSION
  "beyond --tool-speed-limit 1 m/s[^\n]*--slow-down 1\\.47 runs the same path within it \\(61\\.7 s instead of 42\\.0 s\\)[^\n]*\nexit 2\nswing_train -> [^\n]*61\\.7 s of motion \\(1\\.47 times slower than the scenario\\)[^\n]*\n  peak tool speed +0\\.995 m/s[^\n]*within --tool-speed-limit 1 \\(99 %\\)\n1\nswing_train: rehearsed[^\n]*\\(40\\.0 s of the trajectory in 61\\.7 s, 1\\.47 times slower[^\n]*\nswing_train: 30870 samples")
