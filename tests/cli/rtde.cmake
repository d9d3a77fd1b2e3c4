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
