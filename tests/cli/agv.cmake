add_test(NAME cli.agv_demo COMMAND twinwatch agv demo --json --speed 20)
set_tests_properties(cli.agv_demo PROPERTIES PASS_REGULAR_EXPRESSION
  "\"pass\":true.*\"alerts\":0,\"expected_alerts\":0,\"name\":\"straight_4rad_s\",\"pass\":true.*\"alerts\":0,\"expected_alerts\":0,\"name\":\"rotate_in_place_4rad_s\",\"pass\":true.*\"alerts\":0,\"expected_alerts\":0,\"name\":\"sudden_stop\",\"pass\":true.*\"alert_duration_s\":(2\\.[89]|3\\.[0-2])[0-9]*,\"alert_spans\":\\[\\{\"channel\":\"angular speed\"[^]]*\\],\"alerts\":1,\"expected_alerts\":1,\"name\":\"forced_divergence\",\"pass\":true")
set(agvd ${PROJECT_BINARY_DIR}/cli-agv)
file(MAKE_DIRECTORY ${agvd})
add_test(NAME cli.agv_make_tests COMMAND twinwatch agv make-tests -o ${agvd}/tests.csv)
set_tests_properties(cli.agv_make_tests PROPERTIES FIXTURES_SETUP agvtests)
add_test(NAME cli.agv_identify COMMAND twinwatch agv identify ${agvd}/tests.csv --json)
set_tests_properties(cli.agv_identify PROPERTIES FIXTURES_REQUIRED agvtests PASS_REGULAR_EXPRESSION "\"left\":\\{\"B\".*\"pi\":\\{\"Kc\":0\\.3.*\"units\":\\{\"B\":\"N·m·s/rad\"")
# --speed must be a factor in range (0 and -1 used to run the demo, 1e-300 overflowed the period)
foreach(speed 0 -1 1e-300)
  add_test(NAME cli.agv_demo_speed_${speed} COMMAND sh -c "$<TARGET_FILE:twinwatch> agv demo --speed ${speed} 2>&1; echo exit \$?")
  set_tests_properties(cli.agv_demo_speed_${speed} PROPERTIES PASS_REGULAR_EXPRESSION "error: --speed must be a factor from 0.05 to 1000, got ${speed}\nexit [1-9]")
endforeach()
# the demo's twin identified from a test file (make-tests' own: the same table as the default)
add_test(NAME cli.agv_demo_tests_file COMMAND twinwatch agv demo --speed 20 --tests ${PROJECT_BINARY_DIR}/cli-agv/tests.csv)
set_tests_properties(cli.agv_demo_tests_file PROPERTIES FIXTURES_REQUIRED agvtests
                     PASS_REGULAR_EXPRESSION "forced_divergence +1 +(2\\.[89]|3\\.[0-2])[0-9] +one alert" FAIL_REGULAR_EXPRESSION "FAIL")
# what a verb prints must reach its file: a full disk is exit 1 (it was 0, the output lost)
execute_process(COMMAND test -c /dev/full RESULT_VARIABLE no_dev_full_out)
if(no_dev_full_out EQUAL 0)
  add_test(NAME cli.output_to_a_full_disk COMMAND sh -c "$<TARGET_FILE:twinwatch> model show ur3e > /dev/full; echo exit \$?")
  set_tests_properties(cli.output_to_a_full_disk PROPERTIES PASS_REGULAR_EXPRESSION "error: the output could not be written \\(standard output: No space left on device\\)\nexit 1")
endif()
# a failed write is an error naming the path (it used to print "wrote /dev/full" and exit 0)
# (only where /dev/full is the device: where it is missing, the write would create a file there)
execute_process(COMMAND test -c /dev/full RESULT_VARIABLE no_dev_full)
if(no_dev_full EQUAL 0)
  add_test(NAME cli.agv_make_tests_disk_full COMMAND sh -c "$<TARGET_FILE:twinwatch> agv make-tests -o /dev/full 2>&1; echo exit \$?")
  set_tests_properties(cli.agv_make_tests_disk_full PROPERTIES PASS_REGULAR_EXPRESSION "error: /dev/full: write error \\(disk full\\?\\)\nexit [1-9]"
                       FAIL_REGULAR_EXPRESSION "wrote")
endif()
# CRLF line ends give the same parameters as LF; a nan cell is named with its line and column
add_test(NAME cli.agv_identify_crlf
         COMMAND sh -c "sed 's/$/\\r/' ${agvd}/tests.csv > ${agvd}/crlf.csv && $<TARGET_FILE:twinwatch> agv identify ${agvd}/tests.csv --json > ${agvd}/lf.json && \
$<TARGET_FILE:twinwatch> agv identify ${agvd}/crlf.csv --json > ${agvd}/crlf.json && cmp ${agvd}/lf.json ${agvd}/crlf.json && echo SAME")
set_tests_properties(cli.agv_identify_crlf PROPERTIES FIXTURES_REQUIRED agvtests PASS_REGULAR_EXPRESSION "SAME")
add_test(NAME cli.agv_identify_nan
         COMMAND sh -c "sed '7s/^\\([a-z]*,[a-z]*,[^,]*\\),[^,]*/\\1,nan/' ${agvd}/tests.csv > ${agvd}/nan.csv && $<TARGET_FILE:twinwatch> agv identify ${agvd}/nan.csv 2>&1; echo exit \$?")
set_tests_properties(cli.agv_identify_nan PROPERTIES FIXTURES_REQUIRED agvtests
                     PASS_REGULAR_EXPRESSION "nan\\.csv:7: field 'current_A': expected a finite number, got 'nan'\nexit [1-9]")
