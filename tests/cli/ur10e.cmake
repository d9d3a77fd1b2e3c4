# The UR10e, a built-in arm since session 57 (data/robots/ur10e.json from the fact sheet), end to end
# as a user with that arm runs it: the UR3e swing pair is too fast for its 2.09 rad/s base, and
# urscript / simulate --as-program say by how much to slow it (they refused it at the scenario's line
# before, whatever --slow-down); then an excitation designed for it, identify with the known payload,
# and the monitor on a healthy run and on faults of its own. The gains are checked against the
# simulator's drive (N kt eta = 101 x 0.125 x 0.9 = 11.36 N·m/A on every joint of this size; evaluation
# only), the faults against their labels.
set(u ${PROJECT_BINARY_DIR}/cli-ur10e)
file(MAKE_DIRECTORY ${u})
set(sc ${PROJECT_SOURCE_DIR}/scenarios/ur3e)
add_test(NAME cli.ur10e_swing_needs_a_slow_down
  COMMAND sh -c "$<TARGET_FILE:twinwatch> urscript ${sc}/train/swing_train.yaml --robot ur10e -o ${u}/never.script 2>&1; echo exit=\$?; \
$<TARGET_FILE:twinwatch> simulate ${sc}/train/swing_train.yaml --robot ur10e --as-program -o ${u}/never.csv 2>&1; echo exit=\$?; \
$<TARGET_FILE:twinwatch> urscript ${sc}/train/swing_train.yaml --robot ur10e --slow-down 1.27 -o ${u}/swing.script -q; echo exit=\$?")
set_tests_properties(cli.ur10e_swing_needs_a_slow_down PROPERTIES
  PASS_REGULAR_EXPRESSION "joint 1 target velocity reaches [^\n]*beyond its limit of 2.0944 rad/s \\(ur10e\\). no program written. --slow-down 1.27 keeps every joint within its speed and acceleration limits[^\n]*\nexit=2\n[^\n]*nothing written. --slow-down 1.27 keeps[^\n]*\nexit=2\nexit=0")
add_test(NAME cli.ur10e_end_to_end
  COMMAND sh -c "cd ${u} && $<TARGET_FILE:twinwatch> excite ur10e -o exc.yaml > /dev/null && $<TARGET_FILE:twinwatch> simulate exc.yaml -o exc.csv -q && \
for s in swing_train swing_train_payload; do $<TARGET_FILE:twinwatch> simulate ${sc}/train/\$s.yaml --robot ur10e --as-program --slow-down 1.27 -o \$s.csv -q || exit 1; done && \
for s in nominal_figure_eight collision_10Nm_link3 payload_loss_8_5s; do $<TARGET_FILE:twinwatch> simulate ${sc}/\$s.yaml --robot ur10e -o \$s.csv -q || exit 1; done && \
rm -f twin.json && $<TARGET_FILE:twinwatch> identify exc.csv swing_train.csv swing_train_payload.csv --robot ur10e --known-payload swing_train_payload.csv=2.0,0.06,0.04,0.05 -o twin.json 2>/dev/null > identify.out && \
awk '/^J[1-6] / { n++; g = \$NF; if (g < 11.02 || g > 11.70) bad = bad \" \" \$1 \"=\" g } END { print (n == 6 && bad == \"\" ? \"gains within 3 % of 11.36\" : \"gains off (\" n \" joints):\" bad) }' identify.out && \
for s in nominal_figure_eight collision_10Nm_link3 payload_loss_8_5s; do echo \"\$s: \$($<TARGET_FILE:twinwatch> monitor --twin twin.json \$s.csv --db '' -q --json 2>/dev/null | head -1)\"; done")
set_tests_properties(cli.ur10e_end_to_end PROPERTIES TIMEOUT 300
  PASS_REGULAR_EXPRESSION "gains within 3 % of 11.36\nnominal_figure_eight: \ncollision_10Nm_link3: [^\n]*\"class\":\"collision\"[^\n]*\"link\":3[^\n]*\npayload_loss_8_5s: [^\n]*\"class\":\"payload_change\"[^\n]*\"magnitude\":-0.4[0-9]*")
# the factor suggested is checked on the program it makes (short ramps round to servo periods, so
# accelerations do not scale exactly as 1/K²): urscript's suggestion for a 5.3 Hz sine on a UR10e passes
# its speed and 40 rad/s² checks; simulate --as-program checks a Panda's published 7.5 rad/s²
add_test(NAME cli.slow_down_suggested_is_one_that_passes
  COMMAND sh -c "d=${PROJECT_SOURCE_DIR}/tests/data/cli; \
k=\$($<TARGET_FILE:twinwatch> urscript \$d/ur10e_fast_sine.yaml -o ${u}/never.script 2>&1 | sed -n 's/.*--slow-down \\([0-9.]*\\) keeps every joint.*/\\1/p'); echo urscript suggests \$k; \
$<TARGET_FILE:twinwatch> urscript \$d/ur10e_fast_sine.yaml --slow-down \$k -o ${u}/fast.script -q; echo exit=\$?; \
$<TARGET_FILE:twinwatch> simulate \$d/panda_fast_sine.yaml --as-program --slow-down 1.16 -o ${u}/never.csv 2>&1; echo exit=\$?; \
k=\$($<TARGET_FILE:twinwatch> simulate \$d/panda_fast_sine.yaml --as-program -o ${u}/never.csv 2>&1 | sed -n 's/.*--slow-down \\([0-9.]*\\) keeps every joint.*/\\1/p'); echo simulate suggests \$k; \
$<TARGET_FILE:twinwatch> simulate \$d/panda_fast_sine.yaml --as-program --slow-down \$k -o ${u}/panda_fast.csv -q; echo exit=\$?")
set_tests_properties(cli.slow_down_suggested_is_one_that_passes PROPERTIES
  PASS_REGULAR_EXPRESSION "urscript suggests [0-9]+[.][0-9]+\nexit=0\n[^\n]*joint 2 target acceleration reaches -?[0-9.]+ rad/s² at t = [0-9.]+ s, beyond its limit of 7.5 rad/s² \\(panda\\)[^\n]*\nexit=2\nsimulate suggests [0-9]+[.][0-9]+\nexit=0")
