# excite -> simulate -> identify-torque -> validate-torque on a short run (fixtures keep the order)
set(d ${PROJECT_BINARY_DIR}/cli-excite)
file(MAKE_DIRECTORY ${d})
add_test(NAME cli.excite_json COMMAND twinwatch excite ur3e -o ${d}/exc.yaml --harmonics 4 --base-frequency 0.25
         --duration 8 --global-evals 200 --local-evals 200 --json)
set_tests_properties(cli.excite_json PROPERTIES FIXTURES_SETUP excite_yaml PASS_REGULAR_EXPRESSION "\"cond_final\": [0-9]")
add_test(NAME cli.excite_simulate COMMAND twinwatch simulate ${d}/exc.yaml -o ${d}/exc.csv)
set_tests_properties(cli.excite_simulate PROPERTIES FIXTURES_REQUIRED excite_yaml FIXTURES_SETUP excite_rec
                     PASS_REGULAR_EXPRESSION "excitation_ur3e: [0-9]+ samples")
add_test(NAME cli.identify_torque COMMAND twinwatch identify-torque ${d}/exc.csv --robot ur3e --signal target_moment
         -o ${d}/rb.json)
set_tests_properties(cli.identify_torque PROPERTIES FIXTURES_REQUIRED excite_rec FIXTURES_SETUP excite_model
                     PASS_REGULAR_EXPRESSION "J6 ")
add_test(NAME cli.validate_torque COMMAND twinwatch validate-torque ${d}/exc.csv --model ${d}/rb.json --published ur3e --json)
set_tests_properties(cli.validate_torque PROPERTIES FIXTURES_REQUIRED excite_model
                     PASS_REGULAR_EXPRESSION "\"published\": \\[")
add_test(NAME cli.excite_bad_duration COMMAND twinwatch excite ur3e -o ${d}/x.yaml --duration 3.3)
set_tests_properties(cli.excite_bad_duration PROPERTIES PASS_REGULAR_EXPRESSION "not a whole number of periods")
add_test(NAME cli.identify_torque_no_torque COMMAND twinwatch identify-torque ${d}/exc.csv --robot ur3e -o ${d}/x.json)
set_tests_properties(cli.identify_torque_no_torque PROPERTIES FIXTURES_REQUIRED excite_rec
                     PASS_REGULAR_EXPRESSION "no actual_joint_torque_\\* columns")
# real data (only where ../shared/data/real is present): the Panda log loads through its column map
set(panda ${PROJECT_SOURCE_DIR}/../shared/data/real/franka_panda_gaz2019_excitation/panda_excitation_combined.csv)
if(EXISTS ${panda})
  add_test(NAME cli.identify_torque_panda COMMAND twinwatch identify-torque ${panda} --robot panda
           --column-map franka_panda_gaz2019 --segment 0:0.65 -o ${d}/panda.json)
  set_tests_properties(cli.identify_torque_panda PROPERTIES PASS_REGULAR_EXPRESSION "J7 ")
  # watched by its joint torque sensors: a twin of them, the monitor on the held-out part (session 54)
  add_test(NAME cli.panda_joint_torque_twin
    COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/panda_joint_torque.sh $<TARGET_FILE:twinwatch> ${panda}
            ${PROJECT_SOURCE_DIR}/data/column_maps/franka_panda_gaz2019.csv ${PROJECT_BINARY_DIR}/cli-panda-torque ${PROJECT_SOURCE_DIR})
  set_tests_properties(cli.panda_joint_torque_twin PROPERTIES PASS_REGULAR_EXPRESSION "PANDA-JOINT-TORQUE-OK" TIMEOUT 120)
endif()
add_test(NAME cli.validate_torque_bad_table COMMAND twinwatch validate-torque ${d}/exc.csv --model ${d}/rb.json --published ur3e
         --friction-table ${PROJECT_SOURCE_DIR}/tests/data/cli/bad_friction_table.csv)
set_tests_properties(cli.validate_torque_bad_table PROPERTIES FIXTURES_REQUIRED excite_model
                     PASS_REGULAR_EXPRESSION "bad_friction_table.csv:4: field 'phi2': expected a finite number, got 'abc'")
add_test(NAME cli.validate_torque_bad_segment COMMAND twinwatch validate-torque ${d}/exc.csv --model ${d}/rb.json --segment 0.7:0.2)
set_tests_properties(cli.validate_torque_bad_segment PROPERTIES FIXTURES_REQUIRED excite_model
                     PASS_REGULAR_EXPRESSION "--segment '0.7:0.2': expected 0 <= FROM < TO <= 1")
# a negative or zero --duration is refused (it used to write one period, `cycles: 1`)
add_test(NAME cli.excite_duration_negative COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/neg.yaml -q --duration -10 2>&1; echo exit \$?")
set_tests_properties(cli.excite_duration_negative PROPERTIES PASS_REGULAR_EXPRESSION
  "error: --duration: expected a time > 0 s and at most 1e\\+06 s \\(the longest run the simulator accepts\\), got -10\nexit [1-9]")
# the search keeps the arm above --min-height (default 0.05 m over the base's mounting plane). The
# middle of the UR3e's ranges (its stretched-out zero pose, the wrist 7 cm over the table) leaves no
# design above it: the centre is raised and the design run again, and the file says so. A height the
# arm cannot keep (its shoulder axis is at 0.152 m) is refused, no file written; a negative height
# (an arm on a pedestal) lets the design go low, with a warning.
add_test(NAME cli.excite_min_height_default
  COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/high.yaml --global-evals 300 --local-evals 300 --json && grep -c 'centre was raised' ${d}/high.yaml")
set_tests_properties(cli.excite_min_height_default PROPERTIES
  PASS_REGULAR_EXPRESSION "\"centre_raised\": true,[^@]*\"lowest_point\": {[^}]*\"z\": 0\\.(0[5-9]|[1-9])[0-9]*[^}]*}[^}]*\"min_height\": 0\\.05,[^@]*\"units\": {[^}]*\"min_height\": \"m\"[^@]*}\n1\n")
add_test(NAME cli.excite_min_height_unreachable
  COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/never_high.yaml --global-evals 100 --local-evals 100 --min-height 0.3 2>&1; echo exit \$?; test -e ${d}/never_high.yaml && echo FILE-EXISTS")
set_tests_properties(cli.excite_min_height_unreachable PROPERTIES
  PASS_REGULAR_EXPRESSION "error: the search found no design above --min-height 0\\.3 m: in the best one, the (flange|J[2-6] axis) comes down to z = \\+0\\.[0-2][0-9]* m [^\n]*no file written[^\n]*\nexit [1-9]\n$"
  FAIL_REGULAR_EXPRESSION "FILE-EXISTS")
add_test(NAME cli.excite_lowest_point_warning COMMAND twinwatch excite ur3e -o ${d}/low.yaml --global-evals 100 --local-evals 100 --min-height -1)
set_tests_properties(cli.excite_lowest_point_warning PROPERTIES
  PASS_REGULAR_EXPRESSION "WARNING: the (flange|J[2-6] axis) comes down to z = -0\\.[0-9]+ m[^\n]*\\(--min-height -1 m\\): [^\n]*may hit the table")
# a tool on the flange is kept above --min-height when its points are given (flange frame, m; three
# numbers an occurrence, repeated for more points): the file says which points were kept up, and
# without one the output says a tool was not checked. A point in mm is refused by its option.
add_test(NAME cli.excite_tool_point
  COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/tool.yaml --global-evals 300 --local-evals 300 --tool-point 0 0 0.2 --tool-point 0.03 0 0.18 && grep 'lowest point' ${d}/tool.yaml")
set_tests_properties(cli.excite_tool_point PROPERTIES PASS_REGULAR_EXPRESSION
  "kept above --min-height 0\\.05 m with tool point 1 \\(0, 0, 0\\.2\\) m. tool point 2 \\(0\\.03, 0, 0\\.18\\) m. no other collision check\\)
.*# lowest point: [^
]*comes down to z = \\+0\\.(0[5-9]|[1-9])[0-9]* m [^
]*\\(kept above 0\\.05 m with tool point 1 \\(0, 0, 0\\.2\\) m. tool point 2")
add_test(NAME cli.excite_no_tool_point COMMAND twinwatch excite ur3e -o ${d}/notool.yaml --global-evals 100 --local-evals 100)
set_tests_properties(cli.excite_no_tool_point PROPERTIES PASS_REGULAR_EXPRESSION
  "a tool on the flange was not checked: give its lowest points with --tool-point X Y Z")
add_test(NAME cli.excite_tool_point_in_mm COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/mm.yaml --tool-point 0 0 0.1 --tool-point 0 0 150 2>&1; echo exit \$?")
set_tests_properties(cli.excite_tool_point_in_mm PROPERTIES PASS_REGULAR_EXPRESSION
  "error: --tool-point \\(number 2 of 2\\) is \\(0, 0, 150\\) m, 150 m from the flange: expected at most 2 m \\(a value in mm\\?\\) \\(ur3e\\)
exit [1-9]")
add_test(NAME cli.excite_tool_point_two_numbers COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e -o ${d}/two.yaml --tool-point 0 0.1 2>&1; echo exit \$?")
set_tests_properties(cli.excite_tool_point_two_numbers PROPERTIES PASS_REGULAR_EXPRESSION "--tool-point: 3 required FLOAT[:A-Z ]* missing[^\n]*\n.*exit [1-9]")
# an option where the third number was due is named as such (it said "Could not convert: --tool-point
# = 0,0,-o"); one period beyond the longest run the simulator takes is refused before the design
# (the file was written, exit 0, and simulate refused it: audit of session 56)
add_test(NAME cli.excite_refuses_what_simulate_would COMMAND sh -c "$<TARGET_FILE:twinwatch> excite ur3e --tool-point 0 0 -o ${d}/x.yaml 2>&1; echo exit \$?; \
$<TARGET_FILE:twinwatch> excite ur3e --base-frequency 1e-9 -o ${d}/lowf.yaml 2>&1; echo exit \$?; ls ${d}/lowf.yaml 2>&1")
set_tests_properties(cli.excite_refuses_what_simulate_would PROPERTIES PASS_REGULAR_EXPRESSION
  "--tool-point: expected three numbers X Y Z \\[m\\] an occurrence, got '-o' \\(an option where a number was due: are numbers missing\\?\\)[^\n]*\n.*exit 2\nerror: --base-frequency 1e-09 Hz: one period is 1e\\+09 s, longer than the longest run the simulator accepts \\(1e\\+06 s\\)[^\n]*\nexit 2\n[^\n]*No such file")
# the library's field names are told as the options the user typed (audit of session 22: "q0 has 3 values")
add_test(NAME cli.excite_option_named COMMAND twinwatch excite ur3e -o ${d}/bad.yaml --q0 0 0 0)
set_tests_properties(cli.excite_option_named PROPERTIES PASS_REGULAR_EXPRESSION "error: --q0 has 3 values, expected 6 \\(model.n_dof\\) or none \\(ur3e\\)")
# a friction table with a joint twice (the later row won), a nan parameter (ended in "no valid
# samples", naming nothing) or another table's header (read by position) is refused at its line
foreach(case "dup;joint,phi1,phi2,phi3\n1,0.1,2,0\n2,0.1,2,0\n3,0.1,2,0\n4,0.1,2,0\n5,0.1,2,0\n6,0.1,2,0\n3,50,2,0\n;:8: field 'joint': joint 3 has a row already"
             "nan;joint,phi1,phi2,phi3\n1,nan,2,0\n;:2: field 'phi1': expected a finite number, got 'nan'"
             "header;a,b,c,d\n1,0.1,2,0\n;:1: expected the header 'joint,phi1,phi2,phi3'")
  list(GET case 0 name)
  list(GET case 1 text)
  list(GET case 2 want)
  add_test(NAME cli.validate_torque_friction_table_${name}
           COMMAND sh -c "printf '${text}' > ${d}/ft_${name}.csv && $<TARGET_FILE:twinwatch> validate-torque ${d}/exc.csv --model ${d}/rb.json --published ur3e --friction-table ${d}/ft_${name}.csv 2>&1; echo exit=\$?")
  set_tests_properties(cli.validate_torque_friction_table_${name} PROPERTIES FIXTURES_REQUIRED excite_model
                       PASS_REGULAR_EXPRESSION "ft_${name}.csv${want}.*exit=2")
endforeach()
# the installation's safety limits as constraints of the design: the tool 0.1 m out kept within
# 0.3 m/s and the elbow within 0.15 m/s, each less the safety system's 0.05 m/s tolerance, said in the
# summary and the file's comment, and the program urscript writes from it passes the same limits
add_test(NAME cli.excite_safety_limits
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T excite ur3e -o ${d}/slow.yaml --harmonics 4 --global-evals 200 --local-evals 200 --duration 20 --tool-point 0 0 0.1 --tool-speed-limit 0.3 --elbow-speed-limit 0.15 2>/dev/null | grep '^peak'; grep -c '^# peak tool speed 0.[0-9]* m/s at tool point 1 (0, 0, 0.1) m (kept within 0.25 m/s' ${d}/slow.yaml; \$T urscript ${d}/slow.yaml -o ${d}/slow.script --tool-point 0 0 0.1 --tool-speed-limit 0.3 --elbow-speed-limit 0.15 | grep -E 'peak (tool|elbow)'; \$T excite ur3e -o ${d}/x.yaml --momentum-limit 0 2>&1; echo exit \$?")
set_tests_properties(cli.excite_safety_limits PROPERTIES PASS_REGULAR_EXPRESSION
  "^peak tool speed 0\\.(1[0-9]*|2[0-4][0-9]*|250) m/s at tool point 1 \\(0, 0, 0\\.1\\) m \\(kept within 0\\.25 m/s \\(the --tool-speed-limit 0\\.3 less the safety system's 0\\.05 m/s tolerance\\)\\), elbow 0\\.(0[0-9]*|100) m/s \\(kept within 0\\.1 m/s \\(the --elbow-speed-limit 0\\.15 less the safety system's 0\\.05 m/s tolerance\\)\\), momentum [0-9.]+ kg m/s of the links \\(not limited: --momentum-limit\\)\n1\n  peak tool speed +0\\.[0-9]+ m/s at [0-9.]+ s \\(tool point 1 \\(0, 0, 0\\.1\\) m\\): within 0\\.25 m/s \\(the --tool-speed-limit 0\\.3 less[^\n]*\\([0-9]+ %\\)\n  peak elbow speed +0\\.[0-9]+ m/s at [0-9.]+ s: within 0\\.1 m/s \\(the --elbow-speed-limit 0\\.15 less[^\n]*\\([0-9]+ %\\)\n--momentum-limit: expected a finite number > 0, got '0'[^\n]*\n[^\n]*\nexit 2\n")
# a design the limits (or a small amplitude) leave too little motion in is written with a warning
# (cond(W) above 1e4; session 46 measured what that costs the twin), in --json too; one that moves is not
add_test(NAME cli.excite_too_little_motion
  COMMAND sh -c "T=$<TARGET_FILE:twinwatch>; \$T excite ur3e -o ${d}/still.yaml --harmonics 4 --global-evals 200 --local-evals 200 --duration 20 --tool-speed-limit 0.08 -q 2>&1; echo exit \$?; test -e ${d}/still.yaml && echo FILE; \$T excite ur3e -o ${d}/still.yaml --harmonics 4 --global-evals 200 --local-evals 200 --duration 20 --tool-speed-limit 0.08 --json 2>/dev/null | grep -A1 '\"warnings\"'; \$T excite ur3e -o ${d}/moves.yaml --harmonics 4 --global-evals 200 --local-evals 200 --duration 20 --json 2>&1 | grep -E 'WARNING|\"warnings\"'")
set_tests_properties(cli.excite_too_little_motion PROPERTIES PASS_REGULAR_EXPRESSION
  "^WARNING: cond\\(W\\) is [0-9.e+]+, above 10000: the design moves the arm too little to identify its dynamics well \\(the safety limits scaled it down: peak tool speed 0\\.0[0-9]+ m/s\\)[^\n]*Identify it together with the swing pair[^\n]*\nexit 0\nFILE\n  \"warnings\": \\[\n    \"cond\\(W\\) is [^\n]*\n  \"warnings\": \\[\\]\n$")
