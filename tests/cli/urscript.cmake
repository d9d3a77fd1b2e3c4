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
  "error: [^\n]*swing_train.yaml: --lookahead: expected 0\\.03 to 0\\.2 s \\(servoj's range\\), got 0\\.5\nexit 2\nerror: [^\n]*swing_train.yaml: --ramp: the target does not start at rest, and a ramp of 0 s would make the arm take a step of velocity[^\n]*\nexit 2\nerror: [^\n]*swing_train.yaml: --duration: 1 s is shorter than half the ramps: expected at least 2 s of the trajectory, or a shorter ramp\nexit 2\nerror: [^\n]*swing_train.yaml: cannot write: it is the input [^\n]*\nexit 2\n")
# the virtual robot rehearses the program: 40 s of the swing in 42 s, from rest (J1's first measured
# velocity ~0, where the scenario starts it at 2.6 rad/s); --ramp only with --as-program, and a
# Cartesian path has no program to rehearse
add_test(NAME cli.simulate_as_program
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T simulate ${S}/train/swing_train.yaml -o ${d}/swr.csv --as-program && awk -F, 'NR==1{for(i=1;i<=NF;i++) if(\$i==\"actual_qd_0\") c=i} NR==2{v=\$c; if (v<0) v=-v; print (v < 0.01 ? \"AT-REST\" : \"MOVING \" \$c)}' ${d}/swr.csv; \$T simulate ${S}/excitation.yaml -o ${d}/x.csv --ramp 3 2>&1; echo exit \$?; \$T simulate ${S}/nominal_figure_eight.yaml -o ${d}/x.csv --as-program 2>&1; echo exit \$?")
set_tests_properties(cli.simulate_as_program PROPERTIES PASS_REGULAR_EXPRESSION
  "swing_train: rehearsed as its URScript program runs it: started at rest, the clock rising over 2\\.0 s and falling over 2\\.0 s \\(40\\.0 s of the trajectory in 42\\.0 s[^\n]*\nswing_train: 21000 samples[^\n]*\nAT-REST\nerror: --ramp applies only with --as-program\nexit 2\nerror: [^\n]*nominal_figure_eight.yaml:[0-9]+: trajectory 'figure_eight' has no closed form[^\n]*\nexit 2\n")
# the installation's safety limits: the swing's flange reaches 1.463 m/s (a tool point 0.1 m out
# 1.693 m/s), refused under a limit that less the safety system's 0.05 m/s tolerance is below that,
# no file written; within them each is reported as a share of what it keeps; an unchecked one says
# which option checks it; the elbow at the faster end of its housing (0.593 m/s, 0.12 m out)
add_test(NAME cli.urscript_safety_limits
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; rm -f ${d}/lim.script; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --tool-speed-limit 1.0 2>&1; echo exit \$?; test -e ${d}/lim.script && echo FILE-EXISTS; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --tool-point 0 0 0.1 --tool-point 0.05 0 0.02 --tool-speed-limit 2 --momentum-limit 25 | grep -E 'peak (tool|elbow|momentum)'; grep -c 'if tw_far > 0.5:' ${d}/lim.script; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --tool-point 0 0 5 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/lim.script --max-approach 7 2>&1; echo exit \$?")
set_tests_properties(cli.urscript_safety_limits PROPERTIES
  PASS_REGULAR_EXPRESSION "error: [^\n]*swing_train.yaml: the program exceeds the installation's limits: its tool speed reaches 1\\.463 m/s at 19\\.61 s \\(the flange's centre\\), beyond 0\\.95 m/s \\(the --tool-speed-limit 1 less the safety system's 0\\.05 m/s tolerance\\): the arm would be slowed or stopped mid-run. no program written[^\n]*\nexit 2\n  peak tool speed +1\\.693 m/s at 19\\.59 s \\(tool point 1 \\(0, 0, 0\\.1\\) m\\): within 1\\.95 m/s \\(the --tool-speed-limit 2 less the safety system's 0\\.05 m/s tolerance\\) \\(87 %\\)\n  peak elbow speed +0\\.593 m/s at [0-9.]+ s: not checked \\(the installation's limit: --elbow-speed-limit\\)\n  peak momentum +4\\.800 kg·m/s at [0-9.]+ s: within 22 kg·m/s \\(the --momentum-limit 25 less the safety system's 3 kg·m/s tolerance\\) \\(22 %\\)\n1\nerror: --tool-point \\(number 1 of 1\\): expected a point within 2 m of the flange[^\n]*\nexit 2\nerror: [^\n]*--max-approach: expected > 0 and at most 2 pi rad, got 7\nexit 2\n"
  FAIL_REGULAR_EXPRESSION "FILE-EXISTS")
# a slow-down fits the same path within the limits: refused at 1 m/s (0.95 m/s kept) with the factor
# that fits (1.55, and the program's time with it), written with it (the flange at 0.944 m/s), and
# rehearsed with it; with no tolerance 1.47 fits 1 m/s (0.995 m/s)
add_test(NAME cli.urscript_slow_down
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T urscript ${S}/train/swing_train.yaml -o ${d}/slow.script --tool-speed-limit 1.0 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/slow.script --tool-speed-limit 1.0 --slow-down 1.55 | grep -E 'URScript|peak tool'; grep -c 'runs 1.55 times slower' ${d}/slow.script; \$T simulate ${S}/train/swing_train.yaml -o ${d}/slow.csv --as-program --slow-down 1.55; \$T urscript ${S}/train/swing_train.yaml -o ${d}/slow.script --tool-speed-limit 1.0 --speed-tolerance 0 --slow-down 1.47 | grep -E 'peak tool'")
set_tests_properties(cli.urscript_slow_down PROPERTIES PASS_REGULAR_EXPRESSION
  "beyond 0\\.95 m/s \\(the --tool-speed-limit 1 less[^\n]*--slow-down 1\\.55 runs the same path within it \\(65\\.1 s instead of 42\\.0 s\\)[^\n]*\nexit 2\nswing_train -> [^\n]*65\\.1 s of motion \\(1\\.55 times slower than the scenario\\)[^\n]*\n  peak tool speed +0\\.944 m/s[^\n]*within 0\\.95 m/s \\(the --tool-speed-limit 1 less the safety system's 0\\.05 m/s tolerance\\) \\(99 %\\)\n1\nswing_train: rehearsed[^\n]*\\(40\\.0 s of the trajectory in 65\\.1 s, 1\\.55 times slower[^\n]*\nswing_train: 32550 samples[^\n]*\n  peak tool speed +0\\.995 m/s[^\n]*within 1 m/s \\(the --tool-speed-limit as entered\\) \\(99 %\\)\n")
# what the drives can follow and what the flange carries (review of session 45): a ramp of 2 ms
# commanded 1000 rad/s² (refused, naming the ramps); a joint whose torque_max the rigid body needs more
# than (a robot file with J2's 54 N·m cut to 5); a tool too heavy for the arm; the tool's mass counted
# in the momentum (2 kg at 5 cm: 7.800 kg·m/s, the 2 kg payload of the swing at its CoG gives 7.95);
# every limit passed is named, with the factor that fits them all; a limit within its tolerance is refused
add_test(NAME cli.urscript_drives_and_tool
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; awk '/torque_max.: 54/ {n++; if (n==2) sub(/: 54/, \": 5\")} {print}' ${CMAKE_SOURCE_DIR}/data/robots/ur3e.json > ${d}/weak.json; \$T urscript ${S}/train/swing_train.yaml -o ${d}/d.script --ramp 0.002 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/d.script --robot ${d}/weak.json 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train_payload.yaml -o ${d}/d.script --tool-mass 1.5 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/d.script --tool-mass 2 --tool-cog 0 0 0.05 --momentum-limit 25 --momentum-tolerance 0 | grep 'peak momentum'; \$T urscript ${S}/train/swing_train.yaml -o ${d}/d.script --tool-speed-limit 1.0 --elbow-speed-limit 0.3 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/d.script --momentum-limit 3 2>&1; echo exit \$?; \$T urscript ${S}/train/swing_train.yaml -o ${d}/d.script --tool-cog 0 0 0.1 2>&1; echo exit \$?")
set_tests_properties(cli.urscript_drives_and_tool PROPERTIES PASS_REGULAR_EXPRESSION
  "error: [^\n]*swing_train.yaml: the program accelerates J1 at up to 1\\.04e\\+03 rad/s², beyond 40 rad/s²[^\n]*Its ramps are short \\(--ramp 0\\.002 s\\): lengthen them[^\n]*\nexit 2\nerror: [^\n]*swing_train.yaml: the program's motion needs [0-9.]+ N·m on J2 at [0-9.]+ s \\(rigid body, no friction\\), beyond its 5 N·m: the drive cannot follow it. no program written[^\n]*\nexit 2\nerror: --tool-mass 1\\.5 kg and the scenario's 2 kg payload: the flange would carry 3\\.5 kg, beyond the rated payload of ur3e \\(3 kg\\)\nexit 2\n  peak momentum +7\\.800 kg·m/s at [0-9.]+ s: within 25 kg·m/s \\(the --momentum-limit as entered\\)[^\n]*\nerror: [^\n]*its tool speed reaches 1\\.463 m/s[^\n]*beyond 0\\.95 m/s[^\n]*. its elbow speed reaches 0\\.593 m/s at [0-9.]+ s, beyond 0\\.25 m/s \\(the --elbow-speed-limit 0\\.3 less[^\n]*--slow-down 2\\.38 runs the same path within them[^\n]*\nexit 2\nerror: --momentum-limit 3: the safety system keeps a motion 3 kg·m/s below it \\(--momentum-tolerance\\), which leaves nothing to move at[^\n]*\nexit 2\nerror: --tool-cog applies only with --tool-mass[^\n]*\nexit 2\n")
# the payload declared with set_target_payload (PolyScope 5.10+: mass, CoG, inertia about the CoG),
# which implies --declare-payload; the summary and --json say which call
add_test(NAME cli.urscript_set_target_payload
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T urscript ${S}/train/swing_train_payload.yaml -o ${d}/tp.script --set-target-payload | grep 'payload:'; grep -E '^  (set_target_payload|set_payload)' ${d}/tp.script; \$T urscript ${S}/train/swing_train_payload.yaml -o ${d}/tp.script --declare-payload --json | grep payload_command")
set_tests_properties(cli.urscript_set_target_payload PROPERTIES PASS_REGULAR_EXPRESSION
  "  payload: declared with set_target_payload\\(2 kg, \\[0\\.06, 0\\.04, 0\\.05\\] m, its inertia about the CoG\\)\n  set_target_payload\\(2\\.0, \\[0\\.06, 0\\.04, 0\\.05\\], \\[0\\.0, 0\\.0, 0\\.0, 0\\.0, 0\\.0, 0\\.0\\]\\)\n  \"payload_command\": \"set_payload\",\n$")
# the tool on the flange is declared with the scenario's payload (URScript's payload is everything on
# it): 2 kg at (0.06, 0.04, 0.05) and 0.8 kg at (0, 0, 0.1) make 2.8 kg at their common centre (review)
add_test(NAME cli.urscript_tool_declared
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T urscript ${S}/train/swing_train_payload.yaml -o ${d}/td.script --tool-mass 0.8 --tool-cog 0 0 0.1 --declare-payload | grep 'payload:'; grep -E '^  set_payload' ${d}/td.script")
set_tests_properties(cli.urscript_tool_declared PROPERTIES PASS_REGULAR_EXPRESSION
  "  payload: declared with set_payload\\(2\\.8 kg, \\[0\\.0428571, 0\\.0285714, 0\\.0642857\\] m\\)\n  set_payload\\(2\\.8, \\[0\\.0428571429, 0\\.0285714286, 0\\.0642857143\\]\\)\n$")
