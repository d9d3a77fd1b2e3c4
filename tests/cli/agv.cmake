add_test(NAME cli.agv_demo COMMAND twinwatch agv demo --json --speed 20)
set_tests_properties(cli.agv_demo PROPERTIES PASS_REGULAR_EXPRESSION
  "\"alerts\":0,\"name\":\"straight_4rad_s\".*\"alerts\":0,\"name\":\"rotate_in_place_4rad_s\".*\"alerts\":0,\"name\":\"sudden_stop\".*\"alert_duration_s\":(2\\.[89]|3\\.[0-2])[0-9]*,\"alerts\":1,\"name\":\"forced_divergence\"")
set(agvd ${PROJECT_BINARY_DIR}/cli-agv)
file(MAKE_DIRECTORY ${agvd})
add_test(NAME cli.agv_make_tests COMMAND twinwatch agv make-tests -o ${agvd}/tests.csv)
set_tests_properties(cli.agv_make_tests PROPERTIES FIXTURES_SETUP agvtests)
add_test(NAME cli.agv_identify COMMAND twinwatch agv identify ${agvd}/tests.csv --json)
set_tests_properties(cli.agv_identify PROPERTIES FIXTURES_REQUIRED agvtests PASS_REGULAR_EXPRESSION "\"left\":\\{\"B\"")
