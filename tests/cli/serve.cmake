# `twinwatch serve`: the live dashboard (serve.sh: the replay read over HTTP as a browser and a
# script would, its events those of monitor), and what it refuses
set(d ${PROJECT_BINARY_DIR}/cli-pipeline)
if(BUILD_DASHBOARD)
  add_test(NAME cli.serve_dashboard
           COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/serve.sh $<TARGET_FILE:twinwatch> ${d}/twin.json ${d}/collision.csv ${d}/serve)
  set_tests_properties(cli.serve_dashboard PROPERTIES FIXTURES_REQUIRED "twin;collision_recording" PASS_REGULAR_EXPRESSION "PASS"
                       TIMEOUT 120)
  add_test(NAME cli.serve_bad_listen COMMAND twinwatch serve --twin ${d}/twin.json ${d}/collision.csv --listen 127.0.0.1:99999)
  set_tests_properties(cli.serve_bad_listen PROPERTIES FIXTURES_REQUIRED "twin;collision_recording"
                       PASS_REGULAR_EXPRESSION "--listen 127.0.0.1:99999: the port must be a whole number from 0 to 65535, got '99999'")
  add_test(NAME cli.serve_speed_live COMMAND twinwatch serve --twin ${d}/twin.json --rtde 127.0.0.1:1 --speed 2)
  set_tests_properties(cli.serve_speed_live PROPERTIES FIXTURES_REQUIRED twin
                       PASS_REGULAR_EXPRESSION "--speed applies only with a RECORDING. a live robot sets its own pace")
endif()
# the page's script parses (where node is installed: a syntax error would leave the page blank with
# nothing said but in the browser's console)
find_program(NODE_EXECUTABLE node)
if(BUILD_DASHBOARD AND NODE_EXECUTABLE)
  add_test(NAME cli.dashboard_page_script_parses
           COMMAND sh -c "sed -n '/^<script>$/,/^<\\/script>$/p' ${PROJECT_SOURCE_DIR}/web/dashboard.html | sed '1d;$d' > ${PROJECT_BINARY_DIR}/dashboard_page.js && \
test -s ${PROJECT_BINARY_DIR}/dashboard_page.js && ${NODE_EXECUTABLE} --check ${PROJECT_BINARY_DIR}/dashboard_page.js && echo PARSES")
  set_tests_properties(cli.dashboard_page_script_parses PROPERTIES PASS_REGULAR_EXPRESSION "PARSES")
endif()
